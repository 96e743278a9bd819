// Mirror of `core/src/driver/footprint.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

struct FilteredDriver {
    mean: f32,
    std_dev: f32,
    mean_gradient: vec2<f32>,
    gradient_cov: vec3<f32>, // xx, yy, xy
}
