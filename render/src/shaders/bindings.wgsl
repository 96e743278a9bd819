// The material's GPU bindings: the parameter block and the data buffer every file reads, and shared
// constants. All positions are relative to the camera target (the CPU folds 2π k·target into each
// wave's phase in f64), which keeps f32 phases accurate far from the origin.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

const PI: f32 = 3.14159265;

const TAU: f32 = 6.2831853;

const FRAC_1_PI: f32 = 0.31830988;

const SQRT_2: f32 = 1.4142135;

// The material's parameter block `Params` is generated from Rust (gpu_types.rs `MaterialParams`,
// in the prelude before this file), with each field documented.

@group(0) @binding(0) var<storage, read> params: Params;

// data-access: storage (begin)
// The material's data (tables, grids, images) as a storage buffer: how the exported snippet reads
// it. The views read the same words from a texture instead (`shaders::view_material`, which
// replaces this block with `shaders/data_texture.wgsl`).
@group(0) @binding(1) var<storage, read> data: array<f32>;

// Entry i of the material's data. GPU only.
fn datum(i: u32) -> f32 {
    return data[i];
}
// data-access: storage (end)

// GPU only. Set when a loop stopped before its own condition ended it. Mesa's gallivm (llvmpipe,
// lavapipe) gives a whole invocation of its SIMD batch ONE budget of 65535 loop iterations
// (`lp_exec_mask_function_init`: one limiter per function, and every shader function is inlined
// into the entry point): every iteration of every loop spends it, counted while any of the 8 lanes
// runs, and it is never refilled; once spent, every later loop leaves after its first iteration,
// whatever its own condition, silently. (Unrolled loops spend nothing, but naga's loops are not
// unrolled.) A long march reaches that, and so can the shading after it: the heavy per-node and
// per-term loops are therefore written four or eight steps per iteration. The march's loops say so
// themselves (note_cut), and note_budget, called last, catches a cut in any loop. The view counts
// the pixels and rays it touched (view.wgsl `cut_count`) instead of showing a wrong answer as
// right. Cleared per ray or pixel by the view.
var<private> loop_cut: bool;

// GPU only. The work of this invocation's ray (or pixel) so far, in units of eight waves summed plus
// one per march step: what a ground-truth ray of a pixel costs, for cost-aware ray counts
// (view.wgsl `work_sum`, ViewTarget::read_work). Private, so zero at every invocation's start.
var<private> work: u32;

// GPU only: add `units` to this invocation's work.
fn note_work(units: u32) {
    work = work + units;
}

// GPU only: record that a loop was cut (`cut` true).
fn note_cut(cut: bool) {
    loop_cut = loop_cut || cut;
}

// GPU only: record whether the invocation's loop budget (see loop_cut) ran out, which would have
// cut some loop: a loop of `two` (= 2) iterations comes back short once it has. Called after the
// last loop of a ray or pixel. `two` must be a value whose bound the compiler cannot see, or it
// unrolls the loop (an unrolled loop spends no budget); and the loop's count is read from a
// state that has no closed form (a linear congruential step), or the compiler computes it from
// `two` without running the loop (measured: a plain counter read 2 after a cut loop).
fn note_budget(two: u32) {
    var k = 0u;
    var s = two;
    loop {
        k = k + 1u;
        s = budget_step(s);
        if (k >= two) {
            break;
        }
    }
    note_cut(s != budget_step(budget_step(two)));
}

// GPU only: note_budget's state, one step on.
fn budget_step(s: u32) -> u32 {
    return s * 1664525u + 1013904223u;
}
