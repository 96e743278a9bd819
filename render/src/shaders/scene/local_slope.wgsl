// Mirror of `core/src/scene/local_slope.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
//#if noise
// LocalSlope::lipschitz_on (with LocalSlope::level_of_detail's widening when lod): a bound of |G′|
// over [lo, hi] for a transfer curve, at most g_lip; g_lip for the identity.
fn lipschitz_on(lo: f32, hi: f32, lod: bool, sf: f32) -> f32 {
//#if transfer_curve
    if (params.transfer_kind != TRANSFER_IDENTITY) {
        var widen = 0.0;
        var tail = 0.0;
        if (lod) {
            let dm = (params.tt_m_max - params.tt_m_min) / f32(max(params.tt_size_m, 2u) - 1u);
            let ds = params.tt_sigma_max / f32(max(params.tt_size_s, 2u) - 1u);
            widen = 6.0 * (sf + ds) + dm;
            tail = 2e-9 * params.g_lip;
        }
        let g = poly_max_abs_on(params.tp_offset, params.tp_knots, 2u, 1u, lo - widen, hi + widen);
        return min(g * (1.0 + 1e-5) + tail, params.g_lip);
    }
//#endif
    return params.g_lip;
}
//#endif
//#endif
