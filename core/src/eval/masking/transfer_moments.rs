//! The Gaussian moments of a transfer masking table's columns
//! ([`crate::eval::masking::transfer_masking_table`], #17), tabulated: what the transfer mixture's bins
//! read instead of integrating a column per sub-value.
//!
//! At driver value x (global σ) a ray's conditioned `G1` depends on the footprint's whitened
//! driver slopes only through `t = len·a`, `a ~ N(0, 1)`, with `len` the length of the ray's
//! projection ([`crate::eval::masking::transfer_masking_table::TransferRays`]). Its weight needs
//! `E[g]`, `E[a g]` and `E[a² g]`, exact per column ([`log_linear_moments`]). Tabulated per
//! (azimuth, ν) entry at every value node and at [`LENGTH_NODES`] lengths over [0, 1]:
//! - `len ≤ 1` always: the projection is `Lᵀd/σ_t` with `L Lᵀ` the footprint's unresolved
//!   gradient covariance, which is at most the global one;
//! - in `a` (standard) units the moments are smooth in `len`, down to `len = 0` where they are
//!   `(g(0), 0, g(0))`;
//! - a lookup blends moments linearly in every axis (a mixture of valid moment sets stays valid).
//!
//! On the GPU this is 48 reads a ray weight with no special function, where the exact form
//! integrates 16 cells with two `erfcx` each (and Mesa's loop limiter cut it: docs/design/transfer-curves.md).

use crate::math::log_linear_moments::log_linear_moments;

/// Projection lengths of the table: `LENGTH_STEP·k`, k < LENGTH_NODES, over [0, 1].
pub const LENGTH_NODES: usize = 9;
/// Step of the length nodes.
pub const LENGTH_STEP: f64 = 1.0 / (LENGTH_NODES - 1) as f64;
/// The moments `(E[g], E[a g], E[a² g])`, `a ~ N(0, 1)`, of `g = exp(ln G1(len·a))` for one
/// column of `ln G1` values at the slope nodes `knots` (σ units of the table).
pub fn column_moments(knots: &[f64], column: &[f64], len: f64) -> [f64; 3] {
    let (m0, m1, m2) = log_linear_moments(knots, column, len);
    if len > crate::math::log_linear_moments::MIN_DEVIATION {
        [m0, m1 / len, m2 / (len * len)]
    } else {
        [m0, 0.0, m0]
    }
}

/// The moment block of one (azimuth, ν) entry of `ln G1` values, value-major with one value per
/// slope node `knots`: per value, [`LENGTH_NODES`] × 3 moments.
pub fn entry_moments(entry: &[f64], knots: &[f64]) -> Vec<f32> {
    let n = knots.len().max(1);
    let mut out = Vec::with_capacity(entry.len() / n * LENGTH_NODES * 3);
    for column in entry.chunks_exact(n) {
        for k in 0..LENGTH_NODES {
            out.extend(column_moments(knots, column, LENGTH_STEP * k as f64).map(|v| v as f32));
        }
    }
    out
}

/// The length nodes `k, k + 1` around `len` and the weight of `k + 1`, clamped to [0, 1] (NaN
/// reads 0).
pub fn length_cell(len: f64) -> (usize, f64) {
    let len = if len.is_nan() { 0.0 } else { len };
    let u = (len / LENGTH_STEP).clamp(0.0, (LENGTH_NODES - 1) as f64);
    let k = (u as usize).min(LENGTH_NODES - 2);
    (k, u - k as f64)
}

/// The moments at the value cell `(i, fi)` (the nodes i, i + 1 and the weight of i + 1) and
/// projection length `len` from one ray's blended moment block, bilinear in the value and the
/// length, the length clamped to [0, 1].
pub fn moments_at(block: &[f64], (i, fi): (usize, f64), len: f64) -> [f64; 3] {
    let (k, fk) = length_cell(len);
    let mut out = [0.0; 3];
    for (ii, wi) in [(i, 1.0 - fi), (i + 1, fi)] {
        for (kk, wk) in [(k, 1.0 - fk), (k + 1, fk)] {
            let w = wi * wk;
            if w == 0.0 {
                continue;
            }
            let b = (ii * LENGTH_NODES + kk) * 3;
            for (o, v) in out.iter_mut().zip(&block[b..b + 3]) {
                *o += w * v;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const NODES: usize = 17;

    fn knots() -> Vec<f64> {
        (0..NODES).map(|j| -4.0 + 0.5 * j as f64).collect()
    }

    /// A flat column is its value with the standard normal's moments at every length; a column
    /// falling toward the ray tilts its weight toward negative slopes more the longer the
    /// projection; at a node the block reads the exact moments, and between nodes it stays
    /// between them.
    #[test]
    fn the_block_holds_the_columns_moments() {
        let k = knots();
        let flat = [-0.3; NODES];
        for len in [0.0, 0.4, 1.0] {
            let m = column_moments(&k, &flat, len);
            let g = (-0.3f64).exp();
            assert!((m[0] - g).abs() < 1e-12 && m[1].abs() < 1e-12 && (m[2] - g).abs() < 1e-12);
        }
        let falling: Vec<f64> = k.iter().map(|t| -0.5 * (t + 4.0)).collect();
        let tilt = |len: f64| {
            let m = column_moments(&k, &falling, len);
            m[1] / m[0]
        };
        assert!(tilt(0.0) == 0.0 && tilt(0.5) < -0.1 && tilt(1.0) < tilt(0.5));
        let values = 12;
        let mut entry = vec![0.0; values * NODES];
        for i in 0..values {
            for j in 0..NODES {
                entry[i * NODES + j] = -0.1 * (i as f64) * (k[j] + 4.0) / 8.0;
            }
        }
        let block: Vec<f64> = entry_moments(&entry, &k)
            .iter()
            .map(|v| f64::from(*v))
            .collect();
        assert_eq!(block.len(), values * LENGTH_NODES * 3);
        let (i, l) = (7, 3);
        let exact = column_moments(
            &k,
            &entry[i * NODES..(i + 1) * NODES],
            LENGTH_STEP * l as f64,
        );
        let got = moments_at(&block, (i, 0.0), LENGTH_STEP * l as f64);
        for c in 0..3 {
            assert!((got[c] - exact[c]).abs() < 1e-6, "{got:?} vs {exact:?}");
        }
        let mid = moments_at(&block, (i, 0.4), 0.4);
        let lo = moments_at(&block, (i, 0.0), 0.4);
        let hi = moments_at(&block, (i + 1, 0.0), 0.4);
        assert!(mid[0] <= lo[0].max(hi[0]) && mid[0] >= lo[0].min(hi[0]));
        for len in [f64::NAN, -1.0, 0.0, 7.0] {
            assert!(
                moments_at(&block, (values - 2, 1.0), len)
                    .iter()
                    .all(|v| v.is_finite())
            );
        }
    }
}
