//! Masking conditioned on the facet's slope (#17; docs/design/slope-masking.md, "The grazing diffuse error is
//! slope-conditioned masking").
//!
//! Smith's masking makes a facet's visibility depend on its height alone. On a correlated surface it
//! also depends on the facet's slope: a facet leaning toward the silhouette has the surface rising
//! in front of it along the ray, one facing the eye has it falling away. Along a horizontal
//! direction d the height of a random-phase sum of sinusoids is a stationary Gaussian process of
//! autocovariance `R(τ) = Σ c_i cos(ω_i τ)` (`c_i = ½a_i²`, or `½a_i²(1 − g_i²)` for what a
//! footprint leaves unresolved, `ω_i = 2π k_i·d`). Given the start's height and slope along d,
//! `(h(0), h′(0)) = (h₀, t)`, the pair `(h(τ), h′(τ))` is Gaussian with mean
//! `(R h₀/λ₀ − R′t/λ₂, R′h₀/λ₀ − R″t/λ₂)` (`λ₀ = R(0)`, `λ₂ = −R″(0)`) and the Schur complement as
//! covariance. The ray `r(τ) = h₀ + μτ` (μ = cot θ) is crossed at Rice's rate
//! `E[(h′ − μ)⁺ | h = r]·p(h = r)/P(h < r)` (Smith's "below the ray so far" [Smith 1967; HN12
//! Eq. 5]), so `G1(h₀, t) = exp(−∫ rate dτ)`. Without the conditioning (an independent future) it is
//! Smith's `Φ(h₀)^Λ` [HN12 Eqs. 4–6].
//!
//! The views keep their height-correlated G2 and D_h and weight the visible (height, slope) pairs
//! by G1 relative to Smith's, `r(h₀, t)` ([`JointMasking`]): each slope sees its own heights, and
//! the mean visibility stays Smith's, only its share among the pairs moves
//! ([`crate::eval::masking::slope_weights`]). [`conditioned_masking`], the height-averaged profile
//! `E_h₀[G1(h₀, t)]`, is what session 18's views used (colour and slopes reweighted separately,
//! which failed with the light opposite the view; docs/design/slope-masking.md); the measurements keep it.
//!
//! Units: the process is normalised to unit height and slope variance ([`LineProcess`]), so the
//! slope is `z = t/σ_t` and the ray's slope `ν = μ/σ_t`, with `σ_t = √λ₂` the slope's standard
//! deviation along d; the result depends on the spectrum's shape alone, not on σ_h.

use crate::math::special::{log_norm_cdf, norm_cdf, norm_pdf, smith_lambda};
use serde::{Deserialize, Serialize};

/// How the filtered view's masking and shadowing treat a facet's slope.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum SlopeMasking {
    /// Smith's: visibility depends on the height alone (the papers' model, [HN12 Eqs. 4–6]).
    Smith,
    /// Masking conditioned on the facet's height and slope along the view jointly
    /// ([`JointMasking`]; default): each visible slope sees its own heights, so the colour (which
    /// follows the height) and the shading (which follows the slope) are summed together. Noise
    /// drivers only: an image driver's process is not a sum of sinusoids, and it keeps Smith's.
    #[default]
    Conditioned,
}

/// The slopes (in σ_t) at which [`conditioned_masking`] is tabulated: −4 to 4 by 1.
pub const SLOPE_NODES: usize = 9;

/// Slope of node `j` of [`SLOPE_NODES`], in standard deviations: `−4 + j`.
pub fn slope_node(j: usize) -> f64 {
    -4.0 + j as f64
}

/// Heights of the start, in σ_h, over which G1 is averaged (a rule in `[−4.5, 4.5]` of step 1,
/// trapezoid-weighted by φ(h)).
pub const HEIGHT_NODES: usize = 10;

/// The ray is followed until it is this many σ_h above the mean plane, where nothing crosses it
/// (Φ(6) = 1 − 1e-9).
const TOP: f64 = 6.0;

/// Most integration steps per start (the step grows to keep within it on the most grazing rays).
const MAX_STEPS: usize = 3000;

/// The height process along one horizontal direction, normalised to unit height and slope
/// variance: `R̂(τ) = Σ c_i cos(ω_i τ)` with `Σ c_i = 1`, `Σ c_i ω_i² = 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct LineProcess {
    terms: Vec<(f64, f64)>,
}

impl LineProcess {
    /// From each component's variance `c_i ≥ 0` and angular frequency `ω_i` along the direction.
    /// `None` when the process has no height variance or no slope along the direction (then no
    /// slope conditions anything). Non-finite or negative terms are dropped.
    pub fn new(terms: impl IntoIterator<Item = (f64, f64)>) -> Option<Self> {
        let terms: Vec<(f64, f64)> = terms
            .into_iter()
            .filter(|(c, w)| c.is_finite() && w.is_finite() && *c > 0.0)
            .map(|(c, w)| (c, w.abs()))
            .collect();
        let l0: f64 = terms.iter().map(|(c, _)| c).sum();
        let l2: f64 = terms.iter().map(|(c, w)| c * w * w).sum();
        if !(l0 > 0.0 && l2 > 1e-300 * l0 && l0.is_finite() && l2.is_finite()) {
            return None;
        }
        let scale = (l0 / l2).sqrt();
        Some(Self {
            terms: terms
                .into_iter()
                .map(|(c, w)| (c / l0, w * scale))
                .collect(),
        })
    }

    /// `(R̂, R̂′, R̂″)` at τ.
    fn at(&self, tau: f64) -> (f64, f64, f64) {
        self.terms
            .iter()
            .fold((0.0, 0.0, 0.0), |(r, r1, r2), (c, w)| {
                let (s, co) = (w * tau).sin_cos();
                (r + c * co, r1 - c * w * s, r2 - c * w * w * co)
            })
    }

    /// The highest normalised frequency.
    fn max_frequency(&self) -> f64 {
        self.terms.iter().map(|(_, w)| *w).fold(0.0, f64::max)
    }
}

/// The masking of [`conditioned_masking`] by slope, averaged over heights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConditionedMasking {
    /// `E_h₀[G1(h₀, z)]` at the slopes of [`slope_node`] (back faces hold the last front value).
    pub slopes: [f64; SLOPE_NODES],
}

impl ConditionedMasking {
    /// No conditioning: 1 at every slope.
    pub fn none() -> Self {
        Self {
            slopes: [1.0; SLOPE_NODES],
        }
    }
}

/// Height of node `i` of [`HEIGHT_NODES`], in σ_h: `−4.5 + i`.
pub fn height_node(i: usize) -> f64 {
    -4.5 + i as f64
}

/// `E_h₀[G1(h₀, t)]` at the slopes `t = z_j σ_t` of [`slope_node`], for a ray of slope `ν = μ/σ_t`
/// over `process` (module docs): h₀ ~ N(0, 1), independent of t at the same point. Back faces
/// (`z ≥ ν`) hold the last front value. Up to a constant this is the factor by which the visible
/// slopes are reweighted.
///
/// Edge cases: `ν ≤ 0` or NaN (the ray never leaves the surface) gives all zeros; `ν ≥ 8` (no
/// masking within 8 slope deviations) gives 1 everywhere. Always finite, in [0, 1].
pub fn conditioned_masking(process: &LineProcess, nu: f64) -> ConditionedMasking {
    if !(nu > 0.0 && nu < 8.0) {
        // Nothing to integrate: the edge cases of `conditioned_masking_on`.
        return conditioned_masking_on(
            &ProcessGrid {
                dt: 1.0,
                values: vec![],
                memory: 0,
            },
            nu,
        );
    }
    conditioned_masking_on(&ProcessGrid::new(process, nu), nu)
}

/// `(R̂, R̂′, R̂″)` of a process at the midpoints of a τ grid: fine enough for its highest
/// frequency (step `min(0.1, 0.25/ω̂_max)`), long enough for the lowest start of a ray of slope
/// `nu_min` to climb out of the surface (coarser when that would pass [`MAX_STEPS`]). One grid
/// serves every ν ≥ `nu_min` ([`conditioned_masking_on`]).
///
/// Past `memory` steps the process has forgotten the start (|R̂|, |R̂′|, |R̂″| stay below
/// [`MEMORY`] on the rest of the grid): the rate there is Smith's, unconditioned, and its integral
/// to the end is closed, `−E[(h′ − ν)⁺]·ln Φ(r)/ν` from the ray's height r at the cut.
#[derive(Clone, Debug, PartialEq)]
pub struct ProcessGrid {
    dt: f64,
    values: Vec<(f64, f64, f64)>,
    memory: usize,
}

/// Below this the process's correlation with the start is neglected ([`ProcessGrid`]).
const MEMORY: f64 = 0.01;

impl ProcessGrid {
    /// The grid of `process` for rays of slope at least `nu_min` (> 0).
    pub fn new(process: &LineProcess, nu_min: f64) -> Self {
        let span = (TOP + 4.5) / nu_min.max(1e-3);
        let mut dt = (0.25 / process.max_frequency().max(1.0)).min(0.1);
        if span / dt > MAX_STEPS as f64 {
            dt = span / MAX_STEPS as f64;
        }
        let steps = (span / dt).ceil() as usize;
        let values: Vec<(f64, f64, f64)> = (0..steps)
            .map(|i| process.at((i as f64 + 0.5) * dt))
            .collect();
        let mut memory = values.len();
        while memory > 0 {
            let (r, r1, r2) = values[memory - 1];
            if r.abs().max(r1.abs()).max(r2.abs()) >= MEMORY {
                break;
            }
            memory -= 1;
        }
        Self { dt, values, memory }
    }

    /// The τ step.
    pub fn step(&self) -> f64 {
        self.dt
    }

    /// `(R̂, R̂′, R̂″)` at the midpoints of the steps for as long as the process remembers the
    /// start (past them the rate is Smith's, unconditioned).
    pub fn remembered(&self) -> &[(f64, f64, f64)] {
        &self.values[..self.memory]
    }
}

/// [`conditioned_masking`] on a grid built for rays at most as grazing as `nu`.
pub fn conditioned_masking_on(grid: &ProcessGrid, nu: f64) -> ConditionedMasking {
    let mut out = ConditionedMasking {
        slopes: [0.0; SLOPE_NODES],
    };
    if !(nu > 0.0) {
        return out;
    }
    if nu >= 8.0 {
        return ConditionedMasking::none();
    }
    let (dt, grid) = (grid.dt, &grid.values[..grid.memory]);
    let hw: Vec<f64> = (0..HEIGHT_NODES)
        .map(|i| {
            let end = i == 0 || i == HEIGHT_NODES - 1;
            (if end { 0.5 } else { 1.0 }) * norm_pdf(height_node(i))
        })
        .collect();
    let hsum: f64 = hw.iter().sum();
    for j in 0..SLOPE_NODES {
        let t = slope_node(j);
        if t >= nu {
            // A back face: the clamped cosine and u⁺ already take it out; its factor holds the
            // last front value, so that a profile used as a weight neither drops it from a
            // normalisation (the light's: Smith's V̄ counts it) nor falls to 0 toward the
            // silhouette between two nodes.
            out.slopes[j] = if j > 0 { out.slopes[j - 1] } else { 1.0 };
            continue;
        }
        let o = &mut out.slopes[j];
        let mut acc = 0.0;
        for (i, w) in hw.iter().enumerate() {
            acc += w * g1(grid, dt, height_node(i), t, nu);
        }
        *o = (acc / hsum).clamp(0.0, 1.0);
    }
    out
}

/// `G1(h₀, t)` on the τ grid of `(R̂, R̂′, R̂″)` at the midpoints of steps `dt` (module docs).
fn g1(grid: &[(f64, f64, f64)], dt: f64, h0: f64, t: f64, nu: f64) -> f64 {
    log_g1(grid, dt, h0, t, nu).exp()
}

/// Largest crossing integral followed: `G1 < e^−700` counts as 0 (`ln G1 = −∞`).
const MAX_LOG: f64 = 700.0;

/// `ln G1(h₀, t)` ([`g1`]): `−∞` where the start is certainly masked.
fn log_g1(grid: &[(f64, f64, f64)], dt: f64, h0: f64, t: f64, nu: f64) -> f64 {
    let mut integral = 0.0f64;
    for (i, &(r, r1, r2)) in grid.iter().enumerate() {
        let tau = (i as f64 + 0.5) * dt;
        let ray = h0 + nu * tau;
        if ray > TOP {
            return -integral;
        }
        let Some(rate) = conditioned_rate((r, r1, r2), (h0, t), (ray, nu)) else {
            // The ray is certainly below the conditioned surface: it is crossed.
            return f64::NEG_INFINITY;
        };
        integral += rate * dt;
        if integral > MAX_LOG {
            return f64::NEG_INFINITY;
        }
    }
    // The process has forgotten the start (or the grid ends): Smith's tail in closed form.
    let ray = h0 + nu * grid.len() as f64 * dt;
    let excess = norm_pdf(nu) - nu * norm_cdf(-nu);
    integral -= excess.max(0.0) / nu * log_norm_cdf(ray);
    -integral
}

/// Rice's crossing rate with Smith's "below so far", for a normalised process conditioned on its
/// start: `E[(h′ − ν)⁺ | h = r]·p(h = r)/P(h < r)` at a lag where the autocovariance is
/// `(R̂, R̂′, R̂″)`, the start `(h₀, t)`, and the level `r` crossed with slope `ν` (the ray's
/// height and slope, or a curved barrier's, [`crate::microfacet::barrier_masking`]). The pair
/// `(h, h′)` at the lag is Gaussian with mean `(R̂h₀ − R̂′t, R̂′h₀ − R̂″t)` and the Schur complement as
/// covariance (module docs). `None` where the level is certainly below the surface (crossed).
pub fn conditioned_rate(
    (r, r1, r2): (f64, f64, f64),
    (h0, t): (f64, f64),
    (level, slope): (f64, f64),
) -> Option<f64> {
    let mh = r * h0 - r1 * t;
    let mp = r1 * h0 - r2 * t;
    let vh = (1.0 - r * r - r1 * r1).max(1e-12);
    let vp = 1.0 - r1 * r1 - r2 * r2;
    let c = -r * r1 - r1 * r2;
    let sh = vh.sqrt();
    let z = (level - mh) / sh;
    let below = norm_cdf(z);
    if below < 1e-300 {
        return None;
    }
    let m2 = mp + c / vh * (level - mh) - slope;
    let s2 = (vp - c * c / vh).max(1e-12).sqrt();
    let q = m2 / s2;
    let up = s2 * norm_pdf(q) + m2 * norm_cdf(q);
    Some(up * norm_pdf(z) / sh / below)
}

/// Bound on `|ln r|` of [`JointMasking`]: where the conditioned and Smith's masking differ by more
/// than e⁸ both are below anything D_h weights.
pub const MAX_LOG_RATIO: f64 = 8.0;

/// Masking conditioned on the start's height and slope jointly, relative to Smith's:
/// `ln r(h_i, z_j) = ln G1(h_i, z_j) − Λ(ν)·ln Φ(h_i)` at the heights of [`height_node`] and the
/// slopes of [`slope_node`], clamped to ±[`MAX_LOG_RATIO`]. Smith's `Φ(h)^Λ` [HN12 Eqs. 4–6] is
/// what the views' D_h already carries; `r` is the share the slope moves, and it is not
/// separable: high starts are seen at every slope, low ones mostly when they face the eye.
/// Back faces (`z ≥ ν`) hold the last front row, as in [`conditioned_masking`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointMasking {
    /// `ln r`, height-major: `log_ratio[i][j]` at `(height_node(i), slope_node(j))`.
    pub log_ratio: [[f64; SLOPE_NODES]; HEIGHT_NODES],
}

impl JointMasking {
    /// Smith's masking: `r ≡ 1`.
    pub fn none() -> Self {
        Self {
            log_ratio: [[0.0; SLOPE_NODES]; HEIGHT_NODES],
        }
    }

    /// `ln r(h, z_j)` at height `h` (σ_h units), linear between the height nodes and clamped to
    /// the end nodes (NaN reads height 0).
    pub fn log_ratio_at(&self, h: f64, j: usize) -> f64 {
        let (i, f) = height_cell(h);
        self.log_ratio[i][j] * (1.0 - f) + self.log_ratio[i + 1][j] * f
    }
}

/// The height nodes `i, i + 1` around height `h` (σ_h units; NaN reads 0) and the weight of
/// `i + 1`, clamped to the end nodes.
pub fn height_cell(h: f64) -> (usize, f64) {
    let h = if h.is_nan() { 0.0 } else { h };
    let x = (h - height_node(0)).clamp(0.0, (HEIGHT_NODES - 1) as f64);
    let i = (x as usize).min(HEIGHT_NODES - 2);
    (i, x - i as f64)
}

/// The height nodes that [`JointMasking::log_ratio_at`] reads for heights in `[lo, hi]`: rows
/// `first..=last`.
pub fn height_rows(lo: f64, hi: f64) -> (usize, usize) {
    let (a, _) = height_cell(lo.min(hi));
    let (b, _) = height_cell(lo.max(hi));
    (a, b + 1)
}

impl JointMasking {}

/// [`JointMasking`] of a ray of slope `nu` (in σ_t) on a grid built for rays at most as grazing.
/// Edge cases as [`conditioned_masking`]: `ν ≥ 8`, `ν ≤ 0` or NaN give Smith's (`r ≡ 1`; there
/// nothing is seen, or nothing masked). Always finite.
pub fn joint_masking_on(grid: &ProcessGrid, nu: f64) -> JointMasking {
    let mut out = JointMasking::none();
    if !(nu > 0.0 && nu < 8.0) {
        return out;
    }
    let lambda = smith_lambda(nu / std::f64::consts::SQRT_2);
    let (dt, values) = (grid.dt, &grid.values[..grid.memory]);
    for j in 0..SLOPE_NODES {
        let t = slope_node(j);
        for i in 0..HEIGHT_NODES {
            out.log_ratio[i][j] = if t >= nu {
                // A back face holds the last front value (see conditioned_masking_on).
                if j > 0 { out.log_ratio[i][j - 1] } else { 0.0 }
            } else {
                let h = height_node(i);
                let d = log_g1(values, dt, h, t, nu) - lambda * log_norm_cdf(h);
                if d.is_nan() {
                    0.0
                } else {
                    d.clamp(-MAX_LOG_RATIO, MAX_LOG_RATIO)
                }
            };
        }
    }
    out
}

/// Linear interpolation of a [`conditioned_masking`] profile at slope `z` (in σ_t), clamped to
/// the end nodes; NaN gives the profile's value at 0.
pub fn profile_at(profile: &[f64; SLOPE_NODES], z: f64) -> f64 {
    let (i, f) = slope_cell(z);
    profile[i] * (1.0 - f) + profile[i + 1] * f
}

/// The slope nodes `j, j + 1` around slope `z` (σ_t units; NaN reads 0) and the weight of
/// `j + 1`, clamped to the end nodes.
pub fn slope_cell(z: f64) -> (usize, f64) {
    let z = if z.is_nan() { 0.0 } else { z };
    let x = (z - slope_node(0)).clamp(0.0, (SLOPE_NODES - 1) as f64);
    let j = (x as usize).min(SLOPE_NODES - 2);
    (j, x - j as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A process of many components over two octaves of frequency, all directions.
    fn broad() -> LineProcess {
        LineProcess::new((0..48).map(|i| {
            let o = (i % 3) as f64;
            let angle = 0.7 * i as f64;
            (0.25f64.powf(o), 2f64.powf(o) * angle.cos() * 6.0)
        }))
        .expect("process")
    }

    #[test]
    fn without_conditioning_the_average_is_smiths() {
        // At t = 0 and with R ≡ 0 beyond the start, G1 averaged over h₀ is E[Φ(h₀)^Λ] = 1/(1 + Λ).
        // A process whose correlation vanishes quickly (many incommensurate high frequencies)
        // approaches that; here the check is the weaker, exact one: the average over slopes,
        // weighted by the projected area, is within a few percent of Smith's 1/(1 + Λ).
        let p = broad();
        for nu in [0.5, 1.0, 2.0] {
            let prof = conditioned_masking(&p, nu).slopes;
            let (mut num, mut den) = (0.0, 0.0);
            for (j, g) in prof.iter().enumerate() {
                let z = slope_node(j);
                let u = (nu - z).max(0.0) * norm_pdf(z);
                num += u * g;
                den += u;
            }
            let smith = 1.0 / (1.0 + smith_lambda(nu / std::f64::consts::SQRT_2));
            let ours = num / den;
            assert!(
                (ours / smith - 1.0).abs() < 0.12,
                "ν {nu}: conditioned mean {ours:.4} against Smith {smith:.4}"
            );
        }
    }

    #[test]
    fn facets_leaning_to_the_silhouette_are_masked_more() {
        let p = broad();
        for nu in [0.4, 1.0, 2.5] {
            let prof = conditioned_masking(&p, nu).slopes;
            let front: Vec<f64> = (0..SLOPE_NODES)
                .filter(|j| slope_node(*j) < nu)
                .map(|j| prof[j])
                .collect();
            assert!(
                front.windows(2).all(|w| w[1] <= w[0] + 1e-9),
                "ν {nu}: {front:?}"
            );
            assert!(front[0] > front[front.len() - 1]);
        }
    }

    #[test]
    fn edge_cases_are_finite() {
        assert!(LineProcess::new([(0.0, 1.0)]).is_none());
        assert!(LineProcess::new([(1.0, 0.0)]).is_none());
        assert!(LineProcess::new([(f64::NAN, 1.0)]).is_none());
        let p = LineProcess::new([(1.0, 1.0)]).expect("one wave");
        for nu in [
            f64::NAN,
            -1.0,
            0.0,
            1e-9,
            1e-3,
            0.1,
            7.9,
            8.0,
            1e9,
            f64::INFINITY,
        ] {
            let c = conditioned_masking(&p, nu);
            assert!(
                c.slopes
                    .iter()
                    .all(|v| v.is_finite() && (0.0..=1.0).contains(v))
            );
        }
        let prof = conditioned_masking(&p, 1.0).slopes;
        for z in [f64::NAN, -1e9, -4.0, 0.3, 4.0, 1e9] {
            assert!(profile_at(&prof, z).is_finite());
        }
    }
}
