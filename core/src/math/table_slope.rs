//! Bounds of the slope of a pre-convolved table's mean channel along m, as its bilinear sampler
//! interpolates it: what the level-of-detail march needs to step over `G(m) = E[g(m + σ_f Z)]`
//! (issue #15).
//!
//! At a fixed σ the sampler ([`PreconvolvedTable::sample`]) blends two rows `j0, j1` with weights
//! `1 − b, b`, and within a column interval `[m_i, m_{i+1}]` each row is linear, so `G` is piecewise
//! linear in m with slope `((1 − b)Δ_{j0,i} + bΔ_{j1,i})/Δm`, `Δ_{j,i} = T_{j,i+1} − T_{j,i}`. Hence
//! over any range of m, `|G′| ≤ max_i max(|Δ_{j0,i}|, |Δ_{j1,i}|)/Δm` over the columns the range
//! meets, and beyond the table's edges G is constant (clamped). Per row, a max-pyramid over the
//! column intervals answers that in two lookups per row ([`RowSlope::lipschitz_on`]).
//!
//! Why not bound `E[g′]` from the curve: on the curve's flats g′ is near 0, but the footprint's
//! Gaussian reaches the risers, so a bound of `g′` widened by 6σ_f (what the march used before) is
//! the riser's slope as soon as σ_f is a fraction of the curve's width, while the smoothed `G` is
//! several times flatter. At the 96×64 bench footprints of sponge and terraces that made every
//! level-of-detail step a global-Lipschitz step (18–26 steps per camera ray against 8–11 on the
//! default preset).
//!
//! Layout (also the GPU's, `scene/local_slope.wgsl`): `P` = the column intervals rounded up to a
//! power of two; per row, `2P` f32 (the last unused): level `k` (`P >> k` entries, each the max of
//! `2^k` intervals of level 0) starts at `2P − (2P >> k)`. Entries are rounded up to f32.

use crate::math::preconvolved::PreconvolvedTable;
use crate::math::rounding::f32_up;

/// Per-row max-pyramids of a pre-convolved table's mean-channel slope (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct TableSlope {
    /// Column intervals per level-0 row, rounded up to a power of two.
    pub p: usize,
    /// Rows of the table.
    pub rows: usize,
    /// `2P` entries per row, row after row (module docs).
    pub entries: Vec<f32>,
    /// The table's first column's m.
    pub m_min: f64,
    /// The distance between columns (> 0).
    pub dm: f64,
    /// Column intervals (`size_m − 1`).
    pub intervals: usize,
}

impl TableSlope {
    /// The pyramids of `table`'s channel 0.
    pub fn new(table: &PreconvolvedTable) -> Self {
        let nm = table.size_m.max(2);
        let intervals = nm - 1;
        let p = intervals.next_power_of_two();
        let dm = (table.m_max - table.m_min) / intervals as f64;
        let dm = if dm > 0.0 && dm.is_finite() { dm } else { 1.0 };
        let mut entries = vec![0.0f32; 2 * p * table.size_sigma];
        for (j, row) in entries.chunks_mut(2 * p).enumerate() {
            let t = &table.texels[j * table.size_m..(j + 1) * table.size_m];
            for i in 0..intervals.min(t.len().saturating_sub(1)) {
                let d = (f64::from(t[i + 1][0]) - f64::from(t[i][0])).abs() / dm;
                row[i] = if d.is_finite() { f32_up(d) } else { f32::MAX };
            }
            let (mut from, mut n) = (0, p);
            while n > 1 {
                let to = from + n;
                for i in 0..n / 2 {
                    row[to + i] = row[from + 2 * i].max(row[from + 2 * i + 1]);
                }
                from = to;
                n /= 2;
            }
        }
        Self {
            p,
            rows: table.size_sigma,
            entries,
            m_min: table.m_min,
            dm,
            intervals,
        }
    }

    /// The bounds at σ: the two rows the sampler blends there ([`PreconvolvedTable::sigma_rows`]).
    pub fn at(&self, table: &PreconvolvedTable, sigma: f64) -> RowSlope<'_> {
        let (j0, j1) = table.sigma_rows(sigma);
        RowSlope {
            slopes: self,
            rows: (j0.min(self.rows - 1), j1.min(self.rows - 1)),
        }
    }

    /// Level `k`'s entry `i` of row `j`.
    fn entry(&self, j: usize, k: u32, i: usize) -> f64 {
        let base = 2 * self.p - ((2 * self.p) >> k);
        f64::from(self.entries[j * 2 * self.p + base + i])
    }
}

/// [`TableSlope`] at one σ: the slope bounds of `G(m)` = the table's mean at that σ.
#[derive(Clone, Copy, Debug)]
pub struct RowSlope<'a> {
    /// The pyramids.
    pub slopes: &'a TableSlope,
    /// The two rows blended at this σ.
    pub rows: (usize, usize),
}

impl RowSlope<'_> {
    /// A bound of |G′| over `[lo, hi]`: the largest slope of either row over the column intervals
    /// the range meets, widened by one interval on each side (so a sampler that rounds m into the
    /// neighbouring column is covered). The whole row's bound for a NaN or reversed range.
    pub fn lipschitz_on(&self, lo: f64, hi: f64) -> f64 {
        let s = self.slopes;
        let last = s.intervals - 1;
        let column = |m: f64| {
            let u = ((m - s.m_min) / s.dm).floor();
            if u.is_nan() {
                0
            } else {
                u.clamp(0.0, last as f64) as usize
            }
        };
        if !(lo <= hi) {
            return self.max();
        }
        let (a, b) = (column(lo).saturating_sub(1), (column(hi) + 1).min(last));
        let mut k = 0;
        while (b >> k) - (a >> k) > 1 {
            k += 1;
        }
        let (j0, j1) = self.rows;
        [j0, j1]
            .iter()
            .flat_map(|&j| [s.entry(j, k, a >> k), s.entry(j, k, b >> k)])
            .fold(0.0, f64::max)
    }

    /// A bound of |G′| everywhere: the pyramids' tops.
    pub fn max(&self) -> f64 {
        let s = self.slopes;
        let top = s.p.trailing_zeros();
        s.entry(self.rows.0, top, 0)
            .max(s.entry(self.rows.1, top, 0))
    }
}

#[cfg(test)]
mod tests {
    use crate::eval::compiled::CompiledTransfer;
    use crate::math::preconvolved::TableSpec;
    use crate::math::random::splitmix;
    use crate::microfacet::transfer::{Curve, TransferFunction};

    /// The bound holds every difference quotient of the sampled table over random ranges (any
    /// two points in the range, down to 1e-6 apart, where f32 texel rounding cannot reach: the
    /// quotients of a piecewise linear function are exactly bounded by its slopes), at σ from 0 to
    /// past the last row; and it is tight: at least the largest quotient of the column intervals
    /// inside the range, and on the sponge at σ_f = 0.7 under 0.4 of the curve's max |g′| (0.35).
    #[test]
    fn the_bound_holds_the_sampled_table_and_is_tight() {
        let mut rng = 5u64;
        for c in [Curve::sponge(), Curve::moss(), Curve::terraces(5)] {
            let t = TransferFunction::Curve(c.clone());
            let g_lip = t.max_derivative();
            let spec = TableSpec::default();
            let CompiledTransfer::Curve { table, slopes } = CompiledTransfer::new(&t, spec) else {
                panic!("a curve compiles to a table")
            };
            let dm = (table.m_max - table.m_min) / (table.size_m - 1) as f64;
            for _ in 0..300 {
                let lo = table.m_min - 1.0 + (table.m_max - table.m_min + 2.0) * splitmix(&mut rng);
                let hi = lo + 3.0 * splitmix(&mut rng).powi(3) + 1e-6;
                let sf = [0.0, 0.01, 0.2, 0.7, 1.5][(splitmix(&mut rng) * 5.0) as usize % 5];
                let rs = slopes.at(&table, sf);
                let bound = rs.lipschitz_on(lo, hi);
                assert!(bound <= rs.max() && rs.max() <= g_lip * 1.001 + 1e-6);
                let g = |x| table.sample(x, sf)[0];
                for _ in 0..20 {
                    let a = lo + (hi - lo) * splitmix(&mut rng);
                    let b = lo + (hi - lo) * splitmix(&mut rng);
                    if (b - a).abs() < 1e-6 {
                        continue;
                    }
                    let q = (g(b) - g(a)).abs() / (b - a).abs();
                    assert!(
                        q <= bound * (1.0 + 1e-9) + 1e-9,
                        "σ_f {sf} on [{lo}, {hi}]: {q} > {bound}"
                    );
                }
                // Tight: the steepest whole column interval inside the range is in the bound, and
                // the bound reaches no further than 2× the range plus two intervals on each side.
                let first = ((lo - table.m_min) / dm).ceil().max(0.0);
                let mut i = first;
                let mut steepest = 0.0f64;
                while table.m_min + (i + 1.0) * dm <= hi && (i as usize) < table.size_m - 1 {
                    let (a, b) = (table.m_min + i * dm, table.m_min + (i + 1.0) * dm);
                    steepest = steepest.max((g(b) - g(a)).abs() / dm);
                    i += 1.0;
                }
                assert!(steepest <= bound * (1.0 + 1e-6) + 1e-9);
            }
            if c == Curve::sponge() {
                let rs = slopes.at(&table, 0.7);
                assert!(rs.max() < 0.4 * g_lip, "{} vs g_lip {g_lip}", rs.max());
            }
        }
    }

    /// Beyond the table's columns G is clamped: a range entirely outside it gets the edge
    /// interval's slope (the one-interval widening), never more than the row's bound; NaN and
    /// reversed ranges get the row's bound.
    #[test]
    fn ranges_outside_or_invalid_are_bounded() {
        let t = TransferFunction::Curve(Curve::terraces(5));
        let CompiledTransfer::Curve { table, slopes } =
            CompiledTransfer::new(&t, TableSpec::default())
        else {
            panic!("a curve compiles to a table")
        };
        let rs = slopes.at(&table, 0.3);
        for (lo, hi) in [(-1e9, -1e8), (1e8, 1e9), (-1e30, 1e30)] {
            let b = rs.lipschitz_on(lo, hi);
            assert!(b.is_finite() && b <= rs.max());
        }
        assert_eq!(rs.lipschitz_on(f64::NAN, 1.0), rs.max());
        assert_eq!(rs.lipschitz_on(2.0, 1.0), rs.max());
        assert_eq!(rs.lipschitz_on(-1e30, 1e30), rs.max());
    }
}
