// Mirror of `core/src/microfacet/slope_masking.rs` (the lookup half: the profiles themselves are
// tabulated on the CPU, `eval/slope_masking_table.wgsl`).
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
// slope_masking::profile_at: linear between the profile's nodes (slopes −4 to 4 by 1, in σ_t),
// clamped to the ends; NaN reads the value at 0.
fn profile_at(profile: array<f32, SLOPE_NODES>, z: f32) -> f32 {
    var p = profile;
    var zz = z;
    if (zz != zz) {
        zz = 0.0;
    }
    let x = clamp(zz + 4.0, 0.0, f32(SLOPE_NODES - 1u));
    let i = min(u32(x), SLOPE_NODES - 2u);
    let f = x - f32(i);
    return p[i] * (1.0 - f) + p[i + 1u] * f;
}
//#endif
