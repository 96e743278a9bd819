//! Slopes under a transfer curve as a mixture of Gaussians over the driver's value, binned the
//! way a shader can afford (#17; docs/design/transfer-curves.md, "Transfer curves").
//!
//! For a Gaussian driver f ~ N(f̄, σ_f²) over the footprint, the value and the gradient of f at a
//! point are independent, so the transformed surface h = σ_h·g(f) has, given f, Gaussian slopes
//! N(σ_h g′(f)·∇f̄, σ_h² g′(f)²·Σ_∇f): a scale mixture, not one Gaussian, whenever g is not
//! linear (flat treads and steep risers for terraces, a flat top and steep pits for a sponge).
//! The footprint's quantiles u = Φ((f − f̄)/σ_f) are cut into bins ([`mixture_edges`]): equal
//! probability, and at the curve's knots, where g′ changes regime, so that a tread and a riser
//! never share a bin. Each bin is one Gaussian with the bin's mean g′ and E[g′²].
//!
//! Masking with slopes that depend on height (Smith 1967; Bourlier et al. 2002): heights ordered
//! like f (a non-decreasing g), a point at quantile u is visible along ω with probability
//! `G(u) = exp(−∫_u^1 Λ(u′)/u′ du′)`; with Λ constant over a bin [lo, hi] this is
//! `G_top·(u/hi)^Λ` inside it, so the bin's weight times its mean visibility is exact in closed
//! form ([`bin_masking`]), and the bin below starts at `G_top·(lo/hi)^Λ`.

use crate::microfacet::slope_rule::SlopeRule;
use serde::{Deserialize, Serialize};

/// How the filtered view models the slopes of a surface under a transfer curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum TransferSlopes {
    /// A mixture of Gaussians over bins of the driver's value, with height-dependent masking
    /// (default; only transfer curves use it: under the identity it is one Gaussian).
    #[default]
    Mixture,
    /// One Gaussian of the same second moment [HNPN14 Eqs. 19–26] (the papers' model: 34–51% off
    /// the ray-traced truth on the sponge and terraces presets).
    Gaussian,
}

/// Bins of equal probability before the knots are added: 16 (8 left terraces 1.3–1.6% off the
/// ray-traced truth at 0° and 60°, 16 brings it to 0.6–0.9%; docs/design/transfer-curves.md).
pub const MIXTURE_BINS: usize = 16;

/// Knots of the curve used as bin edges, at most (inside the footprint's quantile range; when
/// more fall inside, every k-th is used, k the smallest stride that fits).
pub const MAX_KNOT_EDGES: usize = 16;

/// Most bins a footprint can have.
pub const MAX_MIXTURE_BINS: usize = MIXTURE_BINS + MAX_KNOT_EDGES;

/// Samples per bin (midpoints in u) for the bin's moments of g′ and its mean colour; 16 changed
/// no preset by more than 0.1% (measured, `core/src/eval/mixture.rs` `binned_against_fine`).
pub const BIN_SAMPLES: usize = 4;

/// n of the polar slope rule per bin (n² nodes) without a slope colour: 4 is within 0.7% of 8
/// on the presets.
pub const MIXTURE_SLOPE_POINTS: usize = 4;

/// The slope rule per bin: n × n with n = [`MIXTURE_SLOPE_POINTS`] (or the material's n when
/// smaller), the material's own rule (`Material::slope_rule`) when it has a slope colour term,
/// whose C_s(n) can turn within a fraction of σ_n (snow: 8% off with 4 at the normal, measured).
pub fn bin_slope_points(material: SlopeRule, slope_color: bool) -> SlopeRule {
    if slope_color {
        material
    } else {
        SlopeRule::square(material.radii.min(MIXTURE_SLOPE_POINTS))
    }
}

/// Knots whose quantile is within this of 0 or 1 are left out (their bin would hold nothing).
pub const KNOT_MARGIN: f64 = 1e-6;

/// The bin edges in u = Φ(z), increasing from 0 to 1: `i/MIXTURE_BINS` merged with the quantiles
/// `Φ((x − mean)/std)` of the knots `x` (increasing) that fall inside `(KNOT_MARGIN, 1 −
/// KNOT_MARGIN)`, at most [`MAX_KNOT_EDGES`] of them. `std = 0` (or NaN) keeps only the equal
/// bins. Equal edges may repeat (an empty bin weighs nothing).
pub fn mixture_edges(knots: &[f64], mean: f64, std: f64) -> Vec<f64> {
    let z_of = |x: f64| (x - mean) / std.max(1e-30);
    let inside: Vec<f64> = if std > 0.0 {
        knots
            .iter()
            .map(|&x| crate::math::special::norm_cdf(z_of(x)))
            .filter(|u| *u > KNOT_MARGIN && *u < 1.0 - KNOT_MARGIN)
            .collect()
    } else {
        Vec::new()
    };
    let stride = inside.len().div_ceil(MAX_KNOT_EDGES).max(1);
    let mut knot_u = inside.into_iter().step_by(stride).peekable();
    let mut edges = Vec::with_capacity(MAX_MIXTURE_BINS + 1);
    for i in 0..=MIXTURE_BINS {
        let e = i as f64 / MIXTURE_BINS as f64;
        while let Some(&u) = knot_u.peek() {
            if u >= e {
                break;
            }
            edges.push(u);
            knot_u.next();
        }
        edges.push(e);
    }
    edges
}

/// `∫_lo^hi G(u) du` for a bin of constant exponent `lambda` whose top is seen with
/// `exp(−above)`: `exp(−above)·hi·(1 − (lo/hi)^{Λ+1})/(Λ + 1)` (the bin's weight times its mean
/// visibility; stable for any Λ ≥ 0 and 0 ≤ lo ≤ hi ≤ 1; 0 for an empty bin).
pub fn bin_masking(lo: f64, hi: f64, lambda: f64, above: f64) -> f64 {
    if !(hi > 0.0) || !(hi > lo) {
        return 0.0;
    }
    let l = lambda.max(0.0);
    let r = (lo / hi).clamp(0.0, 1.0);
    (-above).exp() * hi * (1.0 - r.powf(l + 1.0)) / (l + 1.0)
}

/// The exponent a bin adds to every bin below it: `Λ·ln(hi/lo)` (0 for an empty bin, and for
/// the bottom bin, lo = 0, which has nothing below it).
pub fn bin_exponent(lo: f64, hi: f64, lambda: f64) -> f64 {
    if lo > 0.0 && hi > lo {
        lambda.max(0.0) * (hi / lo).ln()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::special::norm_cdf;

    /// The edges are sorted, start at 0 and end at 1, hold every equal-probability edge and the
    /// knots inside the range; too many knots are thinned to MAX_KNOT_EDGES.
    #[test]
    fn edges_merge_the_knots_into_the_equal_bins() {
        let knots = [-3.0, -0.3, 0.3, 0.9, 1.6, 3.0];
        let e = mixture_edges(&knots, 0.2, 0.5);
        assert!(e.windows(2).all(|w| w[0] <= w[1]), "{e:?}");
        assert_eq!((e[0], *e.last().unwrap()), (0.0, 1.0));
        for i in 0..=MIXTURE_BINS {
            assert!(e.contains(&(i as f64 / MIXTURE_BINS as f64)));
        }
        // −3 is 6.4σ below (u ≈ 8e-11): left out; 3.0 is 5.6σ above: left out.
        assert_eq!(e.len(), MIXTURE_BINS + 1 + 4, "{e:?}");
        assert!(e.contains(&norm_cdf((0.9 - 0.2) / 0.5)));
        // No spread: the equal bins alone.
        assert_eq!(mixture_edges(&knots, 0.2, 0.0).len(), MIXTURE_BINS + 1);
        assert_eq!(mixture_edges(&knots, 0.2, f64::NAN).len(), MIXTURE_BINS + 1);
        // 40 knots inside: thinned to at most 16.
        let many: Vec<f64> = (0..40).map(|i| -2.0 + 0.1 * i as f64).collect();
        let e = mixture_edges(&many, 0.0, 1.0);
        assert!(e.len() <= MAX_MIXTURE_BINS + 1 && e.len() > MIXTURE_BINS + 10);
    }

    /// bin_masking integrates G_top·(u/hi)^Λ over the bin (checked by the midpoint rule), and the
    /// bins of [0, 1] chained top-down give ∫_0^1 u^Λ du = 1/(Λ + 1) for a constant Λ.
    #[test]
    fn bins_integrate_the_visibility_exactly() {
        for l in [0.0, 0.3, 2.0, 40.0, 1e4] {
            let (lo, hi, above): (f64, f64, f64) = (0.2, 0.55, 0.7);
            let n = 200_000;
            let quad: f64 = (0..n)
                .map(|k| {
                    let u = lo + (hi - lo) * (k as f64 + 0.5) / n as f64;
                    (-above).exp() * (u / hi).powf(l) * (hi - lo) / n as f64
                })
                .sum();
            let b = bin_masking(lo, hi, l, above);
            // (The midpoint rule itself is 4e-5 off at Λ = 10⁴.)
            assert!(
                (b - quad).abs() <= 1e-9 + 1e-4 * quad,
                "Λ {l}: {b} vs {quad}"
            );
            let edges = mixture_edges(&[-0.5, 0.1, 0.7], 0.0, 1.0);
            let (mut acc, mut sum) = (0.0, 0.0);
            for w in edges.windows(2).rev() {
                sum += bin_masking(w[0], w[1], l, acc);
                acc += bin_exponent(w[0], w[1], l);
            }
            assert!(
                (sum - 1.0 / (l + 1.0)).abs() < 1e-12 * (1.0 + 1.0 / (l + 1.0)),
                "{sum}"
            );
        }
        assert_eq!(bin_masking(0.3, 0.3, 2.0, 0.0), 0.0);
        assert_eq!(bin_exponent(0.3, 0.3, 2.0), 0.0);
        assert!(bin_masking(0.0, 0.125, 1e30, 0.0).is_finite());
    }
}
