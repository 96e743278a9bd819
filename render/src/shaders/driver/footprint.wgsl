// Mirror of `core/src/driver/footprint.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

// Footprint::min_std: the square root of Σ_p's smaller eigenvalue (fp = xx, yy, xy); 0 when
// degenerate.
fn footprint_min_std(fp: vec3<f32>) -> f32 {
    let l = 0.5 * (fp.x + fp.y) - sqrt(0.25 * (fp.x - fp.y) * (fp.x - fp.y) + fp.z * fp.z);
    return select(0.0, sqrt(l), l > 0.0);
}

struct FilteredDriver {
    mean: f32,
    std_dev: f32,
    mean_gradient: vec2<f32>,
    gradient_cov: vec3<f32>, // xx, yy, xy
}
