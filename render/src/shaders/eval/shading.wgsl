// Mirror of `core/src/eval/shading.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

// Evaluator::slope_color_at (CompiledSlopeColor::sample) at a world normal.
fn slope_color_at(nw: vec3<f32>) -> vec3<f32> {
//#if slope_color
    let k = params.sp_knots;
    if (k == 0u) {
        return vec3<f32>(0.0);
    }
    let t = dot(nw, params.sc_dir);
    return vec3<f32>(poly_eval(params.sp_offset, k, 3u, 0u, t), poly_eval(params.sp_offset, k, 3u, 1u, t), poly_eval(params.sp_offset, k, 3u, 2u, t));
//#else
    return vec3<f32>(0.0);
//#endif
}

// Sh9::irradiance (coefficients pre-multiplied by Â_l, coefficient-major RGB) at a world normal.
fn environment_at(nw: vec3<f32>) -> vec3<f32> {
//#if environment
    if (params.has_env == 0u) {
        return vec3<f32>(0.0);
    }
    let o = params.env_offset;
    let x = nw.x;
    let y = nw.y;
    let z = nw.z;
    // The nine terms written out: a loop's iterations count against the software adapter's
    // per-invocation budget (bindings.wgsl), and this runs at every slope node.
    var e = 0.282095 * sh9_coefficient(o, 0u);
    e = e + (0.488603 * y) * sh9_coefficient(o, 1u);
    e = e + (0.488603 * z) * sh9_coefficient(o, 2u);
    e = e + (0.488603 * x) * sh9_coefficient(o, 3u);
    e = e + (1.092548 * x * y) * sh9_coefficient(o, 4u);
    e = e + (1.092548 * y * z) * sh9_coefficient(o, 5u);
    e = e + (0.315392 * (3.0 * z * z - 1.0)) * sh9_coefficient(o, 6u);
    e = e + (1.092548 * x * z) * sh9_coefficient(o, 7u);
    e = e + (0.546274 * (x * x - y * y)) * sh9_coefficient(o, 8u);
    return max(e, vec3<f32>(0.0));
//#else
    return vec3<f32>(0.0);
//#endif
}

//#if environment
// Coefficient i (RGB) of the environment's Sh9 at `o`.
fn sh9_coefficient(o: u32, i: u32) -> vec3<f32> {
    return vec3<f32>(datum(o + 3u * i), datum(o + 3u * i + 1u), datum(o + 3u * i + 2u));
}

//#endif
// The tangent frame's axes in the world (identity on the plane; the cylinder sets its own before
// shading): slope colour and environment are looked up at world normals.
var<private> shading_frame: mat3x3<f32> = mat3x3<f32>(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);

struct SlopeShading {
    cos: f32,
    cs_cos: vec3<f32>,
    env: vec3<f32>,
    cs_env: vec3<f32>,
}

// Evaluator::point_shading.
fn point_shading(n: vec3<f32>, wi: vec3<f32>) -> SlopeShading {
    var r: SlopeShading;
    r.cos = max(dot(n, wi), 0.0);
    let nw = shading_frame * n;
    let cs = slope_color_at(nw);
    r.env = environment_at(nw);
    r.cs_cos = cs * r.cos;
    r.cs_env = cs * r.env;
    return r;
}

// Evaluator::radiance (with the channel weights kd_rgb, f0_rgb).
fn radiance(sun_color: Affine, env_color: Affine, s: SlopeShading, v: f32, spec: vec3<f32>) -> vec3<f32> {
    let sun = params.sun * v;
    let kd = params.albedo * FRAC_1_PI * params.kd_rgb;
    return kd * (sun * (sun_color.a * s.cos + sun_color.k * s.cs_cos) + env_color.a * s.env + env_color.k * s.cs_env) + sun * spec * specular_tint(sun_color, s);
}

// shading::specular_tint: 1, or the lit facets' mean colour for a measured BRDF.
fn specular_tint(color: Affine, s: SlopeShading) -> vec3<f32> {
    if (params.measured == 0u) {
        return vec3<f32>(1.0);
    }
    var cs = vec3<f32>(0.0);
    if (s.cos > 0.0) {
        cs = s.cs_cos / s.cos;
    }
    return color.a + color.k * cs;
}

// Evaluator::specular_lobes: the base lobe, or a measured BRDF's fitted lobes, over the visible
// slopes N(mean, cov) (world slope space).
fn specular_lobes(mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
//#if measured
    if (params.measured != 0u) {
        let f = fresnel_factor(wi, wo);
        var out = vec3<f32>(0.0);
        for (var k = 0u; k < params.lobe_count; k = k + 1u) {
            let o = params.lobe_offset + 7u * k;
            let sigma = datum(o);
            let v = filtered_lobe(1.0, sigma, mean, cov, wo, wi) * facet_frame_factor(sigma, mean, cov, wo, wi);
            out = out + v * (vec3<f32>(datum(o + 1u), datum(o + 2u), datum(o + 3u)) + vec3<f32>(datum(o + 4u), datum(o + 5u), datum(o + 6u)) * f);
        }
        return out;
    }
//#endif
    return vec3<f32>(filtered_specular(mean, cov, wo, wi));
}

// Evaluator::facet_specular: the base lobe at facet n, or a measured BRDF's fitted lobes in the
// facet's own frame.
fn facet_specular(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
//#if measured
    if (params.measured != 0u) {
        let f = fresnel_factor(wi, wo);
        let t = basis_t(n);
        let b = basis_b(n);
        let wo_l = vec3<f32>(dot(wo, t), dot(wo, b), dot(wo, n));
        let wi_l = vec3<f32>(dot(wi, t), dot(wi, b), dot(wi, n));
        var out = vec3<f32>(0.0);
        for (var k = 0u; k < params.lobe_count; k = k + 1u) {
            let o = params.lobe_offset + 7u * k;
            let v = specular_lobe(1.0, datum(o), vec3<f32>(0.0, 0.0, 1.0), wo_l, wi_l, vec3<f32>(0.0));
            out = out + v * (vec3<f32>(datum(o + 1u), datum(o + 2u), datum(o + 3u)) + vec3<f32>(datum(o + 4u), datum(o + 5u), datum(o + 6u)) * f);
        }
        return out;
    }
//#endif
    return vec3<f32>(specular_with(n, wo, wi, vec3<f32>(0.0)));
}

//#if measured
// shading::FACET_FRAME_MAX.
const FACET_FRAME_MAX: f32 = 2.0;

// shading::facet_frame_factor: the facet-frame lobe over the slope-space one, both averaged over
// the posterior N(s*, Σ*) of the slopes that carry the lobe on a 3 × 3 Gauss–Hermite rule.
fn facet_frame_factor(sigma_lobe: f32, mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (!(wo.z > 0.0 && wi.z > 0.0)) {
        return 1.0;
    }
    let h = normalize(wo + wi);
    if (!(h.z > 1e-9)) {
        return 1.0;
    }
    let p = lobe_posterior(mean, cov, slope_of(h), sigma_lobe);
    let post = p.mean;
    let l = cholesky(p.cov);
    let z = array<f32, 3>(-1.7320508, 0.0, 1.7320508);
    let w = array<f32, 3>(1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0);
    var facet = 0.0;
    var slope_space = 0.0;
    for (var i = 0u; i < 3u; i = i + 1u) {
        for (var j = 0u; j < 3u; j = j + 1u) {
            let s = post + vec2<f32>(l.x * z[i], l.y * z[i] + l.z * z[j]);
            let n = normal_of(s);
            let no = dot(n, wo);
            let nh = dot(n, h);
            let wt = w[i] * w[j];
            let root = sqrt(1.0 + dot(s, s));
            if (no > 0.0) {
                slope_space = slope_space + wt * no * root;
                if (nh > 1e-6) {
                    facet = facet + wt * root / pow(nh, 4.0);
                }
            }
        }
    }
    // At most FACET_FRAME_MAX (core's comment: the fit lacks the tables' masking at silhouettes).
    let r = facet * pow(h.z, 4.0) * wo.z / slope_space;
    if (slope_space > 0.0 && r == r && abs(r) < 3.0e38) {
        return min(r, FACET_FRAME_MAX);
    }
    return 1.0;
}
//#endif

// Evaluator::facet_radiance (the frame is shading_frame): the base BRDF at facet n, or a measured
// BRDF's table in the facet's frame tinted by its colour.
fn facet_radiance(color: Affine, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, v: f32) -> vec3<f32> {
    let s = point_shading(n, wi);
//#if measured
    if (params.measured != 0u) {
        var rho = vec3<f32>(0.0);
        if (v > 0.0) {
            rho = measured_eval_facet(n, wi, wo);
        }
        let sun = params.sun * v;
        let kd = params.albedo * FRAC_1_PI * params.kd_rgb;
        return sun * (color.a * s.cos + color.k * s.cs_cos) * rho + kd * (color.a * s.env + color.k * s.cs_env);
    }
//#endif
    return radiance(color, color, s, v, facet_specular(n, wo, wi));
}

fn has_environment() -> bool {
//#if environment
    return params.has_env != 0u;
//#else
    return false;
//#endif
}

//#if relief
// Evaluator::visible_shading: point_shading averaged on the nodes of D_s (visible_slope_nodes),
// world slope space, slopes N(mean, cov).
fn visible_shading(mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> SlopeShading {
    let sums = visible_shading_sums(mean, cov, wo, wi, params.slope_rule_offset, params.slope_nodes);
    var acc = sums.s;
    if (sums.den > 0.0) {
        let inv = 1.0 / sums.den;
        acc.cos = acc.cos * inv;
        acc.cs_cos = acc.cs_cos * inv;
        acc.env = acc.env * inv;
        acc.cs_env = acc.cs_env * inv;
    }
    return acc;
}

// The sums visible_shading divides, and the sum of the weights.
struct ShadingSums {
    s: SlopeShading,
    den: f32,
}

// Evaluator::visible_shading_sums, on the rule of `nodes` nodes stored at `rule_off`. (Four
// nodes per loop iteration spent a quarter of the loop budget, bindings.wgsl, but cost 20% more
// time on llvmpipe: snow-under-sky's naive view at 80°, 145 against 176 ms.)
fn visible_shading_sums(mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, rule_off: u32, nodes: u32) -> ShadingSums {
    let l = cholesky(cov);
    var acc: SlopeShading;
    acc.cos = 0.0;
    acc.cs_cos = vec3<f32>(0.0);
    acc.env = vec3<f32>(0.0);
    acc.cs_env = vec3<f32>(0.0);
    var den = 0.0;
    for (var i = 0u; i < nodes; i = i + 1u) {
        let b = rule_off + 3u * i;
        let z = vec3<f32>(datum(b), datum(b + 1u), datum(b + 2u));
        let s = mean + vec2<f32>(l.x * z.x, l.y * z.x + l.z * z.y);
        let u = max(wo.z - s.x * wo.x - s.y * wo.y, 0.0);
        let wt = z.z * u;
        if (wt > 0.0) {
            let n = normal_of(s);
            let p = point_shading(n, wi);
            acc.cos = acc.cos + wt * p.cos;
            acc.cs_cos = acc.cs_cos + wt * p.cs_cos;
            acc.env = acc.env + wt * p.env;
            acc.cs_env = acc.cs_env + wt * p.cs_env;
            den = den + wt;
        }
    }
    return ShadingSums(acc, den);
}

//#endif
