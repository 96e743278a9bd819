// Mirror of `core/src/eval/naive.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

// Evaluator::naive (sun_visible: the directional light's shadow test on the level-of-detail surface).
fn eval_naive(x0: vec2<f32>, fp: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, sun_visible: f32) -> vec3<f32> {
    let loc = footprint_stats(x0, fp);
    let n = normal_of(loc.stats.slope_mean);
    return facet_radiance(affine(color_at(loc.driver.mean)), n, wo, wi, sun_visible * lit(wi, n));
}
