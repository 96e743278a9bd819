//! Exact moments of `g(t) = exp(ℓ(t))` under a centred Gaussian `t ~ N(0, s²)`, for `ℓ`
//! piecewise linear on increasing knots and constant beyond the first and last: `E[g]`,
//! `E[t g]`, `E[t² g]`. What a conditioned masking table's column is (`ln G1` linear between its
//! slope nodes, [`crate::eval::masking::transfer_masking_table::entry_at`]), whose Gaussian moments the
//! transfer mixture needs.
//!
//! A Gauss–Hermite rule is the wrong tool for it: `ln G1` drops by up to 30 across one cell near
//! the back faces, and 6 to 24 points spread by 14% in `E[g]` on terraces (measured), never
//! converging. Here:
//! - **Mass.** On a cell `[a, b]` with slope β, completing the square,
//!   `∫ exp(ℓ_a + β(t − a)) N(t; 0, s²) dt = exp(ℓ_a − βa + ½β²s²)·[Φ(u_b) − Φ(u_a)]`,
//!   `u = (t − βs²)/s`. The bracket is taken from the tail both ends share, scaled by the
//!   integrand's largest value ([`erfcx`]), so a steep cell far in its tail neither overflows nor
//!   cancels.
//! - **First and second moments** by Stein's identity `E[t h(t)] = s² E[h′(t)]` (g is continuous):
//!   `E[t g] = s² Σ β_j I_j` and `E[t² g] = s² E[g] + s⁴ (Σ β_j² I_j + Σ_k Δβ_k g(t_k) N(t_k; 0, s²))`,
//!   `I_j` the cells' masses and `Δβ_k` the change of slope at knot k (β = 0 beyond the ends).

use crate::math::special::{erfcx, norm_cdf, norm_pdf};
use std::f64::consts::FRAC_1_SQRT_2;

/// Below this deviation the Gaussian is a point: `(g(0), 0, 0)`.
pub const MIN_DEVIATION: f64 = 1e-9;
/// Deviations above this are clamped to it, and `ℓ` to `[−745, 300]`: every moment stays finite
/// (a masking column is `ln G1 ≤ 0` with deviations of a few units).
pub const MAX_DEVIATION: f64 = 1e6;

/// `(E[g], E[t g], E[t² g])` for `t ~ N(0, s²)` of `g = exp(ℓ)` with `ℓ(knots[k]) = values[k]`
/// (module docs). `knots` increasing, as many as `values` (at least one). NaN and values below
/// −745 count as −745 (nothing), values above 300 as 300; `s` NaN or ≤ [`MIN_DEVIATION`] reads
/// `g(0)`, and `s` above [`MAX_DEVIATION`] is clamped to it.
pub fn log_linear_moments(knots: &[f64], values: &[f64], s: f64) -> (f64, f64, f64) {
    let n = knots.len().min(values.len());
    if n == 0 {
        return (0.0, 0.0, 0.0);
    }
    let v = |k: usize| {
        let x = values[k];
        if x.is_nan() {
            -745.0
        } else {
            x.clamp(-745.0, 300.0)
        }
    };
    let s = s.min(MAX_DEVIATION);
    if !(s > MIN_DEVIATION) {
        // ℓ(0), linear between the knots around it.
        let k = knots[..n].partition_point(|t| *t <= 0.0);
        let l = match k {
            0 => v(0),
            k if k >= n => v(n - 1),
            k => {
                let w = (0.0 - knots[k - 1]) / (knots[k] - knots[k - 1]);
                v(k - 1) + w * (v(k) - v(k - 1))
            }
        };
        return (l.exp(), 0.0, 0.0);
    }
    // Tails: constant beyond the ends.
    let mut m0 = v(0).exp() * norm_cdf(knots[0] / s) + v(n - 1).exp() * norm_cdf(-knots[n - 1] / s);
    let (mut sb, mut sbb, mut nodes) = (0.0, 0.0, 0.0);
    let mut beta_left = 0.0;
    for k in 0..n {
        let beta_right = if k + 1 < n {
            let h = knots[k + 1] - knots[k];
            if h > 0.0 { (v(k + 1) - v(k)) / h } else { 0.0 }
        } else {
            0.0
        };
        let t = knots[k];
        nodes += (beta_right - beta_left) * (v(k).exp() * norm_pdf(t / s) / s);
        if k + 1 < n && knots[k + 1] > t {
            let i = cell_mass(t, knots[k + 1], v(k), beta_right, s);
            m0 += i;
            sb += beta_right * i;
            sbb += beta_right * beta_right * i;
        }
        beta_left = beta_right;
    }
    let s2 = s * s;
    (m0, s2 * sb, s2 * m0 + s2 * s2 * (sbb + nodes))
}

/// `∫_a^b exp(l + β(t − a)) N(t; 0, s²) dt` (module docs), `a < b`, `s > 0`. With
/// `u = (t − βs²)/s`, the cell is below the tilted Gaussian's mean (`u_b ≤ 0`), above it
/// (`u_a ≥ 0`) or around it; each case factors out the integrand's largest value, `ℓ − ½(t/s)²`
/// at b, a or the mean, and the rest is a ratio of scaled complementary error functions ([`erfcx`])
/// or a difference of Φ near the middle. No term exceeds the integrand's logarithm, so nothing
/// cancels in f32 either.
fn cell_mass(a: f64, b: f64, l: f64, beta: f64, s: f64) -> f64 {
    let shift = beta * s;
    let (ua, ub) = (a / s - shift, b / s - shift);
    if ub <= 0.0 {
        let lb = l + beta * (b - a) - 0.5 * (b / s) * (b / s);
        let ratio = scaled_cdf(ua) / scaled_cdf(ub) * (-0.5 * (ua - ub) * (ua + ub)).exp();
        lb.exp() * scaled_cdf(ub) * (1.0 - ratio).max(0.0)
    } else if ua >= 0.0 {
        let la = l - 0.5 * (a / s) * (a / s);
        let ratio = scaled_cdf(-ub) / scaled_cdf(-ua) * (-0.5 * (ub - ua) * (ub + ua)).exp();
        la.exp() * scaled_cdf(-ua) * (1.0 - ratio).max(0.0)
    } else {
        let t = beta * s * s;
        let peak = l + beta * (t - a) - 0.5 * (t / s) * (t / s);
        peak.exp() * (norm_cdf(ub) - norm_cdf(ua)).max(0.0)
    }
}

/// `Φ(u)·e^{u²/2} = ½erfcx(−u/√2)`: the normal CDF scaled by its own tail's decay (finite and
/// accurate far below 0, where Φ underflows).
fn scaled_cdf(u: f64) -> f64 {
    0.5 * erfcx(-u * FRAC_1_SQRT_2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The moments by a dense midpoint rule over ±12s (and the knots' span).
    fn brute(knots: &[f64], values: &[f64], s: f64) -> (f64, f64, f64) {
        let ell = |t: f64| {
            let k = knots.partition_point(|x| *x <= t);
            match k {
                0 => values[0],
                k if k >= knots.len() => values[knots.len() - 1],
                k => {
                    let w = (t - knots[k - 1]) / (knots[k] - knots[k - 1]);
                    values[k - 1] + w * (values[k] - values[k - 1])
                }
            }
        };
        let (lo, hi) = (-12.0 * s, 12.0 * s);
        let n = 400_000;
        let h = (hi - lo) / n as f64;
        let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let t = lo + (i as f64 + 0.5) * h;
            let w = h * ell(t).exp() * norm_pdf(t / s) / s;
            a += w;
            b += w * t;
            c += w * t * t;
        }
        (a, b, c)
    }

    /// Against brute force: a masking column that falls by 30 across one cell (a back face), a
    /// gentle one, and Gaussians narrower than a cell, about one cell and wider than the knots.
    #[test]
    fn moments_are_the_brute_force() {
        let knots: Vec<f64> = (0..17).map(|j| -4.0 + 0.5 * j as f64).collect();
        let steep: Vec<f64> = knots
            .iter()
            .map(|t| if *t < 1.0 { -0.1 * (t + 4.0) } else { -30.0 })
            .collect();
        let gentle: Vec<f64> = knots
            .iter()
            .map(|t| -0.3 * (t + 4.0) - 0.05 * t * t)
            .collect();
        for values in [&steep, &gentle] {
            for s in [0.1, 0.37, 1.0, 2.5, 9.0] {
                let got = log_linear_moments(&knots, values, s);
                let want = brute(&knots, values, s);
                let tol = |w: f64, scale: f64| 1e-6 * scale + 1e-7 * w.abs();
                assert!(
                    (got.0 - want.0).abs() <= tol(want.0, want.0),
                    "s {s}: {got:?} vs {want:?}"
                );
                assert!(
                    (got.1 - want.1).abs() <= tol(want.1, want.0 * s),
                    "s {s}: {got:?} vs {want:?}"
                );
                assert!(
                    (got.2 - want.2).abs() <= tol(want.2, want.0 * s * s),
                    "s {s}: {got:?} vs {want:?}"
                );
            }
        }
    }

    /// Exact identities: a constant is its value with the Gaussian's moments; an exponential
    /// `exp(βt)` with its knots far out is the log-normal moments `e^{½β²s²}(1, βs², s² + β²s⁴)`;
    /// a point Gaussian reads ℓ(0); nothing is NaN on hostile input.
    #[test]
    fn exact_cases_and_hostile_input() {
        let (m0, m1, m2) = log_linear_moments(&[-1.0, 2.0], &[-0.5, -0.5], 0.7);
        let c = (-0.5f64).exp();
        assert!((m0 - c).abs() < 1e-14 && m1.abs() < 1e-14 && (m2 - c * 0.49).abs() < 1e-14);
        let (beta, s) = (0.8, 0.6);
        let got = log_linear_moments(&[-40.0, 40.0], &[-40.0 * beta, 40.0 * beta], s);
        let e = (0.5 * beta * beta * s * s).exp();
        let want = (e, e * beta * s * s, e * (s * s + beta * beta * s.powi(4)));
        assert!((got.0 - want.0).abs() < 1e-12 && (got.1 - want.1).abs() < 1e-12);
        assert!((got.2 - want.2).abs() < 1e-12, "{got:?} vs {want:?}");
        let (m0, _, _) = log_linear_moments(&[-1.0, 1.0], &[-2.0, 0.0], 0.0);
        assert!((m0 - (-1.0f64).exp()).abs() < 1e-14);
        for s in [f64::NAN, -1.0, 0.0, 1e-300, 1e300, f64::INFINITY] {
            for v in [[f64::NAN, 0.0], [f64::NEG_INFINITY, -1e300], [0.0, 700.0]] {
                let (a, b, c) = log_linear_moments(&[-1.0, 1.0], &v, s);
                assert!(a.is_finite() && b.is_finite() && c.is_finite(), "{s} {v:?}");
            }
        }
        assert_eq!(log_linear_moments(&[], &[], 1.0), (0.0, 0.0, 0.0));
    }
}
