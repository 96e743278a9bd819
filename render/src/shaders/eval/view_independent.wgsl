// Mirror of `core/src/eval/view_independent.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
//#if slope_color
// visible_slopes::slope_mean of C_s: the footprint average without visibility weight.
fn slope_color_mean(mean: vec2<f32>, cov: vec3<f32>) -> vec3<f32> {
    let l = cholesky(cov);
    let nodes = params.slope_nodes;
    var acc = vec3<f32>(0.0);
    for (var i = 0u; i < nodes; i = i + 1u) {
        let z = slope_node(i);
        let s = mean + vec2<f32>(l.x * z.x, l.y * z.x + l.z * z.y);
        acc = acc + z.z * slope_color_at(shading_frame * normal_of(s));
    }
    return acc;
}

//#endif
//#endif
// Evaluator::view_independent.
fn eval_view_independent(x0: vec2<f32>, fp: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, sun_visible: f32) -> vec3<f32> {
    let loc = footprint_stats(x0, fp);
    let ms = input_distribution(loc);
    let c = color_of_distribution(ms.x, ms.y, 0.0, vec2<f32>(0.0, 1.0), ms.y * ms.y);
    let n = normal_of(loc.stats.slope_mean);
    let aff = affine(c);
    var sh = point_shading(n, wi);
//#if slope_color
//#if relief
    let cs = slope_color_mean(loc.stats.slope_mean, loc.stats.slope_cov);
//#else
    let cs = slope_color_at(shading_frame * n);
//#endif
    sh.cs_cos = cs * sh.cos;
    sh.cs_env = cs * sh.env;
//#endif
    return radiance(aff, aff, sh, sun_visible * lit(wi, n), facet_specular(n, wo, wi));
}
