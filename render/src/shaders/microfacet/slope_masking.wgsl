// Mirror of `core/src/microfacet/slope_masking.rs` (the lookup half: the profiles themselves are
// tabulated on the CPU, `eval/slope_masking_table.wgsl`).
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
// ConditionedMasking's slope profile: its SLOPE_NODES = 9 values, node j at m[j / 3][j % 3] (a
// matrix, not an array: the GLSL the export translates to does not round-trip arrays of a
// constant's size; render's gpu_codes tests that SLOPE_NODES is 9).
struct SlopeProfile {
    m: mat3x3<f32>,
}

// slope_masking::profile_at: linear between the profile's nodes (slopes −4 to 4 by 1, in σ_t),
// clamped to the ends; NaN reads the value at 0.
fn profile_at(profile: SlopeProfile, z: f32) -> f32 {
    var p = profile.m;
    var zz = z;
    if (zz != zz) {
        zz = 0.0;
    }
    let x = clamp(zz + 4.0, 0.0, f32(SLOPE_NODES - 1u));
    let i = min(u32(x), SLOPE_NODES - 2u);
    let f = x - f32(i);
    let j = i + 1u;
    return p[i / 3u][i % 3u] * (1.0 - f) + p[j / 3u][j % 3u] * f;
}
//#endif
