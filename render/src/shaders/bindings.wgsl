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

@group(0) @binding(1) var<storage, read> data: array<f32>;
