//! Local Lipschitz constants of a transfer curve for the octave march ([`LocalSlope`]): the
//! steepest riser bounds g′ everywhere, but on the curve's flats g′ is far smaller, and the march
//! only needs a bound over the range f can reach in one step (issue #15).

use crate::math::piecewise::PiecewisePoly;
use crate::math::table_slope::RowSlope;

/// A bound of |G′| over an interval of f, for the octave march's local steps.
#[derive(Clone, Copy, Debug)]
pub enum LocalSlope<'a> {
    /// The explicit surface, G = g: the largest |g′| over the interval, exact for the curve's
    /// piecewise quadratic g′ ([`PiecewisePoly::max_abs_on`] of the curve's
    /// [`crate::microfacet::transfer::Curve::moment_poly`], channel 2).
    Curve(&'a PiecewisePoly),
    /// The level-of-detail surface, G = the pre-convolved table's mean at the footprint's σ_f as
    /// its sampler interpolates it: the largest slope of the table's two rows over the columns the
    /// interval meets ([`RowSlope::lipschitz_on`]). Before, this bounded `E[g′(m + σ_f Z)]` by |g′|
    /// over the interval widened by 6σ_f, which at frame footprints was the riser's slope everywhere.
    Table(RowSlope<'a>),
}

impl LocalSlope<'_> {
    /// The channel of g′ in [`crate::microfacet::transfer::Curve::moment_poly`].
    pub const DERIVATIVE_CHANNEL: usize = 2;

    /// A bound of |G′| on [lo, hi] (before the march's cap at its global bound).
    pub fn lipschitz_on(&self, lo: f64, hi: f64) -> f64 {
        match self {
            Self::Curve(poly) => poly.max_abs_on(Self::DERIVATIVE_CHANNEL, lo, hi) * (1.0 + 1e-9),
            Self::Table(rows) => rows.lipschitz_on(lo, hi),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::splitmix;
    use crate::microfacet::transfer::{Curve, TransferFunction};

    /// On the explicit surface the bound holds g's difference quotients over random intervals of
    /// the sponge, moss and terraces curves (the table's bound has its own test in
    /// [`crate::math::table_slope`]).
    #[test]
    fn local_bounds_hold_the_curves() {
        let mut rng = 21u64;
        for c in [Curve::sponge(), Curve::moss(), Curve::terraces(5)] {
            let poly = c.moment_poly();
            let t = TransferFunction::Curve(c.clone());
            let g_lip = t.max_derivative();
            for _ in 0..300 {
                let lo = -4.0 + 8.0 * splitmix(&mut rng);
                let hi = lo + 2.0 * splitmix(&mut rng).powi(2) + 2e-3;
                let le = LocalSlope::Curve(&poly).lipschitz_on(lo, hi);
                assert!(le <= g_lip * (1.0 + 1e-6));
                for _ in 0..20 {
                    let a = lo + (hi - lo) * splitmix(&mut rng);
                    let b = lo + (hi - lo) * splitmix(&mut rng);
                    if (b - a).abs() < 1e-3 {
                        continue;
                    }
                    let q = (t.eval(b) - t.eval(a)).abs() / (b - a).abs();
                    assert!(
                        q <= le * (1.0 + 1e-9) + 1e-9,
                        "g on [{lo}, {hi}]: {q} > {le}"
                    );
                }
            }
        }
    }
}
