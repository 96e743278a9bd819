//! The f32 mirror of [`crate::math::special`]: the exact algorithms `render/src/shaders/special.wgsl`
//! copies, function for function and under the same names.
//!
//! Differences from the f64 versions, all chosen so a shader can run them with fixed loops:
//! * the series/continued-fraction switch is at 1 (not 2) and the continued fraction has a fixed
//!   depth of 48, which reaches 2e-8 relative at the switch point (measured with mpmath);
//! * `1 − erf` is used below 1, losing at most a factor 6.4 (1/erfc(1)) of relative accuracy;
//! * `e^{−x²}` is evaluated from an f32 `x²`, whose rounding costs up to `x² · 6e-8` relative
//!   (5e-6 at x = 9, where erfc underflows f32).
//!
//! Measured against the 60-digit references: relative error ≤ 1e-5 wherever the result is a
//! normal f32 (the tests below assert it).

/// √π in f32.
pub const SQRT_PI: f32 = 1.772_453_9;
/// 1/√(2π) in f32.
pub const FRAC_1_SQRT_2PI: f32 = 0.398_942_3;
/// 2/√π in f32.
pub const FRAC_2_SQRT_PI: f32 = std::f32::consts::FRAC_2_SQRT_PI;
/// Λ's argument is clamped to at least this (Λ saturates near 2.8e29, finite in f32).
pub const NU_MIN: f32 = 1e-30;
const CF_THRESHOLD: f32 = 1.0;
const CF_DEPTH: u32 = 48;
const SERIES_TERMS: u32 = 24;

/// `Σ 2ⁿ x^{2n+1}/(2n+1)!!` for |x| < 1 [A&S 7.1.6]; fixed 24 terms (≤ 1e-9 relative).
pub fn erf_series_sum(x: f32) -> f32 {
    let x2 = x * x;
    let mut term = x;
    let mut sum = x;
    for n in 1..=SERIES_TERMS {
        term *= 2.0 * x2 / (2.0 * n as f32 + 1.0);
        sum += term;
    }
    sum
}

/// Continued-fraction tail `R(x) = x + 1/(x + (3/2)/(x + …))` for x ≥ 1 [A&S 7.1.14], depth 48.
pub fn cf_tail(x: f32) -> f32 {
    let mut t = x;
    let mut n = CF_DEPTH;
    while n >= 1 {
        t = x + (n as f32 + 1.0) * 0.5 / t;
        n -= 1;
    }
    t
}

/// `erfc(x)` for x ≥ 1 by the continued fraction; 0 past 10.5 (f32 underflow).
pub fn erfc_upper(x: f32) -> f32 {
    if x > 10.5 {
        return 0.0;
    }
    (-x * x).exp() / (SQRT_PI * (x + 0.5 / cf_tail(x)))
}

/// `erf(x)` for |x| < 1 by the series.
pub fn erf_small(x: f32) -> f32 {
    FRAC_2_SQRT_PI * (-x * x).exp() * erf_series_sum(x)
}

/// `erfcx(x) = e^{x²} erfc(x)`; saturates to `f32::MAX` for x < −9.3 where it overflows.
pub fn erfcx(x: f32) -> f32 {
    if x >= CF_THRESHOLD {
        if x > 1e18 {
            return 1.0 / (SQRT_PI * x);
        }
        1.0 / (SQRT_PI * (x + 0.5 / cf_tail(x)))
    } else if x > -CF_THRESHOLD {
        (x * x).exp() - FRAC_2_SQRT_PI * erf_series_sum(x)
    } else {
        let y = -x;
        let v = 2.0 * (x * x).exp() - 1.0 / (SQRT_PI * (y + 0.5 / cf_tail(y)));
        if v.is_finite() { v } else { f32::MAX }
    }
}

/// `erf(x)`, odd.
pub fn erf(x: f32) -> f32 {
    let a = x.abs();
    let v = if a < CF_THRESHOLD {
        erf_small(a)
    } else {
        1.0 - erfc_upper(a)
    };
    if x < 0.0 { -v } else { v }
}

/// `erfc(x)` with relative accuracy in the upper tail; 0 past x ≈ 10.5.
pub fn erfc(x: f32) -> f32 {
    if x >= CF_THRESHOLD {
        erfc_upper(x)
    } else if x > -CF_THRESHOLD {
        1.0 - erf_small(x)
    } else {
        2.0 - erfc_upper(-x)
    }
}

/// Standard normal density φ(z).
pub fn norm_pdf(z: f32) -> f32 {
    FRAC_1_SQRT_2PI * (-0.5 * z * z).exp()
}

/// Standard normal cdf Φ(z) = ½ erfc(−z/√2).
pub fn norm_cdf(z: f32) -> f32 {
    0.5 * erfc(-z * std::f32::consts::FRAC_1_SQRT_2)
}

/// ln Φ(z); finite for every finite z (uses erfcx below z = −3; `ln(1 − Q)` by its series for small Q).
pub fn log_norm_cdf(z: f32) -> f32 {
    if z < -3.0 {
        // x² overflows f32 beyond x ≈ 1.8e19, where ln Φ < −1.6e38: the result saturates at
        // f32::MIN there (as in the WGSL, which cannot test for infinity reliably).
        let x = -z * std::f32::consts::FRAC_1_SQRT_2;
        if x >= 1.8e19 {
            return f32::MIN;
        }
        ((0.5 * erfcx(x)).ln() - x * x).max(f32::MIN)
    } else if z < 0.0 {
        norm_cdf(z).ln()
    } else {
        let q = 0.5 * erfc(z * std::f32::consts::FRAC_1_SQRT_2);
        // ln(1 − q) = −q(1 + q/2 + q²/3 + q³/4 + q⁴/5 + …): truncation ≤ q⁵/6 < 6e-8 relative.
        if q < 0.05 {
            -q * (1.0 + q * (0.5 + q * (1.0 / 3.0 + q * (0.25 + q * 0.2))))
        } else {
            (1.0 - q).ln()
        }
    }
}

/// Smith's Λ(ν) [HN12 Eq. 6], cancellation-free above ν = 1 (see [`crate::math::special::smith_lambda`]).
pub fn smith_lambda(nu: f32) -> f32 {
    let nu = if nu.is_nan() { nu } else { nu.max(NU_MIN) };
    if nu >= CF_THRESHOLD {
        if nu > 10.5 {
            return 0.0;
        }
        let tail = 0.5 / cf_tail(nu);
        let k = nu + tail;
        (-nu * nu).exp() / (2.0 * SQRT_PI) * tail / (nu * k)
    } else {
        0.5 * ((-nu * nu).exp() / (nu * SQRT_PI) - erfc(nu))
    }
}

/// Standard normal quantile Φ⁻¹(p): Acklam's rational approximation (relative error 1.2e-9 in
/// exact arithmetic), then for p < 0.2 one Newton step on Φ(x) = p: in f32 the central branch's
/// denominator cancels near its edge (p ≈ 0.024: 5e-5 off without the step, measured), while
/// near p = 0.5, where Φ(x) − p would cancel instead, the rational form is well conditioned.
/// `p > 0.5` is mirrored through `1 − p` (exact in f32 there); p is clamped to
/// [1e-30, 1 − 2⁻²⁴] (NaN to the lower end): the result is always finite, within ±11.47.
pub fn norm_quantile(p: f32) -> f32 {
    let p = if p > 1e-30 {
        p.min(1.0 - 5.960_464_5e-8)
    } else {
        1e-30
    };
    if p > 0.5 {
        return -lower_quantile(1.0 - p);
    }
    lower_quantile(p)
}

/// [`norm_quantile`] for `0 < p ≤ 0.5`.
fn lower_quantile(p: f32) -> f32 {
    let x = acklam(p);
    if p < 0.2 {
        let d = norm_pdf(x);
        if d > 0.0 {
            return x - (norm_cdf(x) - p) / d;
        }
    }
    x
}

/// Acklam's approximation for `0 < p ≤ 0.5` (core's `special::acklam` in f32).
fn acklam(p: f32) -> f32 {
    const A: [f32; 6] = [
        -3.969_683e1,
        2.209_461e2,
        -2.759_285e2,
        1.383_577_5e2,
        -3.066_479_8e1,
        2.506_628_3,
    ];
    const B: [f32; 5] = [
        -5.447_61e1,
        1.615_858_4e2,
        -1.556_989_8e2,
        6.680_131e1,
        -1.328_068_1e1,
    ];
    const C: [f32; 6] = [
        -7.784_894e-3,
        -3.223_964_6e-1,
        -2.400_758_3,
        -2.549_732_5,
        4.374_664,
        2.938_164,
    ];
    const D: [f32; 4] = [7.784_696e-3, 3.224_671_3e-1, 2.445_134_1, 3.754_408_6];
    if p < 0.02425 {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::special::tests::reference;

    #[test]
    fn f32_mirror_matches_reference_to_1e_5() {
        let mut checked = 0;
        let mut worst = 0.0_f64;
        for (name, x, want) in reference() {
            if x.abs() > 1e30 || (x != 0.0 && x.abs() < 1e-30) {
                continue; // not representable in f32
            }
            let xf = x as f32;
            if f64::from(xf) != x && name != "norm_quantile" {
                // Evaluate the f64 reference at the f32-rounded argument would need new data;
                // instead require the argument to be exactly representable or skip it.
                if ((f64::from(xf) - x) / x).abs() > 1e-12 {
                    continue;
                }
            }
            let got = match name.as_str() {
                "erf" => erf(xf),
                "erfc" => erfc(xf),
                "erfcx" => erfcx(xf),
                "norm_cdf" => norm_cdf(xf),
                "norm_pdf" => norm_pdf(xf),
                "log_norm_cdf" => log_norm_cdf(xf),
                "lambda" => smith_lambda(xf),
                _ => continue,
            };
            let got = f64::from(got);
            if want.abs() < 1e-36 {
                assert!(got.abs() < 1e-35, "{name}({x}) = {got}, want {want}");
                continue;
            }
            if want.abs() > 3e38 {
                continue;
            }
            let rel = ((got - want) / want).abs();
            worst = worst.max(rel);
            assert!(
                rel <= 1e-5,
                "{name}({x}): f32 {got:e}, want {want:e}, rel {rel:e}"
            );
            checked += 1;
        }
        assert!(checked > 200, "only {checked} f32 cases checked");
        eprintln!("f32 mirror worst relative error {worst:e} over {checked} cases");
    }

    #[test]
    fn f32_mirror_tracks_f64_on_a_dense_grid() {
        // Many inputs, compared with the f64 functions (themselves checked to 1e-12).
        for i in 0..20_000 {
            let x = -9.0 + 18.0 * (i as f64 + 0.5) / 20_000.0;
            let xf = x as f32;
            let x = f64::from(xf);
            let pairs = [
                (f64::from(erf(xf)), crate::math::special::erf(x)),
                (f64::from(erfc(xf)), crate::math::special::erfc(x)),
                (f64::from(norm_cdf(xf)), crate::math::special::norm_cdf(x)),
                (
                    f64::from(log_norm_cdf(xf)),
                    crate::math::special::log_norm_cdf(x),
                ),
            ];
            for (k, (a, b)) in pairs.iter().enumerate() {
                if b.abs() < 1e-36 {
                    continue;
                }
                let rel = ((a - b) / b).abs();
                assert!(
                    rel < 1e-5 || (a - b).abs() < 1e-7 && k == 0,
                    "fn {k} at {x}: {a} vs {b}"
                );
            }
            if x > 0.0 {
                let a = f64::from(smith_lambda(xf));
                let b = crate::math::special::smith_lambda(x);
                if b > 1e-36 {
                    assert!(((a - b) / b).abs() < 2e-5, "Λ at {x}: {a} vs {b}");
                }
            }
        }
    }
}
