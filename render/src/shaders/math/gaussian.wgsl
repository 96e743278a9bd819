// Mirror of `core/src/math/gaussian.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief|measured
fn cholesky(c: vec3<f32>) -> vec3<f32> {
    let l11 = sqrt(max(c.x, 0.0));
    var l21 = 0.0;
    if (l11 > 0.0) {
        l21 = c.z / l11;
    }
    return vec3<f32>(l11, l21, sqrt(max(c.y - l21 * l21, 0.0)));
}
//#endif
