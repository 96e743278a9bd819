// Mirror of `core/src/microfacet/slope_masking.rs` (the lookup half: the masking itself is
// tabulated on the CPU, `eval/masking/slope_masking_table.wgsl`).
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
// A slope profile: SLOPE_NODES = 9 values, node j at m[j / 3][j % 3] (a matrix, not an array:
// the GLSL the export translates to does not round-trip arrays of a constant's size; render's
// gpu_codes tests that SLOPE_NODES is 9).
struct SlopeProfile {
    m: mat3x3<f32>,
}

// Node j of a profile.
fn profile_node(p: SlopeProfile, j: u32) -> f32 {
    return p.m[j / 3u][j % 3u];
}

// slope_masking::profile_at: linear between the profile's nodes (slopes −4 to 4 by 1, in σ_t),
// clamped to the ends; NaN reads the value at 0.
fn profile_at(profile: SlopeProfile, z: f32) -> f32 {
    var zz = z;
    if (zz != zz) {
        zz = 0.0;
    }
    let x = clamp(zz + 4.0, 0.0, f32(SLOPE_NODES - 1u));
    let i = min(u32(x), SLOPE_NODES - 2u);
    let f = x - f32(i);
    return profile_node(profile, i) * (1.0 - f) + profile_node(profile, i + 1u) * f;
}

// JointMasking of the pixel being shaded: ln r at HEIGHT_NODES × SLOPE_NODES (= 90, tested in
// gpu_codes) nodes, height-major, written by slope_masking_lookup.
var<private> joint_masking: array<f32, 90>;

// height_cell: the height nodes i, i + 1 around h (σ_h units, from −HEIGHT_NODE_DEPTH by 1; NaN
// reads 0) and the weight of i + 1, clamped to the end nodes.
fn height_cell(h: f32) -> vec2<f32> {
    var hh = h;
    if (hh != hh) {
        hh = 0.0;
    }
    let x = clamp(hh + HEIGHT_NODE_DEPTH, 0.0, f32(HEIGHT_NODES - 1u));
    let i = min(floor(x), f32(HEIGHT_NODES - 2u));
    return vec2<f32>(i, x - i);
}

// height_rows: the rows first..=last that log_ratio_at reads for heights in [lo, hi].
fn height_rows(lo: f32, hi: f32) -> vec2<u32> {
    let a = height_cell(min(lo, hi));
    let b = height_cell(max(lo, hi));
    return vec2<u32>(u32(a.x), u32(b.x) + 1u);
}

// JointMasking::log_ratio_at: ln r(h, z_j), linear between the height nodes.
fn log_ratio_at(h: f32, j: u32) -> f32 {
    let c = height_cell(h);
    let i = u32(c.x);
    return joint_masking[i * SLOPE_NODES + j] * (1.0 - c.y) + joint_masking[(i + 1u) * SLOPE_NODES + j] * c.y;
}
//#endif
