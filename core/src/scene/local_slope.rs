//! Local Lipschitz constants of a transfer curve for the octave march ([`LocalSlope`]): the
//! steepest riser bounds g′ everywhere, but on the curve's flats g′ is far smaller, and the march
//! only needs a bound over the range f can reach in one step (issue #15).

use crate::material::preconvolved::PreconvolvedTable;
use crate::math::piecewise::PiecewisePoly;

/// A bound of |G′| over an interval of f, for the octave march's local steps: the largest |g′| over
/// the interval widened by `widen` (exact for the curve's piecewise quadratic g′,
/// [`PiecewisePoly::max_abs_on`]), plus `tail`, never more than the global `g_lip`.
///
/// On the explicit surface G = g (`widen = tail = 0`). On the level-of-detail surface G(m) is the
/// table of `E[g(m + σ_f Z)]`, interpolated between nodes; its slope between nodes is
/// `E[g′(m′ + σ′Z)]` at some node-interval point m′ and row σ′ ≤ σ_f + Δσ, at most the largest |g′|
/// within 6(σ_f + Δσ) of the interval widened by one column Δm, plus `g_lip·P(|Z| > 6) < 2e-9·g_lip`.
#[derive(Clone, Copy, Debug)]
pub struct LocalSlope<'a> {
    /// The curve's [`crate::material::transfer::Curve::moment_poly`] (channel 2 is g′).
    pub poly: &'a PiecewisePoly,
    /// How far the interval is widened on either side.
    pub widen: f64,
    /// Added to the bound.
    pub tail: f64,
}

impl<'a> LocalSlope<'a> {
    /// The channel of g′ in [`crate::material::transfer::Curve::moment_poly`].
    pub const DERIVATIVE_CHANNEL: usize = 2;

    /// The bound for the level-of-detail surface, whose G is `table` (the curve's pre-convolved
    /// moments) at σ_f = `sf`: widened by `6(σ_f + Δσ) + Δm` with `tail = 2e-9·g_lip` (struct docs).
    pub fn level_of_detail(
        poly: &'a PiecewisePoly,
        table: &PreconvolvedTable,
        sf: f64,
        g_lip: f64,
    ) -> Self {
        let dm = (table.m_max - table.m_min) / (table.size_m.max(2) - 1) as f64;
        let ds = table.sigma_max / (table.size_sigma.max(2) - 1) as f64;
        Self {
            poly,
            widen: 6.0 * (sf.max(0.0) + ds) + dm.abs(),
            tail: 2e-9 * g_lip,
        }
    }

    /// A bound of |G′| on [lo, hi] (before the cap at the global `g_lip`).
    pub fn lipschitz_on(&self, lo: f64, hi: f64) -> f64 {
        self.poly
            .max_abs_on(Self::DERIVATIVE_CHANNEL, lo - self.widen, hi + self.widen)
            * (1.0 + 1e-9)
            + self.tail
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::compiled::CompiledTransfer;
    use crate::material::preconvolved::TableSpec;
    use crate::material::transfer::{Curve, TransferFunction};
    use crate::math::random::splitmix;

    /// On the explicit surface the bound holds g's difference quotients over random intervals of
    /// the sponge, moss and terraces curves; on the level-of-detail surface it holds those of the
    /// pre-convolved table the march reads (at σ_f from 0 to past the table's last row). Pairs at
    /// least 1e-3 apart, so the table's f32 texels' rounding (1e-7) stays below the tolerance.
    #[test]
    fn local_bounds_hold_the_curves_and_their_tables() {
        let mut rng = 21u64;
        for c in [Curve::sponge(), Curve::moss(), Curve::terraces(5)] {
            let poly = c.moment_poly();
            let t = TransferFunction::Curve(c.clone());
            let g_lip = t.max_derivative();
            let CompiledTransfer::Curve { table } = CompiledTransfer::new(&t, TableSpec::default())
            else {
                panic!("a curve compiles to a table")
            };
            for _ in 0..300 {
                let lo = -4.0 + 8.0 * splitmix(&mut rng);
                let hi = lo + 2.0 * splitmix(&mut rng).powi(2) + 2e-3;
                let sf = [0.0, 0.01, 0.2, 0.7, 1.5][(splitmix(&mut rng) * 5.0) as usize % 5];
                let explicit = LocalSlope {
                    poly: &poly,
                    widen: 0.0,
                    tail: 0.0,
                };
                let lod = LocalSlope::level_of_detail(&poly, &table, sf, g_lip);
                let (le, ll) = (explicit.lipschitz_on(lo, hi), lod.lipschitz_on(lo, hi));
                assert!(le <= g_lip && ll <= g_lip * 1.0001 + 1e-9 && le <= ll + 1e-12);
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
                    let m = |x| table.sample(x, sf)[0];
                    let q = (m(b) - m(a)).abs() / (b - a).abs();
                    assert!(q <= ll + 1e-4, "G at σ_f {sf} on [{lo}, {hi}]: {q} > {ll}");
                }
            }
        }
    }
}
