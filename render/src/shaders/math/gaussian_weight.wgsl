// Mirror of `core/src/math/gaussian_weight.rs`, function for function (methods prefixed
// `gaussian_weight_`): a positive weight w(z) = exp(c − ½ zᵀQz + bᵀz) over the plane, closed
// under products and powers, with closed-form expectations under any Gaussian. Core's `None` is
// `ok = false` here; a weight with nothing in it has ok = false too. The symmetric Q and C are
// stored as (xx, xy, yy): the exported GLSL snippet's std140 has no two-row matrices.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if transfer_mixture
struct GaussianWeight {
    log_scale: f32,
    q: vec3<f32>,
    b: vec2<f32>,
    ok: bool,
}

// The weight reweighting N(0, I) into mass·N(mean, cov) (GaussianWeight::tilted).
struct TiltedGaussian {
    mass: f32,
    mean: vec2<f32>,
    cov: vec3<f32>,
    ok: bool,
}

// symmetric_matrix: (xx, xy, yy) as a matrix.
fn symmetric_matrix(m: vec3<f32>) -> mat2x2<f32> {
    return mat2x2<f32>(m.x, m.y, m.y, m.z);
}

// GaussianWeight::along: the weight of a function of e·z alone with moments m0, m1, m2 over
// N(0, 1) along the unit vector e.
fn gaussian_weight_along(e: vec2<f32>, m0: f32, m1: f32, m2: f32) -> GaussianWeight {
    var w: GaussianWeight;
    w.ok = m0 > 1e-30 && abs(m1) < F32_MAX && abs(m2) < F32_MAX && m0 < F32_MAX;
    if (!w.ok) {
        return w;
    }
    let mu = m1 / m0;
    let s2 = max(m2 / m0 - mu * mu, GAUSSIAN_WEIGHT_MIN_VARIANCE);
    let q = 1.0 / s2 - 1.0;
    let xy = q * e.x * e.y;
    w.log_scale = log(m0) - 0.5 * log(s2) - 0.5 * mu * mu / s2;
    w.q = vec3<f32>(q * e.x * e.x, xy, q * e.y * e.y);
    w.b = e * (mu / s2);
    return w;
}

// GaussianWeight::powf: w^k.
fn gaussian_weight_powf(w: GaussianWeight, k: f32) -> GaussianWeight {
    return GaussianWeight(w.log_scale * k, w.q * k, w.b * k, w.ok);
}

// GaussianWeight's Mul: w·v.
fn gaussian_weight_mul(w: GaussianWeight, v: GaussianWeight) -> GaussianWeight {
    return GaussianWeight(w.log_scale + v.log_scale, w.q + v.q, w.b + v.b, w.ok && v.ok);
}

// GaussianWeight::at: w(z).
fn gaussian_weight_at(w: GaussianWeight, z: vec2<f32>) -> f32 {
    return exp(w.log_scale - 0.5 * dot(z, symmetric_matrix(w.q) * z) + dot(w.b, z));
}

// GaussianWeight::expect_under: E[w(z)] over z ~ N(mu, L Lᵀ), as (value, 1) or (0, 0) where it
// diverges or overflows.
fn gaussian_weight_expect_under(w: GaussianWeight, mu: vec2<f32>, l: mat2x2<f32>) -> vec2<f32> {
    let q = symmetric_matrix(w.q);
    let a = mat2x2<f32>(1.0, 0.0, 0.0, 1.0) + transpose(l) * q * l;
    let det = determinant(a);
    if (!(w.ok && det > 0.0 && a[0][0] > 0.0)) {
        return vec2<f32>(0.0, 0.0);
    }
    let inv = mat2x2<f32>(a[1][1], -a[0][1], -a[1][0], a[0][0]) * (1.0 / det);
    let beta = transpose(l) * (w.b - q * mu);
    let log_w = w.log_scale - 0.5 * dot(mu, q * mu) + dot(w.b, mu);
    let e = log_w + 0.5 * dot(beta, inv * beta);
    if (!(e < 88.0)) {
        return vec2<f32>(0.0, 0.0);
    }
    return vec2<f32>(exp(e) / sqrt(det), 1.0);
}

// GaussianWeight::tilted: (E[w], m, C) with w(z)·N(z; 0, I) = E[w]·N(z; m, C).
fn gaussian_weight_tilted(w: GaussianWeight) -> TiltedGaussian {
    var t: TiltedGaussian;
    let m = gaussian_weight_expect_under(w, vec2<f32>(0.0), mat2x2<f32>(1.0, 0.0, 0.0, 1.0));
    t.ok = m.y > 0.0 && m.x > 1e-30;
    if (!t.ok) {
        return t;
    }
    // (I + Q)⁻¹.
    let a = w.q + vec3<f32>(1.0, 0.0, 1.0);
    let det = a.x * a.z - a.y * a.y;
    t.mass = m.x;
    t.cov = vec3<f32>(a.z, -a.y, a.x) / det;
    t.mean = symmetric_matrix(t.cov) * w.b;
    return t;
}
//#endif
