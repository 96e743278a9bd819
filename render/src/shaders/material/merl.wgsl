// Mirror of `core/src/material/merl.rs` (the lookup), function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if measured
// merl::THETA_H_RES, THETA_D_RES, PHI_D_RES, ENTRIES.
const MERL_THETA_H_RES: u32 = 90u;
const MERL_THETA_D_RES: u32 = 90u;
const MERL_PHI_D_RES: u32 = 180u;
const MERL_ENTRIES: u32 = 1458000u;

// merl::half_diff: (θ_h, θ_d, φ_d) of the pair. The polar angles are taken with atan2 of the
// vector's length in the plane and its z (acos near 1 loses the first θ_h bins in f32).
fn half_diff(wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let sum = wi + wo;
    let len = length(sum);
    if (!(len > 1e-6)) {
        return vec3<f32>(0.0, 0.5 * PI, 0.0);
    }
    let h = sum / len;
    let theta_h = atan2(length(h.xy), h.z);
    let phi_h = atan2(h.y, h.x);
    // ωi in h's frame: rotate by −φ_h about z, then by −θ_h about y.
    let s1 = sin(-phi_h);
    let c1 = cos(-phi_h);
    let a = vec3<f32>(c1 * wi.x - s1 * wi.y, s1 * wi.x + c1 * wi.y, wi.z);
    let s2 = sin(-theta_h);
    let c2 = cos(-theta_h);
    let d = vec3<f32>(c2 * a.x + s2 * a.z, a.y, -s2 * a.x + c2 * a.z);
    return vec3<f32>(theta_h, atan2(length(d.xy), d.z), atan2(d.y, d.x));
}

// merl::theta_h_index (square-root spacing).
fn theta_h_index(theta_h: f32) -> u32 {
    if (!(theta_h > 0.0)) {
        return 0u;
    }
    return min(u32(sqrt(theta_h / (0.5 * PI)) * f32(MERL_THETA_H_RES)), MERL_THETA_H_RES - 1u);
}

// merl::theta_d_index.
fn theta_d_index(theta_d: f32) -> u32 {
    if (!(theta_d > 0.0)) {
        return 0u;
    }
    return min(u32(theta_d / (0.5 * PI) * f32(MERL_THETA_D_RES)), MERL_THETA_D_RES - 1u);
}

// merl::phi_d_index (folded into [0, π) by reciprocity).
fn phi_d_index(phi_d: f32) -> u32 {
    let p = phi_d - PI * floor(phi_d / PI);
    return min(u32(max(p, 0.0) / PI * f32(MERL_PHI_D_RES)), MERL_PHI_D_RES - 1u);
}

// MerlBrdf::eval: ρ per channel of the pair in the tangent frame (0 at or below the horizon).
fn merl_eval(wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    let a = half_diff(wi, wo);
    let i = params.merl_offset + phi_d_index(a.z) + MERL_PHI_D_RES * (theta_d_index(a.y) + MERL_THETA_D_RES * theta_h_index(a.x));
    return vec3<f32>(datum(i), datum(i + MERL_ENTRIES), datum(i + 2u * MERL_ENTRIES));
}
//#endif
