// Mirror of `core/src/driver/noise.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if noise
fn wave(i: u32) -> vec4<f32> {
    return texel4(params.waves_offset, i);
}

// UNROLL. llvmpipe (Mesa's CPU driver, what tests and CI run on) ends every loop of a shader
// invocation once all loops together have taken 65535 back-edges (LP_MAX_TGSI_LOOP_ITERATIONS,
// "shared between every loop", per 8-lane vector). A grazing march of a few thousand steps over
// 48 waves used to reach it; every later wave sum was then cut short for all 8 lanes: the "dashes"
// of wrong pixels in runs of exactly 8 (355 of 100 000 pixels of snow-under-sky at 78°, for
// example). The wave sums that run per march step take eight waves per iteration, which moves the
// limit 8× further; real GPUs have no such limit.
// Wave i's (value, gradient) at x.
fn wave_term(i: u32, x: vec2<f32>) -> vec3<f32> {
    let w = wave(i);
    let ph = TAU * dot(w.xy, x) + w.w;
    return vec3<f32>(w.z * cos(ph), -w.xy * (w.z * TAU * sin(ph)));
}
//#endif
