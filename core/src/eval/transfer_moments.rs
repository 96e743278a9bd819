//! The Gaussian moments of a transfer masking table's columns
//! ([`crate::eval::transfer_masking_table`], #17), tabulated: what the transfer mixture's bins
//! read instead of integrating a column per sub-value.
//!
//! At driver value x (global σ) a ray's conditioned `G1` depends on the footprint's whitened
//! driver slopes only through `t = len·a`, `a ~ N(0, 1)`, with `len` the length of the ray's
//! projection ([`crate::eval::transfer_masking_table::TransferRays`]). Its weight needs
//! `E[g]`, `E[a g]` and `E[a² g]`, exact per column ([`log_linear_moments`]). Tabulated per
//! (azimuth, ν) entry at every value node and at [`LENGTH_NODES`] lengths over [0, 1]:
//! - `len ≤ 1` always: the projection is `Lᵀd/σ_t` with `L Lᵀ` the footprint's unresolved
//!   gradient covariance, which is at most the global one;
//! - in `a` (standard) units the moments are smooth in `len`, down to `len = 0` where they are
//!   `(g(0), 0, g(0))`;
//! - a lookup blends moments linearly in every axis (a mixture of valid moment sets stays valid).
//!
//! On the GPU this is 48 reads a ray weight with no special function, where the exact form
//! integrates 16 cells with two `erfcx` each (and Mesa's loop limiter cut it: docs/design.md).

use crate::eval::transfer_masking_table::{
    SLOPE_NODES, TRANSFER_ENTRY, VALUE_NODES, slope_node, value_cell,
};
use crate::math::log_linear_moments::log_linear_moments;

/// Projection lengths of the table: `LENGTH_STEP·k`, k < LENGTH_NODES, over [0, 1].
pub const LENGTH_NODES: usize = 9;
/// Step of the length nodes.
pub const LENGTH_STEP: f64 = 1.0 / (LENGTH_NODES - 1) as f64;
/// f32 values per (azimuth, ν) entry: value-major, then length, then the three moments.
pub const MOMENT_ENTRY: usize = VALUE_NODES * LENGTH_NODES * 3;

/// The moments `(E[g], E[a g], E[a² g])`, `a ~ N(0, 1)`, of `g = exp(ln G1(len·a))` for one
/// entry's column of [`SLOPE_NODES`] `ln G1` values at the slope nodes.
pub fn column_moments(column: &[f64; SLOPE_NODES], len: f64) -> [f64; 3] {
    let knots: [f64; SLOPE_NODES] = std::array::from_fn(slope_node);
    let (m0, m1, m2) = log_linear_moments(&knots, column, len);
    if len > crate::math::log_linear_moments::MIN_DEVIATION {
        [m0, m1 / len, m2 / (len * len)]
    } else {
        [m0, 0.0, m0]
    }
}

/// The moment block of one (azimuth, ν) entry of `ln G1` values ([`TRANSFER_ENTRY`], value-major).
pub fn entry_moments(entry: &[f64]) -> Vec<f32> {
    let mut out = Vec::with_capacity(MOMENT_ENTRY);
    for i in 0..VALUE_NODES {
        let column: [f64; SLOPE_NODES] = std::array::from_fn(|j| entry[i * SLOPE_NODES + j]);
        for k in 0..LENGTH_NODES {
            out.extend(column_moments(&column, LENGTH_STEP * k as f64).map(|v| v as f32));
        }
    }
    debug_assert_eq!(entry.len(), TRANSFER_ENTRY);
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

/// The moments at driver value `x` (global σ) and projection length `len` from one ray's blended
/// moment block ([`MOMENT_ENTRY`] values), bilinear in the value and the length, clamped.
pub fn moments_at(block: &[f64], x: f64, len: f64) -> [f64; 3] {
    let (i, fi) = value_cell(x);
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
    use crate::eval::transfer_masking_table::value_node;

    /// A flat column is its value with the standard normal's moments at every length; a column
    /// falling toward the ray tilts its weight toward negative slopes more the longer the
    /// projection; at a node the block reads the exact moments, and between nodes it stays
    /// between them.
    #[test]
    fn the_block_holds_the_columns_moments() {
        let flat = [-0.3; SLOPE_NODES];
        for len in [0.0, 0.4, 1.0] {
            let m = column_moments(&flat, len);
            let g = (-0.3f64).exp();
            assert!((m[0] - g).abs() < 1e-12 && m[1].abs() < 1e-12 && (m[2] - g).abs() < 1e-12);
        }
        let falling: [f64; SLOPE_NODES] = std::array::from_fn(|j| -0.5 * (slope_node(j) + 4.0));
        let tilt = |len: f64| {
            let m = column_moments(&falling, len);
            m[1] / m[0]
        };
        assert!(tilt(0.0) == 0.0 && tilt(0.5) < -0.1 && tilt(1.0) < tilt(0.5));
        let mut entry = vec![0.0; TRANSFER_ENTRY];
        for i in 0..VALUE_NODES {
            for j in 0..SLOPE_NODES {
                entry[i * SLOPE_NODES + j] = -0.1 * (i as f64) * (slope_node(j) + 4.0) / 8.0;
            }
        }
        let block: Vec<f64> = entry_moments(&entry)
            .iter()
            .map(|v| f64::from(*v))
            .collect();
        let (i, k) = (7, 3);
        let column: [f64; SLOPE_NODES] = std::array::from_fn(|j| entry[i * SLOPE_NODES + j]);
        let exact = column_moments(&column, LENGTH_STEP * k as f64);
        let got = moments_at(&block, value_node(i), LENGTH_STEP * k as f64);
        for c in 0..3 {
            assert!((got[c] - exact[c]).abs() < 1e-6, "{got:?} vs {exact:?}");
        }
        let mid = moments_at(&block, value_node(i) + 0.1, 0.4);
        let lo = moments_at(&block, value_node(i), 0.4);
        let hi = moments_at(&block, value_node(i + 1), 0.4);
        assert!(mid[0] <= lo[0].max(hi[0]) && mid[0] >= lo[0].min(hi[0]));
        for x in [f64::NAN, -1e9, 1e9] {
            for len in [f64::NAN, -1.0, 0.0, 7.0] {
                assert!(moments_at(&block, x, len).iter().all(|v| v.is_finite()));
            }
        }
    }
}
