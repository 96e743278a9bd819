// Mirror of `core/src/microfacet/smith.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
fn cot_theta(w: vec3<f32>) -> f32 {
    if (!(w.z > 0.0)) {
        return 0.0;
    }
    let r = length(w.xy);
    if (r == 0.0) {
        return 3.0e38;
    }
    return w.z / r;
}

fn projected_std(cov: vec3<f32>, c: f32, s: f32) -> f32 {
    return sqrt(max(c * c * cov.x + 2.0 * c * s * cov.z + s * s * cov.y, 0.0));
}

// smith::lambda [HN12 Eq. 6].
fn lambda(w: vec3<f32>, cov: vec3<f32>) -> f32 {
    let mu = cot_theta(w);
    if (mu >= 3.0e38) {
        return 0.0;
    }
    let r = length(w.xy);
    let sigma = projected_std(cov, w.x / r, w.y / r);
    if (!(sigma > 0.0)) {
        return 0.0;
    }
    return smith_lambda(mu / (SQRT_2 * sigma));
}
//#endif
