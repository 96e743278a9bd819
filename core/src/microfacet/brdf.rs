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

use crate::microfacet::slopes::{SlopeCov, slope_of};
use crate::microfacet::visible_slopes::expected_positive_part;
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_1_PI, TAU};

/// Base BRDF parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BaseBrdf {
    /// Diffuse albedo scale applied to the colour map's linear RGB, in [0, 1].
    pub albedo: f64,
    /// Specular reflectance at normal incidence F0 (grey), in [0, 1].
    pub specular: f64,
    /// Base roughness σ_n0: standard deviation of the base BRDF's facet slopes (Beckmann α = √2 σ_n0).
    pub roughness: f64,
    /// A measured BRDF (a MERL `.binary` file, its path relative to the preset's folder) that
    /// replaces this analytic one: albedo, specular and roughness are then unused, the views take
    /// the table or its fit ([`crate::material::measured`]). `None`: the analytic BRDF.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measured: Option<String>,
}

impl Default for BaseBrdf {
    fn default() -> Self {
        Self {
            albedo: 1.0,
            specular: 0.0,
            roughness: 0.2,
            measured: None,
        }
    }
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
    /// Diffuse part of a facet, `albedo/π · (n·ωi)⁺` (the caller multiplies by the facet's colour C).
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

    /// The largest [`specular_with`](Self::specular_with) any facet gives the pair (ωo, ωi) with
    /// no added covariance: the lobe at its peak (facet normal along the half vector),
    /// `F0 / (2π σ_n0²) / (4 h_z⁴ ωo_z)`. What one ground-truth ray's specular term can reach, for
    /// sampling rules that must not stop before rare glints had their chance to be seen
    /// (`lodestone diagnose`). 0 when F0 = 0 or either direction is at or below the horizon;
    /// σ_n0² is floored at 1e-14 as in [`gaussian2`], so it stays finite as σ_n0 → 0.
    pub fn specular_peak(&self, wo: DVec3, wi: DVec3) -> f64 {
        if !(self.specular > 0.0 && wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        if h.z <= 1e-9 {
            return 0.0;
        }
        let v = (self.roughness * self.roughness).max(1e-14);
        self.specular / (TAU * v) / (4.0 * h.z.powi(4) * wo.z)
    }
}

/// Specular averaged over D_s, in world slope space with facet slopes `s ~ N(s̄, Σ)` each carrying
/// the base lobe `N(s_h − s; σ0²I)` (the explicit facets' BRDF, [`crate::microfacet::brdf`]) and weighted by its
/// projected area `u⁺(s)`, `u(s) = ωo_z − s·ωo_xy` (docs/design/filtered-model.md, "Visible slope distribution"):
///
/// `F0·∫N(s; s̄, Σ)N(s_h − s; σ0²I)u⁺(s)ds / (4 h_z⁴ ωo_z E[u⁺])
///  = F0·N(s_h − s̄; Σ + σ0²I)·E_post[u⁺] / (4 h_z⁴ ωo_z E[u⁺])`,
///
/// exactly, because the product of the two Gaussians is the convolved lobe times the posterior
/// `N(s*, Σ*)`, `s* = s̄ + K(s_h − s̄)`, `Σ* = Σ − KΣ`, `K = Σ(Σ + σ0²I)⁻¹`; both expectations of u⁺
/// are closed forms ([`expected_positive_part`]). With σ0 = 0 the posterior is the point s_h; when the
/// base lobe dominates (σ0 ≫ Σ) it is the footprint's own distribution and the ratio is 1. (Taking u
/// at s_h for every base roughness, as before, overestimated grazing highlights: 2.5× at 75° with
/// σ0 = 0.25, σ_n = 0.1.)
pub fn filtered_specular(
    f0: f64,
    roughness: f64,
    mean: DVec2,
    sigma: &SlopeCov,
    wo: DVec3,
    wi: DVec3,
) -> f64 {
    if f0 <= 0.0 || wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let h = (wo + wi).normalize();
    if h.z <= 1e-9 {
        return 0.0;
    }
    let sh = slope_of(h);
    let b = DVec2::new(wo.x, wo.y);
    let s0 = roughness.max(0.0);
    let total = *sigma + SlopeCov::isotropic(s0);
    let (post_mean, post_cov) = lobe_posterior(mean, sigma, sh, roughness);
    let u_post = expected_positive_part(wo.z, b, post_mean, &post_cov);
    let eu = expected_positive_part(wo.z, b, mean, sigma);
    let d = gaussian2(sh - mean, total);
    f0 * d * (u_post / eu.max(1e-300)) / (4.0 * h.z.powi(4) * wo.z)
}

/// The facet slopes that carry a lobe: facet slopes `N(s̄, Σ)` times the base lobe
/// `N(s_h − s; σ0²I)` is, up to a constant, `N(s*, Σ*)` with `s* = s̄ + K(s_h − s̄)`,
/// `Σ* = Σ − KΣ`, `K = Σ(Σ + σ0²I)⁻¹` (its diagonal floored at 0 against round-off). When both
/// are degenerate (Σ = 0, σ0 = 0) the point s_h.
pub fn lobe_posterior(
    mean: DVec2,
    sigma: &SlopeCov,
    sh: DVec2,
    roughness: f64,
) -> (DVec2, SlopeCov) {
    let total = *sigma + SlopeCov::isotropic(roughness.max(0.0));
    let (sm, cm) = (sigma.to_mat(), total.to_mat());
    let det = cm.determinant();
    if !(det > 1e-30 && det.is_finite()) {
        return (sh, SlopeCov::default());
    }
    let k = sm * cm.inverse();
    let c = SlopeCov::from_mat(sm - k * sm);
    (
        mean + k * (sh - mean),
        SlopeCov {
            xx: c.xx.max(0.0),
            yy: c.yy.max(0.0),
            xy: c.xy,
        },
    )
}

/// [`lobe_posterior`] at the half vector of ωo and ωi: `None` when either is below the horizon
/// or their half vector is not above it.
pub fn half_vector_posterior(
    mean: DVec2,
    sigma: &SlopeCov,
    wo: DVec3,
    wi: DVec3,
    roughness: f64,
) -> Option<(DVec2, SlopeCov)> {
    if !(wo.z > 0.0 && wi.z > 0.0) {
        return None;
    }
    let h = (wo + wi).normalize();
    (h.z > 1e-9).then(|| lobe_posterior(mean, sigma, slope_of(h), roughness))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::quadrature::gauss_hermite_normal;
    use crate::scene::direction::direction;

    #[test]
    fn specular_peak_bounds_every_facet_and_is_reached_at_the_half_vector() {
        let b = BaseBrdf {
            albedo: 0.5,
            specular: 0.6,
            roughness: 0.04,
            measured: None,
        };
        for (tv, tl, az) in [(1.31, 0.52, 0.0), (0.2, 0.9, 2.5), (1.5, 1.5, 3.1)] {
            let (wo, wi) = (direction(tv, 0.0), direction(tl, az));
            let peak = b.specular_peak(wo, wi);
            let h = (wo + wi).normalize();
            let at_h = b.specular_with(h, wo, wi, SlopeCov::isotropic(0.0));
            assert!((at_h - peak).abs() <= 1e-9 * peak, "{at_h} vs {peak}");
            // Brute force over facet slopes around the half vector's.
            for i in -20..=20 {
                for j in -20..=20 {
                    let s = slope_of(h) + DVec2::new(f64::from(i), f64::from(j)) * 0.01;
                    let n = DVec3::new(-s.x, -s.y, 1.0).normalize();
                    let v = b.specular_with(n, wo, wi, SlopeCov::isotropic(0.0));
                    assert!(v <= peak * (1.0 + 1e-12), "{v} > {peak}");
                }
            }
        }
        assert_eq!(
            b.specular_peak(direction(1.0, 0.0), direction(1.7, 0.0)),
            0.0
        );
        let sharp = BaseBrdf {
            roughness: 0.0,
            ..b
        };
        assert!(sharp.specular_peak(DVec3::Z, DVec3::Z).is_finite());
    }

    #[test]
    fn lambert_reflects_albedo_over_pi() {
        let b = BaseBrdf {
            albedo: 0.8,
            specular: 0.0,
            roughness: 0.1,
            measured: None,
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
            measured: None,
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

    /// The filtered specular equals the explicit facets' lobes averaged over the visible slopes,
    /// by brute-force quadrature over s, for isotropic and anisotropic footprints, base lobes from
    /// narrower to much wider than the footprint, and views up to 80°.
    #[test]
    fn filtered_specular_is_the_visible_average_of_the_facet_lobes() {
        let sigmas = [
            (DVec2::ZERO, SlopeCov::isotropic(0.1)),
            (
                DVec2::new(0.1, -0.05),
                SlopeCov {
                    xx: 0.09,
                    yy: 0.01,
                    xy: 0.02,
                },
            ),
            (DVec2::ZERO, SlopeCov::isotropic(0.35)),
        ];
        for (mean, sigma) in sigmas {
            for s0 in [0.05, 0.25] {
                for (wo, wi) in [
                    (direction(0.5, 0.3), direction(0.7, 2.9)),
                    (
                        direction(75f64.to_radians(), 0.0),
                        direction(30f64.to_radians(), std::f64::consts::PI),
                    ),
                    (
                        direction(80f64.to_radians(), 1.0),
                        direction(60f64.to_radians(), 1.3),
                    ),
                ] {
                    let h = (wo + wi).normalize();
                    let sh = slope_of(h);
                    // The grid covers the footprint's slopes and the half vector's (the posterior lies between).
                    let reach = (sh - mean).abs();
                    let (sx, sy) = (
                        sigma.xx.sqrt() + reach.x / 6.0,
                        sigma.yy.sqrt() + reach.y / 6.0,
                    );
                    let n = 500;
                    let (mut num, mut den) = (0.0, 0.0);
                    for j in 0..n {
                        for i in 0..n {
                            let s = mean
                                + DVec2::new(
                                    (i as f64 + 0.5) / n as f64 * 12.0 * sx - 6.0 * sx,
                                    (j as f64 + 0.5) / n as f64 * 12.0 * sy - 6.0 * sy,
                                );
                            let p = gaussian2(s - mean, sigma);
                            let u = (wo.z - s.x * wo.x - s.y * wo.y).max(0.0);
                            // The explicit facet's lobe in slope space (brdf::specular_with without
                            // its facet-horizon cut, which the statistics do not model).
                            let lobe = gaussian2(sh - s, SlopeCov::isotropic(s0))
                                / (4.0 * h.z.powi(4) * wo.z);
                            num += p * u * lobe;
                            den += p * u;
                        }
                    }
                    let want = num / den;
                    // den is E[u⁺] over the grid, which must cover the footprint's slopes too.
                    assert!(den > 0.0);
                    let got = filtered_specular(1.0, s0, mean, &sigma, wo, wi);
                    assert!(
                        (got - want).abs() < 2e-3 * want + 1e-9,
                        "σ {sigma:?}, σ0 {s0}, wo {wo:?}: closed form {got} vs quadrature {want}"
                    );
                }
            }
        }
    }
}
