//! Smith masking for Gaussian slopes: Λ(ω) [HN12 Eq. 6] and the visibility of a point at a given
//! height, `V(ω, h) = P(h)^Λ(ω)` [HN12 Eqs. 4–5], [HNPN14 Eq. 2].
//!
//! Directions are unit vectors in the tangent frame of the macro-surface (z = macro normal).

use crate::math::special::{log_norm_cdf, smith_lambda};
use crate::microfacet::slopes::SlopeCov;
use glam::DVec3;
use std::f64::consts::SQRT_2;

/// cot θ of a direction: its slope `μ = z / |(x, y)|`.
///
/// Edge cases: the normal itself (x = y = 0, z > 0) gives +∞; a direction on or below the horizon
/// (z ≤ 0) gives 0 (such a direction sees nothing; see [`visibility`]); NaN components give 0.
pub fn cot_theta(w: DVec3) -> f64 {
    if !(w.z > 0.0) {
        return 0.0;
    }
    let r = w.x.hypot(w.y);
    if r == 0.0 { f64::INFINITY } else { w.z / r }
}

/// Λ(ω) for Gaussian slopes with covariance `slopes`, projected on ω's azimuth [HN12 Eq. 6]:
/// `ν = cot θ / (√2 σ(φ))`, `Λ = ½(e^{−ν²}/(ν√π) − erfc ν)` ([`smith_lambda`]).
///
/// Edge cases (all finite): ω at the normal or σ(φ) = 0 → 0 (no masking); ω at or below the
/// horizon → the saturated value ≈ 2.8e29 (visibility then 0); σ(φ) huge → large but finite.
pub fn lambda(w: DVec3, slopes: &SlopeCov) -> f64 {
    let mu = cot_theta(w);
    if mu == f64::INFINITY {
        return 0.0;
    }
    let r = w.x.hypot(w.y);
    let sigma = slopes.projected_std(w.x / r, w.y / r);
    if !(sigma > 0.0) {
        return 0.0;
    }
    let nu = mu / (SQRT_2 * sigma);
    smith_lambda(if nu.is_finite() { nu } else { f64::INFINITY })
}

/// Smith's visibility of a point at standardized height `t = (h − h̄)/σ_h` from a direction with
/// masking `lam` = Λ(ω): `V = Φ(t)^Λ` [HN12 Eqs. 4–5], computed as `exp(Λ · ln Φ(t))` so that it
/// neither underflows early nor produces `0^0`. Λ = 0 gives exactly 1.
pub fn visibility(t: f64, lam: f64) -> f64 {
    if lam == 0.0 {
        return 1.0;
    }
    (lam * log_norm_cdf(t)).exp()
}

/// [`visibility`] for a direction: 0 when ω is at or below the horizon.
pub fn visibility_dir(w: DVec3, t: f64, slopes: &SlopeCov) -> f64 {
    if !(w.z > 0.0) {
        return 0.0;
    }
    visibility(t, lambda(w, slopes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::quadrature::integrate;
    use crate::math::special::norm_pdf;
    use crate::scene::direction::direction;

    /// Λ from its definition: Λ(μ) = (1/μ) ∫_μ^∞ (q − μ) p(q) dq with p the projected slope pdf
    /// (Smith 1967), integrated numerically.
    fn lambda_by_quadrature(mu: f64, sigma: f64) -> f64 {
        let f = |q: f64| (q - mu) * norm_pdf(q / sigma) / sigma;
        integrate(f, mu, mu + 40.0 * sigma, 400) / mu
    }

    #[test]
    fn lambda_matches_its_integral_definition() {
        for &sigma in &[0.05, 0.3, 1.0, 3.0] {
            for &deg in &[5.0_f64, 30.0, 60.0, 75.0, 85.0, 89.0] {
                let w = direction(deg.to_radians(), 0.7);
                let mu = cot_theta(w);
                let want = lambda_by_quadrature(mu, sigma);
                let got = lambda(w, &SlopeCov::isotropic(sigma));
                assert!(
                    (got - want).abs() <= 1e-10 * want.max(1e-300) + 1e-300,
                    "σ={sigma} θ={deg}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn anisotropy_uses_the_azimuth() {
        let s = SlopeCov::from_std(0.5, 0.1);
        let along_x = lambda(direction(1.2, 0.0), &s);
        let along_y = lambda(direction(1.2, std::f64::consts::FRAC_PI_2), &s);
        assert!((along_x - lambda(direction(1.2, 0.0), &SlopeCov::isotropic(0.5))).abs() < 1e-15);
        assert!((along_y - lambda(direction(1.2, 0.0), &SlopeCov::isotropic(0.1))).abs() < 1e-15);
        assert!(along_x > along_y);
    }

    #[test]
    fn edge_cases_are_finite() {
        let dirs = [
            DVec3::Z,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, -0.1).normalize(),
            direction(89.999_f64.to_radians(), 1.0),
            direction(1e-7, 1.0),
            DVec3::new(0.0, 0.0, -1.0),
        ];
        for s in [0.0, 1e-9, 1.0, 1e6] {
            for (k, w) in dirs.iter().enumerate() {
                let l = lambda(*w, &SlopeCov::isotropic(s));
                assert!(l.is_finite() && l >= 0.0, "Λ({k}, σ={s}) = {l}");
                for t in [-40.0, -3.0, 0.0, 3.0, 40.0] {
                    let v = visibility_dir(*w, t, &SlopeCov::isotropic(s));
                    assert!((0.0..=1.0).contains(&v), "V({k}, σ={s}, t={t}) = {v}");
                }
            }
        }
        // Below the horizon nothing is visible; at the normal everything is.
        assert_eq!(
            visibility_dir(DVec3::new(1.0, 0.0, -0.1), 5.0, &SlopeCov::isotropic(0.3)),
            0.0
        );
        assert_eq!(
            visibility_dir(DVec3::Z, -5.0, &SlopeCov::isotropic(0.3)),
            1.0
        );
    }
}
