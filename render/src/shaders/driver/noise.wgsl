// Mirror of `core/src/driver/noise.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if noise
fn wave(i: u32) -> vec4<f32> {
    return texel4(params.waves_offset, i);
}

// The waves in workgroup memory, for the loops that run per march step (lod_prepare, lod_mean,
// octave_march, wave_term): on llvmpipe the storage-buffer loads of every wave at every step cost
// 20–30% of a view's frame (default preset, 96×64, 60°: naive 56 → 42 ms, truth 6.7 → 5.3 µs per
// ray). Filled by fill_wave_cache at the start of view_main; entry points that do not fill it (the
// exported snippet's eval_* functions) never reach these loops. GPU only.
var<workgroup> wave_cache: array<vec4<f32>, 256>;

// Copy the waves into wave_cache, `local` being the invocation's index in a workgroup of `size`;
// every invocation must call it (it ends with a barrier). GPU only.
fn fill_wave_cache(local: u32, size: u32) {
    for (var k = local; k < min(params.wave_count, 256u); k = k + size) {
        wave_cache[k] = wave(k);
    }
    workgroupBarrier();
}

// Wave i from wave_cache. GPU only.
fn cached_wave(i: u32) -> vec4<f32> {
    return wave_cache[i];
}

// UNROLL. llvmpipe (Mesa's CPU driver, what tests and CI run on) ends every loop of a shader
// invocation once all loops together have taken 65535 back-edges (LP_MAX_TGSI_LOOP_ITERATIONS,
// "shared between every loop", per 8-lane vector). A grazing march of a few thousand steps over
// 48 waves used to reach it; every later wave sum was then cut short for all 8 lanes: the "dashes"
// of wrong pixels in runs of exactly 8 (355 of 100 000 pixels of snow-under-sky at 78°, for
// example). The wave sums that run per march step take eight waves per iteration, which moves the
// limit 8× further; real GPUs have no such limit.
// Wave i's (value, gradient) at x, from wave_cache (value_and_gradient runs per step of the
// reference march and in ground-truth shading, in view_main only).
fn wave_term(i: u32, x: vec2<f32>) -> vec3<f32> {
    let w = cached_wave(i);
    let ph = TAU * dot(w.xy, x) + w.w;
    return vec3<f32>(w.z * cos(ph), -w.xy * (w.z * TAU * sin(ph)));
}
//#endif
