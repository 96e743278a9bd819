//! Histogram-preserving filtering of an image driver [HN18 Sec. 3, histogram transformation;
//! HNPN14 Sec. 8, "when the Gaussian approximation fails"].
//!
//! The filtered model pre-convolves the colour map over `N(f̄, σ_f²)`: exact for the noise (its values
//! are Gaussian at every scale) but not for an image whose histogram is skewed or multimodal (bricks
//! with mortar, tiles with grout): at a coarse footprint the map is averaged over a bell the image
//! does not have. Here the image's value distribution defines a transfer `T = Φ⁻¹∘F` to a Gaussian
//! space G (F the CDF of the explicit surface's values), and the footprint's values are modelled as
//! `T⁻¹(N(μ_G, σ_G²))` with `(μ_G, σ_G)` chosen so that the model's mean and standard deviation are
//! the footprint's `(f̄, σ_f)` (moment matching):
//! * **exact at both ends of the zoom**: at σ_f → 0 it is the point value, and over the whole image
//!   it is the image's histogram, whatever its shape (`μ_G = 0, σ_G = 1`);
//! * **linear maps stay exact** (the model's mean is f̄), so the naive view's mean and the filtered
//!   one agree where the colour map is linear;
//! * **masking stays exact in G**: Smith's visibility depends on the heights only through their
//!   CDF [HNPN14 Eq. 12], and a rank is the same in f and in G, so the visible-height moments of the
//!   Gaussian model [HNPN14 Eqs. 14–17] apply to G unchanged;
//! * **the GPU path is one table lookup longer**: the image pyramid still carries (f̄, f²‾), a
//!   table `H(f̄, σ_f) = (μ_G, σ_G)` ([`DriverHistogram::gaussianize_table`]) maps them, and the colour
//!   map's table is pre-convolved over G of `C∘T⁻¹` ([`DriverHistogram::compose`], exact).
//!
//! `T⁻¹` is the quantile function of the bilinear surface's values (4×4 samples per cell, fewer on
//! large images), piecewise linear in G on [`CENTRAL_KNOTS`] equal-probability knots plus the tail
//! probabilities [`TAIL_PROBABILITIES`] and the extremes at `G = ±`[`G_END`].

use crate::driver::image::ImageDriver;
use crate::math::piecewise::{PiecewisePoly, fast_upper};
use crate::math::preconvolved::PreconvolvedTable;
use crate::math::special::{norm_pdf, norm_quantile};
use serde::{Deserialize, Serialize};

/// How the filtered view models an image driver's values inside a footprint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum ImageHistogram {
    /// The image's own histogram, moment-matched to the footprint (default; see the module docs).
    #[default]
    Preserving,
    /// A Gaussian of the footprint's mean and standard deviation [HNPN14 Sec. 4.2] (the papers'
    /// model: exact for the noise, off where the image's histogram is skewed or multimodal).
    Gaussian,
}

/// Equal-probability knots of `T⁻¹` between the tails.
pub const CENTRAL_KNOTS: usize = 256;
/// Tail probabilities with their own knot (and one minus each).
pub const TAIL_PROBABILITIES: [f64; 4] = [1e-6, 1e-5, 1e-4, 1e-3];
/// G of the extreme knots, where `T⁻¹` reaches the smallest and largest value.
pub const G_END: f64 = 5.5;
/// Columns (f̄) and rows (σ_f) of the table H.
pub const H_SIZE: usize = 256;
/// Range of μ_G in the table builder and in the colour table over G.
pub const MU_RANGE: f64 = 6.0;
/// Largest σ_G (a footprint split between two far modes needs more than 1).
pub const SIGMA_G_MAX: f64 = 4.0;
/// Knots of `T⁻¹` that a straight line through their neighbours passes within this fraction of
/// the value range are dropped (fewer pieces for the tables to integrate; plateaus become one).
pub const SIMPLIFY_TOLERANCE: f64 = 2e-4;

/// The driver's value distribution as `T⁻¹`: G knots and the driver's values there.
#[derive(Clone, Debug, PartialEq)]
pub struct DriverHistogram {
    /// Knots in Gaussian space, increasing, from `−G_END` to `G_END`.
    pub gauss: Vec<f64>,
    /// `T⁻¹` at the knots: the driver's quantile at `Φ(G)`, non-decreasing.
    pub value: Vec<f64>,
}

impl DriverHistogram {
    /// The histogram of an image driver's explicit surface (the bilinear interpolant of its
    /// standardized texels, [`ImageDriver::value_and_gradient`]), sampled on a regular sub-grid of
    /// each cell.
    pub fn of_image(image: &ImageDriver) -> Self {
        let mut samples = Vec::new();
        image.for_each_surface_sample(|f, _| samples.push(f));
        Self::from_samples(samples)
    }

    /// The histogram of equally weighted samples (non-finite ones are dropped; none left gives the
    /// constant 0).
    pub fn from_samples(mut samples: Vec<f64>) -> Self {
        samples.retain(|v| v.is_finite());
        if samples.is_empty() {
            samples.push(0.0);
        }
        samples.sort_unstable_by(f64::total_cmp);
        let n = samples.len();
        let quantile = |p: f64| {
            let u = (p * n as f64 - 0.5).clamp(0.0, (n - 1) as f64);
            let i = (u.floor() as usize).min(n - 1);
            let j = (i + 1).min(n - 1);
            samples[i] + (u - i as f64) * (samples[j] - samples[i])
        };
        let mut probs: Vec<f64> = TAIL_PROBABILITIES.to_vec();
        probs.extend((0..CENTRAL_KNOTS).map(|k| (k as f64 + 0.5) / CENTRAL_KNOTS as f64));
        probs.extend(TAIL_PROBABILITIES.iter().rev().map(|p| 1.0 - p));
        let mut gauss = vec![-G_END];
        let mut value = vec![samples[0]];
        for p in probs {
            gauss.push(norm_quantile(p));
            value.push(quantile(p));
        }
        gauss.push(G_END);
        value.push(samples[n - 1]);
        let tol = SIMPLIFY_TOLERANCE * (samples[n - 1] - samples[0]);
        let (gauss, value) = simplify(&gauss, &value, tol);
        Self { gauss, value }
    }

    /// `T⁻¹(g)`: the driver value of Gaussian-space value g (constant beyond the ends).
    pub fn inverse(&self, g: f64) -> f64 {
        let n = self.gauss.len();
        if !(g > self.gauss[0]) {
            return self.value[0];
        }
        if g >= self.gauss[n - 1] {
            return self.value[n - 1];
        }
        let i = self.gauss.partition_point(|k| *k <= g) - 1;
        let t = (g - self.gauss[i]) / (self.gauss[i + 1] - self.gauss[i]);
        self.value[i] + t * (self.value[i + 1] - self.value[i])
    }

    /// Smallest and largest driver value.
    pub fn range(&self) -> (f64, f64) {
        (self.value[0], self.value[self.value.len() - 1])
    }

    /// `p∘T⁻¹`, exactly: a map of the driver value (a colour map's polynomial) as a map of G.
    pub fn compose(&self, p: &PiecewisePoly) -> PiecewisePoly {
        p.compose_linear(&self.gauss, &self.value)
    }

    /// Mean and standard deviation of `T⁻¹(X)`, `X ~ N(μ, σ²)`, in closed form per linear piece
    /// (truncated-normal moments of z = (X − μ)/σ, no cancellation however narrow the piece).
    pub fn moments(&self, mu: f64, sigma: f64) -> (f64, f64) {
        let n = self.gauss.len();
        if !(sigma > 0.0) {
            return (self.inverse(mu), 0.0);
        }
        let z = |g: f64| (g - mu) / sigma;
        let (lo, hi) = (self.value[0], self.value[n - 1]);
        // Tails: constant below the first and above the last knot.
        let (q0, qn) = (
            fast_upper(z(self.gauss[0])),
            fast_upper(z(self.gauss[n - 1])),
        );
        let mut e1 = (1.0 - q0) * lo + qn * hi;
        let mut e2 = (1.0 - q0) * lo * lo + qn * hi * hi;
        let (mut za, mut qa, mut pa) = (z(self.gauss[0]), q0, norm_pdf(z(self.gauss[0])));
        for i in 0..n - 1 {
            let zb = z(self.gauss[i + 1]);
            if zb < -10.0 || za > 10.0 {
                za = zb;
                qa = fast_upper(zb);
                pa = norm_pdf(zb);
                continue;
            }
            let (qb, pb) = (fast_upper(zb), norm_pdf(zb));
            // f = p + q·z on the piece; E[z^k; piece] for k = 0, 1, 2.
            let slope = (self.value[i + 1] - self.value[i]) / (self.gauss[i + 1] - self.gauss[i]);
            let p = self.value[i] + slope * (mu - self.gauss[i]);
            let q = slope * sigma;
            let m0 = qa - qb;
            let m1 = pa - pb;
            let m2 = m0 + za * pa - zb * pb;
            e1 += p * m0 + q * m1;
            e2 += p * p * m0 + 2.0 * p * q * m1 + q * q * m2;
            (za, qa, pa) = (zb, qb, pb);
        }
        (e1, (e2 - e1 * e1).max(0.0).sqrt())
    }

    /// The Gaussian-space footprint `(μ_G, σ_G)` whose image under `T⁻¹` has mean `m` and standard
    /// deviation `s`, by damped Newton on [`Self::moments`] (the reference for
    /// [`Self::gaussianize_table`]); unreachable `(m, s)` (outside the image's range, or a spread
    /// the image cannot have at that mean) end at the nearest reachable point.
    pub fn gaussianize(&self, m: f64, s: f64) -> (f64, f64) {
        let (lo, hi) = self.range();
        if !(hi > lo) {
            return (0.0, 0.0);
        }
        let sg = s.clamp(0.0, SIGMA_G_MAX);
        let start = (self.forward_mean_inverse(m.clamp(lo, hi), sg), sg);
        self.newton(start, m, s, 40)
    }

    /// Damped Newton on `moments(μ, σ) = (m, s)` from `start`, at most `iterations` steps, μ kept
    /// within ±[`MU_RANGE`] and σ within `[0, SIGMA_G_MAX]`; each step only if it lowers the residual.
    fn newton(&self, start: (f64, f64), m: f64, s: f64, iterations: usize) -> (f64, f64) {
        let (lo, hi) = self.range();
        let m = m.clamp(lo, hi);
        let s = s.max(0.0);
        let residual = |x: (f64, f64)| {
            let (em, es) = self.moments(x.0, x.1);
            (em - m, es - s)
        };
        let norm = |r: (f64, f64)| r.0 * r.0 + r.1 * r.1;
        let mut x = start;
        let mut r = residual(x);
        for _ in 0..iterations {
            if norm(r) < 1e-22 {
                break;
            }
            let d = 1e-6;
            let rm = residual((x.0 + d, x.1));
            let rs = residual((x.0, x.1 + d));
            let (a, b, c, e) = (
                (rm.0 - r.0) / d,
                (rs.0 - r.0) / d,
                (rm.1 - r.1) / d,
                (rs.1 - r.1) / d,
            );
            let det = a * e - b * c;
            if !(det.abs() > 1e-300) {
                break;
            }
            let step = ((e * r.0 - b * r.1) / det, (a * r.1 - c * r.0) / det);
            let mut t = 1.0;
            let mut moved = false;
            for _ in 0..20 {
                let cand = (
                    (x.0 - t * step.0).clamp(-MU_RANGE, MU_RANGE),
                    (x.1 - t * step.1).clamp(0.0, SIGMA_G_MAX),
                );
                let rc = residual(cand);
                if norm(rc) < norm(r) {
                    (x, r, moved) = (cand, rc, true);
                    break;
                }
                t *= 0.5;
            }
            if !moved {
                break;
            }
        }
        x
    }

    /// μ with `moments(μ, σ).0 = m` by bisection (the mean is non-decreasing in μ).
    fn forward_mean_inverse(&self, m: f64, sigma: f64) -> f64 {
        let (mut a, mut b) = (-MU_RANGE, MU_RANGE);
        for _ in 0..60 {
            let c = 0.5 * (a + b);
            if self.moments(c, sigma).0 < m {
                a = c;
            } else {
                b = c;
            }
        }
        0.5 * (a + b)
    }

    /// The table `H(f̄, σ_f) = (μ_G, σ_G, 0, 1)`: [`H_SIZE`]² texels over `f̄ ∈ [min, max]` of the
    /// image and `σ_f ∈ [0, (max − min)/2]` (the largest spread any footprint can have), in the
    /// layout of [`crate::math::preconvolved`]. Built by inverting the forward moments on a
    /// (μ, σ) grid: per σ the mean is monotone in μ, per mean the spread is followed along σ to its
    /// first crossing (spreads beyond the reachable end at the widest σ).
    pub fn gaussianize_table(&self) -> PreconvolvedTable {
        let (lo, hi) = self.range();
        let hi = if hi > lo { hi } else { lo + 1e-6 };
        let s_max = 0.5 * (hi - lo);
        let (nmu, nsig) = (385usize, 161usize);
        let mus: Vec<f64> = (0..nmu)
            .map(|i| -MU_RANGE + 2.0 * MU_RANGE * i as f64 / (nmu - 1) as f64)
            .collect();
        let sigmas: Vec<f64> = (0..nsig)
            .map(|j| SIGMA_G_MAX * (j as f64 / (nsig - 1) as f64).powi(2))
            .collect();
        let n = H_SIZE;
        let targets: Vec<f64> = (0..n)
            .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
            .collect();
        // Per σ row: for every target mean, the μ that reaches it and the spread there.
        let rows: Vec<Vec<(f64, f64)>> = {
            use rayon::prelude::*;
            sigmas
                .par_iter()
                .map(|&sigma| {
                    let fwd: Vec<(f64, f64)> =
                        mus.iter().map(|&mu| self.moments(mu, sigma)).collect();
                    targets
                        .iter()
                        .map(|&m| invert_monotone(&mus, &fwd, m))
                        .collect()
                })
                .collect()
        };
        let mut texels = vec![[0.0f32, 0.0, 0.0, 1.0]; n * n];
        {
            use rayon::prelude::*;
            texels.par_chunks_mut(n).enumerate().for_each(|(k, row)| {
                let s = s_max * k as f64 / (n - 1) as f64;
                for (i, texel) in row.iter_mut().enumerate() {
                    let (mut mu, mut sg) = (rows[nsig - 1][i].0, sigmas[nsig - 1]);
                    // First σ whose spread reaches s.
                    for j in 1..nsig {
                        let (s0, s1) = (rows[j - 1][i].1, rows[j][i].1);
                        if s1 >= s {
                            let t = if s1 > s0 {
                                ((s - s0) / (s1 - s0)).clamp(0.0, 1.0)
                            } else {
                                1.0
                            };
                            mu = rows[j - 1][i].0 + t * (rows[j][i].0 - rows[j - 1][i].0);
                            sg = sigmas[j - 1] + t * (sigmas[j] - sigmas[j - 1]);
                            break;
                        }
                    }
                    if k == 0 {
                        (mu, sg) = (rows[0][i].0, 0.0);
                    }
                    *texel = [mu as f32, sg as f32, 0.0, 1.0];
                }
            });
        }
        PreconvolvedTable {
            m_min: lo,
            m_max: hi,
            sigma_max: s_max,
            size_m: n,
            size_sigma: n,
            texels,
        }
    }

    /// The largest gap between the driver's CDF and the standard normal's, `sup |F(x) − Φ(x)|`
    /// at the knots (Kolmogorov's distance): 0 for a Gaussian image, about 0.01 for noise
    /// sampled on a 256² grid, 0.1 and more for tiles with grout.
    pub fn kolmogorov_distance(&self) -> f64 {
        self.gauss
            .iter()
            .zip(&self.value)
            .map(|(g, v)| (fast_upper(*g) - fast_upper(*v)).abs())
            .fold(0.0, f64::max)
    }
}

/// The knots of a piecewise-linear function kept so that the interpolant of the kept ones is
/// within `tol` of every dropped one (greedy: each piece extends as far as it can).
fn simplify(xs: &[f64], ys: &[f64], tol: f64) -> (Vec<f64>, Vec<f64>) {
    let n = xs.len();
    if n <= 2 {
        return (xs.to_vec(), ys.to_vec());
    }
    let (mut kx, mut ky) = (vec![xs[0]], vec![ys[0]]);
    let mut anchor = 0;
    let mut j = 2;
    while j < n {
        let fits = (anchor + 1..j).all(|k| {
            let t = (xs[k] - xs[anchor]) / (xs[j] - xs[anchor]);
            (ys[anchor] + t * (ys[j] - ys[anchor]) - ys[k]).abs() <= tol
        });
        if !fits {
            anchor = j - 1;
            kx.push(xs[anchor]);
            ky.push(ys[anchor]);
        }
        j += 1;
    }
    kx.push(xs[n - 1]);
    ky.push(ys[n - 1]);
    (kx, ky)
}

/// For a non-decreasing forward mean `fwd[i].0` over `mus`, the μ where it reaches `m` (the
/// ends when it does not) and the spread `fwd.1` there, by linear interpolation.
fn invert_monotone(mus: &[f64], fwd: &[(f64, f64)], m: f64) -> (f64, f64) {
    let n = mus.len();
    if !(m > fwd[0].0) {
        // Below (or at) the smallest mean: the left end, at the last μ still reaching it.
        let i = fwd.iter().rposition(|f| f.0 <= fwd[0].0).unwrap_or(0);
        return (mus[i], fwd[i].1);
    }
    if m >= fwd[n - 1].0 {
        let i = fwd
            .iter()
            .position(|f| f.0 >= fwd[n - 1].0)
            .unwrap_or(n - 1);
        return (mus[i], fwd[i].1);
    }
    let i = fwd.partition_point(|f| f.0 < m).clamp(1, n - 1);
    let (a, b) = (fwd[i - 1], fwd[i]);
    let t = if b.0 > a.0 {
        (m - a.0) / (b.0 - a.0)
    } else {
        0.0
    };
    (
        mus[i - 1] + t * (mus[i] - mus[i - 1]),
        a.1 + t * (b.1 - a.1),
    )
}

#[cfg(test)]
mod tests;
