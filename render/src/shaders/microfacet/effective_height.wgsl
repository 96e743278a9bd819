// Mirror of `core/src/microfacet/effective_height.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
// HeightMoments: mean and std of the effective height distribution D_h, standardized (`std` is
// reserved in WGSL: the field is `std_dev`, as in FilteredDriver).
struct HeightMoments {
    mean: f32,
    std_dev: f32,
}

// height_moments: EffectiveHeightTable::lookup, or the paper's fits [HNPN14 Eqs. 16–17]
// (paper_fit_moments; constants from core, see the generated prelude).
fn height_moments(l_in: f32) -> HeightMoments {
    let l = max(l_in, 0.0);
    if (params.height_filter == HEIGHT_FILTER_PAPER_FIT) {
        let lc = min(l, 1e30);
        return HeightMoments(DH_FIT_ALPHA_MU * log(1.0 + DH_FIT_BETA_MU * lc), 1.0 / (1.0 + DH_FIT_ALPHA_SIGMA * log(1.0 + DH_FIT_BETA_SIGMA * lc)));
    }
    let n = params.dh_size;
    let off = params.dh_offset;
    let l_min = exp(params.dh_ln_min);
    if (l < l_min) {
        let s = l / l_min;
        return HeightMoments(s * datum(off), 1.0 + s * (datum(off + 1u) - 1.0));
    }
    let u = clamp((log(l) - params.dh_ln_min) / (params.dh_ln_max - params.dh_ln_min) * f32(n - 1u), 0.0, f32(n - 1u));
    let i = min(u32(floor(u)), n - 2u);
    let f = u - f32(i);
    let a = vec2<f32>(datum(off + 2u * i), datum(off + 2u * i + 1u));
    let b = vec2<f32>(datum(off + 2u * i + 2u), datum(off + 2u * i + 3u));
    let v = mix(a, b, f);
    return HeightMoments(v.x, v.y);
}
//#endif
