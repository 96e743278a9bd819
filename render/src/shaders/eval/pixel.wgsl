// Mirror of `core/src/eval/pixel.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

// Evaluator::pixel: method 0 naive, 1 view-independent, 2 filtered.
fn analytic_pixel(method: u32, origin: vec3<f32>, dir: vec3<f32>, wi: vec3<f32>, fp: vec3<f32>) -> vec3<f32> {
    if (dir.z >= 0.0) {
        return vec3<f32>(0.0);
    }
//#if relief
    let sf = lod_prepare(fp);
    let top = params.h_max * 1.001 + 1e-6;
    let t0 = max((origin.z - top) / -dir.z, 0.0);
    let o = origin + dir * t0;
    let t = lod_march(o, dir, sf);
    if (t < 0.0) {
        return vec3<f32>(0.0);
    }
    let p = o + dir * t;
//#else
    // Flat: the plane z = 0.
    let p = origin + dir * (-origin.z / dir.z);
//#endif
    var v = select(0.0, 1.0, wi.z > 0.0);
//#if shadows
    if (v > 0.0 && lod_march(p, wi, sf) >= 0.0) {
        v = 0.0;
    }
//#endif
    if (v == 0.0 && !has_environment()) {
        return vec3<f32>(0.0);
    }
    if (method == MODE_NAIVE) {
        return eval_naive(p.xy, fp, -dir, wi, v);
    } else if (method == MODE_VIEW_INDEPENDENT) {
        return eval_view_independent(p.xy, fp, -dir, wi, v);
    }
    return eval_filtered(p.xy, fp, -dir, wi, v);
}
