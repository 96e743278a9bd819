//! A procedural driver with analytic footprint statistics: a sum of random-phase sinusoids,
//! `f(x) = Σ a_i cos(2π k_i·x + φ_i)` (docs/design/noise.md, "One noise, three uses").
//!
//! * Unit variance: `Σ a_i²/2 = 1`, so f is (approximately, by the central limit theorem) N(0, 1),
//!   the Gaussian driver of [HNPN14 Sec. 4.2].
//! * Its gradient covariance `Σ a_i² (2π)² k_i k_iᵀ / 2` equals a target exactly: the wave vectors are
//!   mapped by `T^{1/2} G^{−1/2}` after drawing them, which is how the material's σ_nx, σ_ny (and so
//!   anisotropy) are met exactly for `h = σ_h·f`.
//! * A Gaussian pixel footprint of texture-space covariance Σ_p attenuates each component exactly by
//!   `g_i = exp(−2π² k_iᵀ Σ_p k_i)`. Hence the footprint mean `f̄ = Σ a_i g_i cos(…)` (also the
//!   level-of-detail geometry), the phase-averaged footprint variance `σ_f² = Σ a_i² (1 − g_i²)/2`
//!   [HNPN14 Sec. 4.2, with the square the extracted text drops], and the unresolved gradient
//!   covariance `Σ a_i² (2π)² k_i k_iᵀ (1 − g_i²)/2`. Close up (g → 1) everything is geometry; far
//!   away (g → 0) everything is statistics; in between each component moves smoothly from one to the
//!   other, so nothing pops.

use crate::driver::footprint::{FilteredDriver, Footprint};
use crate::math::random::splitmix;
use crate::microfacet::slopes::SlopeCov;
use glam::{DMat2, DVec2};
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// Parameters of the sum-of-sinusoids noise.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(default)]
pub struct NoiseParams {
    /// Random seed.
    pub seed: u64,
    /// Total number of sinusoids (more is more Gaussian: excess kurtosis ≈ −3/(2N) for equal amplitudes).
    pub components: u32,
    /// Number of octaves (frequency doubles per octave).
    pub octaves: u32,
    /// Amplitude ratio between successive octaves.
    pub gain: f64,
    /// Relative spread of |k| within an octave (0 = a single ring).
    pub bandwidth: f64,
    /// Base frequency in cycles per unit length, used only when the slopes cannot set the scale
    /// (a flat surface, σ_h = 0 or σ_n = 0); otherwise the frequencies follow from σ_n/σ_h.
    pub frequency: f64,
}

impl Default for NoiseParams {
    fn default() -> Self {
        Self {
            seed: 1,
            components: 48,
            octaves: 3,
            gain: 0.5,
            bandwidth: 0.4,
            frequency: 1.0,
        }
    }
}

impl NoiseParams {
    /// Largest accepted number of components (GPU uniform budget and cost per sample).
    pub const MAX_COMPONENTS: u32 = 256;
}

/// At most this many nested octave levels in the fast march ([`crate::scene::octave_march`]; the GPU carries their ends in a `vec4<u32>`); more octaves are
/// grouped.
pub const MAX_LEVELS: usize = 4;

/// The ends of the nested levels of `n` waves in `octaves` octaves (wave `i` is in octave
/// `i·octaves/n`, as [`SumOfSines::new`] lays them out), at most
/// [`MAX_LEVELS`], the last always `n`. Edge cases: `n = 0` gives `[0]`; one octave gives `[n]`.
pub fn level_ends(n: usize, octaves: usize) -> Vec<usize> {
    let octaves = octaves.max(1);
    let groups = octaves.min(MAX_LEVELS);
    let mut ends: Vec<usize> = (1..=groups)
        .map(|g| {
            // The first wave of octave ⌈g·octaves/groups⌉: the smallest i with i·octaves/n ≥ that.
            let o = (g * octaves).div_ceil(groups);
            (o * n).div_ceil(octaves).min(n)
        })
        .filter(|&e| e > 0)
        .collect();
    ends.dedup();
    if ends.last() != Some(&n) {
        ends.push(n);
    }
    ends
}

/// One sinusoid `a cos(2π k·x + φ)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wave {
    /// Wave vector in cycles per unit length.
    pub k: DVec2,
    /// Amplitude.
    pub amplitude: f64,
    /// Phase in radians.
    pub phase: f64,
}

/// A realised sum of sinusoids.
#[derive(Clone, Debug, PartialEq)]
pub struct SumOfSines {
    /// The components, coarse octave first.
    pub waves: Vec<Wave>,
    /// The number of octaves the waves are spread over (wave `i` is in octave `i·octaves/n`).
    pub octaves: usize,
}

/// Symmetric square root of a symmetric positive semi-definite 2×2 matrix (closed form).
fn sqrt_spd(m: DMat2) -> DMat2 {
    let det = m.determinant().max(0.0);
    let s = det.sqrt();
    let t = (m.x_axis.x + m.y_axis.y + 2.0 * s).max(0.0).sqrt();
    if t == 0.0 {
        DMat2::ZERO
    } else {
        (m + DMat2::from_diagonal(DVec2::splat(s))) * (1.0 / t)
    }
}

impl SumOfSines {
    /// Realise the noise with unit variance and gradient covariance `grad_cov` (per unit of f).
    /// A zero target falls back to the isotropic scale set by `params.frequency`.
    pub fn new(params: &NoiseParams, grad_cov: SlopeCov) -> Self {
        let n = params.components.clamp(1, NoiseParams::MAX_COMPONENTS) as usize;
        let octaves = params.octaves.clamp(1, 12) as usize;
        let gain = if params.gain.is_finite() {
            params.gain.clamp(0.0, 4.0)
        } else {
            0.5
        };
        let bw = if params.bandwidth.is_finite() {
            params.bandwidth.clamp(0.0, 1.5)
        } else {
            0.0
        };
        let mut state = params.seed ^ 0x5DEE_CE66_D1CE_4E5B;
        let mut waves = Vec::with_capacity(n);
        for i in 0..n {
            let o = i * octaves / n;
            let radius = 2f64.powi(o as i32) * (1.0 + bw * (splitmix(&mut state) - 0.5));
            let angle = PI * (i as f64 + splitmix(&mut state)) / n as f64 * 7.0; // spread directions
            let amplitude = gain.powi(o as i32).max(1e-6);
            let phase = TAU * splitmix(&mut state);
            waves.push(Wave {
                k: DVec2::from_angle(angle) * radius,
                amplitude,
                phase,
            });
        }
        // Unit variance.
        let var: f64 = waves.iter().map(|w| w.amplitude * w.amplitude / 2.0).sum();
        let norm = 1.0 / var.sqrt();
        for w in &mut waves {
            w.amplitude *= norm;
        }
        let mut me = Self { waves, octaves };
        // Exact gradient covariance: k ↦ T^{1/2} G^{−1/2} k.
        let target = {
            let t = grad_cov.to_mat();
            let ok = t.x_axis.x.is_finite() && t.y_axis.y.is_finite() && t.x_axis.y.is_finite();
            if ok && t.x_axis.x + t.y_axis.y > 0.0 {
                t
            } else {
                let f = if params.frequency.is_finite() && params.frequency > 0.0 {
                    params.frequency
                } else {
                    1.0
                };
                // An isotropic ring at frequency f has per-axis gradient variance (2πf)²/2.
                DMat2::from_diagonal(DVec2::splat((TAU * f).powi(2) / 2.0))
            }
        };
        let g = me.gradient_cov_matrix(Footprint::point());
        let g_half = sqrt_spd(g);
        let map = sqrt_spd(target) * g_half.inverse();
        for w in &mut me.waves {
            w.k = map * w.k;
        }
        me
    }

    fn gradient_cov_matrix(&self, fp: Footprint) -> DMat2 {
        let mut m = DMat2::ZERO;
        for w in &self.waves {
            let g = self.attenuation(w, fp);
            let s = w.amplitude * w.amplitude * TAU * TAU * (1.0 - g * g) / 2.0;
            let s = if fp.cov == DMat2::ZERO {
                w.amplitude * w.amplitude * TAU * TAU / 2.0
            } else {
                s
            };
            m += DMat2::from_cols(w.k * w.k.x, w.k * w.k.y) * s;
        }
        m
    }

    /// Attenuation `exp(−2π² kᵀ Σ_p k)` of one component under a Gaussian footprint.
    pub fn attenuation(&self, w: &Wave, fp: Footprint) -> f64 {
        (-2.0 * PI * PI * w.k.dot(fp.cov * w.k)).exp()
    }

    /// f(x).
    pub fn value(&self, x: DVec2) -> f64 {
        self.waves
            .iter()
            .map(|w| w.amplitude * (TAU * w.k.dot(x) + w.phase).cos())
            .sum()
    }

    /// f(x) and ∇f(x).
    pub fn value_and_gradient(&self, x: DVec2) -> (f64, DVec2) {
        let mut v = 0.0;
        let mut g = DVec2::ZERO;
        for w in &self.waves {
            let (s, c) = (TAU * w.k.dot(x) + w.phase).sin_cos();
            v += w.amplitude * c;
            g -= w.k * (w.amplitude * TAU * s);
        }
        (v, g)
    }

    /// Footprint statistics at x (see the module docs).
    pub fn filtered(&self, x: DVec2, fp: Footprint) -> FilteredDriver {
        let mut mean = 0.0;
        let mut var = 0.0;
        let mut grad = DVec2::ZERO;
        let mut cov = DMat2::ZERO;
        for w in &self.waves {
            let g = self.attenuation(w, fp);
            let (s, c) = (TAU * w.k.dot(x) + w.phase).sin_cos();
            mean += w.amplitude * g * c;
            grad -= w.k * (w.amplitude * g * TAU * s);
            let u = w.amplitude * w.amplitude * (1.0 - g * g) / 2.0;
            var += u;
            cov += DMat2::from_cols(w.k * w.k.x, w.k * w.k.y) * (u * TAU * TAU);
        }
        FilteredDriver {
            mean,
            std: var.max(0.0).sqrt(),
            mean_gradient: grad,
            gradient_cov: SlopeCov::from_mat(cov),
        }
    }

    /// The unresolved gradient at a footprint as a random-phase sum of sinusoids: per wave
    /// `v_i = 2π a_i √(1 − α_i²)·k_i` (α_i its [`SumOfSines::attenuation`]), whose covariance
    /// `Σ ½ v_i v_iᵀ` is [`SumOfSines::filtered`]'s gradient covariance. Far away (α → 0) these are
    /// the waves' own gradients: the exact slope distribution is the density of `Σ v_i sin ψ_i`
    /// ([`crate::microfacet::slope_density`]). Waves with nothing left unresolved are skipped.
    pub fn unresolved_gradient_terms(&self, fp: Footprint) -> Vec<DVec2> {
        self.waves
            .iter()
            .filter_map(|w| {
                let g = self.attenuation(w, fp);
                let r = (1.0 - g * g).max(0.0).sqrt();
                (r > 0.0).then(|| w.k * (TAU * w.amplitude * r))
            })
            .collect()
    }

    /// The ends of the fast march's nested octave levels
    /// ([`level_ends`]).
    pub fn level_ends(&self) -> Vec<usize> {
        level_ends(self.waves.len(), self.octaves)
    }

    /// `Σ|a_i|`: a bound on |f| (and on |f̄| at any footprint).
    pub fn amplitude_bound(&self) -> f64 {
        self.waves.iter().map(|w| w.amplitude.abs()).sum()
    }

    /// A Lipschitz constant of f along the horizontal unit direction `dir`: `Σ|a_i| 2π |k_i·dir|`.
    pub fn lipschitz_along(&self, dir: DVec2) -> f64 {
        self.waves
            .iter()
            .map(|w| w.amplitude.abs() * TAU * w.k.dot(dir).abs())
            .sum()
    }

    /// The gradient covariance of the unfiltered noise (equals the construction target).
    pub fn gradient_cov(&self) -> SlopeCov {
        SlopeCov::from_mat(self.gradient_cov_matrix(Footprint::point()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_follow_octaves_and_end_at_n() {
        assert_eq!(level_ends(48, 3), vec![16, 32, 48]);
        assert_eq!(level_ends(64, 3), vec![22, 43, 64]);
        assert_eq!(level_ends(48, 1), vec![48]);
        assert_eq!(level_ends(0, 3), vec![0]);
        assert_eq!(level_ends(2, 3), vec![1, 2]);
        // 8 octaves grouped into 4 levels of 2.
        assert_eq!(level_ends(64, 8), vec![16, 32, 48, 64]);
        // 6 octaves into 4: boundaries at octaves 2, 3, 5.
        assert_eq!(level_ends(60, 6), vec![20, 30, 50, 60]);
        for n in 0..70 {
            for o in 1..13 {
                let e = level_ends(n, o);
                assert!(e.len() <= MAX_LEVELS && *e.last().unwrap() == n);
                assert!(e.windows(2).all(|w| w[0] < w[1]), "{n} {o} {e:?}");
                // Every boundary is an octave boundary.
                for &b in &e[..e.len() - 1] {
                    assert_ne!((b - 1) * o / n, b * o / n, "{n} {o} {e:?}");
                }
            }
        }
    }

    fn noise(target: SlopeCov) -> SumOfSines {
        SumOfSines::new(
            &NoiseParams {
                components: 64,
                ..NoiseParams::default()
            },
            target,
        )
    }

    #[test]
    fn construction_meets_its_targets_exactly() {
        let target = SlopeCov {
            xx: 2.0,
            yy: 0.5,
            xy: 0.3,
        };
        let n = noise(target);
        let var: f64 = n
            .waves
            .iter()
            .map(|w| w.amplitude * w.amplitude / 2.0)
            .sum();
        assert!((var - 1.0).abs() < 1e-12);
        let g = n.gradient_cov();
        assert!(
            (g.xx - 2.0).abs() < 1e-9 && (g.yy - 0.5).abs() < 1e-9 && (g.xy - 0.3).abs() < 1e-9,
            "{g:?}"
        );
    }

    /// Low-discrepancy sample positions over a square of side `extent` (R2 sequence).
    fn sample_points(count: usize, extent: f64) -> impl Iterator<Item = DVec2> {
        let (a1, a2) = (0.754_877_666_246_692_7, 0.569_840_290_998_053_3);
        (0..count).map(move |i| {
            DVec2::new((0.5 + a1 * i as f64).fract(), (0.5 + a2 * i as f64).fract()) * extent
        })
    }

    #[test]
    fn large_realisation_matches_analytic_statistics_within_2_percent() {
        let target = SlopeCov::from_std(1.5, 0.6);
        let n = noise(target);
        let (mut s1, mut s2, mut s4, mut gxx, mut gyy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let count = 200_000;
        // ~100 periods of the lowest octave.
        for x in sample_points(count, 1000.0) {
            let (v, g) = n.value_and_gradient(x);
            s1 += v;
            s2 += v * v;
            s4 += v.powi(4);
            gxx += g.x * g.x;
            gyy += g.y * g.y;
        }
        let c = count as f64;
        let mean = s1 / c;
        let var = s2 / c - mean * mean;
        assert!(mean.abs() < 0.02, "mean {mean}");
        assert!((var - 1.0).abs() < 0.02, "variance {var}");
        assert!(
            (gxx / c / target.xx - 1.0).abs() < 0.02,
            "σ_nx² {} vs {}",
            gxx / c,
            target.xx
        );
        assert!(
            (gyy / c / target.yy - 1.0).abs() < 0.02,
            "σ_ny² {} vs {}",
            gyy / c,
            target.yy
        );
        // Close to Gaussian: kurtosis near 3.
        assert!(
            (s4 / c / (var * var) - 3.0).abs() < 0.15,
            "kurtosis {}",
            s4 / c / (var * var)
        );
    }

    #[test]
    fn footprint_statistics_match_brute_force() {
        let n = noise(SlopeCov::isotropic(2.0));
        // Footprints from sub-feature to many features. The model's σ_f² is the expected (phase-averaged)
        // footprint variance: compare it with the average over many footprint centres, within the
        // sampling error of that average.
        for &r in &[0.02, 0.1, 0.3, 1.0] {
            let fp = Footprint::isotropic(r);
            let mut vars = vec![];
            let mut mean_err = 0.0_f64;
            let mut model = 0.0;
            for x0 in sample_points(300, 500.0) {
                let (mut w_sum, mut m1, mut m2) = (0.0, 0.0, 0.0);
                let k = 24;
                for i in -k..=k {
                    for j in -k..=k {
                        let d = DVec2::new(i as f64, j as f64) * (4.0 * r / k as f64);
                        let w = (-d.length_squared() / (2.0 * r * r)).exp();
                        let v = n.value(x0 + d);
                        w_sum += w;
                        m1 += w * v;
                        m2 += w * v * v;
                    }
                }
                let bm = m1 / w_sum;
                vars.push(m2 / w_sum - bm * bm);
                let f = n.filtered(x0, fp);
                mean_err = mean_err.max((f.mean - bm).abs());
                model = f.std * f.std;
            }
            assert!(mean_err < 2e-3, "r={r}: footprint mean off by {mean_err}");
            let c = vars.len() as f64;
            let avg = vars.iter().sum::<f64>() / c;
            let se = (vars.iter().map(|v| (v - avg).powi(2)).sum::<f64>() / (c - 1.0) / c).sqrt();
            assert!(
                (avg - model).abs() < 3.0 * se + 0.01 * model,
                "r={r}: footprint variance {avg} ± {se} vs analytic {model}"
            );
        }
    }

    #[test]
    fn degenerate_targets_are_finite() {
        for t in [
            SlopeCov::default(),
            SlopeCov::from_std(1.0, 0.0),
            SlopeCov::isotropic(1e6),
            SlopeCov::isotropic(1e-9),
        ] {
            let n = noise(t);
            let f = n.filtered(DVec2::new(0.3, 0.2), Footprint::isotropic(0.5));
            assert!(f.mean.is_finite() && f.std.is_finite() && f.mean_gradient.is_finite());
            assert!(n.value(DVec2::new(1.0, 2.0)).is_finite());
        }
    }
}
