// Mirror of `core/src/microfacet/attribute.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if attribute_color
fn attribute_shape(t: f32) -> f32 {
    return erf(t * FRAC_1_SQRT_2);
}

fn mean_attribute_shape(l: f32) -> f32 {
    return 1.0 - 2.0 / (max(l, 0.0) + 2.0);
}
//#endif
