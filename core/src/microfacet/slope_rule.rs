//! Which polar rule averages over a footprint's slopes ([`SlopeRule`]): `radii` rings × `angles`
//! nodes per ring, the nodes and weights from [`crate::microfacet::visible_slopes::slope_rule`]'s
//! construction (Gauss–Legendre in the radial CDF, uniform angles, odd rings turned by half a
//! step).
//!
//! A material with a slope colour gets twice the angles: `C_s(n)` is a function of the facet's
//! orientation, which turns across about one σ of slope in azimuth, while the shading terms
//! (clamped cosine, environment) are smooth in it. Measured on the far patch over #17's 30
//! configurations, largest deviation from the 32 × 32 rule: snake-skin 1.26% with 8 × 8, 0.70%
//! with 12 × 12 (144 nodes), 0.27% with 8 × 16 (128 nodes), 0.12% with 16 × 16; snow-under-sky
//! 0.47%, 0.24%, 0.33%, 0.04%. More radii without more angles does little (6 × 12: snake-skin
//! 0.27% but dirt-in-crevices 0.60%), so the angles double and the radii stay the author's n.

use glam::DVec2;
use std::sync::OnceLock;

/// Largest n of a rule (`filtering.slope_points` is clamped to 1..=32).
pub const MAX_RADII: usize = 32;

/// A polar rule over the standard bivariate normal: `radii` × `angles` nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SlopeRule {
    /// Rings (Gauss–Legendre in the radial CDF), 1..=[`MAX_RADII`].
    pub radii: usize,
    /// Nodes per ring: `radii` or `2·radii`.
    pub angles: usize,
}

impl SlopeRule {
    /// `n` radii × `n` angles (n clamped to 1..=[`MAX_RADII`]); n = 1 is the mean.
    pub fn square(n: usize) -> Self {
        let n = n.clamp(1, MAX_RADII);
        Self {
            radii: n,
            angles: n,
        }
    }

    /// The rule of a material's footprint averages: `points` radii (`filtering.slope_points`)
    /// and, with a slope colour term, twice as many angles (module docs).
    pub fn for_material(points: u32, slope_color: bool) -> Self {
        let r = Self::square(points as usize);
        if slope_color && r.radii > 1 {
            Self {
                angles: 2 * r.radii,
                ..r
            }
        } else {
            r
        }
    }

    /// Nodes: `radii · angles` (1 for the mean).
    pub fn len(self) -> usize {
        if self.radii <= 1 {
            1
        } else {
            self.radii * self.angles
        }
    }

    /// Never empty (the mean at least); for clippy's `len_without_is_empty`.
    pub fn is_empty(self) -> bool {
        false
    }

    /// Nodes `z` and weights (summing to 1), so `E[q(s)] ≈ Σ w q(μ + L z)` for
    /// `s ~ N(μ, LLᵀ)`; built once per rule and kept for the process.
    pub fn nodes(self) -> &'static [(DVec2, f64)] {
        static SQUARE: [OnceLock<Vec<(DVec2, f64)>>; MAX_RADII] =
            [const { OnceLock::new() }; MAX_RADII];
        static DOUBLE: [OnceLock<Vec<(DVec2, f64)>>; MAX_RADII] =
            [const { OnceLock::new() }; MAX_RADII];
        let n = self.radii.clamp(1, MAX_RADII);
        let double = self.angles > n;
        let cache = if double { &DOUBLE } else { &SQUARE };
        cache[n - 1].get_or_init(|| build(n, if double { 2 * n } else { n }))
    }
}

impl From<usize> for SlopeRule {
    /// [`SlopeRule::square`].
    fn from(n: usize) -> Self {
        Self::square(n)
    }
}

/// The nodes of `radii` rings × `angles` per ring (module docs).
fn build(radii: usize, angles: usize) -> Vec<(DVec2, f64)> {
    if radii == 1 {
        return vec![(DVec2::ZERO, 1.0)];
    }
    let (x, w) = crate::math::quadrature::gauss_legendre(radii);
    let mut nodes = Vec::with_capacity(radii * angles);
    for (k, (xk, wk)) in x.iter().zip(&w).enumerate() {
        let u = 0.5 * (xk + 1.0);
        let r = (-2.0 * (-u).ln_1p()).sqrt();
        let turn = 0.5 * (k % 2) as f64;
        for j in 0..angles {
            let phi = std::f64::consts::TAU * (j as f64 + turn) / angles as f64;
            nodes.push((
                DVec2::new(r * phi.cos(), r * phi.sin()),
                0.5 * wk / angles as f64,
            ));
        }
    }
    nodes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Weights sum to 1; the second moments are isotropic and near the identity's (the radius's
    /// rule is Gauss–Legendre in its CDF, not exact for r²); angular harmonics below `angles`
    /// vanish on every ring, so the doubled rule is exact for twice the degree in the angle.
    #[test]
    fn rules_integrate_the_normal() {
        for n in [3, 8, 13, 32] {
            for rule in [
                SlopeRule::square(n),
                SlopeRule::for_material(n as u32, true),
            ] {
                let nodes = rule.nodes();
                assert_eq!(nodes.len(), rule.len());
                let sum: f64 = nodes.iter().map(|(_, w)| w).sum();
                let xx: f64 = nodes.iter().map(|(z, w)| w * z.x * z.x).sum();
                let yy: f64 = nodes.iter().map(|(z, w)| w * z.y * z.y).sum();
                let xy: f64 = nodes.iter().map(|(z, w)| w * z.x * z.y).sum();
                assert!((sum - 1.0).abs() < 1e-12, "{rule:?}");
                assert!((xx - yy).abs() < 1e-12 && xy.abs() < 1e-12, "{rule:?}");
                assert!((xx - 1.0).abs() < 0.2 / n as f64, "{rule:?}: {xx}");
                // The angular harmonic just below `angles` vanishes on every ring.
                let k = (rule.angles - 1) as f64;
                let h: f64 = nodes
                    .iter()
                    .map(|(z, w)| w * (k * z.y.atan2(z.x)).cos())
                    .sum();
                assert!(h.abs() < 1e-9, "{rule:?}: {h}");
            }
        }
    }

    /// The doubled rule resolves a colour that turns within a fraction of the circle where the
    /// square one does not: the share of a 50° sector of the plane (exactly 50/360) on 8 radii.
    #[test]
    fn doubled_angles_resolve_an_azimuthal_edge() {
        let share = |rule: SlopeRule| -> f64 {
            rule.nodes()
                .iter()
                .filter(|(z, _)| z.y.atan2(z.x).abs() < 25f64.to_radians())
                .map(|(_, w)| w)
                .sum()
        };
        let exact = 50.0 / 360.0;
        let square = (share(SlopeRule::square(8)) - exact).abs();
        let double = (share(SlopeRule::for_material(8, true)) - exact).abs();
        assert!(double < 0.5 * square, "{square} {double}");
    }

    #[test]
    fn the_material_picks_the_shape() {
        assert_eq!(SlopeRule::for_material(8, false), SlopeRule::square(8));
        assert_eq!(SlopeRule::for_material(8, true).angles, 16);
        assert_eq!(SlopeRule::for_material(1, true).len(), 1);
        assert_eq!(SlopeRule::for_material(0, true), SlopeRule::square(1));
        assert_eq!(SlopeRule::for_material(99, false).len(), 32 * 32);
    }
}
