// Mirror of `core/src/microfacet/brdf.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if specular
fn gaussian2(d: vec2<f32>, c: vec3<f32>) -> f32 {
    let xx = max(c.x, 1e-14);
    let yy = max(c.y, 1e-14);
    let det = max(xx * yy - c.z * c.z, 1e-28);
    let q = (yy * d.x * d.x - 2.0 * c.z * d.x * d.y + xx * d.y * d.y) / det;
    return exp(-0.5 * q) / (TAU * sqrt(det));
}

//#endif
fn specular_with(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, extra: vec3<f32>) -> f32 {
    return specular_lobe(params.specular, params.roughness, n, wo, wi, extra);
}

// BaseBrdf::specular_with for a lobe of weight f0 and deviation `roughness` (the base lobe, or one
// of a measured BRDF's fitted lobes).
fn specular_lobe(f0: f32, roughness: f32, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, extra: vec3<f32>) -> f32 {
//#if specular
    if (f0 <= 0.0 || dot(n, wi) <= 0.0 || dot(n, wo) <= 0.0 || wo.z <= 0.0 || wi.z <= 0.0) {
        return 0.0;
    }
    let h = normalize(wo + wi);
    if (h.z <= 1e-9) {
        return 0.0;
    }
    let s0 = max(roughness, 0.0);
    let d = gaussian2(slope_of(h) - slope_of(n), extra + vec3<f32>(s0 * s0, s0 * s0, 0.0));
    return f0 * d / (4.0 * pow(h.z, 4.0) * wo.z);
//#else
    return 0.0;
//#endif
}

// brdf::filtered_specular (world slope space, facet slopes N(mean, cov)) of the base lobe.
fn filtered_specular(mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    return filtered_lobe(params.specular, params.roughness, mean, cov, wo, wi);
}

// brdf::filtered_specular of a lobe of weight f0 and deviation `roughness`.
fn filtered_lobe(f0: f32, roughness: f32, mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
//#if specular
    if (f0 <= 0.0 || wo.z <= 0.0 || wi.z <= 0.0) {
        return 0.0;
    }
    let h = normalize(wo + wi);
    if (h.z <= 1e-9) {
        return 0.0;
    }
    let sh = slope_of(h);
    let s0 = max(roughness, 0.0);
    let total = cov + vec3<f32>(s0 * s0, s0 * s0, 0.0);
    let post = lobe_posterior(mean, cov, sh, roughness);
    let u_post = expected_positive_part(wo.z, wo.xy, post.mean, post.cov);
    let eu = expected_positive_part(wo.z, wo.xy, mean, cov);
    let dens = gaussian2(sh - mean, total);
    return f0 * dens * (u_post / max(eu, 1e-30)) / (4.0 * pow(h.z, 4.0) * wo.z);
//#else
    return 0.0;
//#endif
}

//#if specular|measured
// brdf::lobe_posterior: the facet slopes that carry a lobe, N(s*, Σ*) with s* = s̄ + K(s_h − s̄),
// Σ* = Σ − KΣ, K = Σ(Σ + σ0²I)⁻¹; the point s_h when both are degenerate.
struct LobePosterior {
    mean: vec2<f32>,
    cov: vec3<f32>,
}

fn lobe_posterior(mean: vec2<f32>, cov: vec3<f32>, sh: vec2<f32>, roughness: f32) -> LobePosterior {
    let s0 = max(roughness, 0.0);
    let total = cov + vec3<f32>(s0 * s0, s0 * s0, 0.0);
    let det = total.x * total.y - total.z * total.z;
    var r: LobePosterior;
    r.mean = sh;
    r.cov = vec3<f32>(0.0);
    if (det > 1e-30) {
        let inv = vec3<f32>(total.y, total.x, -total.z) / det;
        // K = Σ·C⁻¹ (general 2×2: columns k0, k1).
        let k0 = vec2<f32>(cov.x * inv.x + cov.z * inv.z, cov.z * inv.x + cov.y * inv.z);
        let k1 = vec2<f32>(cov.x * inv.z + cov.z * inv.y, cov.z * inv.z + cov.y * inv.y);
        let d = sh - mean;
        r.mean = mean + k0 * d.x + k1 * d.y;
        // KΣ: columns K·(xx, xy) and K·(xy, yy).
        let c0 = k0 * cov.x + k1 * cov.z;
        let c1 = k0 * cov.z + k1 * cov.y;
        r.cov = vec3<f32>(max(cov.x - c0.x, 0.0), max(cov.y - c1.y, 0.0), cov.z - 0.5 * (c0.y + c1.x));
    }
    return r;
}
//#endif

