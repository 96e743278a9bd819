// The material model on the GPU: the WGSL mirror of lodestone-core's noise.rs, transfer.rs,
// preconvolved.rs, effective_height.rs, smith.rs, shadowing.rs, attribute.rs, brdf.rs and
// footprint.rs, function for function under the same names (prefixes only where WGSL needs them).
// Needs special.wgsl before it. All positions are relative to the camera target (the CPU folds
// 2π k·target into each wave's phase in f64), which keeps f32 phases accurate far from the origin.
// `//#if feature` blocks are removed when a scene does not use the feature (specialize.rs); this
// file as written is the all-features shader only after specialize() has stripped the directives.

const PI: f32 = 3.14159265;
const TAU: f32 = 6.2831853;
const FRAC_1_PI: f32 = 0.31830988;
const SQRT_2: f32 = 1.4142135;
// Over-relaxation of the sphere-tracing marches (surface::RELAXATION).
const RELAXATION: f32 = 1.6;

// Flat parameter block; kept in sync with `GpuParams` in gpu_types.rs by a layout test.
struct Params {
    eye: vec3<f32>,
    tan_half_fov: f32,
    right: vec3<f32>,
    aspect: f32,
    up: vec3<f32>,
    pixel_sigma: f32,
    forward: vec3<f32>,
    frame: u32,
    light: vec3<f32>,
    mode: u32,
    attr_mean: vec3<f32>,
    dh_ln_min: f32,
    attr_corr: vec3<f32>,
    dh_ln_max: f32,
    width: u32,
    height: u32,
    shape: u32,
    wave_count: u32,
    sigma_h: f32,
    albedo: f32,
    specular: f32,
    roughness: f32,
    h_max: f32,
    g_lip: f32,
    min_step: f32,
    transfer_kind: u32,
    color_kind: u32,
    correlation: u32,
    height_filter: u32,
    slope_points: u32,
    g_mean: f32,
    g_std: f32,
    dh_size: u32,
    gh_offset: u32,
    ct_offset: u32,
    ct_size_m: u32,
    ct_size_s: u32,
    ct_m_min: f32,
    ct_m_max: f32,
    ct_sigma_max: f32,
    tt_offset: u32,
    tt_size_m: u32,
    tt_size_s: u32,
    tt_m_min: f32,
    tt_m_max: f32,
    tt_sigma_max: f32,
    cp_offset: u32,
    cp_knots: u32,
    tp_offset: u32,
    tp_knots: u32,
    waves_offset: u32,
    dh_offset: u32,
    radius: f32,
    slope_bound: f32,
    driver_kind: u32,
    image_offset: u32,
    image_levels: u32,
    image_scale: f32,
    image_u0: f32,
    image_v0: f32,
    image_lip_x: f32,
    image_lip_y: f32,
    // Colour terms (ColorTerms; an absent term has weight 0) and lighting.
    c0: vec3<f32>,
    kappa0: f32,
    sc_dir: vec3<f32>,
    kappa2: f32,
    kappa1: f32,
    combine_mode: u32,
    sun: f32,
    sp_knots: u32,
    sp_offset: u32,
    env_offset: u32,
    has_env: u32,
    pad1: u32,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> data: array<f32>;

// ---------------------------------------------------------------- preconvolved.rs
fn texel4(off: u32, i: u32) -> vec4<f32> {
    let b = off + 4u * i;
    return vec4<f32>(data[b], data[b + 1u], data[b + 2u], data[b + 3u]);
}

//#if driver_color|height_color|transfer_curve
// (i0, i1, blend) of a continuous texel coordinate, clamped (mirror of preconvolved::split).
fn split_coord(f_in: f32, n: u32) -> vec3<f32> {
    let f = clamp(f_in, 0.0, f32(n - 1u));
    let i0 = min(u32(floor(f)), n - 2u);
    return vec3<f32>(f32(i0), f32(i0 + 1u), f - f32(i0));
}

// PreconvolvedTable::sample: bilinear, clamp-to-edge.
fn table_sample(off: u32, nm: u32, ns: u32, m_min: f32, m_max: f32, sigma_max: f32, m: f32, sigma: f32) -> vec4<f32> {
    let u = split_coord((m - m_min) / (m_max - m_min) * f32(nm - 1u), nm);
    let v = split_coord(sigma / sigma_max * f32(ns - 1u), ns);
    let i0 = u32(u.x);
    let i1 = u32(u.y);
    let j0 = u32(v.x);
    let j1 = u32(v.y);
    let top = mix(texel4(off, j0 * nm + i0), texel4(off, j0 * nm + i1), u.z);
    let bot = mix(texel4(off, j1 * nm + i0), texel4(off, j1 * nm + i1), u.z);
    return mix(top, bot, v.z);
}
//#endif

// ---------------------------------------------------------------- effective_height.rs
//#if relief
// EffectiveHeightTable::lookup (x = mean, y = std), or the paper's fits [HNPN14 Eqs. 16–17].
fn height_moments(l_in: f32) -> vec2<f32> {
    let l = max(l_in, 0.0);
    if (params.height_filter == 1u) {
        let lc = min(l, 1e30);
        return vec2<f32>(0.39 * log(1.0 + 4.75 * lc), 1.0 / (1.0 + 0.26 * log(1.0 + 1.13 * lc)));
    }
    let n = params.dh_size;
    let off = params.dh_offset;
    let l_min = exp(params.dh_ln_min);
    if (l < l_min) {
        let s = l / l_min;
        return vec2<f32>(s * data[off], 1.0 + s * (data[off + 1u] - 1.0));
    }
    let u = clamp((log(l) - params.dh_ln_min) / (params.dh_ln_max - params.dh_ln_min) * f32(n - 1u), 0.0, f32(n - 1u));
    let i = min(u32(floor(u)), n - 2u);
    let f = u - f32(i);
    let a = vec2<f32>(data[off + 2u * i], data[off + 2u * i + 1u]);
    let b = vec2<f32>(data[off + 2u * i + 2u], data[off + 2u * i + 3u]);
    return mix(a, b, f);
}
//#endif

// ---------------------------------------------------------------- piecewise.rs (eval, degree ≤ 3)
//#if driver_color|height_color|transfer_curve|slope_color
// Layout at `off`: knots[k], then per segment per channel 4 coefficients, then left[ch], right[ch].
fn poly_eval(off: u32, k: u32, channels: u32, ch: u32, x: f32) -> f32 {
    let coeff = off + k;
    let tails = coeff + 4u * channels * (k - 1u);
    if (x < data[off]) {
        return data[tails + ch];
    }
    if (x >= data[off + k - 1u]) {
        return data[tails + channels + ch];
    }
    // Last knot ≤ x.
    var seg = 0u;
    for (var i = 1u; i < k - 1u; i = i + 1u) {
        if (data[off + i] <= x) {
            seg = i;
        }
    }
    let a = data[off + seg];
    let b = data[off + seg + 1u];
    let t = (x - a) / (b - a);
    let c = coeff + 4u * (seg * channels + ch);
    return ((data[c + 3u] * t + data[c + 2u]) * t + data[c + 1u]) * t + data[c];
}
//#endif

// ---------------------------------------------------------------- noise.rs
struct FilteredDriver {
    mean: f32,
    std_dev: f32,
    mean_gradient: vec2<f32>,
    gradient_cov: vec3<f32>, // xx, yy, xy
}

//#if noise
fn wave(i: u32) -> vec4<f32> {
    return texel4(params.waves_offset, i);
}
//#endif

// UNROLL. llvmpipe (Mesa's CPU driver, what tests and CI run on) ends every loop of a shader
// invocation once all loops together have taken 65535 back-edges (LP_MAX_TGSI_LOOP_ITERATIONS,
// "shared between every loop", per 8-lane vector). A grazing march of a few thousand steps over
// 48 waves used to reach it; every later wave sum was then cut short for all 8 lanes: the "dashes"
// of wrong pixels in runs of exactly 8 (355 of 100 000 pixels of snow-under-sky at 78°, for
// example). The wave sums that run per march step take eight waves per iteration, which moves the
// limit 8× further; real GPUs have no such limit.

//#if noise
// Wave i's (value, gradient) at x.
fn wave_term(i: u32, x: vec2<f32>) -> vec3<f32> {
    let w = wave(i);
    let ph = TAU * dot(w.xy, x) + w.w;
    return vec3<f32>(w.z * cos(ph), -w.xy * (w.z * TAU * sin(ph)));
}
//#endif

// DriverField::value_and_gradient: (f, ∂f/∂x, ∂f/∂y) of the noise (SumOfSines) or the image.
fn value_and_gradient(x: vec2<f32>) -> vec3<f32> {
//#if image
    if (params.driver_kind == 1u) {
        let v = image_value_and_gradient(image_texel(x));
        return vec3<f32>(v.x, v.yz * params.image_scale);
    }
//#endif
//#if noise
    // Eight waves per iteration: see UNROLL.
    var s = vec3<f32>(0.0);
    let n8 = params.wave_count & ~7u;
    var i = 0u;
    for (; i < n8; i = i + 8u) {
        s = s + wave_term(i, x) + wave_term(i + 1u, x) + wave_term(i + 2u, x) + wave_term(i + 3u, x)
            + wave_term(i + 4u, x) + wave_term(i + 5u, x) + wave_term(i + 6u, x) + wave_term(i + 7u, x);
    }
    for (; i < params.wave_count; i = i + 1u) {
        s = s + wave_term(i, x);
    }
    return s;
//#else
    return vec3<f32>(0.0);
//#endif
}

// DriverField::filtered (SumOfSines::filtered for the noise) with footprint covariance (xx, yy, xy).
fn filtered_driver(x: vec2<f32>, fp: vec3<f32>) -> FilteredDriver {
//#if image
    if (params.driver_kind == 1u) {
        return image_filtered_driver(x, fp);
    }
//#endif
    var r: FilteredDriver;
    r.mean = 0.0;
    r.mean_gradient = vec2<f32>(0.0);
    r.gradient_cov = vec3<f32>(0.0);
    var var_sum = 0.0;
//#if noise
    for (var i = 0u; i < params.wave_count; i = i + 1u) {
        let w = wave(i);
        let q = w.x * w.x * fp.x + 2.0 * w.x * w.y * fp.z + w.y * w.y * fp.y;
        let g = exp(-2.0 * PI * PI * q);
        let ph = TAU * dot(w.xy, x) + w.w;
        r.mean = r.mean + w.z * g * cos(ph);
        r.mean_gradient = r.mean_gradient - w.xy * (w.z * g * TAU * sin(ph));
        let u = w.z * w.z * (1.0 - g * g) * 0.5;
        var_sum = var_sum + u;
        r.gradient_cov = r.gradient_cov + vec3<f32>(w.x * w.x, w.y * w.y, w.x * w.y) * (u * TAU * TAU);
    }
//#endif
    r.std_dev = sqrt(max(var_sum, 0.0));
    return r;
}

// ---------------------------------------------------------------- transfer.rs
// TransferFunction::eval and ::derivative: (g, g′). Identity when transfer_kind == 0.
fn transfer_eval(f: f32) -> vec2<f32> {
//#if transfer_curve
    if (params.transfer_kind != 0u) {
        return vec2<f32>(poly_eval(params.tp_offset, params.tp_knots, 2u, 0u, f), poly_eval(params.tp_offset, params.tp_knots, 2u, 1u, f));
    }
//#endif
    return vec2<f32>(f, 1.0);
}

// Moments (ḡ, σ_g, ḡ′, σ_g′) [HNPN14 Eqs. 21–28], from the table for curves.
fn transfer_moments(m: f32, s: f32) -> vec4<f32> {
//#if transfer_curve
    if (params.transfer_kind != 0u) {
        let v = table_sample(params.tt_offset, params.tt_size_m, params.tt_size_s, params.tt_m_min, params.tt_m_max, params.tt_sigma_max, m, s);
        return vec4<f32>(v.x, max(v.y, 0.0), v.z, max(v.w, 0.0));
    }
//#endif
    return vec4<f32>(m, max(s, 0.0), 1.0, 0.0);
}

struct SurfaceStats {
    height_mean: f32,
    height_std: f32,
    slope_mean: vec2<f32>,
    slope_cov: vec3<f32>,
}

// transformed_statistics [HNPN14 Eqs. 19–26].
fn transformed_statistics(tm: vec4<f32>, sigma_h: f32, grad_mean: vec2<f32>, grad_cov: vec3<f32>) -> SurfaceStats {
    let var_d = tm.w * tm.w;
    let md2 = tm.z * tm.z;
    let second = grad_cov + vec3<f32>(grad_mean.x * grad_mean.x, grad_mean.y * grad_mean.y, grad_mean.x * grad_mean.y);
    var s: SurfaceStats;
    s.slope_cov = (second * var_d + grad_cov * md2) * (sigma_h * sigma_h);
    s.height_mean = sigma_h * tm.x;
    s.height_std = abs(sigma_h) * tm.y;
    s.slope_mean = grad_mean * (sigma_h * tm.z);
    return s;
}

// ---------------------------------------------------------------- smith.rs / shadowing.rs
//#if relief
fn cot_theta(w: vec3<f32>) -> f32 {
    if (!(w.z > 0.0)) {
        return 0.0;
    }
    let r = length(w.xy);
    if (r == 0.0) {
        return 3.0e38;
    }
    return w.z / r;
}

fn projected_std(cov: vec3<f32>, c: f32, s: f32) -> f32 {
    return sqrt(max(c * c * cov.x + 2.0 * c * s * cov.z + s * s * cov.y, 0.0));
}

// smith::lambda [HN12 Eq. 6].
fn lambda(w: vec3<f32>, cov: vec3<f32>) -> f32 {
    let mu = cot_theta(w);
    if (mu >= 3.0e38) {
        return 0.0;
    }
    let r = length(w.xy);
    let sigma = projected_std(cov, w.x / r, w.y / r);
    if (!(sigma > 0.0)) {
        return 0.0;
    }
    return smith_lambda(mu / (SQRT_2 * sigma));
}

fn azimuth_factor(d: f32) -> f32 {
    let a = min(abs(d), PI);
    return 4.41 * a / (4.41 * a + 1.0);
}

fn azimuth_difference(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let ra = length(a.xy);
    let rb = length(b.xy);
    if (!(ra > 0.0 && rb > 0.0)) {
        return 0.0;
    }
    let c = clamp(dot(a.xy, b.xy) / (ra * rb), -1.0, 1.0);
    let s = (a.x * b.y - a.y * b.x) / (ra * rb);
    return atan2(abs(s), c);
}

// MaskingShadowing::from_directions: (Λo, Λi, excess, total).
fn masking(wo: vec3<f32>, wi: vec3<f32>, cov: vec3<f32>) -> vec4<f32> {
    let lo = max(lambda(wo, cov), 0.0);
    let li = max(lambda(wi, cov), 0.0);
    var excess = li;
    if (params.correlation == 1u) {
        let k = azimuth_factor(azimuth_difference(wo, wi));
        excess = select((li - lo) + k * lo, k * li, lo >= li);
    }
    return vec4<f32>(lo, li, excess, lo + excess);
}

// MaskingShadowing::mean_shadowing [HNPN14 Eq. 12].
fn mean_shadowing(m: vec4<f32>) -> f32 {
    return 1.0 / (1.0 + m.z / (1.0 + m.x));
}
//#endif

// ---------------------------------------------------------------- attribute.rs
//#if attribute_color
fn attribute_shape(t: f32) -> f32 {
    return erf(t * FRAC_1_SQRT_2);
}

fn mean_attribute_shape(l: f32) -> f32 {
    return 1.0 - 2.0 / (max(l, 0.0) + 2.0);
}
//#endif

// ---------------------------------------------------------------- brdf.rs
fn slope_of(n: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(-n.x, -n.y) / max(n.z, 1e-30);
}

fn normal_of(s: vec2<f32>) -> vec3<f32> {
    return normalize(vec3<f32>(-s.x, -s.y, 1.0));
}

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
//#if specular
    if (params.specular <= 0.0 || dot(n, wi) <= 0.0 || dot(n, wo) <= 0.0 || wo.z <= 0.0 || wi.z <= 0.0) {
        return 0.0;
    }
    let h = normalize(wo + wi);
    if (h.z <= 1e-9) {
        return 0.0;
    }
    let s0 = max(params.roughness, 0.0);
    let d = gaussian2(slope_of(h) - slope_of(n), extra + vec3<f32>(s0 * s0, s0 * s0, 0.0));
    return params.specular * d / (4.0 * pow(h.z, 4.0) * wo.z);
//#else
    return 0.0;
//#endif
}


// ---------------------------------------------------------------- color_terms.rs, slope_color.rs, sh.rs
// ColorTerms::affine: C = a + k ⊙ C_s for colour-model value ch (absent terms have weight 0, which
// is "no contribution" when linear and "white" when multiplicative).
struct Affine {
    a: vec3<f32>,
    k: vec3<f32>,
}

fn affine(ch: vec3<f32>) -> Affine {
    var r: Affine;
    if (params.combine_mode == 1u) {
        let p = (vec3<f32>(1.0 - params.kappa0) + params.kappa0 * params.c0) * (vec3<f32>(1.0 - params.kappa1) + params.kappa1 * ch);
        r.a = p * (1.0 - params.kappa2);
        r.k = p * params.kappa2;
        return r;
    }
    r.a = params.kappa0 * params.c0 + params.kappa1 * ch;
    r.k = vec3<f32>(params.kappa2);
    return r;
}

// Prepared::slope_color_at (CompiledSlopeColor::sample) at a world normal.
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
    let b = array<f32, 9>(0.282095, 0.488603 * y, 0.488603 * z, 0.488603 * x, 1.092548 * x * y, 1.092548 * y * z, 0.315392 * (3.0 * z * z - 1.0), 1.092548 * x * z, 0.546274 * (x * x - y * y));
    var e = vec3<f32>(0.0);
    for (var i = 0u; i < 9u; i = i + 1u) {
        e = e + b[i] * vec3<f32>(data[o + 3u * i], data[o + 3u * i + 1u], data[o + 3u * i + 2u]);
    }
    return max(e, vec3<f32>(0.0));
//#else
    return vec3<f32>(0.0);
//#endif
}

// The tangent frame's axes in the world (identity on the plane; the cylinder sets its own before
// shading): slope colour and environment are looked up at world normals.
var<private> shading_frame: mat3x3<f32> = mat3x3<f32>(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);

struct SlopeShading {
    cos: f32,
    cs_cos: vec3<f32>,
    env: vec3<f32>,
    cs_env: vec3<f32>,
}

// Prepared::point_shading.
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

// Prepared::radiance.
fn radiance(sun_color: Affine, env_color: Affine, s: SlopeShading, v: f32, spec: f32) -> vec3<f32> {
    let sun = params.sun * v;
    let kd = params.albedo * FRAC_1_PI;
    return kd * (sun * (sun_color.a * s.cos + sun_color.k * s.cs_cos) + env_color.a * s.env + env_color.k * s.cs_env) + vec3<f32>(sun * spec);
}

fn has_environment() -> bool {
//#if environment
    return params.has_env != 0u;
//#else
    return false;
//#endif
}

// ---------------------------------------------------------------- footprint.rs
//#if relief
fn cholesky(c: vec3<f32>) -> vec3<f32> {
    let l11 = sqrt(max(c.x, 0.0));
    var l21 = 0.0;
    if (l11 > 0.0) {
        l21 = c.z / l11;
    }
    return vec3<f32>(l11, l21, sqrt(max(c.y - l21 * l21, 0.0)));
}

// Node i of footprint::slope_rule: (z.x, z.y, weight) of the standard bivariate normal.
fn slope_node(i: u32) -> vec3<f32> {
    let b = params.gh_offset + 3u * i;
    return vec3<f32>(data[b], data[b + 1u], data[b + 2u]);
}

// Prepared::visible_shading: point_shading averaged on the nodes of D_s (visible_slope_nodes),
// world slope space, slopes N(mean, cov).
fn visible_shading(mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> SlopeShading {
    let l = cholesky(cov);
    let nodes = params.slope_points * params.slope_points;
    var acc: SlopeShading;
    acc.cos = 0.0;
    acc.cs_cos = vec3<f32>(0.0);
    acc.env = vec3<f32>(0.0);
    acc.cs_env = vec3<f32>(0.0);
    var den = 0.0;
    for (var i = 0u; i < nodes; i = i + 1u) {
        let z = slope_node(i);
        let s = mean + vec2<f32>(l.x * z.x, l.y * z.x + l.z * z.y);
        let u = max(wo.z - s.x * wo.x - s.y * wo.y, 0.0);
        let wt = z.z * u;
        if (wt > 0.0) {
            let p = point_shading(normal_of(s), wi);
            acc.cos = acc.cos + wt * p.cos;
            acc.cs_cos = acc.cs_cos + wt * p.cs_cos;
            acc.env = acc.env + wt * p.env;
            acc.cs_env = acc.cs_env + wt * p.cs_env;
            den = den + wt;
        }
    }
    if (den > 0.0) {
        let inv = 1.0 / den;
        acc.cos = acc.cos * inv;
        acc.cs_cos = acc.cs_cos * inv;
        acc.env = acc.env * inv;
        acc.cs_env = acc.cs_env * inv;
    }
    return acc;
}

//#if slope_color
// footprint::slope_mean of C_s: the footprint average without visibility weight.
fn slope_color_mean(mean: vec2<f32>, cov: vec3<f32>) -> vec3<f32> {
    let l = cholesky(cov);
    let nodes = params.slope_points * params.slope_points;
    var acc = vec3<f32>(0.0);
    for (var i = 0u; i < nodes; i = i + 1u) {
        let z = slope_node(i);
        let s = mean + vec2<f32>(l.x * z.x, l.y * z.x + l.z * z.y);
        acc = acc + z.z * slope_color_at(shading_frame * normal_of(s));
    }
    return acc;
}
//#endif
//#endif

// footprint::filtered_specular (world slope space, facet slopes N(mean, cov)).
fn filtered_specular(mean: vec2<f32>, cov: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
//#if specular
    if (params.specular <= 0.0 || wo.z <= 0.0 || wi.z <= 0.0) {
        return 0.0;
    }
    let h = normalize(wo + wi);
    if (h.z <= 1e-9) {
        return 0.0;
    }
    let sh = slope_of(h);
    let s0 = max(params.roughness, 0.0);
    let total = cov + vec3<f32>(s0 * s0, s0 * s0, 0.0);
    // Posterior of the facet slope given the half vector: s* = s̄ + K(s_h − s̄), Σ* = Σ − KΣ.
    let det = total.x * total.y - total.z * total.z;
    var post_mean = sh;
    var post_cov = vec3<f32>(0.0);
    if (det > 1e-30) {
        let inv = vec3<f32>(total.y, total.x, -total.z) / det;
        // K = Σ·C⁻¹ (general 2×2: columns k0, k1).
        let k0 = vec2<f32>(cov.x * inv.x + cov.z * inv.z, cov.z * inv.x + cov.y * inv.z);
        let k1 = vec2<f32>(cov.x * inv.z + cov.z * inv.y, cov.z * inv.z + cov.y * inv.y);
        let d = sh - mean;
        post_mean = mean + k0 * d.x + k1 * d.y;
        // KΣ: columns K·(xx, xy) and K·(xy, yy).
        let c0 = k0 * cov.x + k1 * cov.z;
        let c1 = k0 * cov.z + k1 * cov.y;
        post_cov = vec3<f32>(max(cov.x - c0.x, 0.0), max(cov.y - c1.y, 0.0), cov.z - 0.5 * (c0.y + c1.x));
    }
    let u_post = expected_positive_part(wo.z, wo.xy, post_mean, post_cov);
    let eu = expected_positive_part(wo.z, wo.xy, mean, cov);
    let dens = gaussian2(sh - mean, total);
    return params.specular * dens * (u_post / max(eu, 1e-30)) / (4.0 * pow(h.z, 4.0) * wo.z);
//#else
    return 0.0;
//#endif
}

//#if specular
// footprint::expected_positive_part: E[(a − s·b)⁺] for s ~ N(mean, cov).
fn expected_positive_part(a: f32, b: vec2<f32>, mean: vec2<f32>, cov: vec3<f32>) -> f32 {
    let m = a - dot(mean, b);
    let v = b.x * b.x * cov.x + 2.0 * b.x * b.y * cov.z + b.y * b.y * cov.y;
    if (v > 1e-30) {
        let sv = sqrt(v);
        let r = clamp(m / sv, -40.0, 40.0);
        return m * norm_cdf(r) + sv * norm_pdf(r);
    }
    return max(m, 0.0);
}
//#endif

// Prepared::point_input: (colour-map input, standardized height) at driver value f.
fn point_input(f: f32) -> vec2<f32> {
    let t = (transfer_eval(f).x - params.g_mean) / params.g_std;
    if (params.color_kind == 0u) {
        return vec2<f32>(f, t);
    }
    return vec2<f32>(t, t);
}

// Prepared::color_at.
fn color_at(f: f32) -> vec3<f32> {
    let it = point_input(f);
//#if attribute_color
    if (params.color_kind == 2u) {
        let s = attribute_shape(it.y);
        return max(params.attr_mean + params.attr_corr * s, vec3<f32>(0.0));
    }
//#endif
//#if driver_color|height_color
    let k = params.cp_knots;
    return vec3<f32>(poly_eval(params.cp_offset, k, 3u, 0u, it.x), poly_eval(params.cp_offset, k, 3u, 1u, it.x), poly_eval(params.cp_offset, k, 3u, 2u, it.x));
//#else
    return vec3<f32>(0.0);
//#endif
}

// Prepared::color_of_distribution.
fn color_of_distribution(mean: f32, sd: f32, l: f32, far: vec2<f32>, w: f32) -> vec3<f32> {
//#if attribute_color
    if (params.color_kind == 2u) {
        let g = erf(mean / sqrt(2.0 * (1.0 + sd * sd)));
        let gf = erf(far.x / sqrt(2.0 * (1.0 + far.y * far.y)));
        let s = g + clamp(w, 0.0, 1.0) * (mean_attribute_shape(l) - gf);
        return max(params.attr_mean + params.attr_corr * s, vec3<f32>(0.0));
    }
//#endif
//#if driver_color|height_color
    return table_sample(params.ct_offset, params.ct_size_m, params.ct_size_s, params.ct_m_min, params.ct_m_max, params.ct_sigma_max, mean, sd).xyz;
//#else
    return vec3<f32>(0.0);
//#endif
}

struct Local {
    driver: FilteredDriver,
    transfer: vec4<f32>,
    stats: SurfaceStats,
}

fn local_stats(x0: vec2<f32>, fp: vec3<f32>) -> Local {
    var loc: Local;
    loc.driver = filtered_driver(x0, fp);
    loc.transfer = transfer_moments(loc.driver.mean, loc.driver.std_dev);
    loc.stats = transformed_statistics(loc.transfer, params.sigma_h, loc.driver.mean_gradient, loc.driver.gradient_cov);
    return loc;
}

// Prepared::input_distribution.
fn input_distribution(loc: Local) -> vec2<f32> {
    if (params.color_kind == 0u) {
        return vec2<f32>(loc.driver.mean, loc.driver.std_dev);
    }
    return vec2<f32>((loc.transfer.x - params.g_mean) / params.g_std, loc.transfer.y / params.g_std);
}

fn lit(wi: vec3<f32>, n: vec3<f32>) -> f32 {
    return select(0.0, 1.0, wi.z > 0.0 && dot(n, wi) > 0.0);
}

// Prepared::naive (sun_visible: the directional light's shadow test on the level-of-detail surface).
fn eval_naive(x0: vec2<f32>, fp: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, sun_visible: f32) -> vec3<f32> {
    let loc = local_stats(x0, fp);
    let n = normal_of(loc.stats.slope_mean);
    let aff = affine(color_at(loc.driver.mean));
    let spec = specular_with(n, wo, wi, vec3<f32>(0.0));
    return radiance(aff, aff, point_shading(n, wi), sun_visible * lit(wi, n), spec);
}

// Prepared::view_independent.
fn eval_view_independent(x0: vec2<f32>, fp: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, sun_visible: f32) -> vec3<f32> {
    let loc = local_stats(x0, fp);
    let ms = input_distribution(loc);
    let c = color_of_distribution(ms.x, ms.y, 0.0, vec2<f32>(0.0, 1.0), ms.y * ms.y);
    let n = normal_of(loc.stats.slope_mean);
    let aff = affine(c);
    var sh = point_shading(n, wi);
//#if slope_color
//#if relief
    let cs = slope_color_mean(loc.stats.slope_mean, loc.stats.slope_cov);
//#else
    let cs = slope_color_at(shading_frame * n);
//#endif
    sh.cs_cos = cs * sh.cos;
    sh.cs_env = cs * sh.env;
//#endif
    let spec = specular_with(n, wo, wi, vec3<f32>(0.0));
    return radiance(aff, aff, sh, sun_visible * lit(wi, n), spec);
}

//#if relief
// footprint::basis (Duff et al. 2017).
fn basis_t(n: vec3<f32>) -> vec3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

fn basis_b(n: vec3<f32>) -> vec3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(b, sign + n.y * n.y * a, -n.y);
}
//#endif

// Prepared::filtered.
fn eval_filtered(x0: vec2<f32>, fp: vec3<f32>, wo_w: vec3<f32>, wi_w: vec3<f32>, sun_visible: f32) -> vec3<f32> {
    let loc = local_stats(x0, fp);
//#if relief
    let nbar = normal_of(loc.stats.slope_mean);
    let t = basis_t(nbar);
    let b = basis_b(nbar);
    let wo = vec3<f32>(dot(wo_w, t), dot(wo_w, b), dot(wo_w, nbar));
    let wi = vec3<f32>(dot(wi_w, t), dot(wi_w, b), dot(wi_w, nbar));
    if (wo.z <= 0.0 || wo_w.z <= 0.0) {
        return vec3<f32>(0.0);
    }
    let cov = loc.stats.slope_cov;
    let ms = masking(wo, wi, cov);
    let d = input_distribution(loc);
    // The colour model over the visible and lit heights (L = Λo + Λi) for the directional light,
    // over the visible heights (L = Λo) for the unshadowed environment.
    let hm = height_moments(ms.w);
    let sun_color = affine(color_of_distribution(d.x + d.y * hm.x, d.y * hm.y, ms.w, hm, d.y * d.y));
    var env_color = sun_color;
//#if environment
    let hmo = height_moments(ms.x);
    env_color = affine(color_of_distribution(d.x + d.y * hmo.x, d.y * hmo.y, ms.x, hmo, d.y * d.y));
//#endif
    var vbar = 0.0;
    if (wi.z > 0.0 && wi_w.z > 0.0) {
        // Kept without the shadows feature: a light at the world normal is oblique to a tilted
        // mean normal, so Λ(ω_i) need not be 0 in the footprint's frame.
        vbar = mean_shadowing(ms);
    }
    // The footprint's slopes are N(s̄, Σ) in world slope space, exactly: average the facets there.
    let s_mean = loc.stats.slope_mean;
    let shading = visible_shading(s_mean, cov, wo_w, wi_w);
    let spec = filtered_specular(s_mean, cov, wo_w, wi_w);
    return radiance(sun_color, env_color, shading, sun_visible * vbar, spec);
//#else
    // Flat: every facet faces +z, nothing masks or shadows (Λ = 0, and D_h at L = 0 is the
    // identity, so the colour is that of the footprint's own distribution).
    if (wo_w.z <= 0.0) {
        return vec3<f32>(0.0);
    }
    let d = input_distribution(loc);
    let aff = affine(color_of_distribution(d.x, d.y, 0.0, vec2<f32>(0.0, 1.0), d.y * d.y));
    let spec = filtered_specular(vec2<f32>(0.0), vec3<f32>(0.0), wo_w, wi_w);
    return radiance(aff, aff, point_shading(vec3<f32>(0.0, 0.0, 1.0), wi_w), sun_visible * select(0.0, 1.0, wi_w.z > 0.0), spec);
//#endif
}

// ---------------------------------------------------------------- surface.rs (ground truth)
//#if relief|curved
fn surface_height(x: vec2<f32>) -> f32 {
    return params.sigma_h * transfer_eval(value_and_gradient(x).x).x;
}

//#endif

//#if relief
fn lipschitz_along(dir: vec2<f32>) -> f32 {
//#if image
    if (params.driver_kind == 1u) {
        return params.sigma_h * params.g_lip * image_lipschitz_along(dir);
    }
//#endif
    var s = 0.0;
//#if noise
    for (var i = 0u; i < params.wave_count; i = i + 1u) {
        let w = wave(i);
        s = s + abs(w.z) * TAU * abs(dot(w.xy, dir));
    }
//#endif
    return params.sigma_h * params.g_lip * s;
}

// Height of the explicit surface (lod = false) or of the level-of-detail surface (lod = true, needs
// lod_prepare first).
fn field_height(x: vec2<f32>, lod: bool, sf: f32) -> f32 {
    if (lod) {
        return lod_height(x, sf);
    }
    return surface_height(x);
}

// surface::march_heightfield (over-relaxed; backs off when the safe intervals of two points do not
// cover the step, before concluding anything at the new point): t of the first crossing, or -1 when
// the ray leaves the slab.

fn march_heightfield(o: vec3<f32>, d: vec3<f32>, rate: f32, lod: bool, sf: f32) -> f32 {
    if (!(rate > 0.0)) {
        return -1.0;
    }
    let top = params.h_max * (1.0 + 1e-6) + 1e-30;
    // f32 guard (core marches in f64 and needs none): a step must move the point by more than the
    // rounding of its coordinates, or a march leaving the surface never leaves it (its rounding-level
    // negative gap then reads as a crossing: false shadows at extreme frequencies, σ_n ≫ σ_h).
    let min_step = max(params.min_step, 4.8e-7 * (max(max(abs(o.x), abs(o.y)), abs(o.z)) + top));
    var t = 0.0;
    var prev_t = 0.0;
    var prev_r = 0.0;
    var relaxed = false;
    for (var it = 0u; it < 20000u; it = it + 1u) {
        let p = o + d * t;
        var gap = p.z - field_height(p.xy, lod, sf);
        if (gap < 0.0 && t == 0.0) {
            // The origin is on the surface by contract: a negative gap here is rounding.
            gap = 0.0;
        }
        let r = max(gap, 0.0) / rate;
        if (relaxed && t - prev_t > prev_r + r) {
            // The relaxed step left a stretch no safe interval covers: back off and step safely.
            t = prev_t + max(prev_r, min_step);
            relaxed = false;
            continue;
        }
        if ((d.z >= 0.0 && p.z > top) || (d.z < 0.0 && p.z < -top - 1.0)) {
            return -1.0;
        }
        if (gap < 0.0) {
            var a = prev_t;
            var b = t;
            for (var j = 0u; j < 24u; j = j + 1u) {
                let m = 0.5 * (a + b);
                let q = o + d * m;
                if (q.z - field_height(q.xy, lod, sf) >= 0.0) {
                    a = m;
                } else {
                    b = m;
                }
            }
            return a;
        }
        prev_t = t;
        prev_r = r;
        let safe = max(r, min_step);
        let step = max(RELAXATION * r, min_step);
        relaxed = step > safe;
        t = t + step;
    }
    return -1.0;
}

// Surface::march.
fn march(o: vec3<f32>, d: vec3<f32>) -> f32 {
    let r = length(d.xy);
    var k = 0.0;
    if (r > 0.0) {
        k = lipschitz_along(d.xy / r);
    }
    return march_heightfield(o, d, abs(d.z) + k * r, false, 0.0);
}

fn sees(p: vec3<f32>, d: vec3<f32>) -> bool {
    if (d.z <= 0.0) {
        return false;
    }
    return march(p, d) < 0.0;
}
//#endif

// Prepared::trace_pixel_sample for a camera ray (origin, unit direction).
fn trace_ray(origin: vec3<f32>, dir: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (dir.z >= 0.0) {
        return vec3<f32>(0.0);
    }
//#if relief
    // Start on the top of the slab.
    let top = params.h_max * 1.001 + 1e-6;
    let t0 = max((origin.z - top) / -dir.z, 0.0);
    let o = origin + dir * t0;
    let t = march(o, dir);
    if (t < 0.0) {
        return vec3<f32>(0.0);
    }
    let p = o + dir * t;
    let fg = value_and_gradient(p.xy);
    let gd = transfer_eval(fg.x);
    let n = normal_of(fg.yz * (params.sigma_h * gd.y));
//#else
    // Flat: the plane z = 0, facing +z everywhere.
    let p = origin + dir * (-origin.z / dir.z);
    let fg = value_and_gradient(p.xy);
    let n = vec3<f32>(0.0, 0.0, 1.0);
//#endif
    return shade_hit(fg.x, n, -dir, wi, p);
}

// Prepared::shade_hit on the plane (the shadow ray only when the directional light can contribute).
fn shade_hit(f: f32, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, p: vec3<f32>) -> vec3<f32> {
    let lit = dot(n, wi) > 0.0 && params.sun > 0.0;
    if (!lit && !has_environment()) {
        return vec3<f32>(0.0);
    }
    var v = select(0.0, 1.0, lit && wi.z > 0.0);
//#if shadows
    if (v > 0.0 && !sees(p, wi)) {
        v = 0.0;
    }
//#endif
    return shade_point(f, n, wo, wi, v);
}

// The end of Prepared::shade_hit: colour terms and radiance at a facet with light visibility v.
fn shade_point(f: f32, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, v: f32) -> vec3<f32> {
    let aff = affine(color_at(f));
    let spec = specular_with(n, wo, wi, vec3<f32>(0.0));
    return radiance(aff, aff, point_shading(n, wi), v, spec);
}

// ---------------------------------------------------------------- footprint.rs (level-of-detail surface)
//#if relief
// Per-invocation cache of each wave's footprint attenuation exp(−2π² kᵀΣk): constant along a pixel's
// rays, so the march evaluates only cosines per step. Filled by lod_prepare (MAX_COMPONENTS = 256).
//#if noise
var<private> lod_att: array<f32, 256>;
//#endif
//#if image
// The image's probe plan for the pixel's footprint (set by lod_prepare).
var<private> lod_plan: ProbePlan;
//#endif

// Fill lod_att (or lod_plan) for footprint fp; returns the position-averaged footprint std σ_f
// (DriverField::lod_moments).
fn lod_prepare(fp: vec3<f32>) -> f32 {
//#if image
    if (params.driver_kind == 1u) {
        let cov = fp * (params.image_scale * params.image_scale);
        lod_plan = image_plan(cov);
        let area = sqrt(sqrt(max(cov.x * cov.y - cov.z * cov.z, 0.0)));
        return image_mean_std(lod_for_std(area));
    }
//#endif
    var v = 0.0;
//#if noise
    for (var i = 0u; i < params.wave_count; i = i + 1u) {
        let w = wave(i);
        let q = w.x * w.x * fp.x + 2.0 * w.x * w.y * fp.z + w.y * w.y * fp.y;
        let g = exp(-2.0 * PI * PI * q);
        lod_att[i] = g;
        v = v + w.z * w.z * (1.0 - g * g) * 0.5;
    }
//#endif
    return sqrt(max(v, 0.0));
}

//#if noise
// Wave i's term of f̄(x).
fn lod_term(i: u32, x: vec2<f32>) -> f32 {
    let w = wave(i);
    return w.z * lod_att[i] * cos(TAU * dot(w.xy, x) + w.w);
}
//#endif

// f̄(x) with the cached attenuations.
fn lod_mean(x: vec2<f32>) -> f32 {
//#if image
    if (params.driver_kind == 1u) {
        return image_footprint_mean(image_texel(x), lod_plan);
    }
//#endif
    var m = 0.0;
//#if noise
    // Eight waves per iteration: see UNROLL.
    let n8 = params.wave_count & ~7u;
    var i = 0u;
    for (; i < n8; i = i + 8u) {
        m = m + lod_term(i, x) + lod_term(i + 1u, x) + lod_term(i + 2u, x) + lod_term(i + 3u, x)
            + lod_term(i + 4u, x) + lod_term(i + 5u, x) + lod_term(i + 6u, x) + lod_term(i + 7u, x);
    }
    for (; i < params.wave_count; i = i + 1u) {
        m = m + lod_term(i, x);
    }
//#endif
    return m;
}

// Prepared::lod_height.
fn lod_height(x: vec2<f32>, sf: f32) -> f32 {
    return params.sigma_h * transfer_moments(lod_mean(x), sf).x;
}

// Prepared::lod_rate.
fn lod_rate(d: vec3<f32>) -> f32 {
    let r = length(d.xy);
    var k = 0.0;
    if (r > 0.0) {
        let dir = d.xy / r;
//#if image
        if (params.driver_kind == 1u) {
            k = image_lipschitz_along(dir);
        }
//#endif
//#if noise
        for (var i = 0u; i < params.wave_count; i = i + 1u) {
            let w = wave(i);
            k = k + abs(w.z) * lod_att[i] * TAU * abs(dot(w.xy, dir));
        }
//#endif
        k = k * params.sigma_h * params.g_lip;
    }
    return abs(d.z) + k * r;
}

// Prepared::lod_march: t of the first crossing of h̄, or -1 (needs lod_prepare first).
fn lod_march(o: vec3<f32>, d: vec3<f32>, sf: f32) -> f32 {
    return march_heightfield(o, d, lod_rate(d), true, sf);
}
//#endif

// Prepared::pixel: method 0 naive, 1 view-independent, 2 filtered.
fn analytic_pixel(method: u32, origin: vec3<f32>, dir: vec3<f32>, wi: vec3<f32>, fp: vec3<f32>) -> vec3<f32> {
    if (dir.z >= 0.0) {
        return vec3<f32>(0.0);
    }
//#if relief
    let sf = lod_prepare(fp);
    let top = params.h_max * 1.001 + 1e-6;
    let t0 = max((origin.z - top) / -dir.z, 0.0);
    let o = origin + dir * t0;
    let t = lod_march(o, dir, sf);
    if (t < 0.0) {
        return vec3<f32>(0.0);
    }
    let p = o + dir * t;
//#else
    // Flat: the plane z = 0.
    let p = origin + dir * (-origin.z / dir.z);
//#endif
    var v = select(0.0, 1.0, wi.z > 0.0);
//#if shadows
    if (v > 0.0 && lod_march(p, wi, sf) >= 0.0) {
        v = 0.0;
    }
//#endif
    if (v == 0.0 && !has_environment()) {
        return vec3<f32>(0.0);
    }
    if (method == 0u) {
        return eval_naive(p.xy, fp, -dir, wi, v);
    } else if (method == 1u) {
        return eval_view_independent(p.xy, fp, -dir, wi, v);
    }
    return eval_filtered(p.xy, fp, -dir, wi, v);
}
