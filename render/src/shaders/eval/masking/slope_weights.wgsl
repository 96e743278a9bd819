// Mirror of `core/src/eval/masking/slope_weights.rs`: the visible (height, slope) pairs weighted jointly
// by masking conditioned on the facet's height and slope (#17).
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
// SlopeWeights: the view's horizontal direction, the footprint's mean slope and the unresolved
// slopes' deviation along it (off: on = false); the joint masking itself is in joint_masking.
struct SlopeWeights {
    on: bool,
    dir: vec2<f32>,
    mean: f32,
    sd: f32,
}

// SlopeWeights::coordinate: the slope of facet s along the view, in the unresolved deviations.
fn slope_weights_coordinate(w: SlopeWeights, s: vec2<f32>) -> f32 {
    return (dot(s, w.dir) - w.mean) / w.sd;
}

// SlopeWeights::at: a profile's factor at a facet of slope s.
fn slope_weights_at(w: SlopeWeights, profile: SlopeProfile, s: vec2<f32>) -> f32 {
    if (!w.on) {
        return 1.0;
    }
    return profile_at(profile, slope_weights_coordinate(w, s));
}

// height_span: the table rows slope_heights reads for the sun's and the environment's D_h.
fn height_span(a: HeightMoments, b: HeightMoments) -> vec2<u32> {
    let reach = 2.856970013872806;
    let lo = min(a.mean - reach * a.std_dev, b.mean - reach * b.std_dev);
    let hi = max(a.mean + reach * a.std_dev, b.mean + reach * b.std_dev);
    return height_rows(lo, hi);
}

// Evaluator::slope_weights: off without the material's table (Smith's masking, an image
// driver), at the normal, or with no unresolved slope along the view; on, it looks the joint
// masking up into joint_masking, at the rows the D_h of hm_sun and hm_env read.
fn slope_weights(fp: vec3<f32>, mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, hm_sun: HeightMoments, hm_env: HeightMoments) -> SlopeWeights {
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
    slope_masking_lookup(dir, scale, nu, height_span(hm_sun, hm_env));
    return out;
}

// The visible shading split over the slope nodes (SLOPE_NODES = 9), as
// visible_shading_buckets leaves it: each bucket's unnormalised SlopeShading sums and weight,
// field by field (the GLSL export round-trips neither arrays of structs nor structs of arrays).
var<private> bucket_cos: array<f32, 9>;
var<private> bucket_cs_cos: array<vec3<f32>, 9>;
var<private> bucket_env: array<vec3<f32>, 9>;
var<private> bucket_cs_env: array<vec3<f32>, 9>;
var<private> bucket_w: array<f32, 9>;

// Bucket j's sums as a SlopeShading.
fn bucket(j: u32) -> SlopeShading {
    return SlopeShading(bucket_cos[j], bucket_cs_cos[j], bucket_env[j], bucket_cs_env[j]);
}

// Evaluator::visible_shading_buckets: each visible node to the two slope nodes around its slope
// along the view, with linear (hat) weights (into the bucket arrays).
fn visible_shading_buckets(mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, rule_off: u32, nodes: u32, weights: SlopeWeights) {
    let l = cholesky(cov);
    for (var j = 0u; j < SLOPE_NODES; j = j + 1u) {
        bucket_cos[j] = 0.0;
        bucket_cs_cos[j] = vec3<f32>(0.0);
        bucket_env[j] = vec3<f32>(0.0);
        bucket_cs_env[j] = vec3<f32>(0.0);
        bucket_w[j] = 0.0;
    }
    for (var i = 0u; i < nodes; i = i + 1u) {
        let b = rule_off + 3u * i;
        let z = vec3<f32>(datum(b), datum(b + 1u), datum(b + 2u));
        let s = mean + vec2<f32>(l.x * z.x, l.y * z.x + l.z * z.y);
        let u = max(wo.z - s.x * wo.x - s.y * wo.y, 0.0);
        let wt = z.z * u;
        if (wt > 0.0) {
            let n = normal_of(s);
            var c = slope_weights_coordinate(weights, slope_of(n));
            if (c != c) {
                c = 0.0;
            }
            // The hat weights as tents over the slope nodes, the buckets indexed by the loop
            // counter alone (see slope_masking_lookup).
            let x = clamp(c + 4.0, 0.0, f32(SLOPE_NODES - 1u));
            let p = point_shading(n, wi);
            for (var j = 0u; j < SLOPE_NODES; j = j + 1u) {
                let wj = wt * max(1.0 - abs(x - f32(j)), 0.0);
                bucket_cos[j] = bucket_cos[j] + wj * p.cos;
                bucket_cs_cos[j] = bucket_cs_cos[j] + wj * p.cs_cos;
                bucket_env[j] = bucket_env[j] + wj * p.env;
                bucket_cs_env[j] = bucket_cs_env[j] + wj * p.cs_env;
                bucket_w[j] = bucket_w[j] + wj;
            }
        }
    }
}

// SlopeHeights at every slope node: the mass, mean and standard deviation of D_h·r(·, z_j).
struct SlopeHeights {
    mass: SlopeProfile,
    mean: SlopeProfile,
    std_dev: SlopeProfile,
}

// SlopeWeights::heights: 5-point Gauss–Hermite on D_h's Gaussian of moments hm. ln r at each
// node is log_ratio_at's linear interpolation written as tents over the height rows, so that
// joint_masking is indexed by loop counters alone (see slope_masking_lookup).
fn slope_heights(hm: HeightMoments) -> SlopeHeights {
    let gx = array<f32, 5>(-2.856970013872806, -1.355626179974266, 0.0, 1.355626179974266, 2.856970013872806);
    let gw = array<f32, 5>(0.01125741132772069, 0.2220759220056126, 0.5333333333333333, 0.2220759220056126, 0.01125741132772069);
    // Each node's position on the row axis (height_cell's clamped coordinate).
    var x: array<f32, 5>;
    for (var k = 0u; k < 5u; k = k + 1u) {
        let c = height_cell(hm.mean + hm.std_dev * gx[k]);
        x[k] = c.x + c.y;
    }
    var out: SlopeHeights;
    for (var j = 0u; j < SLOPE_NODES; j = j + 1u) {
        var lr = array<f32, 5>(0.0, 0.0, 0.0, 0.0, 0.0);
        for (var i = 0u; i < HEIGHT_NODES; i = i + 1u) {
            let v = joint_masking[i * SLOPE_NODES + j];
            for (var k = 0u; k < 5u; k = k + 1u) {
                lr[k] = lr[k] + max(1.0 - abs(x[k] - f32(i)), 0.0) * v;
            }
        }
        var m0 = 0.0;
        var m1 = 0.0;
        var m2 = 0.0;
        for (var k = 0u; k < 5u; k = k + 1u) {
            let r = gw[k] * exp(lr[k]);
            m0 = m0 + r;
            m1 = m1 + r * gx[k];
            m2 = m2 + r * gx[k] * gx[k];
        }
        var mass = 0.0;
        var mean = hm.mean;
        var sd = hm.std_dev;
        if (m0 > 0.0) {
            let ex = m1 / m0;
            mass = m0;
            mean = hm.mean + hm.std_dev * ex;
            sd = hm.std_dev * sqrt(max(m2 / m0 - ex * ex, 0.0));
        }
        out.mass.m[j / 3u][j % 3u] = mass;
        out.mean.m[j / 3u][j % 3u] = mean;
        out.std_dev.m[j / 3u][j % 3u] = sd;
    }
    return out;
}

// JointInputs: colour terms under the sun and the environment, and the shading inputs.
struct JointInputs {
    sun: Affine,
    env: Affine,
    shading: SlopeShading,
}

// joint_inputs over the buckets visible_shading_buckets left (with the colour terms of each slope
// node's heights computed here: the input distribution d, the masking exponent and D_h moments of
// the sun and the environment).
fn joint_inputs(sun_h: SlopeHeights, env_h: SlopeHeights, d: vec2<f32>, l_sun: f32, hm_sun: HeightMoments, l_env: f32, hm_env: HeightMoments) -> JointInputs {
    var ds = 0.0;
    var de = 0.0;
    for (var j = 0u; j < SLOPE_NODES; j = j + 1u) {
        ds = ds + profile_node(sun_h.mass, j) * bucket_w[j];
        de = de + profile_node(env_h.mass, j) * bucket_w[j];
    }
    var out: JointInputs;
    out.shading.cos = 0.0;
    out.shading.cs_cos = vec3<f32>(0.0);
    out.shading.env = vec3<f32>(0.0);
    out.shading.cs_env = vec3<f32>(0.0);
    // weighted_terms, per side: Σ m v x / Σ m x, or Σ m w v / Σ m w where no weight carries x.
    var sa = vec3<f32>(0.0);
    var sa_d = vec3<f32>(0.0);
    var sk = vec3<f32>(0.0);
    var sk_d = vec3<f32>(0.0);
    var ea = vec3<f32>(0.0);
    var ea_d = vec3<f32>(0.0);
    var ek = vec3<f32>(0.0);
    var ek_d = vec3<f32>(0.0);
    var fsa = vec3<f32>(0.0);
    var fsk = vec3<f32>(0.0);
    var fs_d = 0.0;
    var fea = vec3<f32>(0.0);
    var fek = vec3<f32>(0.0);
    var fe_d = 0.0;
    var mid_sun: Affine;
    var mid_env: Affine;
    for (var j = 0u; j < SLOPE_NODES; j = j + 1u) {
        let s = bucket(j);
        let ms = profile_node(sun_h.mass, j);
        let sun = affine(color_of_distribution(d.x + d.y * profile_node(sun_h.mean, j), d.y * profile_node(sun_h.std_dev, j), l_sun, vec2<f32>(hm_sun.mean, hm_sun.std_dev), d.y * d.y));
        var env = sun;
        var me = ms;
//#if environment
        me = profile_node(env_h.mass, j);
        env = affine(color_of_distribution(d.x + d.y * profile_node(env_h.mean, j), d.y * profile_node(env_h.std_dev, j), l_env, vec2<f32>(hm_env.mean, hm_env.std_dev), d.y * d.y));
//#endif
        if (j == SLOPE_NODES / 2u) {
            mid_sun = sun;
            mid_env = env;
        }
        sa = sa + ms * sun.a * s.cos;
        sa_d = sa_d + vec3<f32>(ms * s.cos);
        sk = sk + ms * sun.k * s.cs_cos;
        sk_d = sk_d + ms * s.cs_cos;
        fsa = fsa + ms * bucket_w[j] * sun.a;
        fsk = fsk + ms * bucket_w[j] * sun.k;
        fs_d = fs_d + ms * bucket_w[j];
        ea = ea + me * env.a * s.env;
        ea_d = ea_d + me * s.env;
        ek = ek + me * env.k * s.cs_env;
        ek_d = ek_d + me * s.cs_env;
        fea = fea + me * bucket_w[j] * env.a;
        fek = fek + me * bucket_w[j] * env.k;
        fe_d = fe_d + me * bucket_w[j];
        if (ds > 0.0) {
            let k = ms / ds;
            out.shading.cos = out.shading.cos + k * s.cos;
            out.shading.cs_cos = out.shading.cs_cos + k * s.cs_cos;
        }
        if (de > 0.0) {
            let k = me / de;
            out.shading.env = out.shading.env + k * s.env;
            out.shading.cs_env = out.shading.cs_env + k * s.cs_env;
        }
    }
    out.sun.a = weighted_term(sa, sa_d, fsa, fs_d, mid_sun.a);
    out.sun.k = weighted_term(sk, sk_d, fsk, fs_d, mid_sun.k);
    out.env.a = weighted_term(ea, ea_d, fea, fe_d, mid_env.a);
    out.env.k = weighted_term(ek, ek_d, fek, fe_d, mid_env.k);
    return out;
}

// weighted_terms' choice per channel: num/den, else the fallback's, else the middle node's.
fn weighted_term(num: vec3<f32>, den: vec3<f32>, fnum: vec3<f32>, fden: f32, mid: vec3<f32>) -> vec3<f32> {
    var fallback = mid;
    if (fden > 0.0) {
        fallback = fnum / fden;
    }
    return select(fallback, num / max(den, vec3<f32>(1e-30)), den > vec3<f32>(0.0));
}

//#if specular|measured
// SlopeWeights::lobe_factor: the sun's lobe × the profile at its posterior slope over the
// profile's visible mean, from the slope buckets' weights (visible_shading_buckets).
fn lobe_factor(w: SlopeWeights, profile: SlopeProfile, mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, roughness: f32) -> f32 {
    if (!(wo.z > 0.0 && wi.z > 0.0)) {
        return 1.0;
    }
    let h = normalize(wo + wi);
    if (!(h.z > 1e-9)) {
        return 1.0;
    }
    let post = lobe_posterior(mean, cov, slope_of(h), roughness);
    var plain = 0.0;
    var weighted = 0.0;
    for (var j = 0u; j < SLOPE_NODES; j = j + 1u) {
        plain = plain + bucket_w[j];
        weighted = weighted + bucket_w[j] * profile_node(profile, j);
    }
    if (weighted > 0.0) {
        return slope_weights_at(w, profile, post.mean) * plain / weighted;
    }
    return 1.0;
}
//#endif
//#endif
