// Mirror of `core/src/scene/local_slope.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
//#if noise
// LocalSlope::lipschitz_on: a bound of |G′| over [lo, hi] for a transfer curve, at most the march's
// global bound (march_g_lip); g_lip for the identity. On the explicit surface the curve's |g′|
// (LocalSlope::Curve); on the level-of-detail surface the slopes of the transfer table's rows at
// the footprint's σ_f (LocalSlope::Table, rows set by lod_prepare).
fn lipschitz_on(lo: f32, hi: f32, lod: bool) -> f32 {
//#if transfer_curve
    if (params.transfer_kind != TRANSFER_IDENTITY) {
        if (lod) {
            return min(table_slope_on(lod_rows, lo, hi) * (1.0 + 1e-5), lod_g_lip);
        }
        let g = poly_max_abs_on(params.tp_offset, params.tp_knots, 2u, 1u, lo, hi);
        return min(g * (1.0 + 1e-5), params.g_lip);
    }
//#endif
    return params.g_lip;
}

// The global bound of |G′| the octave march uses (Evaluator::lod_march's `os.g_lip`): g_lip, or on
// the level-of-detail surface of a transfer curve the largest slope of the table's rows at σ_f.
fn march_g_lip(lod: bool) -> f32 {
//#if transfer_curve
    if (lod && params.transfer_kind != TRANSFER_IDENTITY) {
        return lod_g_lip;
    }
//#endif
    return params.g_lip;
}
//#endif
//#endif
