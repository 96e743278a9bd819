// Mirror of `core/src/object/shading.rs`: a cone element's radiance [HN12 Eq. 13] under the sun
// `object.light`, with the material's base BRDF (`params`).

// GPU only: v in the frame (t1, t2, n) (shading.rs `local`).
fn object_local(v: vec3<f32>, t1: vec3<f32>, t2: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, t1), dot(v, t2), dot(v, n));
}

// ObjectLighting::element_radiance [HN12 Eq. 13]: the voxel's mean plane lit by the sun, seen
// along wo; ā(v, l) by Eq. 17 (the visible heights' attribute), the lobe widened by the voxel's
// slopes, Smith's mean shadowing, the sun's visibility from the shadow cone.
fn element_radiance(s: VoxelSample, wo: vec3<f32>, sun_visible: f32) -> vec3<f32> {
    let wo_l = object_local(wo, s.t1, s.t2, s.normal);
    let wi_l = object_local(object.light, s.t1, s.t2, s.normal);
    if (wo_l.z <= 0.0 || wi_l.z <= 0.0 || sun_visible <= 0.0) {
        return vec3<f32>(0.0);
    }
    let g2 = masking_shadowing(wo_l, wi_l, s.slope_cov);
    let shadow = mean_shadowing(g2);
    let kd = params.albedo * FRAC_1_PI * visible_cosine(s.slope_cov, wo_l, wi_l);
    let spec = filtered_specular(vec2<f32>(0.0), s.slope_cov, wo_l, wi_l);
    let e = object.sun * sun_visible * shadow;
    let a = max(mean_attribute(s.color_mean, s.color_height, g2.total), vec3<f32>(0.0));
    return e * (kd * a + vec3<f32>(spec));
}

// attribute::mean_attribute per channel [HN12 Eq. 17].
fn mean_attribute(mean: vec3<f32>, correlation: vec3<f32>, l: f32) -> vec3<f32> {
    return mean + correlation * mean_attribute_shape(l);
}

// visible_cosine: the visible facets' mean of (n·l)⁺ over slopes N(0, cov), by projected area
// (n·ωo)⁺/n_z, on the 4 × 4 Gauss–Hermite rule VC_X, VC_W (from core). The inner axis written
// out (the loop budget, bindings.wgsl).
fn visible_cosine(cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let l = cholesky(cov);
    let l11 = l.x;
    let l21 = l.y;
    let l22 = l.z;
    var acc = vec2<f32>(0.0);
    for (var i = 0u; i < 4u; i = i + 1u) {
        let a = VC_X[i];
        acc += VC_W[i] * visible_cosine_node(vec2<f32>(l11 * a, l21 * a + l22 * VC_X[0]), VC_W[0], wo, wi);
        acc += VC_W[i] * visible_cosine_node(vec2<f32>(l11 * a, l21 * a + l22 * VC_X[1]), VC_W[1], wo, wi);
        acc += VC_W[i] * visible_cosine_node(vec2<f32>(l11 * a, l21 * a + l22 * VC_X[2]), VC_W[2], wo, wi);
        acc += VC_W[i] * visible_cosine_node(vec2<f32>(l11 * a, l21 * a + l22 * VC_X[3]), VC_W[3], wo, wi);
    }
    if (acc.y > 0.0) {
        return acc.x / acc.y;
    }
    return max(wi.z, 0.0);
}

// GPU only: one node of visible_cosine (its loop body): (weight·p·(n·l)⁺, weight·p), p the facet's
// projected area.
fn visible_cosine_node(s: vec2<f32>, w: f32, wo: vec3<f32>, wi: vec3<f32>) -> vec2<f32> {
    let n = normal_of(s);
    let p = w * max(dot(n, wo), 0.0) / n.z;
    return vec2<f32>(p * max(dot(n, wi), 0.0), p);
}
