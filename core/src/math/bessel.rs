//! Modified Bessel functions of the first kind I0 and I1, in the forms the slope density of a sum
//! of sinusoids needs ([`crate::microfacet::slope_density`]): `E[e^{x sin ψ}] = I0(x)` for ψ
//! uniform, so `ln I0` is a sinusoid's cumulant generating function and `I1/I0` its derivative.
//!
//! Polynomial approximations [Abramowitz & Stegun 9.8.1–9.8.4]: relative error below 2.2e-7 for
//! every x (the large-x forms carry e^x and x^{−1/2} analytically, so nothing overflows: `ln I0`
//! is finite for every finite x). Even in x (`ln I0`), odd (`I1/I0`).

/// `I0(x)` for |x| ≤ 3.75 as a polynomial in t² = (x/3.75)² [A&S 9.8.1].
fn i0_small(t2: f64) -> f64 {
    1.0 + t2
        * (3.515_622_9
            + t2 * (3.089_942_4
                + t2 * (1.206_749_2 + t2 * (0.265_973_2 + t2 * (0.036_076_8 + t2 * 0.004_581_3)))))
}

/// `I1(x)/x` for |x| ≤ 3.75 [A&S 9.8.3].
fn i1_over_x_small(t2: f64) -> f64 {
    0.5 + t2
        * (0.878_905_94
            + t2 * (0.514_988_69
                + t2 * (0.150_849_34
                    + t2 * (0.026_587_33 + t2 * (0.003_015_32 + t2 * 0.000_324_11)))))
}

/// `√x e^{−x} I0(x)` for x ≥ 3.75 as a polynomial in t = 3.75/x [A&S 9.8.2].
fn i0_large(t: f64) -> f64 {
    0.398_942_28
        + t * (0.013_285_92
            + t * (0.002_253_19
                + t * (-0.001_575_65
                    + t * (0.009_162_81
                        + t * (-0.020_577_06
                            + t * (0.026_355_37 + t * (-0.016_476_33 + t * 0.003_923_77)))))))
}

/// `√x e^{−x} I1(x)` for x ≥ 3.75 [A&S 9.8.4].
fn i1_large(t: f64) -> f64 {
    0.398_942_28
        + t * (-0.039_880_24
            + t * (-0.003_620_18
                + t * (0.001_638_01
                    + t * (-0.010_315_55
                        + t * (0.022_829_67
                            + t * (-0.028_953_12 + t * (0.017_876_54 - t * 0.004_200_59)))))))
}

/// `(ln I0(x), A(x), A′(x))` ([`log_bessel_i0`], [`bessel_ratio`], [`bessel_ratio_derivative`])
/// from one evaluation of the polynomials: what the saddlepoint's Newton iteration needs per wave
/// ([`crate::microfacet::slope_density`]).
pub fn bessel_terms(x: f64) -> [f64; 3] {
    let a = x.abs();
    let (ln_i0, r, r_over_x) = if a <= 3.75 {
        let t = a / 3.75;
        let i0 = i0_small(t * t);
        let q = i1_over_x_small(t * t) / i0;
        (i0.ln(), a * q, q)
    } else {
        let t = 3.75 / a;
        let i0 = i0_large(t);
        let r = i1_large(t) / i0;
        (a - 0.5 * a.ln() + i0.ln(), r, r / a)
    };
    [
        ln_i0,
        r.copysign(x),
        (1.0 - r_over_x - r * r).clamp(1e-12, 0.5),
    ]
}

/// `ln I0(x)`: 0 at 0, ≈ |x| − ½ ln(2π|x|) for large |x|.
pub fn log_bessel_i0(x: f64) -> f64 {
    bessel_terms(x)[0]
}

/// `A(x) = I1(x)/I0(x)`, odd, in (−1, 1): the mean of sin ψ under the weight e^{x sin ψ}.
pub fn bessel_ratio(x: f64) -> f64 {
    bessel_terms(x)[1]
}

/// `A′(x) = 1 − A(x)/x − A(x)²` (½ at 0, → 1/(2x²) for large x): the variance of sin ψ under the
/// weight e^{x sin ψ}, so always in (0, ½].
pub fn bessel_ratio_derivative(x: f64) -> f64 {
    bessel_terms(x)[2]
}

/// `(A′, A″, A‴)` of `A = I1/I0`: the variance, third and fourth cumulants of sin ψ under the
/// weight e^{x sin ψ} (the derivatives of `ln I0`). From `A′ = 1 − A/x − A²` differentiated, with
/// the Taylor series `A′ = ½ − 3x²/16`, `A″ = −3x/8 + 5x³/24`, `A‴ = −3/8 + 5x²/8` below
/// |x| = 0.3 where the closed forms cancel.
pub fn bessel_ratio_derivatives(x: f64) -> [f64; 3] {
    let [_, a, a1] = bessel_terms(x);
    if x.abs() < 0.3 {
        let x2 = x * x;
        return [a1, x * (-0.375 + x2 * 5.0 / 24.0), -0.375 + 0.625 * x2];
    }
    let a2 = -a1 / x + a / (x * x) - 2.0 * a * a1;
    let a3 = -a2 / x + 2.0 * a1 / (x * x) - 2.0 * a / (x * x * x) - 2.0 * a1 * a1 - 2.0 * a * a2;
    [a1, a2, a3]
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// I0 and I1 by the trapezoid rule over ψ (spectrally accurate for periodic integrands).
    fn by_quadrature(x: f64) -> (f64, f64) {
        let n = 4000;
        let (mut i0, mut i1) = (0.0, 0.0);
        for k in 0..n {
            let psi = 2.0 * PI * k as f64 / n as f64;
            let e = (x * psi.sin() - x.abs()).exp();
            i0 += e / n as f64;
            i1 += e * psi.sin() / n as f64;
        }
        (i0, i1) // both scaled by e^{−|x|}
    }

    #[test]
    fn against_the_defining_integral() {
        for x in [0.0, 1e-6, 0.3, 1.0, 3.7, 3.8, 7.0, 25.0, 300.0, -2.0, -40.0] {
            let (i0s, i1s) = by_quadrature(x);
            let ln_i0 = x.abs() + i0s.ln();
            assert!(
                (log_bessel_i0(x) - ln_i0).abs() < 5e-7 * (1.0 + ln_i0.abs()),
                "ln I0({x}): {} vs {ln_i0}",
                log_bessel_i0(x)
            );
            let a = i1s / i0s;
            assert!(
                // Each of I0 and I1 is good to 2.2e-7: their ratio to twice that, and a bit.
                (bessel_ratio(x) - a).abs() < 1e-6,
                "A({x}): {} vs {a}",
                bessel_ratio(x)
            );
            // A′ by a central difference of A.
            let h = 1e-4 * (1.0 + x.abs());
            let d = (bessel_ratio(x + h) - bessel_ratio(x - h)) / (2.0 * h);
            assert!(
                (bessel_ratio_derivative(x) - d).abs() < 2e-5 * (1.0 + d),
                "A'({x}): {} vs {d}",
                bessel_ratio_derivative(x)
            );
        }
        assert!(log_bessel_i0(1e300).is_finite() && bessel_ratio(-1e300) < -0.99);
        // A″ and A‴ by differences of A′ and A″, on both sides of the series switch.
        for x in [0.05, 0.29, 0.31, 0.8, 2.0, 5.0, -1.5, 12.0] {
            let h = 1e-4;
            let [_, a2, a3] = bessel_ratio_derivatives(x);
            let d2 = (bessel_ratio_derivative(x + h) - bessel_ratio_derivative(x - h)) / (2.0 * h);
            let d3 = (bessel_ratio_derivatives(x + h)[1] - bessel_ratio_derivatives(x - h)[1])
                / (2.0 * h);
            assert!((a2 - d2).abs() < 2e-3, "A''({x}): {a2} vs {d2}");
            assert!((a3 - d3).abs() < 5e-3, "A'''({x}): {a3} vs {d3}");
        }
    }
}
