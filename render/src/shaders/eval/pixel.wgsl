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
    let at_hit = shade_footprint(method, p, dir, wi, fp, sf);
    if (method == MODE_NAIVE || params.interception == 0u) {
        return at_hit;
    }
    let stop = interception(o, dir, t, fp, sf);
    if (stop.x <= 0.0) {
        return at_hit;
    }
    // The crest, on h̄ below the point of the ray where the relief most likely stopped it.
    let q = o + dir * stop.y;
    let crest = vec3<f32>(q.xy, lod_height(q.xy, sf));
    return stop.x * shade_footprint(method, crest, dir, wi, fp, sf) + (1.0 - stop.x) * at_hit;
//#else
    // Flat: the plane z = 0.
    let p = origin + dir * (-origin.z / dir.z);
    return shade_footprint(method, p, dir, wi, fp, 0.0);
//#endif
}

// Evaluator::shade_footprint: the method at footprint fp around point p seen along dir, lit where a
// shadow ray on h̄ reaches the light.
fn shade_footprint(method: u32, p: vec3<f32>, dir: vec3<f32>, wi: vec3<f32>, fp: vec3<f32>, sf: f32) -> vec3<f32> {
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
