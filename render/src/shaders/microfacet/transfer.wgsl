// Mirror of `core/src/microfacet/transfer.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

// TransferFunction::eval and ::derivative: (g, g′). Identity when transfer_kind == 0.
fn transfer_eval(f: f32) -> vec2<f32> {
//#if transfer_curve
    if (params.transfer_kind != TRANSFER_IDENTITY) {
        return vec2<f32>(poly_eval(params.tp_offset, params.tp_knots, 2u, 0u, f), poly_eval(params.tp_offset, params.tp_knots, 2u, 1u, f));
    }
//#endif
    return vec2<f32>(f, 1.0);
}

// TransferMoments: ḡ, σ_g, ḡ′, σ_g′ of g under N(m, s²) [HNPN14 Eqs. 21, 22, 27, 28].
struct TransferMoments {
    mean: f32,
    std_dev: f32,
    mean_deriv: f32,
    std_deriv: f32,
}

// CompiledTransfer::moments: from the table for curves, exact for the identity.
fn transfer_moments(m: f32, s: f32) -> TransferMoments {
//#if transfer_curve
    if (params.transfer_kind != TRANSFER_IDENTITY) {
        let v = table_sample(params.tt_offset, params.tt_size_m, params.tt_size_s, params.tt_m_min, params.tt_m_max, params.tt_sigma_max, m, s);
        return TransferMoments(v.x, max(v.y, 0.0), v.z, max(v.w, 0.0));
    }
//#endif
    return TransferMoments(m, max(s, 0.0), 1.0, 0.0);
}

struct SurfaceStats {
    height_mean: f32,
    height_std: f32,
    slope_mean: vec2<f32>,
    slope_cov: vec3<f32>,
}

// transformed_statistics [HNPN14 Eqs. 19–26].
fn transformed_statistics(tm: TransferMoments, sigma_h: f32, grad_mean: vec2<f32>, grad_cov: vec3<f32>) -> SurfaceStats {
    let var_d = tm.std_deriv * tm.std_deriv;
    let md2 = tm.mean_deriv * tm.mean_deriv;
    let second = grad_cov + vec3<f32>(grad_mean.x * grad_mean.x, grad_mean.y * grad_mean.y, grad_mean.x * grad_mean.y);
    var s: SurfaceStats;
    s.slope_cov = (second * var_d + grad_cov * md2) * (sigma_h * sigma_h);
    s.height_mean = sigma_h * tm.mean;
    s.height_std = abs(sigma_h) * tm.std_dev;
    s.slope_mean = grad_mean * (sigma_h * tm.mean_deriv);
    return s;
}
