// Mirror of `core/src/eval/mixture_bins.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if transfer_mixture
const BIN_SAMPLES: u32 = 4u;

struct BinMoments {
    mean_deriv: f32,
    rms_deriv: f32,
    color: vec3<f32>,
}

// Evaluator::bin_moments: mean and rms of g′ and the mean colour over the quantiles [lo, hi]; with
// an image's value-conditioned slopes (params.is_on) N(mean, sd²) is in its Gaussian space, a
// point at x has the value T⁻¹(x), g′ = 1 and E[g′²] its slope scale s².
fn bin_moments(mean: f32, sd: f32, lo: f32, hi: f32) -> BinMoments {
    var d1 = 0.0;
    var d2 = 0.0;
    var c = vec3<f32>(0.0);
    let k = 1.0 / f32(BIN_SAMPLES);
    for (var q = 0u; q < BIN_SAMPLES; q = q + 1u) {
        let u = lo + (hi - lo) * (f32(q) + 0.5) * k;
        let x = mean + sd * norm_quantile(u);
        var f = x;
        var gd = 1.0;
        var gd2 = 1.0;
        if (params.is_on == 1u) {
            f = value_at_gauss(x);
            gd2 = scale_at_gauss(x);
        } else {
            gd = transfer_eval(x).y;
            gd2 = gd * gd;
        }
        d1 = d1 + gd * k;
        d2 = d2 + gd2 * k;
        c = c + color_at(f) * k;
    }
    return BinMoments(d1, sqrt(max(d2, 0.0)), c);
}

// Evaluator::bin_slope_scale: E_b[s²] of the image's value-conditioned slopes over the quantiles
// [lo, hi] of N(mean, sd²) in its Gaussian space, on bin_moments' midpoints, without the colour.
fn bin_slope_scale(mean: f32, sd: f32, lo: f32, hi: f32) -> f32 {
    var s = 0.0;
    let k = 1.0 / f32(BIN_SAMPLES);
    for (var q = 0u; q < BIN_SAMPLES; q = q + 1u) {
        let u = lo + (hi - lo) * (f32(q) + 0.5) * k;
        s = s + scale_at_gauss(mean + sd * norm_quantile(u)) * k;
    }
    return s;
}

// Evaluator::filtered_bins: the binned mixture, wo/wi in the mean normal's frame, wo_w/wi_w in
// the macro frame.
fn filtered_bins(loc: FootprintStats, wo_w: vec3<f32>, wi_w: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, sun_visible: f32) -> vec3<f32> {
    let d = loc.driver;
    // An image's bins live in its Gaussian space (the colour's input distribution there).
    var ms = vec2<f32>(d.mean, d.std_dev);
    if (params.is_on == 1u) {
        ms = input_distribution(loc);
    }
    let n = mixture_edges(ms.x, ms.y);
    // The image's slope scale splits the footprint's slope covariance among its values:
    // normalized so that their mean is 1 (the pyramid's total stays).
    var norm = 1.0;
    if (params.is_on == 1u) {
        var total = 0.0;
        for (var j = 1u; j < n; j = j + 1u) {
            let lo = mixture_edge_buf[j - 1u];
            let hi = mixture_edge_buf[j];
            if (hi > lo) {
                total = total + (hi - lo) * bin_slope_scale(ms.x, ms.y, lo, hi);
            }
        }
        if (total > 0.0) {
            norm = 1.0 / sqrt(total);
        }
    }
    let sun_lit = wi.z > 0.0 && wi_w.z > 0.0;
    let kd = params.albedo * FRAC_1_PI * params.kd_rgb;
    let sun = params.sun * sun_visible;
    var above_o = 0.0;
    var above = 0.0;
    var num = vec3<f32>(0.0);
    var den = 0.0;
    // From the top bin down.
    for (var j = 1u; j < n; j = j + 1u) {
        let lo = mixture_edge_buf[n - 1u - j];
        let hi = mixture_edge_buf[n - j];
        if (!(hi > lo)) {
            continue;
        }
        let bin = bin_moments(ms.x, ms.y, lo, hi);
        let s_mean = d.mean_gradient * (params.sigma_h * bin.mean_deriv);
        let scale = params.sigma_h * bin.rms_deriv * norm;
        let cov = d.gradient_cov * (scale * scale);
        let ms = masking_shadowing(wo, wi, cov);
        let w1 = bin_masking(lo, hi, ms.lambda_o, above_o);
        let w2 = bin_masking(lo, hi, ms.total, above);
        above_o = above_o + bin_exponent(lo, hi, ms.lambda_o);
        above = above + bin_exponent(lo, hi, ms.total);
        let sums = visible_shading_sums(s_mean, cov, wo_w, wi_w, params.mix_rule_offset, params.mix_points);
        den = den + w1 * sums.den;
        var v = 0.0;
        var spec = vec3<f32>(0.0);
        if (sun_lit) {
            spec = specular_lobes(s_mean, cov, wo_w, wi_w) * sums.den;
            v = w2 * sun;
        }
        let c = affine(bin.color);
        let s = sums.s;
        num = num + v * (kd * (c.a * s.cos + c.k * s.cs_cos) + spec * specular_tint(c, s)) + w1 * kd * (c.a * s.env + c.k * s.cs_env);
    }
    if (!(den > 0.0)) {
        return vec3<f32>(0.0);
    }
    return num / den;
}
//#endif
