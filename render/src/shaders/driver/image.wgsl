// The image driver on the GPU: the WGSL mirror of lodestone-core's image_driver.rs (in level-0 texel
// units) and of the image half of driver_field.rs, function for function under the same names
// (prefixed `image_` where WGSL needs it). Uses `params` and `data` from material.wgsl.
//
// Data layout (render::material_data): at params.image_offset, per level IMAGE_LEVEL_SLOTS slots
// [value offset, grad offset, width, height (u32 bits), mean_variance, Lipschitz x, y (f32)]; the
// value grid holds (f̄, f²‾) per texel, the cell grid (f_x, f_y, f_x², f_y², f_x·f_y) per texel.

const IMAGE_MAX_PROBES: u32 = 8u;
const IMAGE_LEVEL_SLOTS: u32 = 7u;

struct ImageLevel {
    value_offset: u32,
    grad_offset: u32,
    width: u32,
    height: u32,
    mean_variance: f32,
    lipschitz: vec2<f32>,
}

fn image_level(l: u32) -> ImageLevel {
    let b = params.image_offset + IMAGE_LEVEL_SLOTS * min(l, params.image_levels - 1u);
    var r: ImageLevel;
    r.value_offset = bitcast<u32>(datum(b));
    r.grad_offset = bitcast<u32>(datum(b + 1u));
    r.width = max(bitcast<u32>(datum(b + 2u)), 1u);
    r.height = max(bitcast<u32>(datum(b + 3u)), 1u);
    r.mean_variance = datum(b + 4u);
    r.lipschitz = vec2<f32>(datum(b + 5u), datum(b + 6u));
    return r;
}

// image_driver::cell: the four wrapped texel indices around texel coordinate p of a level (texel i
// centred at i + ½) and the fractions. Indices are always in range, whatever p is.
struct ImageCell {
    i: vec4<u32>,
    a: vec2<f32>,
}

fn image_wrap(v: f32, n: u32) -> u32 {
    let nf = f32(n);
    let w = v - floor(v / nf) * nf;
    return min(u32(max(w, 0.0)), n - 1u);
}

fn image_cell(w: u32, h: u32, p: vec2<f32>) -> ImageCell {
    let f = p - vec2<f32>(0.5);
    let f0 = floor(f);
    var c: ImageCell;
    c.a = clamp(f - f0, vec2<f32>(0.0), vec2<f32>(1.0));
    let x0 = image_wrap(f0.x, w);
    let y0 = image_wrap(f0.y, h);
    let x1 = (x0 + 1u) % w;
    let y1 = (y0 + 1u) % h;
    c.i = vec4<u32>(y0 * w + x0, y0 * w + x1, y1 * w + x0, y1 * w + x1);
    return c;
}

// image_driver::at_level: level-0 texel coordinate in a level's texel units.
fn image_at_level(lv: ImageLevel, base: ImageLevel, p: vec2<f32>) -> vec2<f32> {
    return p * vec2<f32>(f32(lv.width) / f32(base.width), f32(lv.height) / f32(base.height));
}

fn image_bilerp(off: u32, stride: u32, k: u32, c: ImageCell) -> f32 {
    let top = mix(datum(off + stride * c.i.x + k), datum(off + stride * c.i.y + k), c.a.x);
    let bot = mix(datum(off + stride * c.i.z + k), datum(off + stride * c.i.w + k), c.a.x);
    return mix(top, bot, c.a.y);
}

// ImageDriver::value_and_gradient: (f, f_x, f_y) of the bilinear surface, per texel.
fn image_value_and_gradient(p: vec2<f32>) -> vec3<f32> {
    let l = image_level(0u);
    let c = image_cell(l.width, l.height, p);
    let f00 = datum(l.value_offset + 2u * c.i.x);
    let f10 = datum(l.value_offset + 2u * c.i.y);
    let f01 = datum(l.value_offset + 2u * c.i.z);
    let f11 = datum(l.value_offset + 2u * c.i.w);
    let top = f00 + c.a.x * (f10 - f00);
    let bot = f01 + c.a.x * (f11 - f01);
    let fx = (f10 - f00) + c.a.y * ((f11 - f01) - (f10 - f00));
    return vec3<f32>(top + c.a.y * (bot - top), fx, bot - top);
}

// image_driver::lod_for_std.
fn lod_for_std(sigma: f32) -> f32 {
    let v = 4.0 * sigma * sigma;
    if (!(v > 1.0)) {
        return 0.0;
    }
    let l0 = floor(log2(v) * 0.5);
    let t = clamp((v / exp2(2.0 * l0) - 1.0) / 3.0, 0.0, 1.0);
    return l0 + t;
}

struct ProbePlan {
    lod: f32,
    probes: u32,
    step: vec2<f32>,
}

// ImageDriver::plan for a texel-space covariance (xx, yy, xy).
fn image_plan(cov: vec3<f32>) -> ProbePlan {
    var r: ProbePlan;
    r.lod = 0.0;
    r.probes = 1u;
    r.step = vec2<f32>(0.0);
    let tr = 0.5 * (cov.x + cov.y);
    let disc = sqrt(0.25 * (cov.x - cov.y) * (cov.x - cov.y) + cov.z * cov.z);
    let l1 = max(tr + disc, 0.0);
    let l2 = max(tr - disc, 0.0);
    let s1 = sqrt(l1);
    let s2 = sqrt(l2);
    if (!(s1 > 0.0) || !(s1 < 3.0e38)) {
        return r;
    }
    let n = clamp(ceil(s1 / max(s2, 1e-30)), 1.0, f32(IMAGE_MAX_PROBES));
    r.lod = min(lod_for_std(max(s2, s1 / n)), f32(params.image_levels - 1u));
    var axis = vec2<f32>(1.0, 0.0);
    if (disc > 0.0) {
        var v = vec2<f32>(cov.z, l1 - cov.x);
        if (cov.x - cov.y >= 0.0) {
            v = vec2<f32>(l1 - cov.y, cov.z);
        }
        let len = length(v);
        if (len > 0.0) {
            axis = v / len;
        }
    }
    r.probes = u32(n);
    r.step = axis * (sqrt(12.0) * s1 / n);
    return r;
}

struct ImageMoments {
    mean: f32,
    mean_sq: f32,
    grad_mean: vec2<f32>,
    grad_sq: vec3<f32>, // xx, yy, xy
}

// image_driver::level_moments.
fn image_level_moments(l: u32, p: vec2<f32>) -> ImageMoments {
    let lv = image_level(l);
    let base = image_level(0u);
    let c = image_cell(lv.width, lv.height, image_at_level(lv, base, p));
    let g = image_cell(lv.width, lv.height, image_at_level(lv, base, p - vec2<f32>(0.5)));
    var m: ImageMoments;
    m.mean = image_bilerp(lv.value_offset, 2u, 0u, c);
    m.mean_sq = image_bilerp(lv.value_offset, 2u, 1u, c);
    m.grad_mean = vec2<f32>(image_bilerp(lv.grad_offset, 5u, 0u, g), image_bilerp(lv.grad_offset, 5u, 1u, g));
    m.grad_sq = vec3<f32>(image_bilerp(lv.grad_offset, 5u, 2u, g), image_bilerp(lv.grad_offset, 5u, 3u, g), image_bilerp(lv.grad_offset, 5u, 4u, g));
    return m;
}

fn image_mix(a: ImageMoments, b: ImageMoments, t: f32) -> ImageMoments {
    var m: ImageMoments;
    m.mean = mix(a.mean, b.mean, t);
    m.mean_sq = mix(a.mean_sq, b.mean_sq, t);
    m.grad_mean = mix(a.grad_mean, b.grad_mean, t);
    m.grad_sq = mix(a.grad_sq, b.grad_sq, t);
    return m;
}

// ImageDriver::split_lod: the two levels a trilinear lookup blends and the coarser one's weight.
struct LodSplit {
    l0: u32,
    l1: u32,
    t: f32,
}

fn image_split_lod(lod_in: f32) -> LodSplit {
    let last = params.image_levels - 1u;
    let lod = clamp(lod_in, 0.0, f32(last));
    var r: LodSplit;
    r.l0 = min(u32(floor(lod)), last);
    r.l1 = min(r.l0 + 1u, last);
    r.t = lod - f32(r.l0);
    return r;
}

// ImageDriver::moments_at.
fn image_moments_at(p: vec2<f32>, lod_in: f32) -> ImageMoments {
    let sp = image_split_lod(lod_in);
    let l0 = sp.l0;
    let l1 = sp.l1;
    let t = sp.t;
    let m = image_level_moments(l0, p);
    if (t > 0.0 && l1 != l0) {
        return image_mix(m, image_level_moments(l1, p), t);
    }
    return m;
}

// ImageDriver::footprint_moments.
fn image_footprint_moments(p: vec2<f32>, cov: vec3<f32>) -> ImageMoments {
    let plan = image_plan(cov);
    let n = max(plan.probes, 1u);
    var acc: ImageMoments;
    acc.mean = 0.0;
    acc.mean_sq = 0.0;
    acc.grad_mean = vec2<f32>(0.0);
    acc.grad_sq = vec3<f32>(0.0);
    let w = 1.0 / f32(n);
    for (var i = 0u; i < n; i = i + 1u) {
        let o = plan.step * (f32(i) + 0.5 - 0.5 * f32(n));
        let m = image_moments_at(p + o, plan.lod);
        acc.mean = acc.mean + w * m.mean;
        acc.mean_sq = acc.mean_sq + w * m.mean_sq;
        acc.grad_mean = acc.grad_mean + w * m.grad_mean;
        acc.grad_sq = acc.grad_sq + w * m.grad_sq;
    }
    return acc;
}

fn image_level_mean(l: u32, p: vec2<f32>) -> f32 {
    let lv = image_level(l);
    let c = image_cell(lv.width, lv.height, image_at_level(lv, image_level(0u), p));
    return image_bilerp(lv.value_offset, 2u, 0u, c);
}

// ImageDriver::footprint_mean.
fn image_footprint_mean(p: vec2<f32>, plan: ProbePlan) -> f32 {
    let n = max(plan.probes, 1u);
    let sp = image_split_lod(plan.lod);
    let l0 = sp.l0;
    let l1 = sp.l1;
    let t = sp.t;
    var s = 0.0;
    for (var i = 0u; i < n; i = i + 1u) {
        let q = p + plan.step * (f32(i) + 0.5 - 0.5 * f32(n));
        let a = image_level_mean(l0, q);
        var b = a;
        if (t > 0.0) {
            b = image_level_mean(l1, q);
        }
        s = s + a + t * (b - a);
    }
    return s / f32(n);
}

// ImageDriver::mean_std.
fn image_mean_std(lod_in: f32) -> f32 {
    let sp = image_split_lod(lod_in);
    let l0 = sp.l0;
    let l1 = sp.l1;
    let t = sp.t;
    return sqrt(max(mix(image_level(l0).mean_variance, image_level(l1).mean_variance, t), 0.0));
}

// ImageDriver::lod_lipschitz: Lipschitz constants along x and y (per level-0 texel) of
// image_footprint_mean under a plan.
fn image_lod_lipschitz(plan: ProbePlan) -> vec2<f32> {
    let sp = image_split_lod(plan.lod);
    return mix(image_level(sp.l0).lipschitz, image_level(sp.l1).lipschitz, sp.t);
}

// ---------------------------------------------------------------- driver_field.rs (image half)
// World position relative to the camera target → level-0 texel coordinate (the CPU folds the
// target into image_u0/v0 in f64).
fn image_texel(x: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(params.image_u0, params.image_v0) + x * params.image_scale;
}

// ImageMoments::grad_cov (xx, yy, xy), clamped positive semi-definite.
fn image_grad_cov(m: ImageMoments) -> vec3<f32> {
    let g = m.grad_mean;
    let xx = max(m.grad_sq.x - g.x * g.x, 0.0);
    let yy = max(m.grad_sq.y - g.y * g.y, 0.0);
    let lim = sqrt(xx * yy);
    return vec3<f32>(xx, yy, clamp(m.grad_sq.z - g.x * g.y, -lim, lim));
}

// DriverField::filtered for the image.
fn image_filtered_driver(x: vec2<f32>, fp: vec3<f32>) -> FilteredDriver {
    let s = params.image_scale;
    let m = image_footprint_moments(image_texel(x), fp * (s * s));
    var r: FilteredDriver;
    r.mean = m.mean;
    r.std_dev = sqrt(max(m.mean_sq - m.mean * m.mean, 0.0));
    r.mean_gradient = m.grad_mean * s;
    r.gradient_cov = image_grad_cov(m) * (s * s);
    return r;
}

// DriverField::lipschitz_along for the image.
fn image_lipschitz_along(dir: vec2<f32>) -> f32 {
    return params.image_scale * (params.image_lip_x * abs(dir.x) + params.image_lip_y * abs(dir.y));
}

// DriverField::lod_lipschitz_along for the image (needs lod_prepare's plan).
fn image_lod_lipschitz_along(dir: vec2<f32>, plan: ProbePlan) -> f32 {
    let l = image_lod_lipschitz(plan);
    return params.image_scale * (l.x * abs(dir.x) + l.y * abs(dir.y));
}
