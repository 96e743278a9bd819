//! The visible slope distribution D_s(ω_o) [HNPN14 Sec. 5.2], for averaging a slope-dependent
//! quantity (the clamped cosine, slope-correlated colour C_s(n), irradiance) over what a viewer sees
//! of a footprint.
//!
//! **What the renderer runs**: [`visible_slope_nodes`], the polar rule [`slope_rule`] over N(μ, Σ)
//! with each node weighted by its projected area (a − b·s)⁺ (exact D_s, no approximation; WGSL
//! `visible_slope_nodes` mirrors it). [`slope_mean`] is the same rule without the weight (a
//! mip-mapped slope texture). [`VisibleSlopes`] is the Gaussian approximation, kept as the
//! derivation and the measurement below (and for a single-Gaussian lobe where one is wanted).
//!
//! A footprint's facet slopes are `s ~ N(μ, Σ)` (world slope space, `n ∝ (−s_x, −s_y, 1)`). A
//! facet's projected area toward ω_o, per unit of macro-surface area, is `(a − b·s)⁺` with
//! `a = ω_o,z` and `b = ω_o,xy` (`n·ω_o / n_z`). So
//!
//! ```text
//! D_s(s) = N(s; μ, Σ) · (a − b·s)⁺ / Z,      Z = E[(a − b·s)⁺] = √v · (r Φ(r) + φ(r)),
//! m = a − b·μ,   v = bᵀ Σ b,   r = m / √v.
//! ```
//!
//! **Its mean and covariance, exactly** (Stein's lemma: `E[(s−μ) g(s)] = Σ E[∇g]` and
//! `E[(s−μ)(s−μ)ᵀ g] = Σ E[g] + Σ E[∇∇ᵀ g] Σ`, with `∇g = −b·1[a − b·s > 0]` and
//! `∇∇ᵀ g = b bᵀ δ(a − b·s)`, whose expectations are `−b Φ(r)` and `b bᵀ φ(r)/√v`):
//!
//! ```text
//! E_D[s]   = μ − Σb · κ₁/√v
//! Cov_D[s] = Σ − (Σb)(Σb)ᵀ · (κ₁² − κ₂)/v,
//! κ₁ = Φ(r) / (r Φ(r) + φ(r)),   κ₂ = φ(r) / (r Φ(r) + φ(r)).
//! ```
//!
//! Only the direction Σb changes: seen from ω_o, the visible facets lean toward the viewer and
//! their spread along b shrinks (0 ≤ κ₁² − κ₂ ≤ 1). Limits: facing the viewer broadly (r → +∞)
//! the mean moves by Σb/m and the covariance is unchanged to first order; at grazing, where most
//! facets face away (r → −∞), the mean goes to the silhouette line `b·s = a` and the variance
//! across it to 0. Both ratios use the Mills ratio `R = Φ/φ = √(π/2)·erfcx(−r/√2)`
//! (`κ₁ = R/(rR + 1)`, `κ₂ = 1/(rR + 1)`) and, for r ≤ −1 where `rR + 1` cancels, the Mills
//! ratio's continued fraction, which gives both ratios without cancellation; every output is
//! finite for finite inputs.
//!
//! **The approximation.** D_s is not Gaussian (it is a Gaussian times a ramp, cut at the
//! silhouette); [`VisibleSlopes::average`] integrates against `N(E_D[s], Cov_D[s])` on the polar
//! rule [`slope_rule`] (n radii × n angles). The alternative needs no approximation: the same rule
//! over N(μ, Σ) with each node weighted by its projected area (a − b·s)⁺
//! ([`visible_slope_nodes`]). The test
//! `gaussian_average_against_the_exact_visible_distribution` measures both for a snow-on-the-flats
//! colour (white under slope 0.2, rock above 0.8, a C¹ smooth step in |s|) on anisotropic,
//! correlated slopes σ = (0.5, 0.3), against the exact D_s (900² brute force); maximum relative
//! error over RGB for n = 1, 2, 3, 4, 8, 16:
//!
//! | view | Gaussian D_s (this module) | nodes of N(μ, Σ) weighted by (a − b·s)⁺ |
//! |---|---|---|
//! | 0° | 64%, 18%, 2.2%, 1.6%, 0.02%, 0.01% | the same (D_s = N(μ, Σ)) |
//! | 30° | 60%, 17%, 0.8%, 1.0%, 0.16%, 0.10% | 60%, 20%, 4.2%, 1.2%, 0.01%, 0.01% |
//! | 60° | 45%, 9.3%, 2.8%, 2.6%, 3.3%, 3.3% | 60%, 31%, 8.7%, 0.45%, 0.07%, 0.02% |
//! | 80° | 4.9%, 18%, 0.5%, 5.3%, 5.2%, 5.2% | 92%, 68%, 13%, 0.59%, 0.33%, 0.05% |
//!
//! So the Gaussian approximation has a floor of 3–5% at 60°–80° (the silhouette cut) that no
//! number of points removes, while the weighted nodes converge: within 1.6% from n = 4 and 0.33%
//! at n = 8 (the default, 64 nodes) at every angle. **The renderer therefore uses the weighted
//! nodes** ([`crate::eval::Evaluator::filtered`], and its WGSL mirror); this module stays as the
//! derivation, the measurement, and the closed-form mean and covariance of what a viewer sees
//! (useful wherever a single Gaussian is wanted, e.g. a lobe or a pre-convolved lookup). With the
//! earlier n×n Gauss–Hermite product rule the weighted nodes needed n ≥ 16 at grazing (20% at 80°
//! with n = 4 and 8); the polar rule is what made n = 4–8 enough.

use crate::math::gaussian::cholesky;
use crate::math::special::{erfcx, norm_cdf, norm_pdf};
use crate::microfacet::slope_rule::SlopeRule;
use crate::microfacet::slopes::SlopeCov;
use crate::microfacet::slopes::normal_of;
use glam::{DVec2, DVec3};

/// The Gaussian approximation of D_s(ω_o): its exact mean and covariance, and Z (the footprint's
/// mean projected area toward ω_o per unit of macro area, `E[(n·ω_o)⁺/n_z]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisibleSlopes {
    /// E_D[s].
    pub mean: DVec2,
    /// Cov_D[s].
    pub cov: SlopeCov,
    /// Z = E[(a − b·s)⁺] ≥ 0.
    pub projected_area: f64,
}

/// `g₁(x)` of the Mills ratio's continued fraction `Φ̄(x)/φ(x) = 1/(x + 1/g₁)`,
/// `g_k = x + (k+1)/g_{k+1}`, evaluated backward from depth `depth` (x > 0).
fn mills_tail(x: f64, depth: u32) -> f64 {
    let mut g = x;
    for k in (1..depth).rev() {
        g = x + f64::from(k + 1) / g;
    }
    g
}

/// (κ₁, κ₂) of the module docs, for r = m/√v; finite for every finite r.
///
/// For r ≤ −1 (x = −r ≥ 1) the continued fraction gives both without cancellation:
/// `R = g₁/(x g₁ + 1)` and `rR + 1 = 1/(x g₁ + 1)`, so `κ₁ = g₁` and `κ₂ = x g₁ + 1` (depth 400:
/// converged to 1e-13 at x = 1, see the tests). Above, `R = √(π/2)·erfcx(−r/√2)` directly.
fn kappas(r: f64) -> (f64, f64) {
    if r <= -1.0 {
        kappas_continued_fraction(-r)
    } else {
        kappas_erfcx(r)
    }
}

/// κ's from the continued fraction, x = −r > 0.
fn kappas_continued_fraction(x: f64) -> (f64, f64) {
    let x = x.min(1e150);
    let g1 = mills_tail(x, 400);
    (g1, x * g1 + 1.0)
}

/// κ's from `R = √(π/2)·erfcx(−r/√2)`. R saturates at f64::MAX for r > 37.6 (φ underflows):
/// then κ₁ = 1/r and κ₂ = 0, as written.
fn kappas_erfcx(r: f64) -> (f64, f64) {
    let mills = (std::f64::consts::PI / 2.0).sqrt() * erfcx(-r / std::f64::consts::SQRT_2);
    (1.0 / (r + 1.0 / mills), 1.0 / (r * mills + 1.0))
}

impl VisibleSlopes {
    /// D_s for slopes `N(mean, sigma)` seen from the unit direction `wo` (see the module docs).
    /// When no slope variance lies along ω_o's horizontal direction (v = 0: the normal view, or
    /// Σb = 0) every facet has the same projected area and D_s is N(μ, Σ) itself.
    pub fn new(mean: DVec2, sigma: &SlopeCov, wo: DVec3) -> Self {
        let (a, b) = (wo.z, wo.truncate());
        let m = a - mean.dot(b);
        let sb = DVec2::new(
            sigma.xx * b.x + sigma.xy * b.y,
            sigma.xy * b.x + sigma.yy * b.y,
        );
        let v = b.dot(sb);
        if !(v > 1e-300) || !v.is_finite() || !m.is_finite() {
            return Self {
                mean,
                cov: *sigma,
                projected_area: m.max(0.0),
            };
        }
        let sv = v.sqrt();
        let r = m / sv;
        let (k1, k2) = kappas(r);
        let shrink = ((k1 * k1 - k2) / v).max(0.0);
        let cov = SlopeCov {
            xx: (sigma.xx - sb.x * sb.x * shrink).max(0.0),
            yy: (sigma.yy - sb.y * sb.y * shrink).max(0.0),
            xy: sigma.xy - sb.x * sb.y * shrink,
        };
        let projected_area = expected_positive_part(a, b, mean, sigma).max(0.0);
        Self {
            mean: mean - sb * (k1 / sv),
            cov,
            projected_area,
        }
    }

    /// `E[f(s)]` over `N(mean, cov)` on the polar rule [`slope_rule`] with n² nodes (n clamped to
    /// 1..=32; n = 1 is `f(mean)`). Error against n and against the exact D_s: see the module docs.
    pub fn average(&self, n: usize, f: impl Fn(DVec2) -> DVec3) -> DVec3 {
        slope_nodes(self.mean, &self.cov, n).fold(DVec3::ZERO, |sum, (s, w)| sum + f(s) * w)
    }
}

/// The quadrature rule over a standard bivariate normal used for every average over a footprint's
/// slopes, with `n` radii × `n` angles (n² nodes; a material with a slope colour doubles the
/// angles, [`SlopeRule::for_material`]), cached per n:
/// nodes `z` and weights summing to 1, so `E[q(s)] ≈ Σ w q(μ + L z)` for `s ~ N(μ, LLᵀ)`.
///
/// Polar: the radius is Gauss–Legendre in the radial CDF `u = 1 − exp(−r²/2)` (`r = √(−2 ln(1 − u))`,
/// every ring carrying its probability), the angle uniform (trapezoid, exact for trigonometric
/// polynomials of degree < n), odd rings turned by half a step. n = 1 is the mean. Why not the n×n
/// Gauss–Hermite product used before: its nodes sit on few radii with large weights, so a colour
/// that changes with the facet's tilt (snow above a slope angle: a function of |s|) is integrated
/// erratically — measured on `presets/snow-under-sky.ron`'s map, σ = 0.45, view 53°: product GH
/// errors −7.5%, +13%, +11%, +1.0%, −1.3% at n = 4, 6, 8, 12, 16; this rule +1.7%, +0.30%, −0.06%,
/// −0.03%, +0.02%; for the clamped cosine both are within 0.1% from n = 6 (GH +0.03%, this +0.04% at
/// n = 8). Tested in `slope_rule_tests`.
pub fn slope_rule(n: usize) -> &'static [(DVec2, f64)] {
    SlopeRule::square(n).nodes()
}

/// The nodes of the visible slope distribution D_s ∝ N(s; s̄, Σ)·u⁺(s), `u(s) = ωo_z − s·ωo_xy`
/// [HNPN14 Sec. 5.2], on [`slope_rule`]: `visit(n(s), w)` for each node of N(s̄, Σ) with positive
/// weight `w = w_k u⁺(s)`; returns the sum of the weights (divide by it). (The Gaussian
/// approximation of D_s, [`crate::microfacet::visible_slopes::VisibleSlopes`], was measured against weighting
/// the nodes: it has a 3–5% floor at 60°–80°; see that module.)
pub fn visible_slope_nodes(
    mean: DVec2,
    sigma: &SlopeCov,
    wo: DVec3,
    rule: impl Into<SlopeRule>,
    mut visit: impl FnMut(DVec3, f64),
) -> f64 {
    let mut den = 0.0;
    for (s, w) in slope_nodes(mean, sigma, rule) {
        let wt = w * (wo.z - s.x * wo.x - s.y * wo.y).max(0.0);
        if wt > 0.0 {
            visit(normal_of(s), wt);
            den += wt;
        }
    }
    den
}

/// The nodes of [`slope_rule`] mapped onto slopes `s ~ N(mean, Σ)` (`s = mean + L z`, L the
/// Cholesky factor of Σ), with their weights.
pub(crate) fn slope_nodes(
    mean: DVec2,
    sigma: &SlopeCov,
    rule: impl Into<SlopeRule>,
) -> impl Iterator<Item = (DVec2, f64)> {
    let (l11, l21, l22) = cholesky(sigma.xx, sigma.xy, sigma.yy);
    rule.into()
        .nodes()
        .iter()
        .map(move |(z, w)| (mean + DVec2::new(l11 * z.x, l21 * z.x + l22 * z.y), *w))
}

/// `E[q(n(s))]` over N(s̄, Σ) without any visibility weight ([`slope_rule`]): the footprint
/// average of a slope-indexed texture.
pub fn slope_mean(
    mean: DVec2,
    sigma: &SlopeCov,
    rule: impl Into<SlopeRule>,
    q: impl Fn(DVec3) -> [f64; 3],
) -> [f64; 3] {
    let mut acc = [0.0; 3];
    for (s, w) in slope_nodes(mean, sigma, rule) {
        let v = q(normal_of(s));
        for c in 0..3 {
            acc[c] += w * v[c];
        }
    }
    acc
}

/// `E[u⁺]` for `u = a − s·b` with `s ~ N(mean, Σ)`: `mΦ(m/√v) + √v φ(m/√v)`, `m = a − mean·b`,
/// `v = bᵀΣb` — the normaliser Z of the visible slope distribution (its projected area).
///
/// Edge cases: `m⁺` when v ≤ 1e-300 (no spread along b); `m/√v` is clamped to ±40, where the
/// result is `m` or 0 to f64 precision, so it is finite and ≥ 0 for finite inputs.
pub fn expected_positive_part(a: f64, b: DVec2, mean: DVec2, sigma: &SlopeCov) -> f64 {
    let m = a - mean.dot(b);
    let v = b.x * b.x * sigma.xx + 2.0 * b.x * b.y * sigma.xy + b.y * b.y * sigma.yy;
    if v > 1e-300 {
        let sv = v.sqrt();
        let r = (m / sv).clamp(-40.0, 40.0);
        m * norm_cdf(r) + sv * norm_pdf(r)
    } else {
        m.max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::direction::direction;
    use proptest::prelude::*;

    /// Brute-force E_D[f] over the exact D_s: a 2-D midpoint rule over ±9σ of the principal axes.
    fn exact(mean: DVec2, sigma: &SlopeCov, wo: DVec3, f: impl Fn(DVec2) -> [f64; 6]) -> [f64; 6] {
        let (l11, l21, l22) = {
            let l11 = sigma.xx.sqrt();
            let l21 = sigma.xy / l11;
            (l11, l21, (sigma.yy - l21 * l21).sqrt())
        };
        let n = 900;
        let h = 18.0 / n as f64;
        let (mut acc, mut den) = ([0.0; 6], 0.0);
        for i in 0..n {
            let za = -9.0 + (i as f64 + 0.5) * h;
            for j in 0..n {
                let zb = -9.0 + (j as f64 + 0.5) * h;
                let s = mean + DVec2::new(l11 * za, l21 * za + l22 * zb);
                let w =
                    (-0.5 * (za * za + zb * zb)).exp() * (wo.z - wo.x * s.x - wo.y * s.y).max(0.0);
                let v = f(s);
                for k in 0..6 {
                    acc[k] += w * v[k];
                }
                den += w;
            }
        }
        acc.map(|a| a / den)
    }

    fn sigma() -> SlopeCov {
        SlopeCov {
            xx: 0.25,
            yy: 0.09,
            xy: 0.06,
        }
    }

    #[test]
    fn moments_equal_brute_force_over_the_exact_distribution() {
        let mu = DVec2::new(0.1, -0.2);
        for (theta_deg, phi) in [
            (0.0, 0.0),
            (30.0, 0.4),
            (60.0, 2.0),
            (75.0, -1.0),
            (85.0, 0.9),
            (89.0, 3.0),
        ] {
            let wo = direction(f64::to_radians(theta_deg), phi);
            let d = VisibleSlopes::new(mu, &sigma(), wo);
            let e = exact(mu, &sigma(), wo, |s| {
                [s.x, s.y, s.x * s.x, s.y * s.y, s.x * s.y, 1.0]
            });
            let cov = [e[2] - e[0] * e[0], e[3] - e[1] * e[1], e[4] - e[0] * e[1]];
            let tol = 2e-4;
            assert!(
                (d.mean.x - e[0]).abs() < tol && (d.mean.y - e[1]).abs() < tol,
                "{theta_deg}°: mean {:?} vs {:?}",
                d.mean,
                &e[..2]
            );
            assert!(
                (d.cov.xx - cov[0]).abs() < tol,
                "{theta_deg}°: xx {} vs {}",
                d.cov.xx,
                cov[0]
            );
            assert!(
                (d.cov.yy - cov[1]).abs() < tol,
                "{theta_deg}°: yy {} vs {}",
                d.cov.yy,
                cov[1]
            );
            assert!(
                (d.cov.xy - cov[2]).abs() < tol,
                "{theta_deg}°: xy {} vs {}",
                d.cov.xy,
                cov[2]
            );
        }
    }

    #[test]
    fn the_mills_ratio_branches_agree_and_the_grazing_limit_is_the_silhouette() {
        // The two forms agree where both are accurate (rR + 1 cancels little at r ≥ −3), and the
        // continued fraction has converged.
        for r in [-1.0, -2.0, -3.0] {
            let (a1, a2) = kappas_erfcx(r);
            let (b1, b2) = kappas_continued_fraction(-r);
            assert!(
                (a1 / b1 - 1.0).abs() < 1e-12 && (a2 / b2 - 1.0).abs() < 1e-12,
                "r = {r}: {a1} {b1} {a2} {b2}"
            );
        }
        // Against Φ̄/φ from libm's erfc (Python: 0.5·erfc(3/√2)/φ(3)) at x = 3.
        assert!((kappas(-3.0).0 / 3.532_337_517_625_192 - 1.0).abs() < 1e-13);
        for x in [1.0, 3.0, 5.0, 30.0, 1e4] {
            let (g, h) = (mills_tail(x, 400), mills_tail(x, 4000));
            assert!((g / h - 1.0).abs() < 1e-13, "x = {x}: {g} vs {h}");
        }
        // Asymptotically κ₁ → x and κ₂ → x² (rR + 1 ≈ 1/x²).
        let (k1, k2) = kappas(-1e6);
        assert!((k1 / 1e6 - 1.0).abs() < 1e-9 && (k2 / 1e12 - 1.0).abs() < 1e-9);
        // Most facets face away: the mean goes to the silhouette b·s = a, its spread across to 0.
        let wo = direction(89.9f64.to_radians(), 0.0);
        let mu = DVec2::new(1.0, 0.0); // the mean facet faces away from the viewer
        let d = VisibleSlopes::new(mu, &SlopeCov::isotropic(0.01), wo);
        assert!((d.mean.x * wo.x - wo.z).abs() < 1e-3 * wo.x, "{:?}", d.mean);
        assert!(d.cov.xx < 1e-6 && (d.cov.yy - 1e-4).abs() < 1e-12);
        assert!(d.projected_area >= 0.0 && d.projected_area < 1e-100);
        // The normal view and zero variance change nothing.
        let n = VisibleSlopes::new(mu, &sigma(), DVec3::Z);
        assert_eq!((n.mean, n.cov), (mu, sigma()));
        let z = VisibleSlopes::new(mu, &SlopeCov::default(), wo);
        assert_eq!(z.mean, mu);
    }

    /// Snow on the flats: white under slope 0.2, rock above 0.8 (smooth step over about σ).
    fn snow(s: DVec2) -> DVec3 {
        let t = ((s.length() - 0.2) / 0.6).clamp(0.0, 1.0);
        let k = t * t * (3.0 - 2.0 * t);
        DVec3::splat(0.9).lerp(DVec3::new(0.25, 0.2, 0.15), k)
    }

    #[test]
    fn gaussian_average_against_the_exact_visible_distribution() {
        let mu = DVec2::new(0.05, 0.1);
        let mut table = String::new();
        let mut rows = Vec::new();
        for theta_deg in [0.0, 30.0, 60.0, 80.0] {
            let wo = direction(f64::to_radians(theta_deg), 0.7);
            let d = VisibleSlopes::new(mu, &sigma(), wo);
            let e = exact(mu, &sigma(), wo, |s| {
                let c = snow(s);
                [c.x, c.y, c.z, 0.0, 0.0, 0.0]
            });
            let e = DVec3::new(e[0], e[1], e[2]);
            let rel = |c: DVec3| ((c - e).abs() / e).max_element();
            let by_n: Vec<f64> = [1, 2, 3, 4, 8, 16]
                .iter()
                .map(|n| rel(d.average(*n, snow)))
                .collect();
            // For comparison: no Gaussian approximation, the same rule over N(μ, Σ) with each node
            // weighted by its projected area (a − b·s)⁺ (what footprint::visible_slope_nodes does).
            let all = VisibleSlopes {
                mean: mu,
                cov: sigma(),
                projected_area: 1.0,
            };
            let u = |s: DVec2| (wo.z - wo.truncate().dot(s)).max(0.0);
            let weighted: Vec<f64> = [1, 2, 3, 4, 8, 16]
                .iter()
                .map(|n| {
                    let num = all.average(*n, |s| snow(s) * u(s));
                    let den = all.average(*n, |s| DVec3::splat(u(s)));
                    rel(num / den)
                })
                .collect();
            table +=
                &format!("{theta_deg}°: Gaussian D_s {by_n:.4?}; weighted nodes {weighted:.4?}\n");
            rows.push((by_n, weighted));
        }
        eprintln!(
            "relative error against the exact D_s for n = 1, 2, 3, 4, 8, 16 per axis:\n{table}"
        );
        for (i, (g, w)) in rows.iter().enumerate() {
            // n = 16 leaves the Gaussian approximation's own error: small where D_s is nearly
            // Gaussian (0°, 30°), a few percent at 60°–80° where the silhouette cuts it.
            let bound = [0.005, 0.005, 0.04, 0.06][i];
            assert!(g[5] < bound, "Gaussian D_s, n = 16:\n{table}");
            // The map's clamps are only C¹, so the smallest rules are erratic; the Gaussian D_s
            // keeps n = 3 within 8% at every angle (the weighted nodes: 13% at 80°).
            assert!(g[2] < 0.08, "n = 3:\n{table}");
            // Weighted nodes have no approximation error: they converge to the exact value,
            // within 2% from n = 4 and 0.5% at the default n = 8.
            assert!(w[3] < 0.02, "weighted nodes, n = 4:\n{table}");
            assert!(w[4] < 0.005, "weighted nodes, n = 8:\n{table}");
            assert!(w[5] < 0.002, "weighted nodes, n = 16:\n{table}");
        }
    }

    proptest! {
        #[test]
        fn finite_and_a_valid_covariance_everywhere(
            mx in -1e6f64..1e6, my in -1e6f64..1e6,
            sx in 0.0f64..1e6, sy in 0.0f64..1e6, rho in -1.0f64..1.0,
            theta in 0.0f64..std::f64::consts::FRAC_PI_2, phi in -4.0f64..4.0,
            tiny in prop::bool::ANY,
        ) {
            let (sx, sy) = if tiny { (sx * 1e-12, sy * 1e-12) } else { (sx, sy) };
            let sigma = SlopeCov { xx: sx * sx, yy: sy * sy, xy: rho * sx * sy };
            let d = VisibleSlopes::new(DVec2::new(mx, my), &sigma, direction(theta, phi));
            prop_assert!(d.mean.is_finite() && d.projected_area.is_finite() && d.projected_area >= 0.0);
            prop_assert!(d.cov.xx.is_finite() && d.cov.yy.is_finite() && d.cov.xy.is_finite());
            prop_assert!(d.cov.xx >= 0.0 && d.cov.yy >= 0.0);
            prop_assert!(d.cov.xx <= sigma.xx * (1.0 + 1e-12) && d.cov.yy <= sigma.yy * (1.0 + 1e-12));
            let c = d.average(4, snow);
            prop_assert!(c.is_finite());
        }
    }
}

#[cfg(test)]
mod slope_rule_tests {
    use super::*;

    /// Weights sum to 1, odd moments vanish, the variance converges (slowly: the radial CDF's log
    /// tail; −0.9% at n = 8, which the smooth integrands tested against ground truth do not feel), and
    /// a radial step (a probability of the Gaussian, in closed form) is within 0.5/n.
    #[test]
    fn rule_moments_and_a_radial_step() {
        for n in 2..=16 {
            let r = slope_rule(n);
            let sum = |f: &dyn Fn(DVec2) -> f64| r.iter().map(|(z, w)| w * f(*z)).sum::<f64>();
            assert!((sum(&|_| 1.0) - 1.0).abs() < 1e-12, "n {n}");
            assert!(sum(&|z| z.x).abs() < 1e-12 && sum(&|z| z.y).abs() < 1e-12);
            let var = sum(&|z| z.x * z.x);
            eprintln!("n {n}: E x² = {var}");
            assert!(
                var < 1.0 && (n < 4 || 1.0 - var < 0.6 / n as f64),
                "n {n}: E x² {var}"
            );
            assert!(sum(&|z| z.x * z.y).abs() < 1e-12);
            if n >= 6 {
                // P(|z| < 1) = 1 − e^(−1/2).
                let p = sum(&|z| if z.length() < 1.0 { 1.0 } else { 0.0 });
                let want = 1.0 - (-0.5f64).exp();
                eprintln!("n {n}: P(|z| < 1) {p} vs {want}");
                assert!((p - want).abs() < 1.5 / n as f64, "n {n}: {p} vs {want}");
            }
        }
        assert_eq!(slope_rule(1), &[(DVec2::ZERO, 1.0)]);
        assert_eq!(slope_rule(0).len(), 1);
        assert_eq!(slope_rule(99).len(), 32 * 32);
    }
}
