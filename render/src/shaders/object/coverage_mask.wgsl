// Mirror of `core/src/object/coverage_mask.rs`, function for function under the same names
// [HN12 Sec. 5.4]: an element's sub-pixel occupancy as a 64-bit mask (two u32 words, bit i in
// word i / 32) looked up from the precomputed (θ, v) table `object_masks`, which ends with the 65
// thinning masks (one per count of kept sub-rays).

// coverage_mask::element_mask_params: (θ, v) of the half-space `n·w + h ≤ 0` over a cone element of
// radius r and half-length l, in the cone's frame (z along the cone). A plane parallel to the axis
// within the float noise gives v = ±1e30 (all or nothing).
fn element_mask_params(r: f32, l: f32, n: vec3<f32>, h: f32) -> vec2<f32> {
    let nxy = length(n.xy);
    let reach = l * abs(n.z) - h;
    if (!(nxy * r > 1e-12 * (abs(reach) + r))) {
        return vec2<f32>(0.0, select(-1e30, 1e30, reach >= 0.0));
    }
    return vec2<f32>(atan2(n.y, n.x), reach / (r * nxy));
}

// MaskTable::lookup: the nearest entry of the (θ, v) table; v ≤ −1 (or NaN) covers nothing, v ≥ 1
// everything.
fn mask_lookup(theta: f32, v: f32) -> vec2<u32> {
    if (!(v > -1.0)) {
        return vec2<u32>(0u, 0u);
    }
    if (v >= 1.0) {
        return vec2<u32>(0xffffffffu, 0xffffffffu);
    }
    let t = (theta - TAU * floor(theta / TAU)) / TAU * f32(MASK_ANGLES);
    let a = min(u32(t), MASK_ANGLES - 1u);
    let o = min(u32((v + 1.0) * 0.5 * f32(MASK_OFFSETS)), MASK_OFFSETS - 1u);
    return object_masks[a * MASK_OFFSETS + o];
}

// MaskTable::thinning: the sub-rays an occupancy keeps, round(64α) of them in the fixed order
// (thinning_count: all for α ≥ 1 or NaN, none for α ≤ 0).
fn thinning(occupancy: f32) -> vec2<u32> {
    var kept = MASK_BITS;
    if (occupancy < 1.0) {
        kept = u32(max(floor(occupancy * f32(MASK_BITS) + 0.5), 0.0));
    }
    return object_masks[MASK_ANGLES * MASK_OFFSETS + kept];
}
