// Mirror of `core/src/eval/slope_weights.rs`: the visible slopes reweighted by masking and
// shadowing conditioned on the facet's slope (#17).
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
// DirectionWeights: the ray's horizontal direction, the footprint's mean slope and the unresolved
// slopes' deviation along it, and the profile over the slope in those deviations.
struct DirectionWeights {
    on: bool,
    dir: vec2<f32>,
    mean: f32,
    sd: f32,
    profile: array<f32, SLOPE_NODES>,
}

// SlopeWeights: the view's and the light's factors and how G2 combines them.
struct SlopeWeights {
    on: bool,
    view: DirectionWeights,
    light: DirectionWeights,
    correlation: f32,
    view_dominates: bool,
}

// DirectionWeights::at.
fn direction_weight_at(w: DirectionWeights, s: vec2<f32>) -> f32 {
    if (!w.on) {
        return 1.0;
    }
    return profile_at(w.profile, (dot(s, w.dir) - w.mean) / w.sd);
}

// f64::powf as the factors use it: x^0 = 1 (also for x = 0, where WGSL's pow is undefined),
// 0^y = 0 for y > 0.
fn factor_pow(x: f32, y: f32) -> f32 {
    if (y == 0.0) {
        return 1.0;
    }
    if (x <= 0.0) {
        return 0.0;
    }
    return pow(x, y);
}

// SlopeWeights::at: (masking, masking and shadowing) of a facet of slope s.
fn slope_weights_at(w: SlopeWeights, s: vec2<f32>) -> vec2<f32> {
    let o = direction_weight_at(w.view, s);
    let i = direction_weight_at(w.light, s);
    var joint = o * factor_pow(i, w.correlation);
    if (!w.view_dominates) {
        joint = factor_pow(o, w.correlation) * i;
    }
    return vec2<f32>(o, joint);
}

// Evaluator::slope_weights' per-direction closure.
fn direction_weights(w: vec3<f32>, fp: vec3<f32>, mean: vec2<f32>, cov: vec3<f32>) -> DirectionWeights {
    var out: DirectionWeights;
    out.on = false;
    let r = length(w.xy);
    if (!(w.z > 0.0) || !(r > 1e-9)) {
        return out;
    }
    let dir = w.xy / r;
    let sd = sqrt(max(cov.x * dir.x * dir.x + 2.0 * cov.z * dir.x * dir.y + cov.y * dir.y * dir.y, 0.0));
    if (!(sd > 1e-12)) {
        return out;
    }
    let m = dot(mean, dir);
    let nu = (w.z / r - m) / sd;
    let scale = sqrt(max(fp.x * dir.x * dir.x + 2.0 * fp.z * dir.x * dir.y + fp.y * dir.y * dir.y, 0.0));
    out.on = true;
    out.dir = dir;
    out.mean = m;
    out.sd = sd;
    out.profile = slope_masking_lookup(dir, scale, nu);
    return out;
}

// Evaluator::slope_weights: off (on = false) without the material's table (Smith's masking, an
// image driver).
fn slope_weights(fp: vec3<f32>, mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> SlopeWeights {
    var out: SlopeWeights;
    out.on = false;
    if (params.cm_on == 0u) {
        return out;
    }
    out.view = direction_weights(wo, fp, mean, cov);
    out.light = direction_weights(wi, fp, mean, cov);
    let ms = masking_shadowing(wo, wi, cov);
    out.correlation = 1.0;
    if (params.correlation == CORRELATION_HEIGHT_DIRECTION) {
        out.correlation = azimuth_factor(azimuth_difference(wo, wi));
    }
    out.view_dominates = ms.lambda_o >= ms.lambda_i;
    out.on = out.view.on || out.light.on;
    return out;
}

// SlopeWeights::lobe_factor: the sun's lobe × the joint factor at its posterior slope over the
// factor's visible mean.
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
    var joint = 0.0;
    for (var i = 0u; i < points * points; i = i + 1u) {
        let b = rule_off + 3u * i;
        let z = vec3<f32>(data[b], data[b + 1u], data[b + 2u]);
        let s = mean + vec2<f32>(l.x * z.x, l.y * z.x + l.z * z.y);
        let wt = z.z * max(wo.z - s.x * wo.x - s.y * wo.y, 0.0);
        if (wt > 0.0) {
            plain = plain + wt;
            joint = joint + wt * slope_weights_at(w, slope_of(normal_of(s))).y;
        }
    }
    if (joint > 0.0) {
        return slope_weights_at(w, post.mean).y * plain / joint;
    }
    return 1.0;
}
//#endif
