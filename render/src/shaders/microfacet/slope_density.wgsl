// Mirror of `core/src/microfacet/slope_density.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if noise
//#if specular
const SADDLEPOINT_ITERATIONS: u32 = 8u;
const NEWTON_DECREMENT: f32 = 1e-11;
const BACKTRACKS: u32 = 3u;
const F_TOLERANCE: f32 = 2.5e-7;
const MAX_LOG_RATIO: f32 = 4.0;
const MIN_SIGMA0: f32 = 1e-3;
const NEGLIGIBLE_TERM: f32 = 1e-9;

// GPU only: the pixel's unresolved terms that the saddlepoint sums (those not negligible), computed
// once by sinusoid_density_ratio's covariance pass instead of once per Newton evaluation.
var<private> density_terms: array<vec2<f32>, 256>;
var<private> density_count: u32;

// SumOfSines::unresolved_gradient_terms, wave i, times σ_h: σ_h 2π a √(1 − α²) k.
fn unresolved_term(i: u32, fp: vec3<f32>) -> vec2<f32> {
    let w = wave(i);
    let q = w.x * w.x * fp.x + 2.0 * w.x * w.y * fp.z + w.y * w.y * fp.y;
    let g = exp(-2.0 * PI * PI * q);
    return w.xy * (params.sigma_h * TAU * w.z * sqrt(max(1.0 - g * g, 0.0)));
}

// F(τ) = K(τ) − τ·d, its gradient (xy) and Hessian (xx, yy, xy).
struct SaddleObjective {
    f: f32,
    g: vec2<f32>,
    h: vec3<f32>,
}

fn objective(s02: f32, d: vec2<f32>, tau: vec2<f32>) -> SaddleObjective {
    var k = 0.5 * s02 * dot(tau, tau);
    var g = tau * s02 - d;
    var h = vec3<f32>(s02, s02, 0.0);
    for (var i = 0u; i < density_count; i = i + 1u) {
        let v = density_terms[i];
        let b = bessel_terms(dot(tau, v));
        k = k + b.x;
        g = g + v * b.y;
        h = h + vec3<f32>(v.x * v.x, v.y * v.y, v.x * v.y) * b.z;
    }
    return SaddleObjective(k - dot(tau, d), g, h);
}

// The second-order saddlepoint correction at τ̂, hi = (∇²K)⁻¹ as (xx, yy, xy).
fn second_order(tau: vec2<f32>, hi: vec3<f32>) -> f32 {
    // Symmetric tensors: k3 = (xxx, xxy, xyy, yyy), k4 = (xxxx, xxxy, xxyy, xyyy, yyyy).
    var k3 = vec4<f32>(0.0);
    var k4a = vec4<f32>(0.0);
    var k4b = 0.0;
    for (var i = 0u; i < density_count; i = i + 1u) {
        let v = density_terms[i];
        let a = bessel_ratio_derivatives(dot(tau, v));
        let x2 = v.x * v.x;
        let y2 = v.y * v.y;
        k3 = k3 + a.y * vec4<f32>(x2 * v.x, x2 * v.y, v.x * y2, y2 * v.y);
        k4a = k4a + a.z * vec4<f32>(x2 * x2, x2 * v.x * v.y, x2 * y2, v.x * v.y * y2);
        k4b = k4b + a.z * y2 * y2;
    }
    // h as a 2×2 array, the tensors by index count of y.
    var hm = array<f32, 4>(hi.x, hi.z, hi.z, hi.y);
    var rho4 = 0.0;
    var rho13 = 0.0;
    var rho23 = 0.0;
    for (var i = 0u; i < 2u; i = i + 1u) {
        for (var j = 0u; j < 2u; j = j + 1u) {
            for (var k = 0u; k < 2u; k = k + 1u) {
                let t3 = k3[i + j + k];
                for (var l = 0u; l < 2u; l = l + 1u) {
                    let c4 = i + j + k + l;
                    var t4 = k4b;
                    if (c4 < 4u) {
                        t4 = k4a[c4];
                    }
                    rho4 = rho4 + t4 * hm[i * 2u + j] * hm[k * 2u + l];
                    for (var m = 0u; m < 2u; m = m + 1u) {
                        for (var n = 0u; n < 2u; n = n + 1u) {
                            let a = t3 * k3[l + m + n];
                            rho13 = rho13 + a * hm[i * 2u + j] * hm[k * 2u + l] * hm[m * 2u + n];
                            rho23 = rho23 + a * hm[i * 2u + l] * hm[j * 2u + m] * hm[k * 2u + n];
                        }
                    }
                }
            }
        }
    }
    let c = 1.0 + rho4 / 8.0 - (3.0 * rho13 + 2.0 * rho23) / 24.0;
    return clamp(c, 0.25, 2.0);
}

// sinusoid_density_ratio over the unresolved waves of the footprint fp (σ_h included).
fn sinusoid_density_ratio(d: vec2<f32>, sigma0: f32, fp: vec3<f32>) -> f32 {
    let s0 = max(sigma0, MIN_SIGMA0);
    let s02 = s0 * s0;
    var cov = vec3<f32>(s02, s02, 0.0);
    density_count = 0u;
    for (var i = 0u; i < params.wave_count; i = i + 1u) {
        let v = unresolved_term(i, fp);
        let vv = dot(v, v);
        cov = cov + 0.5 * vec3<f32>(v.x * v.x, v.y * v.y, v.x * v.y);
        if (0.5 * vv > NEGLIGIBLE_TERM * s02) {
            density_terms[density_count] = v;
            density_count = density_count + 1u;
        }
    }
    let det_t = cov.x * cov.y - cov.z * cov.z;
    if (!(det_t > 0.0)) {
        return 1.0;
    }
    let cinv = vec3<f32>(cov.y, cov.x, -cov.z) / det_t;
    var tau = vec2<f32>(cinv.x * d.x + cinv.z * d.y, cinv.z * d.x + cinv.y * d.y);
    var o = objective(s02, d, tau);
    for (var it = 0u; it < SADDLEPOINT_ITERATIONS; it = it + 1u) {
        let det = o.h.x * o.h.y - o.h.z * o.h.z;
        if (!(det > 0.0)) {
            break;
        }
        let step = vec2<f32>(o.h.y * o.g.x - o.h.z * o.g.y, o.h.x * o.g.y - o.h.z * o.g.x) / det;
        if (!(dot(o.g, step) > NEWTON_DECREMENT)) {
            break;
        }
        var t = 1.0;
        var moved = false;
        for (var b = 0u; b <= BACKTRACKS; b = b + 1u) {
            let cand = tau - step * t;
            let oc = objective(s02, d, cand);
            if (oc.f <= o.f + F_TOLERANCE * abs(o.f)) {
                tau = cand;
                o = oc;
                moved = true;
                break;
            }
            t = t * 0.5;
        }
        if (!moved) {
            break;
        }
    }
    let det_h = o.h.x * o.h.y - o.h.z * o.h.z;
    if (!(det_h > 0.0)) {
        return 1.0;
    }
    let quad = d.x * (cinv.x * d.x + cinv.z * d.y) + d.y * (cinv.z * d.x + cinv.y * d.y);
    let log_ratio = o.f + 0.5 * quad + 0.5 * log(det_t / det_h);
    let hi = vec3<f32>(o.h.y, o.h.x, -o.h.z) / det_h;
    return exp(min(log_ratio, MAX_LOG_RATIO)) * second_order(tau, hi);
}
//#endif
//#endif
