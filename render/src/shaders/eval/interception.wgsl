// Mirror of `core/src/eval/interception.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
// psi: φ(m) + m·Φ(m) = E[(Z + m)⁺].
fn psi(m: f32) -> f32 {
    return max(norm_pdf(m) + m * norm_cdf(m), 0.0);
}

// Evaluator::interception: (weight, t) where the unresolved relief stops the camera ray o + t·d
// on a crest it passes before meeting h̄ at t_hit; weight 0 for none (needs lod_prepare first).
fn interception(o: vec3<f32>, d: vec3<f32>, t_hit: f32, fp: vec3<f32>, sf: f32) -> vec2<f32> {
    let r = length(d.xy);
    if (!(r > 1e-9) || !(t_hit > 0.0)) {
        return vec2<f32>(0.0);
    }
    let dh = d.xy / r;
    let hit = o + d * t_hit;
    let loc = footprint_stats(hit.xy, fp);
    let stats = loc.stats;
    let c = stats.slope_cov; // xx, yy, xy
    let sq = sqrt(max(dh.x * dh.x * c.x + 2.0 * dh.x * dh.y * c.z + dh.y * dh.y * c.y, 0.0));
    let su = stats.height_std;
    let width = footprint_min_std(fp);
    if (!(su > 1e-12) || !(sq > 0.0) || !(width > 0.0)) {
        return vec2<f32>(0.0);
    }
    // h̄'s slope along the ray: σ_h·max|g′| times the resolved driver gradient's deviation
    // (unfiltered less unresolved); a descent beyond SLOPE_REACH of them never rises.
    let gu = loc.driver.gradient_cov;
    let along_total = dh.x * dh.x * params.grad_cov_xx + 2.0 * dh.x * dh.y * params.grad_cov_xy + dh.y * dh.y * params.grad_cov_yy;
    let along_unresolved = dh.x * dh.x * gu.x + 2.0 * dh.x * dh.y * gu.z + dh.y * dh.y * gu.y;
    let resolved = abs(params.sigma_h) * params.g_lip * sqrt(max(along_total - along_unresolved, 0.0));
    if (abs(d.z) / r > INTERCEPTION_SLOPE_REACH * resolved) {
        return vec2<f32>(0.0);
    }
    let reach = INTERCEPTION_REACH * su;
    let rate = max(lod_rate(d), 1e-12);
    let ds_min = 0.1 * width;
    let ds_max = width;
    var t = 0.0;
    var have_prev = false;
    var t_prev = 0.0;
    var u_prev = 0.0;
    var ds = ds_max;
    var n = 0.0;
    var passed = vec2<f32>(0.0);
    var peak = vec2<f32>(0.0);
    var have_end = false;
    var last_end = 0.0;
    var steps = 0u;
    for (var i = 0u; i < 4u * INTERCEPTION_MAX_STEPS; i = i + 1u) {
        if (t >= t_hit || steps >= INTERCEPTION_MAX_STEPS) {
            break;
        }
        let p = o + d * t;
        let u = p.z - lod_height(p.xy, sf);
        if (u > reach) {
            t = t + max((u - reach) / rate, ds_min / r);
            have_prev = false;
            continue;
        }
        if (have_prev) {
            let len = (t - t_prev) * r;
            let slope = (u - u_prev) / len;
            let mid = 0.5 * (u + u_prev);
            let hazard = max(norm_pdf(mid / su) / su * sq * psi(-slope / sq) * len, 0.0);
            n = n + hazard;
            if (hazard > peak.x) {
                peak = vec2<f32>(hazard, 0.5 * (t + t_prev));
            }
            if (have_end && u > last_end) {
                passed = vec2<f32>(n, peak.y);
            }
            have_end = true;
            last_end = u;
            steps = steps + 1u;
            let du = max(abs(u - u_prev), 1e-30);
            ds = clamp(len * INTERCEPTION_LEVEL_STEP * su / du, ds_min, ds_max);
        }
        have_prev = true;
        t_prev = t;
        u_prev = u;
        t = t + ds / r;
    }
    let weight = 1.0 - exp(-passed.x);
    if (!(weight > INTERCEPTION_MIN_WEIGHT)) {
        return vec2<f32>(0.0);
    }
    return vec2<f32>(weight, passed.y);
}
//#endif
