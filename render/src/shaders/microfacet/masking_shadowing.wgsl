// Mirror of `core/src/microfacet/masking_shadowing.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
fn azimuth_factor(d: f32) -> f32 {
    let a = min(abs(d), PI);
    return AZIMUTH_CORRELATION * a / (AZIMUTH_CORRELATION * a + 1.0);
}

fn azimuth_difference(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let ra = length(a.xy);
    let rb = length(b.xy);
    if (!(ra > 0.0 && rb > 0.0)) {
        return 0.0;
    }
    let c = clamp(dot(a.xy, b.xy) / (ra * rb), -1.0, 1.0);
    let s = (a.x * b.y - a.y * b.x) / (ra * rb);
    return atan2(abs(s), c);
}

// MaskingShadowing (alias G2): Λo, Λi, L − Λo and the joint exponent L of the height-correlated
// masking–shadowing G2 [HNPN14 Eqs. 11–12].
struct MaskingShadowing {
    lambda_o: f32,
    lambda_i: f32,
    excess: f32,
    total: f32,
}

// MaskingShadowing::from_directions.
fn masking_shadowing(wo: vec3<f32>, wi: vec3<f32>, cov: vec3<f32>) -> MaskingShadowing {
    let lo = max(lambda(wo, cov), 0.0);
    let li = max(lambda(wi, cov), 0.0);
    var excess = li;
    if (params.correlation == CORRELATION_HEIGHT_DIRECTION) {
        let k = azimuth_factor(azimuth_difference(wo, wi));
        excess = select((li - lo) + k * lo, k * li, lo >= li);
    }
    return MaskingShadowing(lo, li, excess, lo + excess);
}

// MaskingShadowing::mean_shadowing [HNPN14 Eq. 12].
fn mean_shadowing(m: MaskingShadowing) -> f32 {
    return 1.0 / (1.0 + m.excess / (1.0 + m.lambda_o));
}
//#endif
