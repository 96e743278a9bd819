// Mirror of `core/src/material/measured.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if measured
// MeasuredBrdf::eval_facet: the table in the frame of facet normal n.
fn measured_eval_facet(n: vec3<f32>, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let t = basis_t(n);
    let b = basis_b(n);
    return merl_eval(vec3<f32>(dot(wi, t), dot(wi, b), dot(wi, n)), vec3<f32>(dot(wo, t), dot(wo, b), dot(wo, n)));
}
//#endif
