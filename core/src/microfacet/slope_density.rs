//! The slope density of a random-phase sum of sinusoids, by the saddlepoint approximation (#17).
//!
//! The noise's unresolved slopes at a footprint are `s = Σ_i v_i sin ψ_i` with independent
//! uniform phases (`v_i = σ_h·2π a_i √(1 − α_i²)·k_i`, α_i the wave's attenuation under the
//! footprint: [`crate::driver::noise::SumOfSines::unresolved_gradient_terms`]); the base BRDF adds
//! its own `N(0, σ0² I)`. The filtered model replaces that density by the Gaussian of the same
//! covariance `Σ_t = Σ ½ v_i v_iᵀ + σ0² I`. That is right near the mean and wrong in the tails:
//! the slopes are bounded by `Σ|v_i|`, and a specular half vector 4σ out (bumpy-specular at 75°
//! with the light at 30° on the same side) sees a density 200× below the Gaussian's (measured on
//! the explicit surface: `core/src/eval/independent_tests.rs`, `grazing_specular_decomposition`).
//!
//! The cumulant generating function is exact and cheap:
//! `K(τ) = Σ ln I0(τ·v_i) + ½σ0²|τ|²` ([`log_bessel_i0`]), and the saddlepoint density
//! [Daniels 1954] `p(d) ≈ exp(K(τ̂) − τ̂·d) / (2π √det ∇²K(τ̂))`, `∇K(τ̂) = d`, has a relative
//! error O(1/n) uniformly in d, tails included; with the second-order correction
//! `1 + ρ4/8 − (3ρ13² + 2ρ23²)/24` from the third and fourth cumulants at τ̂ (McCullagh 1987,
//! Sec. 6.3: for twelve waves the first order is 10% off at the mean, the corrected form within
//! 1%, tested) it is O(1/n²). [`sinusoid_density_ratio`] returns `p(d)/N(d; Σ_t)`,
//! which multiplies the filtered model's Gaussian specular lobe; it is exactly 1 at d = 0 and
//! tends to 1 as the waves become many and small (the central limit).

use crate::math::bessel::{bessel_ratio_derivatives, bessel_terms};
use glam::{DMat2, DVec2};
use serde::{Deserialize, Serialize};

/// Which density of the noise's unresolved slopes the filtered specular lobe uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum NoiseSlopes {
    /// The sum of sinusoids' own density (saddlepoint, [`sinusoid_density_ratio`]; default).
    #[default]
    Exact,
    /// The Gaussian of the same covariance (the papers' model).
    Gaussian,
}

/// Newton iterations on the saddlepoint equation (each with up to [`BACKTRACKS`] halvings).
pub const SADDLEPOINT_ITERATIONS: usize = 8;

/// The iteration stops once the Newton decrement `gᵀ(∇²F)⁻¹g` is below this. F is then within half
/// of it of its minimum, but the density's `½ ln det ∇²K` and second-order term move to first
/// order in τ's error (~√decrement), so the stop is tight: the ratio agrees with the full eight
/// iterations to 1e-6 (tested), after 1–3 evaluations within 1σ and 6–7 in the far tail where it
/// made 9–19 (each a pass over every wave on the GPU). f32 still resolves it: g's rounding,
/// ~1e-7 of |d|, puts the decrement near 1e-14·(|d|/σ)².
pub const NEWTON_DECREMENT: f64 = 1e-11;

/// A step is taken when F rises by at most this fraction of |F| (more than f32's rounding of F,
/// 6e-8 relative): near the minimum a full Newton step changes F by less than its rounding, and
/// a strict `F(τ + step) ≤ F(τ)` on the GPU then compares rounding noise, fails, and spends
/// [`BACKTRACKS`] + 1 evaluations for nothing. Measured on the GPU (default preset, 128²,
/// 60°/80° × distance 6/40), evaluations per pixel before this tolerance: 4.3–5.1 on average,
/// 6.6–11.3 for the slowest of every 8 neighbouring pixels, up to 27; with it 2.4–3.1 and
/// 2.9–4.2. F is convex, so a Newton step there is a sound one; far from the minimum F's decrease
/// dwarfs the tolerance and the backtracking guards as before.
pub const F_TOLERANCE: f64 = 2.5e-7;

/// Step halvings per Newton iteration.
pub const BACKTRACKS: usize = 3;

/// The ratio is clamped to `[0, e^MAX_LOG_RATIO]` (the shoulders of a sum of few sinusoids can
/// exceed the Gaussian, never by this much).
pub const MAX_LOG_RATIO: f64 = 4.0;

/// A term whose variance `½|v_i|²` is below this fraction of σ0² is left out of the saddlepoint
/// (kept in the covariance): a wave the footprint has (almost) resolved, whose whole effect on the
/// density is below 1e-9 relative. Near the camera most waves are; the GPU then sums only the rest.
pub const NEGLIGIBLE_TERM: f64 = 1e-9;

/// Smallest σ0 the saddlepoint uses: keeps ∇²K invertible when d lies beyond `Σ|v_i|`.
pub const MIN_SIGMA0: f64 = 1e-3;

/// `F(τ) = K(τ) − τ·d`, its gradient and Hessian.
fn objective(v: &[DVec2], s02: f64, d: DVec2, tau: DVec2) -> (f64, DVec2, DMat2) {
    let mut k = 0.5 * s02 * tau.length_squared();
    let mut g = tau * s02 - d;
    let mut h = DMat2::from_diagonal(DVec2::splat(s02));
    for vi in v {
        let [ln_i0, a, a1] = bessel_terms(tau.dot(*vi));
        k += ln_i0;
        g += *vi * a;
        h += DMat2::from_cols(*vi * vi.x, *vi * vi.y) * a1;
    }
    (k - tau.dot(d), g, h)
}

/// `p(d)/N(d; Σ_t)`: the saddlepoint density of `Σ v_i sin ψ_i + N(0, σ0² I)` at `d` over the
/// Gaussian of the same covariance (module docs). 1 without terms; finite and in
/// `[0, e^MAX_LOG_RATIO]` for every input.
pub fn sinusoid_density_ratio(v: &[DVec2], sigma0: f64, d: DVec2) -> f64 {
    saddlepoint(v, sigma0, d, NEWTON_DECREMENT).0
}

/// [`sinusoid_density_ratio`] with the number of objective evaluations the Newton iteration made
/// (the GPU's cost: each sums every term once), stopping on the Newton decrement `decrement`.
fn saddlepoint(v: &[DVec2], sigma0: f64, d: DVec2, decrement: f64) -> (f64, usize) {
    if v.is_empty() || !d.is_finite() {
        return (1.0, 0);
    }
    let s0 = if sigma0.is_finite() {
        sigma0.max(MIN_SIGMA0)
    } else {
        MIN_SIGMA0
    };
    let s02 = s0 * s0;
    let mut cov = DMat2::from_diagonal(DVec2::splat(s02));
    for vi in v {
        cov += DMat2::from_cols(*vi * vi.x, *vi * vi.y) * 0.5;
    }
    let det_t = cov.determinant();
    if !(det_t > 0.0) || !det_t.is_finite() {
        return (1.0, 0);
    }
    let cinv = cov.inverse();
    let v: Vec<DVec2> = v
        .iter()
        .copied()
        .filter(|vi| 0.5 * vi.length_squared() > NEGLIGIBLE_TERM * s02)
        .collect();
    let v = v.as_slice();
    // Start at the Gaussian's saddlepoint, then damped Newton on the convex F.
    let mut tau = cinv * d;
    let (mut f, mut g, mut h) = objective(v, s02, d, tau);
    let mut evaluations = 1;
    for _ in 0..SADDLEPOINT_ITERATIONS {
        let det = h.determinant();
        if !(det > 0.0) {
            break;
        }
        let step = h.inverse() * g;
        if !(g.dot(step) > decrement) {
            break;
        }
        let mut t = 1.0;
        let mut moved = false;
        for _ in 0..=BACKTRACKS {
            let cand = tau - step * t;
            let (fc, gc, hc) = objective(v, s02, d, cand);
            evaluations += 1;
            if fc.is_finite() && fc <= f + F_TOLERANCE * f.abs() {
                (tau, f, g, h) = (cand, fc, gc, hc);
                moved = true;
                break;
            }
            t *= 0.5;
        }
        if !moved {
            break;
        }
    }
    let det_h = h.determinant();
    if !(det_h > 0.0) {
        return (1.0, evaluations);
    }
    // ln p − ln N = F(τ̂) + ½ dᵀΣ_t⁻¹d + ½ ln(det Σ_t / det H), times the second-order term.
    let log_ratio = f + 0.5 * d.dot(cinv * d) + 0.5 * (det_t / det_h).ln();
    if log_ratio.is_nan() {
        return (1.0, evaluations);
    }
    let correction = second_order(v, tau, &h.inverse());
    (log_ratio.min(MAX_LOG_RATIO).exp() * correction, evaluations)
}

/// `1 + ρ4/8 − (3ρ13² + 2ρ23²)/24` at τ̂ with `h = (∇²K)⁻¹`: the cumulant tensors of K (sums of
/// rank-one terms `A″(x_n) v_n^{⊗3}`, `A‴(x_n) v_n^{⊗4}`; the Gaussian σ0 part has none) held as
/// 2×2×2(×2) arrays, contracted index by index. Clamped to [0.25, 2] (a correction beyond that
/// means the expansion no longer applies).
fn second_order(v: &[DVec2], tau: DVec2, h: &DMat2) -> f64 {
    let mut k3 = [[[0.0f64; 2]; 2]; 2];
    let mut k4 = [[[[0.0f64; 2]; 2]; 2]; 2];
    for vi in v {
        let [_, a2, a3] = bessel_ratio_derivatives(tau.dot(*vi));
        let c = [vi.x, vi.y];
        for i in 0..2 {
            for j in 0..2 {
                for k in 0..2 {
                    let p = c[i] * c[j] * c[k];
                    k3[i][j][k] += a2 * p;
                    for l in 0..2 {
                        k4[i][j][k][l] += a3 * p * c[l];
                    }
                }
            }
        }
    }
    let hm = [[h.x_axis.x, h.y_axis.x], [h.x_axis.y, h.y_axis.y]];
    let (mut rho4, mut rho13, mut rho23) = (0.0, 0.0, 0.0);
    for i in 0..2 {
        for j in 0..2 {
            for k in 0..2 {
                for l in 0..2 {
                    rho4 += k4[i][j][k][l] * hm[i][j] * hm[k][l];
                    for m in 0..2 {
                        for n in 0..2 {
                            let a = k3[i][j][k] * k3[l][m][n];
                            rho13 += a * hm[i][j] * hm[k][l] * hm[m][n];
                            rho23 += a * hm[i][l] * hm[j][m] * hm[k][n];
                        }
                    }
                }
            }
        }
    }
    let c = 1.0 + rho4 / 8.0 - (3.0 * rho13 + 2.0 * rho23) / 24.0;
    if c.is_finite() {
        c.clamp(0.25, 2.0)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::splitmix;
    use std::f64::consts::TAU;

    /// Twelve waves of unequal amplitude in several directions: few enough that the slope density
    /// is far from Gaussian in its tails.
    fn terms() -> Vec<DVec2> {
        (0..12)
            .map(|i| {
                let a = 0.7 + 0.37 * i as f64;
                let r = 0.05 + 0.03 * ((i * 7) % 5) as f64;
                DVec2::new(a.cos(), a.sin()) * r
            })
            .collect()
    }

    /// The Newton iteration from the Gaussian's saddlepoint stops on its decrement after a few
    /// evaluations of the objective (the GPU's cost is one pass over the waves per evaluation;
    /// without the stop it made nine or more), and the answer agrees with one run to the full
    /// eight iterations within 1e-6.
    #[test]
    fn the_newton_iteration_stops_when_converged() {
        let v = terms();
        let s0 = 0.02;
        let sigma = (v.iter().map(|t| 0.5 * t.length_squared()).sum::<f64>() / 2.0).sqrt();
        for (r, most) in [(0.0, 1), (0.5, 3), (1.0, 3), (2.0, 4), (4.0, 7), (6.0, 7)] {
            for a in [0.3f64, 1.9, 4.0] {
                let d = DVec2::new(a.cos(), a.sin()) * (r * sigma);
                let (ratio, n) = saddlepoint(&v, s0, d, NEWTON_DECREMENT);
                let (full, n_full) = saddlepoint(&v, s0, d, 0.0);
                eprintln!(
                    "{r}σ at {a}: {n} evaluations (without the stop {n_full}), off by {:.1e}",
                    ratio / full - 1.0
                );
                assert!(n <= most, "{r}σ at {a}: {n} evaluations");
                assert!(
                    (ratio - full).abs() <= 1e-6 * full,
                    "{r}σ: {ratio} vs {full}"
                );
            }
        }
    }

    /// Against a Monte Carlo histogram of Σ v_i sin ψ_i + N(0, σ0²I) (4M samples, discs of radius
    /// 0.1σ) at 0 to 4.5σ along two directions: within 3% (+ 4 s.e.) where the Gaussian is 10% off
    /// at the mean (the first-order saddlepoint too: the second-order term makes the difference).
    #[test]
    fn matches_a_monte_carlo_histogram_into_the_tails() {
        let v = terms();
        let s0 = 0.02;
        let mut cov = DMat2::from_diagonal(DVec2::splat(s0 * s0));
        for vi in &v {
            cov += DMat2::from_cols(*vi * vi.x, *vi * vi.y) * 0.5;
        }
        let sigma = (0.5 * (cov.x_axis.x + cov.y_axis.y)).sqrt();
        let dirs = [DVec2::new(1.0, 0.0), DVec2::new(0.6, 0.8)];
        let radii = [0.0, 1.0, 2.0, 3.0, 3.8, 4.5];
        let centres: Vec<DVec2> = dirs
            .iter()
            .flat_map(|d| radii.iter().map(move |r| *d * (r * sigma)))
            .collect();
        let rad = 0.1 * sigma;
        let mut counts = vec![0u64; centres.len()];
        let n = 4_000_000u64;
        let mut rng = 17u64;
        for _ in 0..n {
            let mut s = DVec2::ZERO;
            for vi in &v {
                s += *vi * (TAU * splitmix(&mut rng)).sin();
            }
            s += DVec2::new(
                crate::math::random::standard_normal(&mut rng),
                crate::math::random::standard_normal(&mut rng),
            ) * s0;
            for (c, k) in centres.iter().zip(counts.iter_mut()) {
                if (s - *c).length_squared() < rad * rad {
                    *k += 1;
                }
            }
        }
        let cinv = cov.inverse();
        let gauss = |d: DVec2| (-0.5 * d.dot(cinv * d)).exp() / (TAU * cov.determinant().sqrt());
        let mut worst_gauss = 1.0f64;
        for (c, k) in centres.iter().zip(&counts) {
            let area = std::f64::consts::PI * rad * rad;
            let p_mc = *k as f64 / n as f64 / area;
            let se = (*k as f64).max(1.0).sqrt() / n as f64 / area;
            let p_sp = sinusoid_density_ratio(&v, s0, *c) * gauss(*c);
            assert!(
                (p_sp - p_mc).abs() < 0.03 * p_mc + 4.0 * se,
                "at {c:?}: saddlepoint {p_sp:.4e}, Monte Carlo {p_mc:.4e} ± {se:.1e}, Gaussian {:.4e}",
                gauss(*c)
            );
            if *k > 1000 {
                worst_gauss = worst_gauss.max(gauss(*c) / p_mc).max(p_mc / gauss(*c));
            }
        }
        // Where counts are plenty (the tail points are checked within their noise above).
        assert!(
            worst_gauss > 1.08,
            "the test needs a non-Gaussian density: {worst_gauss}"
        );
    }

    /// Below 1 at the mean for few waves (a sum of twelve sinusoids is flatter than a Gaussian);
    /// → 1 for many small waves (central limit); finite and bounded everywhere, far beyond the
    /// slopes' bound included.
    #[test]
    fn flatter_at_the_mean_one_in_the_central_limit_finite_everywhere() {
        let v = terms();
        let r0 = sinusoid_density_ratio(&v, 0.02, DVec2::ZERO);
        assert!(r0 > 0.85 && r0 < 0.97, "{r0}");
        let many: Vec<DVec2> = (0..2000)
            .map(|i| {
                let a = 0.1 * i as f64;
                DVec2::new(a.cos(), a.sin()) * 0.01
            })
            .collect();
        let r = sinusoid_density_ratio(&many, 0.001, DVec2::new(0.45, 0.2));
        assert!((r - 1.0).abs() < 0.05, "central limit: {r}");
        for d in [
            DVec2::new(10.0, 0.0),
            DVec2::new(1e6, -1e6),
            DVec2::new(0.0, 3.0),
            DVec2::new(f64::NAN, 0.0),
        ] {
            for s0 in [0.0, 1e-9, 0.02, 5.0, f64::INFINITY] {
                let r = sinusoid_density_ratio(&v, s0, d);
                assert!(
                    r.is_finite() && (0.0..=MAX_LOG_RATIO.exp()).contains(&r),
                    "{d:?} {s0}: {r}"
                );
            }
        }
        assert_eq!(sinusoid_density_ratio(&[], 0.1, DVec2::ONE), 1.0);
    }
}
