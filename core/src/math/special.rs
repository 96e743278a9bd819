//! Special functions in f64: `erf`, `erfc`, `erfcx`, the standard normal pdf, cdf, log-cdf and
//! quantile, and the Gaussian Smith function Λ(ν).
//!
//! Everything here keeps full *relative* accuracy in the tails, which matters because Smith's
//! Λ [HN12 Eq. 6] is a difference `e^{-ν²}/(ν√π) − erfc ν` of two nearly equal numbers for
//! large ν (docs/numerics.md, "Float32 hazards"). The algorithms:
//!
//! * `|x| < 2`: the everywhere-positive series `erf x = 2/√π · e^{-x²} · Σ 2ⁿ x^{2n+1}/(2n+1)!!`
//!   [Abramowitz & Stegun 7.1.6]; no cancellation.
//! * `x ≥ 2`: Laplace's continued fraction `erfc x = e^{-x²}/√π · 1/(x + ½/(x + 1/(x + (3/2)/(x + …))))`
//!   [A&S 7.1.14], evaluated backwards with a fixed depth that reaches 1e-16 (measured against
//!   mpmath; see `scripts/gen_reference.py`).
//!
//! Measured against 60-digit mpmath references (`core/tests/data/special_reference.csv`):
//! relative error ≤ 1e-13 everywhere the result is a normal f64.
//!
//! The f32 mirror that WGSL copies lives in [`crate::math::special_f32`].

use std::f64::consts::{FRAC_2_SQRT_PI, PI, SQRT_2};

/// √π.
pub const SQRT_PI: f64 = 1.772_453_850_905_516;
/// 1/√(2π).
pub const FRAC_1_SQRT_2PI: f64 = 0.398_942_280_401_432_7;
/// Below this, Λ's argument ν is clamped (Λ then saturates near 2.8e29 instead of overflowing).
pub const NU_MIN: f64 = 1e-30;
/// Switch between the series and the continued fraction.
const CF_THRESHOLD: f64 = 2.0;

/// `Σ 2ⁿ x^{2n+1}/(2n+1)!!`, so that `erf x = 2/√π · e^{-x²} · S(x)` [A&S 7.1.6]. For `|x| < 2`.
fn erf_series_sum(x: f64) -> f64 {
    let x2 = x * x;
    let mut term = x;
    let mut sum = x;
    let mut n = 0.0;
    // Converges in ≤ 40 terms for |x| < 2; all terms share the sign of x.
    while n < 60.0 {
        n += 1.0;
        term *= 2.0 * x2 / (2.0 * n + 1.0);
        sum += term;
        if term.abs() <= sum.abs() * 1e-17 {
            break;
        }
    }
    sum
}

/// The continued-fraction tail `R(x) = x + 1/(x + (3/2)/(x + 2/(x + …)))` for `x ≥ 2`, so that
/// `erfcx x = 1/(√π (x + ½/R))` [A&S 7.1.14]. Backward evaluation; depth chosen for 1e-16.
fn cf_tail(x: f64) -> f64 {
    let depth = if x < 3.0 {
        64
    } else if x < 6.0 {
        32
    } else {
        16
    };
    let mut t = x;
    for n in (1..=depth).rev() {
        t = x + (f64::from(n) + 1.0) * 0.5 / t;
    }
    t
}

/// Scaled complementary error function `erfcx(x) = e^{x²} erfc(x)`.
///
/// Edge cases: `erfcx(0) = 1`; for large `x`, `erfcx(x) ≈ 1/(x√π)` with full relative accuracy
/// (no overflow: `erfcx(1e300)` is finite); for `x < -26.6`, `e^{x²}` overflows and the result is
/// `f64::MAX` (saturated, never infinite or NaN).
pub fn erfcx(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x >= CF_THRESHOLD {
        if x > 1e150 {
            return 1.0 / (SQRT_PI * x);
        }
        let k = x + 0.5 / cf_tail(x);
        1.0 / (SQRT_PI * k)
    } else if x > -CF_THRESHOLD {
        (x * x).exp() - FRAC_2_SQRT_PI * erf_series_sum(x)
    } else {
        let v = 2.0 * (x * x).exp() - erfcx(-x);
        if v.is_finite() { v } else { f64::MAX }
    }
}

/// Error function `erf(x)`, odd, with relative accuracy ≤ 1e-13 for all `x` (including tiny `x`,
/// where `erf x ≈ 2x/√π`). `erf(±∞) = ±1`.
pub fn erf(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    let a = x.abs();
    let v = if a < CF_THRESHOLD {
        FRAC_2_SQRT_PI * (-a * a).exp() * erf_series_sum(a)
    } else {
        1.0 - erfc(a)
    };
    v.copysign(x)
}

/// Complementary error function `erfc(x) = 1 − erf(x)` with full relative accuracy in the upper
/// tail (it underflows to 0 only past `x ≈ 26.5`). `erfc(-∞) = 2`, `erfc(∞) = 0`.
pub fn erfc(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x >= CF_THRESHOLD {
        if x > 27.3 {
            return 0.0;
        }
        (-x * x).exp() * erfcx(x)
    } else if x > -CF_THRESHOLD {
        if x.abs() < 0.5 {
            1.0 - erf(x)
        } else if x > 0.0 {
            // 1 − erf loses at most log10(1/erfc(2)) ≈ 2.3 digits here: still ≤ 1e-13.
            1.0 - FRAC_2_SQRT_PI * (-x * x).exp() * erf_series_sum(x)
        } else {
            1.0 + FRAC_2_SQRT_PI * (-x * x).exp() * erf_series_sum(-x)
        }
    } else {
        2.0 - erfc(-x)
    }
}

/// Standard normal density φ(z) = e^{-z²/2}/√(2π). Finite for every input; 0 for `|z| > 38.6`.
pub fn norm_pdf(z: f64) -> f64 {
    FRAC_1_SQRT_2PI * (-0.5 * z * z).exp()
}

/// Standard normal cumulative distribution Φ(z) = ½ erfc(−z/√2), relatively accurate in the lower
/// tail (down to the f64 underflow near z = −38.4). This is P_h of [HNPN14 Eq. 2] / g(h) of
/// [HN12 Eq. 5] for a unit-variance height.
pub fn norm_cdf(z: f64) -> f64 {
    0.5 * erfc(-z / SQRT_2)
}

/// ln Φ(z), accurate for all z: for `z → −∞` it behaves like `−z²/2 − ln(−z√(2π))` and never
/// returns −∞ for finite z (saturating at `f64::MIN` past |z| ≈ 1.3e154); for large z it is `−Φ(−z)` to full relative accuracy.
pub fn log_norm_cdf(z: f64) -> f64 {
    if z.is_nan() {
        return f64::NAN;
    }
    if z < -5.0 {
        let x = -z / SQRT_2;
        let v = (0.5 * erfcx(x)).ln() - x * x;
        // Only for |z| > 1.3e154, where −z²/2 itself overflows: saturate.
        if v.is_finite() { v } else { f64::MIN }
    } else if z < 0.0 {
        norm_cdf(z).ln()
    } else {
        (-0.5 * erfc(z / SQRT_2)).ln_1p()
    }
}

/// Standard normal quantile Φ⁻¹(p) (probit).
///
/// Acklam's rational approximation as a starting point, then Newton steps on `ln Φ(x) = ln p`,
/// which keeps relative accuracy down to `p = f64::MIN_POSITIVE` (Φ⁻¹ ≈ −37.5). Inputs outside
/// (0, 1) are clamped: `p ≤ 0` gives Φ⁻¹(MIN_POSITIVE) ≈ −37.52 and `p ≥ 1` gives +8.29 (the
/// largest quantile whose upper tail is representable next to 1), never ±∞. NaN stays NaN.
pub fn norm_quantile(p: f64) -> f64 {
    if p.is_nan() {
        return f64::NAN;
    }
    if p > 0.5 {
        let q = (1.0 - p).max(1.1102230246251565e-16);
        return -norm_quantile(q);
    }
    let p = p.max(f64::MIN_POSITIVE);
    let mut x = acklam(p);
    let lp = p.ln();
    for _ in 0..3 {
        // d/dx ln Φ(x) = φ(x)/Φ(x) = √(2/π) / erfcx(−x/√2).
        let ratio = (PI / 2.0).sqrt() * erfcx(-x / SQRT_2);
        let step = (log_norm_cdf(x) - lp) * ratio;
        x -= step;
        if step.abs() <= 1e-16 * x.abs().max(1.0) {
            break;
        }
    }
    x
}

/// Acklam's rational approximation to Φ⁻¹ for `0 < p ≤ 0.5` (relative error ≈ 1e-9).
fn acklam(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
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

/// Smith's Λ for Gaussian slopes as a function of `ν = μ/(√2 σ_n)`, μ = cot θ:
/// `Λ(ν) = ½ (e^{−ν²}/(ν√π) − erfc ν)` [HN12 Eq. 6], [HNPN14 Eq. 2].
///
/// Cancellation-free: for ν ≥ 2 the difference is taken inside Laplace's continued fraction,
/// `Λ = e^{−ν²}/(2√π) · (K − ν)/(ν K)` with `K = ν + ½/R(ν)`, so the relative accuracy stays at
/// 1e-14 where the naive form loses all digits (docs/numerics.md).
///
/// Edge cases: `ν = +∞` (view at the normal, or σ_n = 0) gives 0; `ν ≤ NU_MIN` (grazing, below the
/// horizon, or σ_n huge) is clamped to `NU_MIN` so Λ saturates near 2.8e29, finite. NaN → 0 is *not*
/// done: NaN stays NaN (callers validate their inputs).
pub fn smith_lambda(nu: f64) -> f64 {
    if nu.is_nan() {
        return f64::NAN;
    }
    let nu = nu.max(NU_MIN);
    if nu >= CF_THRESHOLD {
        if nu > 27.3 {
            return 0.0;
        }
        let r = cf_tail(nu);
        let tail = 0.5 / r; // K − ν
        let k = nu + tail;
        (-nu * nu).exp() / (2.0 * SQRT_PI) * tail / (nu * k)
    } else {
        0.5 * ((-nu * nu).exp() / (nu * SQRT_PI) - erfc(nu))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Reference values computed by mpmath at 60 digits (scripts/gen_reference.py).
    pub(crate) fn reference() -> Vec<(String, f64, f64)> {
        include_str!("../../tests/data/special_reference.csv")
            .lines()
            .filter(|l| !l.starts_with('#') && !l.is_empty())
            .map(|l| {
                let mut it = l.split(',');
                let name = it.next().unwrap().to_string();
                let x: f64 = it.next().unwrap().parse().unwrap();
                let v: f64 = it.next().unwrap().parse().unwrap();
                (name, x, v)
            })
            .collect()
    }

    fn eval(name: &str, x: f64) -> Option<f64> {
        Some(match name {
            "erf" => erf(x),
            "erfc" => erfc(x),
            "erfcx" => erfcx(x),
            "norm_cdf" => norm_cdf(x),
            "norm_pdf" => norm_pdf(x),
            "log_norm_cdf" => log_norm_cdf(x),
            "norm_quantile" => norm_quantile(x),
            "lambda" => smith_lambda(x),
            _ => return None,
        })
    }

    #[test]
    fn matches_high_precision_reference_to_1e_12() {
        let rows = reference();
        assert!(rows.len() > 500, "reference data missing");
        let mut worst = (0.0_f64, String::new());
        for (name, x, want) in &rows {
            let got = eval(name, *x).unwrap_or_else(|| panic!("unknown function {name}"));
            if *want == 0.0 {
                assert!(got.abs() < 1e-300, "{name}({x}) = {got}, want 0");
                continue;
            }
            if want.abs() < 1e-300 {
                // Subnormal results: only absolute agreement is meaningful.
                assert!(
                    (got - want).abs() < 1e-310,
                    "{name}({x}) = {got}, want {want}"
                );
                continue;
            }
            let rel = ((got - want) / want).abs();
            if rel > worst.0 {
                worst = (rel, format!("{name}({x}) = {got:e}, want {want:e}"));
            }
            assert!(
                rel <= 1e-12,
                "{name}({x}) = {got:e}, want {want:e}, rel {rel:e}"
            );
        }
        eprintln!("worst relative error: {:e} at {}", worst.0, worst.1);
    }

    #[test]
    fn exact_identities() {
        for i in -400..=400 {
            let x = f64::from(i) * 0.0173;
            assert!(
                (erf(x) + erfc(x) - 1.0).abs() < 2e-16 * 4.0,
                "erf+erfc at {x}"
            );
            assert!((erf(-x) + erf(x)).abs() == 0.0, "erf odd at {x}");
            assert!(
                (erfc(-x) + erfc(x) - 2.0).abs() < 1e-15,
                "erfc reflection at {x}"
            );
            let p = norm_cdf(x);
            // Round trip only where Φ⁻¹ is well conditioned in f64 (p not rounded next to 1).
            if p > 1e-300 && x <= 0.5 {
                let back = norm_quantile(p);
                assert!(
                    (back - x).abs() < 1e-12 * x.abs().max(1.0),
                    "quantile(cdf({x})) = {back}"
                );
            }
        }
    }

    #[test]
    fn edge_cases_are_finite() {
        for &x in &[
            0.0,
            -0.0,
            1e-320,
            f64::MIN_POSITIVE,
            1e-300,
            1e300,
            -1e300,
            f64::MAX,
            f64::MIN,
        ] {
            for v in [
                erf(x),
                erfc(x),
                erfcx(x),
                norm_pdf(x),
                norm_cdf(x),
                smith_lambda(x),
            ] {
                assert!(v.is_finite(), "non-finite at {x}");
            }
            assert!(log_norm_cdf(x).is_finite(), "log cdf at {x}");
        }
        assert_eq!(erf(f64::INFINITY), 1.0);
        assert_eq!(erfc(f64::INFINITY), 0.0);
        assert_eq!(erfc(f64::NEG_INFINITY), 2.0);
        assert_eq!(smith_lambda(f64::INFINITY), 0.0);
        assert!(smith_lambda(0.0) > 1e29 && smith_lambda(0.0).is_finite());
        assert!(norm_quantile(0.0).is_finite() && norm_quantile(0.0) < -37.0);
        assert!(norm_quantile(1.0).is_finite() && norm_quantile(1.0) > 8.0);
        // Λ is monotone decreasing in ν and positive.
        let mut prev = f64::INFINITY;
        for i in 0..3000 {
            let nu = 1e-6 * 1.01_f64.powi(i);
            let l = smith_lambda(nu);
            assert!(l >= 0.0 && l <= prev, "Λ not monotone at ν={nu}");
            prev = l;
        }
    }
}
