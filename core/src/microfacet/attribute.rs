//! The HN12 attribute model: an attribute (a colour channel) correlated with height,
//! `a(h) = ā + a_s·s(h)`, `s(h) = 2P(h) − 1` [HN12 Sec. 5.5, hypothesis H5bis], and its exact
//! view- and light-dependent mean over the visible, lit points [HN12 Eq. 17].

use crate::math::special::erf;
use std::f64::consts::FRAC_1_SQRT_2;

/// The attribute shape `s(t) = 2Φ(t) − 1 = erf(t/√2)` at standardized height `t = h/σ_h` [HN12 H5bis].
/// Odd, in (−1, 1); computed through `erf` so it keeps relative accuracy near 0.
pub fn attribute_shape(t: f64) -> f64 {
    erf(t * FRAC_1_SQRT_2)
}

/// `a(h) = ā + a_s·s(h)` at standardized height t [HN12 H5bis].
pub fn attribute(mean: f64, correlation: f64, t: f64) -> f64 {
    mean + correlation * attribute_shape(t)
}

/// The mean of `s` over the effective height distribution `D_h ∝ P^L p`:
/// `2(L+1)/(L+2) − 1 = L/(L+2)` [HN12 Eq. 17], evaluated as `1 − 2/(L+2)` (docs/numerics.md: finite as
/// L → ∞, where it tends to 1). Negative L is treated as 0.
pub fn mean_attribute_shape(l: f64) -> f64 {
    let l = if l.is_nan() { 0.0 } else { l.max(0.0) };
    1.0 - 2.0 / (l + 2.0)
}

/// `ā(v, l) = ā + a_s·(2(L+1)/(L+2) − 1)` [HN12 Eq. 17], L = Λ(v) + Λ(l) or its correlated form.
pub fn mean_attribute(mean: f64, correlation: f64, l: f64) -> f64 {
    mean + correlation * mean_attribute_shape(l)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::quadrature::integrate;
    use crate::math::special::{log_norm_cdf, norm_pdf};

    #[test]
    fn eq17_matches_quadrature() {
        for &l in &[0.0, 1e-6, 0.1, 0.56, 1.0, 3.7, 45.0, 1e3, 1e5] {
            let w = |t: f64| (l * log_norm_cdf(t)).exp() * norm_pdf(t);
            let num = integrate(|t| attribute_shape(t) * w(t), -12.0, 16.0, 3000);
            let den = integrate(w, -12.0, 16.0, 3000);
            let want = num / den;
            assert!(
                (mean_attribute_shape(l) - want).abs() < 1e-9,
                "L={l}: {} vs {want}",
                mean_attribute_shape(l)
            );
        }
    }

    #[test]
    fn limits() {
        assert_eq!(mean_attribute(0.3, 0.2, 0.0), 0.3);
        assert_eq!(mean_attribute_shape(f64::INFINITY), 1.0);
        assert_eq!(mean_attribute_shape(f64::NAN), 0.0);
        assert!((mean_attribute(0.5, 0.25, 1e300) - 0.75).abs() < 1e-15);
        assert!((attribute(0.5, 0.25, 40.0) - 0.75).abs() < 1e-15);
    }
}
