//! Masking–shadowing G2: how view masking Λo and light shadowing Λi combine into the exponent L of
//! the joint visibility `P(h)^L` (the height-correlated masking–shadowing function G2 of a point at
//! height h is `P(h)^L`; averaged over heights, `G2 = 1/(1 + L)`), and the mean shadowing of visible
//! points V̄ [HNPN14 Eqs. 11–12]. [`MaskingShadowing`] (alias [`G2`]) holds Λo, Λi and L.

use crate::microfacet::slopes::SlopeCov;
use crate::microfacet::smith::lambda;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// How masking (toward the eye) and shadowing (toward the light) are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum Correlation {
    /// The paper's form, masking and shadowing independent: `L = Λo + Λi` [HNPN14 Eq. 12].
    /// Wrong when light and view are close (V̄ = (1+Λ)/(1+2Λ) < 1 where the truth is 1).
    Uncorrelated,
    /// Height–direction correlated Smith form (Ahn et al. 2013; Heitz, JCGT 2014):
    /// `L = max(Λo, Λi) + λ(Δφ)·min(Λo, Λi)`, `λ(Δφ) = 4.41Δφ/(4.41Δφ + 1)` (docs/numerics.md).
    #[default]
    HeightDirection,
}

/// The constant of the azimuthal correlation factor `λ(Δφ) = cΔφ/(cΔφ + 1)`, c = 4.41 (Ahn et al.
/// 2013; Heitz, JCGT 2014; docs/numerics.md).
pub const AZIMUTH_CORRELATION: f64 = 4.41;

/// Azimuthal correlation factor `λ(Δφ) = 4.41Δφ/(4.41Δφ + 1)` for Δφ ∈ [0, π] (docs/numerics.md).
/// 0 when view and light share an azimuth, → 0.93 when opposite.
pub fn azimuth_factor(delta_phi: f64) -> f64 {
    let d = if delta_phi.is_finite() {
        delta_phi.abs().min(std::f64::consts::PI)
    } else {
        0.0
    };
    AZIMUTH_CORRELATION * d / (AZIMUTH_CORRELATION * d + 1.0)
}

/// Azimuth difference Δφ ∈ [0, π] between two directions; 0 if either is along the normal (then
/// its Λ is 0 and the factor is irrelevant).
pub fn azimuth_difference(a: DVec3, b: DVec3) -> f64 {
    let ra = a.x.hypot(a.y);
    let rb = b.x.hypot(b.y);
    if !(ra > 0.0 && rb > 0.0) {
        return 0.0;
    }
    let c = ((a.x * b.x + a.y * b.y) / (ra * rb)).clamp(-1.0, 1.0);
    let s = (a.x * b.y - a.y * b.x) / (ra * rb);
    s.abs().atan2(c)
}

/// Masking and shadowing of one view/light pair: the height-correlated G2's exponent L and its parts.
#[doc(alias = "G2")]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaskingShadowing {
    /// Λ(ωo), view masking [HN12 Eq. 6].
    pub lambda_o: f64,
    /// Λ(ωi), light shadowing [HN12 Eq. 6].
    pub lambda_i: f64,
    /// `L − Λo`, computed without cancellation; ≥ 0.
    pub excess: f64,
    /// Joint exponent L of `P(h)^L`, the exponent of the effective height distribution
    /// [HNPN14 Eq. 15] and of [HN12 Eq. 17].
    pub total: f64,
}

/// The height-correlated masking–shadowing function G2 (Smith; [HNPN14 Eqs. 11–12], Heitz JCGT 2014):
/// [`MaskingShadowing`] under its usual name.
pub type G2 = MaskingShadowing;

impl MaskingShadowing {
    /// Combine Λo and Λi under `correlation`, Δφ the azimuth between view and light.
    pub fn new(lambda_o: f64, lambda_i: f64, delta_phi: f64, correlation: Correlation) -> Self {
        let (lo, li) = (lambda_o.max(0.0), lambda_i.max(0.0));
        let excess = match correlation {
            Correlation::Uncorrelated => li,
            Correlation::HeightDirection => {
                let k = azimuth_factor(delta_phi);
                if lo >= li { k * li } else { (li - lo) + k * lo }
            }
        };
        Self {
            lambda_o: lo,
            lambda_i: li,
            excess,
            total: lo + excess,
        }
    }

    /// From directions: ωo toward the eye, ωi toward the light, both in the tangent frame.
    pub fn from_directions(
        wo: DVec3,
        wi: DVec3,
        slopes: &SlopeCov,
        correlation: Correlation,
    ) -> Self {
        Self::new(
            lambda(wo, slopes),
            lambda(wi, slopes),
            azimuth_difference(wo, wi),
            correlation,
        )
    }

    /// Mean shadowing of the visible points `V̄ = (1 + Λo)/(1 + L)` [HNPN14 Eq. 12]
    /// (with L = Λo + Λi it is the paper's formula), evaluated as `1/(1 + (L − Λo)/(1 + Λo))`, which is
    /// free of the ∞/∞ that the textbook form hits at grazing angles (docs/numerics.md). In [0, 1].
    pub fn mean_shadowing(&self) -> f64 {
        1.0 / (1.0 + self.excess / (1.0 + self.lambda_o))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::quadrature::integrate;
    use crate::math::special::{log_norm_cdf, norm_pdf};
    use crate::scene::direction::direction;

    /// ∫ Φ(t)^a φ(t) dt by quadrature (exactly 1/(a+1)).
    fn power_integral(a: f64) -> f64 {
        integrate(
            |t| (a * log_norm_cdf(t)).exp() * norm_pdf(t),
            -12.0,
            14.0,
            2000,
        )
    }

    #[test]
    fn mean_shadowing_matches_quadrature() {
        // [HNPN14 Eq. 12]: V̄ = ∫P^{Λo+Λi}p / ∫P^{Λo}p, checked by quadrature to 1e-9.
        for &(lo, li) in &[
            (0.0, 0.0),
            (0.1, 0.3),
            (1.0, 0.2),
            (3.0, 7.0),
            (20.0, 0.5),
            (0.0, 5.0),
        ] {
            let m = MaskingShadowing::new(lo, li, 1.0, Correlation::Uncorrelated);
            let want = power_integral(lo + li) / power_integral(lo);
            assert!((m.mean_shadowing() - want).abs() < 1e-9, "Λo={lo} Λi={li}");
        }
    }

    #[test]
    fn correlated_form_removes_the_coincident_light_error() {
        let s = SlopeCov::isotropic(0.4);
        let w = direction(1.3, 0.2);
        let un = MaskingShadowing::from_directions(w, w, &s, Correlation::Uncorrelated);
        let co = MaskingShadowing::from_directions(w, w, &s, Correlation::HeightDirection);
        assert_eq!(
            co.mean_shadowing(),
            1.0,
            "light at the eye shadows nothing visible"
        );
        let l = un.lambda_o;
        assert!((un.mean_shadowing() - (1.0 + l) / (1.0 + 2.0 * l)).abs() < 1e-15);
        // Opposite azimuths approach the uncorrelated sum.
        let opp =
            MaskingShadowing::new(2.0, 2.0, std::f64::consts::PI, Correlation::HeightDirection);
        assert!((opp.total - (2.0 + 2.0 * azimuth_factor(std::f64::consts::PI))).abs() < 1e-15);
    }

    #[test]
    fn extreme_inputs_stay_in_range() {
        for lo in [0.0, 1e-12, 1.0, 1e12, 2.8e29] {
            for li in [0.0, 1e-12, 1.0, 1e12, 2.8e29] {
                for c in [Correlation::Uncorrelated, Correlation::HeightDirection] {
                    let m = MaskingShadowing::new(lo, li, 2.0, c);
                    let v = m.mean_shadowing();
                    assert!(
                        (0.0..=1.0).contains(&v) && m.total.is_finite(),
                        "{lo} {li} {c:?}"
                    );
                }
            }
        }
    }
}
