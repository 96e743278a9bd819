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
    // The masking conditioned on the driver's value and slope (params.tm_on: the material's table
    // at params.tm_offset), blended with Smith's bins by the footprint's far weight.
    var rays: TransferRays;
    var far = 0.0;
    if (params.tm_on == 1u) {
        rays = transfer_rays_new(params.tm_offset, d, wo, wi, sun_lit, params.sigma_h, params.correlation);
        far = rays.far;
    }
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
        let c = affine(bin.color);
        // Smith's bin, weighted by its share (all of it without the conditioned masking).
        if (far < 1.0) {
            let share = 1.0 - far;
            let sums = visible_shading_sums(s_mean, cov, wo_w, wi_w, params.mix_rule_offset, params.mix_nodes);
            den = den + share * w1 * sums.den;
            var v = 0.0;
            var spec = vec3<f32>(0.0);
            if (sun_lit) {
                spec = specular_lobes(s_mean, cov, wo_w, wi_w) * sums.den;
                v = share * w2 * sun;
            }
            let s = sums.s;
            num = num + v * (kd * (c.a * s.cos + c.k * s.cs_cos) + spec * specular_tint(c, s)) + share * w1 * kd * (c.a * s.env + c.k * s.cs_env);
        }
        if (far > 0.0) {
            let b = conditioned_bin(rays, d, lo, hi, wo_w, wi_w, sun_lit);
            let width = hi - lo;
            den = den + far * width * b.s1o;
            var v = 0.0;
            if (sun_lit) {
                v = far * width * sun;
            }
            num = num + v * (kd * (c.a * b.s2.cos + c.k * b.s2.cs_cos) + b.spec * specular_tint(c, b.s2)) + far * width * kd * (c.a * b.s1.env + c.k * b.s1.cs_env);
        }
    }
    if (!(den > 0.0)) {
        return vec3<f32>(0.0);
    }
    return num / den;
}

// What a bin of the conditioned masking adds (core's filtered_bins, its sub-value loop): the
// shading sums under the eye's and the joint term's tilted Gaussians, the eye's projected area,
// and the specular lobes with their visible mass, each summed over the bin's sub-values.
struct ConditionedBin {
    s1: SlopeShading,
    s1o: f32,
    s2: SlopeShading,
    spec: vec3<f32>,
}

// The shading sums under a visibility weight's tilted Gaussian (core's `shade_under`), the
// slopes `mean + lz·z`; mass 0 where nothing is visible.
struct WeightedSums {
    mass: f32,
    sums: ShadingSums,
}

fn shade_under(w: GaussianWeight, mean: vec2<f32>, lz: mat2x2<f32>, wo_w: vec3<f32>, wi_w: vec3<f32>) -> WeightedSums {
    var out: WeightedSums;
    out.mass = 0.0;
    if (!w.ok) {
        return out;
    }
    let t = gaussian_weight_tilted(w);
    if (!t.ok) {
        return out;
    }
    let c = lz * symmetric_matrix(t.cov) * transpose(lz);
    out.mass = t.mass;
    out.sums = visible_shading_sums(mean + lz * t.mean, vec3<f32>(c[0][0], c[1][1], 0.5 * (c[0][1] + c[1][0])), wo_w, wi_w, params.tm_rule_offset, params.tm_nodes);
    return out;
}

fn conditioned_bin(rays: TransferRays, d: FilteredDriver, lo: f32, hi: f32, wo_w: vec3<f32>, wi_w: vec3<f32>, sun_lit: bool) -> ConditionedBin {
    var b: ConditionedBin;
    b.s1o = 0.0;
    b.spec = vec3<f32>(0.0);
    let ks = 1.0 / f32(BIN_SAMPLES);
    let l = rays.chol;
    for (var q = 0u; q < BIN_SAMPLES; q = q + 1u) {
        let xq = rays.mean + rays.std_dev * norm_quantile(lo + (hi - lo) * (f32(q) + 0.5) * ks);
        let gd = transfer_eval(xq * datum(params.tm_offset)).y;
        let mean_q = d.mean_gradient * (params.sigma_h * gd);
        let lz = mat2x2<f32>(l.x, l.y, 0.0, l.z) * (params.sigma_h * gd);
        let w = visibility_weights(rays, xq);
        let e = shade_under(w.eye, mean_q, lz, wo_w, wi_w);
        if (e.mass > 0.0) {
            b.s1 = shading_add(b.s1, e.sums.s, ks * e.mass);
            b.s1o = b.s1o + ks * e.mass * e.sums.den;
        }
        let j = shade_under(w.joint, mean_q, lz, wo_w, wi_w);
        var s2o_q = 0.0;
        if (j.mass > 0.0) {
            b.s2 = shading_add(b.s2, j.sums.s, ks * j.mass);
            s2o_q = j.mass * j.sums.den;
        }
//#if specular
        if (sun_lit && w.joint.ok) {
            let cov_q = d.gradient_cov * (params.sigma_h * gd * params.sigma_h * gd);
            let so_q = expected_positive_part(wo_w.z, wo_w.xy, mean_q, cov_q);
            let lobe = specular_lobes(mean_q, cov_q, wo_w, wi_w);
            let v = lobe_visibility(rays, w.joint, params.sigma_h * gd, mean_q, cov_q, wo_w, wi_w);
            var mass = s2o_q;
            if (v.y > 0.0) {
                mass = v.x * so_q;
            }
            b.spec = b.spec + ks * lobe * mass;
        }
//#endif
    }
    return b;
}

// SlopeShading::add: a + s·w.
fn shading_add(a: SlopeShading, s: SlopeShading, w: f32) -> SlopeShading {
    return SlopeShading(a.cos + w * s.cos, a.cs_cos + w * s.cs_cos, a.env + w * s.env, a.cs_env + w * s.cs_env);
}

//#if specular
// Evaluator::lobe_visibility: the joint term's mean over the lobe's half-vector posterior, in
// closed form, as (value, 1), or (0, 0) where there is no slope to select the facets by.
fn lobe_visibility(rays: TransferRays, v2: GaussianWeight, scale: f32, mean: vec2<f32>, cov: vec3<f32>, wo_w: vec3<f32>, wi_w: vec3<f32>) -> vec2<f32> {
    let l = rays.chol;
    if (!(abs(scale) > 1e-12 && wo_w.z > 0.0 && wi_w.z > 0.0 && l.x > 1e-12 && l.z > 1e-12)) {
        return vec2<f32>(0.0);
    }
    let h = normalize(wo_w + wi_w);
    if (!(h.z > 1e-9)) {
        return vec2<f32>(0.0);
    }
    let p = lobe_posterior(mean, cov, slope_of(h), params.roughness);
    // The posterior in whitened driver slopes: z = L⁻¹ (s − mean)/scale.
    let li = mat2x2<f32>(1.0 / l.x, -l.y / (l.x * l.z), 0.0, 1.0 / l.z) * (1.0 / scale);
    let r = cholesky(p.cov);
    let root = mat2x2<f32>(r.x, r.y, 0.0, r.z);
    return gaussian_weight_expect_under(v2, li * (p.mean - mean), li * root);
}
//#endif
//#endif
