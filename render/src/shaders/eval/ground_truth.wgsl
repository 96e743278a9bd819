// Mirror of `core/src/eval/ground_truth.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

// Evaluator::trace_pixel_sample for a camera ray (origin, unit direction).
fn trace_ray(origin: vec3<f32>, dir: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (dir.z >= 0.0) {
        return vec3<f32>(0.0);
    }
//#if relief
    // Start on the top of the slab.
    let top = params.h_max * 1.001 + 1e-6;
    let t0 = max((origin.z - top) / -dir.z, 0.0);
    let o = origin + dir * t0;
    let t = march(o, dir);
    if (t < 0.0) {
        return vec3<f32>(0.0);
    }
    let p = o + dir * t;
    let fg = value_and_gradient(p.xy);
    let gd = transfer_eval(fg.x);
    let n = normal_of(fg.yz * (params.sigma_h * gd.y));
//#else
    // Flat: the plane z = 0, facing +z everywhere.
    let p = origin + dir * (-origin.z / dir.z);
    let fg = value_and_gradient(p.xy);
    let n = vec3<f32>(0.0, 0.0, 1.0);
//#endif
    return shade_hit(fg.x, n, -dir, wi, p);
}

// Evaluator::shade_hit on the plane (the shadow ray only when the directional light can contribute).
fn shade_hit(f: f32, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, p: vec3<f32>) -> vec3<f32> {
    let lit = dot(n, wi) > 0.0 && params.sun > 0.0;
    if (!lit && !has_environment()) {
        return vec3<f32>(0.0);
    }
    var v = select(0.0, 1.0, lit && wi.z > 0.0);
//#if shadows
    if (v > 0.0 && !sees(p, wi)) {
        v = 0.0;
    }
//#endif
    return shade_point(f, n, wo, wi, v);
}

// The end of Evaluator::shade_hit: colour terms and radiance at a facet with light visibility v.
fn shade_point(f: f32, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, v: f32) -> vec3<f32> {
    return facet_radiance(affine(color_at(f)), n, wo, wi, v);
}
