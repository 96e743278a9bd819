//! The base BRDF of the micro-facets: Lambertian diffuse plus a Beckmann specular lobe written in slope
//! space, so that convolving it with a Gaussian slope distribution only adds variances
//! (`σ_n² + σ_n0²` [HN12 Sec. 5.5]).
//!
//! All functions return `ρ(n, ωo, ωi)·(n·ωi)⁺`, the reflected radiance toward ωo of a facet with unit
//! normal n under unit irradiance from the directional light ωi (directions in the macro tangent frame).
//!
//! Specular, per facet: `F0 · N(s_h − s_n; 0, σ_n0² I) / (4 h_z⁴ ωo_z)` for a facet facing both
//! directions, where `s_h`, `s_n` are the slopes of the half vector and of the facet normal. Averaged
//! over facet slopes `s_n ~ N(s̄, Σ)` with weight ωo_z it becomes the macro Beckmann lobe
//! `F0 · N(s_h; s̄, Σ + σ_n0² I) / (4 h_z⁴ ωo_z)`: the "bumps become roughness" of [HN12 Fig. 12].
//! The base lobe carries no masking term of its own: masking comes from the explicit geometry
//! (ground truth) or from Smith's model (filtered).

use crate::slopes::SlopeCov;
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_1_PI, TAU};

/// Base BRDF parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BaseBrdf {
    /// Diffuse albedo scale applied to the colour map's linear RGB, in [0, 1].
    pub albedo: f64,
    /// Specular reflectance at normal incidence F0 (grey), in [0, 1].
    pub specular: f64,
    /// Base roughness σ_n0: standard deviation of the base BRDF's facet slopes (Beckmann α = √2 σ_n0).
    pub roughness: f64,
}

impl Default for BaseBrdf {
    fn default() -> Self {
        Self {
            albedo: 1.0,
            specular: 0.0,
            roughness: 0.2,
        }
    }
}

/// Slope `(−n_x/n_z, −n_y/n_z)` of a unit vector with n_z > 0.
pub fn slope_of(n: DVec3) -> DVec2 {
    DVec2::new(-n.x, -n.y) / n.z.max(1e-300)
}

/// Unit normal of a facet of slope s: `(−s_x, −s_y, 1)/√(1 + |s|²)`.
pub fn normal_of(s: DVec2) -> DVec3 {
    DVec3::new(-s.x, -s.y, 1.0).normalize()
}

/// Bivariate normal density of `d` under covariance `c` (0 for a singular covariance unless d = 0
/// along the degenerate axis; a tiny floor keeps it finite).
pub fn gaussian2(d: DVec2, c: SlopeCov) -> f64 {
    let (xx, yy) = (c.xx.max(1e-14), c.yy.max(1e-14));
    let det = (xx * yy - c.xy * c.xy).max(1e-28);
    let q = (yy * d.x * d.x - 2.0 * c.xy * d.x * d.y + xx * d.y * d.y) / det;
    (-0.5 * q).exp() / (TAU * det.sqrt())
}

impl BaseBrdf {
    /// Diffuse part for a facet of colour `albedo_rgb`: `albedo·C/π · (n·ωi)⁺`.
    pub fn diffuse(&self, n: DVec3, wi: DVec3) -> f64 {
        self.albedo * FRAC_1_PI * n.dot(wi).max(0.0)
    }

    /// Specular part for a facet of normal n (see the module docs); `extra` is an added slope
    /// covariance (the unresolved slopes of the filtered model; zero for an explicit facet).
    pub fn specular_with(&self, n: DVec3, wo: DVec3, wi: DVec3, extra: SlopeCov) -> f64 {
        if self.specular <= 0.0
            || n.dot(wi) <= 0.0
            || n.dot(wo) <= 0.0
            || wo.z <= 0.0
            || wi.z <= 0.0
        {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        if h.z <= 1e-9 {
            return 0.0;
        }
        let s0 = self.roughness.max(0.0);
        let cov = extra + SlopeCov::isotropic(s0);
        let d = gaussian2(slope_of(h) - slope_of(n), cov);
        self.specular * d / (4.0 * h.z.powi(4) * wo.z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::gauss_hermite_normal;

    #[test]
    fn lambert_reflects_albedo_over_pi() {
        let b = BaseBrdf {
            albedo: 0.8,
            specular: 0.0,
            roughness: 0.1,
        };
        let wi = DVec3::new(0.6, 0.0, 0.8);
        assert!((b.diffuse(DVec3::Z, wi) - 0.8 * 0.8 / std::f64::consts::PI).abs() < 1e-15);
        assert_eq!(
            b.diffuse(DVec3::Z, DVec3::new(1.0, 0.0, -0.1).normalize()),
            0.0
        );
    }

    #[test]
    fn averaging_facets_widens_the_lobe() {
        // E_{s_n ~ N(0, Σ)}[N(s_h − s_n; σ0²)] = N(s_h; Σ + σ0²): checked by 2D Gauss–Hermite.
        let b = BaseBrdf {
            albedo: 0.0,
            specular: 1.0,
            roughness: 0.15,
        };
        let sigma = SlopeCov::from_std(0.2, 0.1);
        let wo = DVec3::new(0.3, 0.1, 0.9).normalize();
        let wi = DVec3::new(-0.2, 0.25, 0.8).normalize();
        let (x, w) = gauss_hermite_normal(40);
        let mut avg = 0.0;
        for (xa, wa) in x.iter().zip(&w) {
            for (xb, wb) in x.iter().zip(&w) {
                let s = DVec2::new(xa * sigma.xx.sqrt(), xb * sigma.yy.sqrt());
                // Facet normal from slope; the specular density depends on the slope only.
                let h = (wo + wi).normalize();
                let d = gaussian2(slope_of(h) - s, SlopeCov::isotropic(0.15));
                avg += wa * wb * d;
            }
        }
        let h = (wo + wi).normalize();
        let want = gaussian2(slope_of(h), sigma + SlopeCov::isotropic(0.15));
        assert!((avg - want).abs() < 1e-9 * want, "{avg} vs {want}");
        let macro_lobe = b.specular_with(DVec3::Z, wo, wi, sigma);
        assert!((macro_lobe - want / (4.0 * h.z.powi(4) * wo.z)).abs() < 1e-12);
    }
}
