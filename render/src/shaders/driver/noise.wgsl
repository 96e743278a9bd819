// Mirror of `core/src/driver/noise.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if noise
fn wave(i: u32) -> vec4<f32> {
    return texel4(params.waves_offset, i);
}

// The waves again as a uniform array (binding 9, `GpuMaterial`'s wave buffer: the first 256 of
// them, zero-padded), for the loops that run per march step (lod_prepare, lod_mean, octave_march,
// wave_term). A loop's index is never "always uniform" to llvmpipe's compiler, and there it loads a
// storage or workgroup array at such an index one lane at a time, in a branchy loop over the eight
// lanes (gallivm's emit_load_mem); a uniform array at any index is one branch-free gather, and on a
// GPU it is the constant cache's broadcast. Measured (default preset, 128², one run, 60°/80° ×
// distances 1.5/6/40): naive 246–347 ms a frame from workgroup memory, see docs/design/software-adapter.md for the
// uniform array's. Only view_main's passes bind it; the exported snippet's eval_* functions never
// reach these loops. GPU only.
@group(0) @binding(9) var<uniform> wave_table: array<vec4<f32>, 256>;

// Wave i from wave_table. GPU only.
fn cached_wave(i: u32) -> vec4<f32> {
    return wave_table[i];
}

// UNROLL. llvmpipe (Mesa's CPU driver, what tests and CI run on) ends every loop of a shader
// invocation once all loops together have taken 65535 back-edges (LP_MAX_TGSI_LOOP_ITERATIONS,
// "shared between every loop", per 8-lane vector). A grazing march of a few thousand steps over
// 48 waves used to reach it; every later wave sum was then cut short for all 8 lanes: the "dashes"
// of wrong pixels in runs of exactly 8 (355 of 100 000 pixels of snow-under-sky at 78°, for
// example). The wave sums that run per march step take eight waves per iteration, which moves the
// limit 8× further; real GPUs have no such limit.
// Wave i's (value, gradient) at x, from wave_table (value_and_gradient runs per step of the
// reference march and in ground-truth shading, in view_main only).
fn wave_term(i: u32, x: vec2<f32>) -> vec3<f32> {
    let w = cached_wave(i);
    let ph = TAU * dot(w.xy, x) + w.w;
    return vec3<f32>(w.z * cos(ph), -w.xy * (w.z * TAU * sin(ph)));
}
//#endif
