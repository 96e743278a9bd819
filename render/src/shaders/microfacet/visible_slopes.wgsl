// Mirror of `core/src/microfacet/visible_slopes.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
// Node i of visible_slopes::slope_rule: (z.x, z.y, weight) of the standard bivariate normal.
fn slope_node(i: u32) -> vec3<f32> {
    let b = params.slope_rule_offset + 3u * i;
    return vec3<f32>(datum(b), datum(b + 1u), datum(b + 2u));
}

//#endif
//#if specular
// visible_slopes::expected_positive_part: E[(a − s·b)⁺] for s ~ N(mean, cov).
fn expected_positive_part(a: f32, b: vec2<f32>, mean: vec2<f32>, cov: vec3<f32>) -> f32 {
    let m = a - dot(mean, b);
    let v = b.x * b.x * cov.x + 2.0 * b.x * b.y * cov.z + b.y * b.y * cov.y;
    if (v > 1e-30) {
        let sv = sqrt(v);
        let r = clamp(m / sv, -40.0, 40.0);
        return m * norm_cdf(r) + sv * norm_pdf(r);
    }
    return max(m, 0.0);
}
//#endif
