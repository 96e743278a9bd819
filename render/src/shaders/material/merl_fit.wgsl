// Mirror of `core/src/material/merl_fit.rs` (what the views evaluate of the fit), function for
// function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if measured
// merl_fit::fresnel_factor: Schlick's (1 − ωi·h)⁵ (0 for ωi = −ωo).
fn fresnel_factor(wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    let s = wi + wo;
    let len = length(s);
    if (!(len > 1e-6)) {
        return 0.0;
    }
    return pow(1.0 - clamp(dot(wi, s) / len, 0.0, 1.0), 5.0);
}
//#endif
