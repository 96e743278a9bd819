// Mirror of `core/src/eval/filtered.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

// Evaluator::filtered.
fn eval_filtered(x0: vec2<f32>, fp: vec3<f32>, wo_w: vec3<f32>, wi_w: vec3<f32>, sun_visible: f32) -> vec3<f32> {
    let loc = footprint_stats(x0, fp);
//#if relief
    let nbar = normal_of(loc.stats.slope_mean);
    let t = basis_t(nbar);
    let b = basis_b(nbar);
    if (wo_w.z <= 0.0) {
        return vec3<f32>(0.0);
    }
    // A mean plane tilted away from a grazing view the ray still meets: the view grazes it.
    let wo = above_horizon(vec3<f32>(dot(wo_w, t), dot(wo_w, b), dot(wo_w, nbar)));
    let wi = vec3<f32>(dot(wi_w, t), dot(wi_w, b), dot(wi_w, nbar));
//#if transfer_mixture
    // A transfer curve, or an image's value-conditioned slopes: the binned mixture (mix_nodes is 0
    // otherwise).
    if (params.mix_nodes > 0u) {
        return filtered_bins(loc, wo_w, wi_w, wo, wi, sun_visible);
    }
//#endif
    let cov = loc.stats.slope_cov;
    let ms = masking_shadowing(wo, wi, cov);
    let d = input_distribution(loc);
    // The colour model over the visible and lit heights (L = Λo + Λi) for the directional light,
    // over the visible heights (L = Λo) for the unshadowed environment.
    let hm = height_moments(ms.total);
    var hmo = hm;
//#if environment
    hmo = height_moments(ms.lambda_o);
//#endif
    var vbar = 0.0;
    if (wi.z > 0.0 && wi_w.z > 0.0) {
        // Kept without the shadows feature: a light at the world normal is oblique to a tilted
        // mean normal, so Λ(ω_i) need not be 0 in the footprint's frame.
        vbar = mean_shadowing(ms);
    }
    // The footprint's slopes are N(s̄, Σ) in world slope space, exactly: average the facets there.
    let s_mean = loc.stats.slope_mean;
    let lit = sun_visible * vbar;
    var spec = specular_lobes(s_mean, cov, wo_w, wi_w);
    var sun_color: Affine;
    var env_color: Affine;
    var shading: SlopeShading;
    let weights = slope_weights(fp, s_mean, cov, wo_w, hm, hmo);
    if (!weights.on) {
        sun_color = affine(color_of_distribution(d.x + d.y * hm.mean, d.y * hm.std_dev, ms.total, vec2<f32>(hm.mean, hm.std_dev), d.y * d.y));
        env_color = sun_color;
//#if environment
        env_color = affine(color_of_distribution(d.x + d.y * hmo.mean, d.y * hmo.std_dev, ms.lambda_o, vec2<f32>(hmo.mean, hmo.std_dev), d.y * d.y));
//#endif
        shading = visible_shading(s_mean, cov, wo_w, wi_w);
    } else {
        // Masking conditioned on height and slope jointly (#17): each slope node sees its own
        // heights, so colour and shading are summed together.
        let sun_h = slope_heights(hm);
        var env_h = sun_h;
//#if environment
        env_h = slope_heights(hmo);
//#endif
        visible_shading_buckets(s_mean, cov, wo_w, wi_w, params.slope_rule_offset, params.slope_nodes, weights);
        let joint = joint_inputs(sun_h, env_h, d, ms.total, hm, ms.lambda_o, hmo);
        sun_color = joint.sun;
        env_color = joint.env;
        shading = joint.shading;
//#if specular|measured
        spec = spec * lobe_factor(weights, sun_h.mass, s_mean, cov, wo_w, wi_w, params.roughness);
//#endif
    }
    // The density ratio scales only the sun's specular term: skipped where it changes nothing.
    if (any(spec > vec3<f32>(0.0)) && lit > 0.0 && params.sun != 0.0) {
        spec = spec * lobe_density_ratio(fp, s_mean, wo_w, wi_w);
    }
    return radiance(sun_color, env_color, shading, lit, spec);
//#else
    // Flat: every facet faces +z, nothing masks or shadows (Λ = 0, and D_h at L = 0 is the
    // identity, so the colour is that of the footprint's own distribution).
    if (wo_w.z <= 0.0) {
        return vec3<f32>(0.0);
    }
    let d = input_distribution(loc);
    let aff = affine(color_of_distribution(d.x, d.y, 0.0, vec2<f32>(0.0, 1.0), d.y * d.y));
    let spec = specular_lobes(vec2<f32>(0.0), vec3<f32>(0.0), wo_w, wi_w);
    return radiance(aff, aff, point_shading(vec3<f32>(0.0, 0.0, 1.0), wi_w), sun_visible * select(0.0, 1.0, wi_w.z > 0.0), spec);
//#endif
}

// Evaluator::lobe_density_ratio: the noise's own unresolved slope density over the Gaussian at
// the half vector (1 for images, transfer curves, no specular, or noise_slopes Gaussian).
fn lobe_density_ratio(fp: vec3<f32>, s_mean: vec2<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
//#if noise
//#if specular
    if (params.driver_kind != DRIVER_IMAGE && params.specular > 0.0 && params.noise_slopes != 0u && params.measured == 0u
        && params.transfer_kind == TRANSFER_IDENTITY && wo.z > 0.0 && wi.z > 0.0) {
        let h = normalize(wo + wi);
        if (h.z > 1e-9) {
            return sinusoid_density_ratio(slope_of(h) - s_mean, params.roughness, fp);
        }
    }
//#endif
//#endif
    return 1.0;
}

// above_horizon: ω kept at least MIN_VIEW_COS above the mean plane's horizon.
const MIN_VIEW_COS: f32 = 1e-3;
fn above_horizon(w: vec3<f32>) -> vec3<f32> {
    if (w.z >= MIN_VIEW_COS) {
        return w;
    }
    let len = length(w.xy);
    let scale = sqrt(1.0 - MIN_VIEW_COS * MIN_VIEW_COS);
    var h = vec2<f32>(scale, 0.0);
    if (len > 0.0) {
        h = w.xy * (scale / len);
    }
    return vec3<f32>(h, MIN_VIEW_COS);
}
