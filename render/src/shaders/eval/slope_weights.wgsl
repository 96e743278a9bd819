// Mirror of `core/src/eval/slope_weights.rs`: the visible slopes reweighted by masking
// conditioned on the facet's slope (#17).
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
// SlopeWeights: the view's horizontal direction, the footprint's mean slope and the unresolved
// slopes' deviation along it, and the profile over the slope in those deviations (off: on = false).
struct SlopeWeights {
    on: bool,
    dir: vec2<f32>,
    mean: f32,
    sd: f32,
    profile: SlopeProfile,
}

// SlopeWeights::at: the masking factor of a facet of slope s.
fn slope_weights_at(w: SlopeWeights, s: vec2<f32>) -> f32 {
    if (!w.on) {
        return 1.0;
    }
    return profile_at(w.profile, (dot(s, w.dir) - w.mean) / w.sd);
}

// Evaluator::slope_weights: off without the material's table (Smith's masking, an image
// driver), at the normal, or with no unresolved slope along the view.
fn slope_weights(fp: vec3<f32>, mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>) -> SlopeWeights {
    var out: SlopeWeights;
    out.on = false;
    if (params.cm_on == 0u) {
        return out;
    }
    let r = length(wo.xy);
    if (!(wo.z > 0.0) || !(r > 1e-9)) {
        return out;
    }
    let dir = wo.xy / r;
    let sd = projected_std(cov, dir.x, dir.y);
    if (!(sd > 1e-12)) {
        return out;
    }
    let m = dot(mean, dir);
    let nu = (wo.z / r - m) / sd;
    // The footprint's standard deviation along the view's azimuth picks the level.
    let scale = projected_std(fp, dir.x, dir.y);
    out.on = true;
    out.dir = dir;
    out.mean = m;
    out.sd = sd;
    out.profile = slope_masking_lookup(dir, scale, nu);
    return out;
}

//#if specular|measured
// SlopeWeights::lobe_factor: the sun's lobe × the factor at its posterior slope over the factor's
// visible mean.
fn lobe_factor(w: SlopeWeights, mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, roughness: f32, rule_off: u32, points: u32) -> f32 {
    if (!(wo.z > 0.0 && wi.z > 0.0)) {
        return 1.0;
    }
    let h = normalize(wo + wi);
    if (!(h.z > 1e-9)) {
        return 1.0;
    }
    let post = lobe_posterior(mean, cov, slope_of(h), roughness);
    let l = cholesky(cov);
    var plain = 0.0;
    var weighted = 0.0;
    for (var i = 0u; i < points * points; i = i + 1u) {
        let b = rule_off + 3u * i;
        let z = vec3<f32>(datum(b), datum(b + 1u), datum(b + 2u));
        let s = mean + vec2<f32>(l.x * z.x, l.y * z.x + l.z * z.y);
        let wt = z.z * max(wo.z - s.x * wo.x - s.y * wo.y, 0.0);
        if (wt > 0.0) {
            plain = plain + wt;
            weighted = weighted + wt * slope_weights_at(w, slope_of(normal_of(s)));
        }
    }
    if (weighted > 0.0) {
        return slope_weights_at(w, post.mean) * plain / weighted;
    }
    return 1.0;
}
//#endif
//#endif
