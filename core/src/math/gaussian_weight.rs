//! A positive weight over the plane that is a Gaussian function,
//! `w(z) = exp(c − ½ zᵀQz + bᵀz)`: closed under products and powers, with closed-form
//! expectations under any Gaussian. What the transfer mixture's conditioned visibility is carried
//! as ([`crate::eval::masking::transfer_masking_table::TransferRays::visibility_weights`], #17): each ray's
//! conditioned `G1` from its own moments along its projection, their joint term `lo·hi^k` as a
//! product, and its mean over a specular lobe's half-vector posterior as an expectation.
//!
//! A weight is exactly a Gaussian function when `w(z)·N(z; 0, I)` is a Gaussian (the visibility's
//! reweighting of the driver slopes' Gaussian, docs/design/transfer-curves.md); for any other weight
//! [`GaussianWeight::along`] matches its mass and its first two moments.

use glam::{DMat2, DVec2};

/// The smallest variance [`GaussianWeight::along`] gives a tilted Gaussian, in the units of z: a
/// weight that is a step still has a finite curvature. The conditioned masking table's slope
/// nodes are 0.5σ apart, so no visibility read from it is sharper than a ramp across 0.5σ
/// (variance about 0.02); 0.01 keeps `c`, `Q` and `b` below about 10² where `c + ½βᵀA⁻¹β`
/// cancels (f32 on the GPU keeps about 5 digits of that sum).
pub const MIN_VARIANCE: f64 = 0.01;

/// `w(z) = exp(log_scale − ½ zᵀ q z + bᵀ z)` (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussianWeight {
    /// `c`.
    pub log_scale: f64,
    /// `Q` (symmetric; need not be positive definite: a weight may rise away from the origin).
    pub q: DMat2,
    /// `b`.
    pub b: DVec2,
}

impl GaussianWeight {
    /// `w ≡ 1`.
    pub const ONE: Self = Self {
        log_scale: 0.0,
        q: DMat2::ZERO,
        b: DVec2::ZERO,
    };

    /// The weight of a function `g` of `a = e·z` alone (`e` a unit vector) from its moments over
    /// `a ~ N(0, 1)`: `m0 = E[g]`, `m1 = E[a g]`, `m2 = E[a² g]`. It is `m0·N(a; μ, s²)/N(a; 0, 1)`
    /// with `μ = m1/m0` and `s² = m2/m0 − μ²` (at least [`MIN_VARIANCE`]), so its mass and its
    /// tilted Gaussian along `e` are g's, and across `e` it is flat. `None` where `m0` is not
    /// positive (nothing visible) or a moment is not finite.
    pub fn along(e: DVec2, m0: f64, m1: f64, m2: f64) -> Option<Self> {
        if !(m0 > 1e-300 && m0.is_finite() && m1.is_finite() && m2.is_finite()) {
            return None;
        }
        let mu = m1 / m0;
        let s2 = (m2 / m0 - mu * mu).max(MIN_VARIANCE);
        let q = 1.0 / s2 - 1.0;
        Some(Self {
            log_scale: m0.ln() - 0.5 * s2.ln() - 0.5 * mu * mu / s2,
            q: DMat2::from_cols(
                DVec2::new(q * e.x * e.x, q * e.x * e.y),
                DVec2::new(q * e.x * e.y, q * e.y * e.y),
            ),
            b: e * (mu / s2),
        })
    }

    /// `w^k`.
    pub fn powf(self, k: f64) -> Self {
        Self {
            log_scale: self.log_scale * k,
            q: self.q * k,
            b: self.b * k,
        }
    }

    /// `w(z)`.
    pub fn at(&self, z: DVec2) -> f64 {
        (self.log_scale - 0.5 * z.dot(self.q * z) + self.b.dot(z)).exp()
    }

    /// `E[w(z)]` over `z ~ N(mu, L Lᵀ)` (`l` any square root of the covariance, singular allowed:
    /// `l = 0` is `w(mu)`). With `A = I + LᵀQL` and `β = Lᵀ(b − Q mu)` it is
    /// `w(mu)·exp(½ βᵀA⁻¹β)/√det A`. `None` where the integral diverges (A not positive definite)
    /// or overflows.
    pub fn expect_under(&self, mu: DVec2, l: DMat2) -> Option<f64> {
        let a = DMat2::IDENTITY + l.transpose() * self.q * l;
        let det = a.determinant();
        if !(det > 0.0 && a.x_axis.x > 0.0) {
            return None;
        }
        let beta = l.transpose() * (self.b - self.q * mu);
        let log_w = self.log_scale - 0.5 * mu.dot(self.q * mu) + self.b.dot(mu);
        let r = (log_w + 0.5 * beta.dot(a.inverse() * beta)).exp() / det.sqrt();
        r.is_finite().then_some(r)
    }

    /// The weight as a reweighting of `N(0, I)`: `(E[w], m, C)` with `w(z)·N(z; 0, I) =
    /// E[w]·N(z; m, C)`, `C = (I + Q)⁻¹`, `m = C b`. `None` where `I + Q` is not positive definite
    /// (no such Gaussian), or nothing is left (`E[w]` below 1e-300).
    pub fn tilted(&self) -> Option<(f64, DVec2, DMat2)> {
        let mass = self.expect_under(DVec2::ZERO, DMat2::IDENTITY)?;
        if !(mass > 1e-300) {
            return None;
        }
        let c = (DMat2::IDENTITY + self.q).inverse();
        let xy = 0.5 * (c.x_axis.y + c.y_axis.x);
        let c = DMat2::from_cols(DVec2::new(c.x_axis.x, xy), DVec2::new(xy, c.y_axis.y));
        Some((mass, c * self.b, c))
    }
}

/// `w·v`: the exponents add.
impl std::ops::Mul for GaussianWeight {
    type Output = Self;
    fn mul(self, v: Self) -> Self {
        Self {
            log_scale: self.log_scale + v.log_scale,
            q: self.q + v.q,
            b: self.b + v.b,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::quadrature::gauss_hermite_normal;

    /// `E[f(z)]`, `z ~ N(mu, L Lᵀ)`, on an n × n Gauss–Hermite product rule.
    fn quadrature(f: impl Fn(DVec2) -> f64, mu: DVec2, l: DMat2, n: usize) -> f64 {
        let (x, w) = gauss_hermite_normal(n);
        let mut acc = 0.0;
        for (a, wa) in x.iter().zip(&w) {
            for (b, wb) in x.iter().zip(&w) {
                acc += wa * wb * f(mu + l * DVec2::new(*a, *b));
            }
        }
        acc
    }

    /// `along` keeps the mass and the tilted Gaussian of the moments it is given, along `e`, and
    /// is flat across it; the same moments of a function that is exactly such a weight are
    /// reproduced by quadrature.
    #[test]
    fn along_matches_the_moments_it_is_given() {
        let e = DVec2::new(0.6, -0.8);
        let w = GaussianWeight::along(e, 0.4, -0.12, 0.25).expect("visible");
        let (m, mean, c) = w.tilted().expect("a Gaussian");
        let (mu, s2) = (-0.3, 0.25 / 0.4 - 0.09);
        assert!((m - 0.4).abs() < 1e-12, "{m}");
        assert!((mean - e * mu).length() < 1e-12, "{mean}");
        assert!((e.dot(c * e) - s2).abs() < 1e-12, "{c}");
        assert!((e.perp().dot(c * e.perp()) - 1.0).abs() < 1e-12, "{c}");
        assert!(e.dot(c * e.perp()).abs() < 1e-12, "{c}");
        // Its own moments by quadrature along e.
        let l = DMat2::IDENTITY;
        let q = |f: &dyn Fn(f64) -> f64| quadrature(|z| w.at(z) * f(e.dot(z)), DVec2::ZERO, l, 40);
        assert!((q(&|_| 1.0) - 0.4).abs() < 1e-9);
        assert!((q(&|a| a) + 0.12).abs() < 1e-9);
        assert!((q(&|a| a * a) - 0.25).abs() < 1e-9);
        assert!(GaussianWeight::along(e, 0.0, 0.0, 0.0).is_none());
        assert!(GaussianWeight::along(e, f64::NAN, 0.0, 0.0).is_none());
        // A step's moments (no variance left) still give a finite weight.
        let step = GaussianWeight::along(e, 0.5, 0.5 * 0.8, 0.5 * 0.64).expect("visible");
        assert!(
            step.tilted()
                .is_some_and(|(m, _, _)| (m - 0.5).abs() < 1e-9)
        );
    }

    /// Products, powers and expectations under a Gaussian against a 48 × 48 Gauss–Hermite
    /// quadrature of the same functions: a full, a rank-one and a zero covariance.
    #[test]
    fn expectations_are_the_quadratures() {
        let a = GaussianWeight::along(DVec2::new(1.0, 0.0), 0.7, -0.2, 0.5).expect("a");
        let b = GaussianWeight::along(DVec2::new(-0.6, 0.8), 0.5, 0.15, 0.3).expect("b");
        let w = a * b.powf(0.6);
        for (mu, l) in [
            (
                DVec2::new(0.3, -0.5),
                DMat2::from_cols(DVec2::new(0.7, 0.2), DVec2::new(0.0, 0.4)),
            ),
            (
                DVec2::new(-0.2, 0.1),
                DMat2::from_cols(DVec2::new(0.5, -0.3), DVec2::ZERO),
            ),
            (DVec2::ZERO, DMat2::IDENTITY),
        ] {
            let want = quadrature(|z| a.at(z) * b.at(z).powf(0.6), mu, l, 48);
            let got = w.expect_under(mu, l).expect("converges");
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "{mu} {l}: {got} vs {want}"
            );
        }
        let mu = DVec2::new(0.4, 0.9);
        assert!((w.expect_under(mu, DMat2::ZERO).expect("a point") - w.at(mu)).abs() < 1e-12);
        // The tilted Gaussian's moments are the weight's.
        let (m, mean, c) = w.tilted().expect("a Gaussian");
        let l = DMat2::IDENTITY;
        let e1 = quadrature(|z| w.at(z) * z.x, DVec2::ZERO, l, 48) / m;
        let e2 = quadrature(|z| w.at(z) * z.y, DVec2::ZERO, l, 48) / m;
        let exy = quadrature(|z| w.at(z) * z.x * z.y, DVec2::ZERO, l, 48) / m;
        assert!((mean - DVec2::new(e1, e2)).length() < 1e-9, "{mean}");
        assert!((c.x_axis.y - (exy - e1 * e2)).abs() < 1e-9, "{c}");
        assert_eq!(c.x_axis.y, c.y_axis.x);
    }

    /// A weight that rises faster than the Gaussian falls has no expectation: `None`, never an
    /// infinity or NaN; `ONE` is 1 under any Gaussian.
    #[test]
    fn divergent_weights_are_none() {
        let wide = GaussianWeight::along(DVec2::X, 1.0, 0.0, 10.0).expect("wide");
        assert!(wide.tilted().is_some());
        assert!(wide.powf(3.0).tilted().is_none());
        assert!(
            wide.powf(3.0)
                .expect_under(DVec2::ZERO, DMat2::IDENTITY * 2.0)
                .is_none()
        );
        let huge = GaussianWeight {
            log_scale: 800.0,
            ..GaussianWeight::ONE
        };
        assert!(huge.expect_under(DVec2::ZERO, DMat2::IDENTITY).is_none());
        for l in [DMat2::ZERO, DMat2::IDENTITY * 3.0] {
            let one = GaussianWeight::ONE.expect_under(DVec2::new(5.0, -2.0), l);
            assert_eq!(one, Some(1.0));
        }
    }
}
