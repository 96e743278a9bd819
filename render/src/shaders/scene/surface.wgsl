// Mirror of `core/src/scene/surface.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief|curved
fn surface_height(x: vec2<f32>) -> f32 {
    return params.sigma_h * transfer_eval(value_and_gradient(x).x).x;
}

//#endif
//#if relief
fn lipschitz_along(dir: vec2<f32>) -> f32 {
//#if image
    if (params.driver_kind == DRIVER_IMAGE) {
        return params.sigma_h * params.g_lip * image_lipschitz_along(dir);
    }
//#endif
    var s = 0.0;
//#if noise
    for (var i = 0u; i < params.wave_count; i = i + 1u) {
        let w = wave(i);
        s = s + abs(w.z) * TAU * abs(dot(w.xy, dir));
    }
//#endif
    return params.sigma_h * params.g_lip * s;
}

// Height of the explicit surface (lod = false) or of the level-of-detail surface (lod = true, needs
// lod_prepare first).
fn field_height(x: vec2<f32>, lod: bool, sf: f32) -> f32 {
    if (lod) {
        return lod_height(x, sf);
    }
    return surface_height(x);
}

// Surface::march: the octave march for a noise driver under MARCH_FAST, else the reference steps.
fn march(o: vec3<f32>, d: vec3<f32>) -> f32 {
//#if noise
    if (params.driver_kind == DRIVER_NOISE && params.march == MARCH_FAST) {
        return octave_march(o, d, false, 0.0);
    }
//#endif
    let r = length(d.xy);
    var k = 0.0;
    if (r > 0.0) {
        k = lipschitz_along(d.xy / r);
    }
    return march_heightfield(o, d, abs(d.z) + k * r, false, 0.0);
}

fn sees(p: vec3<f32>, d: vec3<f32>) -> bool {
    if (d.z <= 0.0) {
        return false;
    }
    return march(p, d) < 0.0;
}
//#endif
