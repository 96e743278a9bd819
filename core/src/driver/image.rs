//! A tabulated driver: a grayscale image with mip-mapped moments [HNPN14 Sec. 4.2], in texel units.
//!
//! * **The surface it drives** is the bilinear interpolant of the (standardized) texels, tiling the
//!   plane: texel i's centre sits at texel coordinate i + ½. That is the explicit micro-geometry the
//!   ground truth marches ([`ImageDriver::value_and_gradient`]).
//! * **Value moments** `f̄` and `f²‾` are mip-mapped by 2×2 box averages of the texels (odd sizes
//!   average the texels available), so every level's moments are exact box statistics of level 0 and
//!   the footprint variance is `σ_f² = f²‾ − f̄²` after interpolating both (docs/numerics.md: the extracted
//!   text drops a square), clamped at 0.
//! * **Gradient moments** `∇f‾` and `∇f∇fᵀ‾` are exact cell averages of the bilinear interpolant's
//!   gradient: in the cell between texel centres with corners f00, f10, f01, f11, `f_x = a + t(b − a)`
//!   (a = f10 − f00, b = f11 − f01, t the fraction along y) and `f_y = c + s(d − c)` (c = f01 − f00,
//!   d = f11 − f10, s the fraction along x), so `E f_x² = (a² + ab + b²)/3`, `E f_y² = (c² + cd + d²)/3`
//!   and, s and t being independent, `E f_x f_y = E f_x · E f_y`. The cell grid sits half a texel
//!   after the texel grid at every level, so it is sampled at `x − ½`.
//!
//! Values are standardized on construction (global mean 0, std 1) so colour maps and transfer
//! functions see the same N(0, 1) convention as the procedural driver; the original mean and std are
//! kept. A constant image standardizes to 0 everywhere.

pub use crate::driver::mip_level::{ImageMoments, MipLevel};
use crate::driver::mip_level::{cell, downsample, level_lipschitz, level_mean, level_moments};
use glam::{DMat2, DVec2};

/// Errors building an image driver.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ImageDriverError {
    /// Width or height is zero, or the data length does not match.
    #[error("image is {width}×{height} but holds {len} values")]
    BadSize {
        /// Declared width.
        width: usize,
        /// Declared height.
        height: usize,
        /// Values supplied.
        len: usize,
    },
    /// The image exceeds the size limit.
    #[error("image is {width}×{height}, larger than the {max}×{max} limit")]
    TooLarge {
        /// Width.
        width: usize,
        /// Height.
        height: usize,
        /// The limit per side.
        max: usize,
    },
    /// A value is NaN or infinite.
    #[error("image value at ({x}, {y}) is not finite")]
    NotFinite {
        /// Column.
        x: usize,
        /// Row.
        y: usize,
    },
}

/// How a Gaussian footprint is sampled from the pyramid: `probes` trilinear lookups at `lod`, spaced
/// by `step` (texels) along the footprint's major axis and centred on it (anisotropic filtering:
/// each probe's box covers the minor axis, together they cover the major one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbePlan {
    /// Mip level (fractional).
    pub lod: f64,
    /// Number of probes, 1..=[`ImageDriver::MAX_PROBES`].
    pub probes: u32,
    /// Spacing of the probes in level-0 texels.
    pub step: DVec2,
}

/// Samples of the bilinear surface the whole-image statistics take (at most): 2²⁰.
pub const SURFACE_SAMPLES: usize = 1 << 20;

/// A mip-mapped image driver.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageDriver {
    /// Levels, finest first.
    pub levels: Vec<MipLevel>,
    /// Mean of the original values.
    pub original_mean: f64,
    /// Standard deviation of the original values (0 for a constant image).
    pub original_std: f64,
    /// Skewness of the texel values (0 for a Gaussian; 0 for a constant image).
    pub skewness: f64,
    /// Excess kurtosis of the texel values (0 for a Gaussian; 0 for a constant image).
    pub excess_kurtosis: f64,
    /// max |f| over the standardized texels (bounds the bilinear surface and every filtered mean).
    pub max_abs: f64,
    /// Largest |f(i+1, j) − f(i, j)| and |f(i, j+1) − f(i, j)| (wrapping): Lipschitz constants of the
    /// bilinear surface along x and y, per texel, and of every filtered level's interpolant.
    pub lipschitz: DVec2,
}

impl ImageDriver {
    /// Largest accepted side, in texels (the GPU keeps seven floats per texel: 1024² is 38 MB).
    pub const MAX_SIDE: usize = 1024;
    /// Most probes along a footprint's major axis.
    pub const MAX_PROBES: u32 = 8;

    /// Build from row-major grayscale values.
    pub fn new(width: usize, height: usize, values: &[f32]) -> Result<Self, ImageDriverError> {
        if width == 0 || height == 0 || values.len() != width * height {
            return Err(ImageDriverError::BadSize {
                width,
                height,
                len: values.len(),
            });
        }
        if width > Self::MAX_SIDE || height > Self::MAX_SIDE {
            return Err(ImageDriverError::TooLarge {
                width,
                height,
                max: Self::MAX_SIDE,
            });
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(ImageDriverError::NotFinite {
                x: i % width,
                y: i / width,
            });
        }
        let n = values.len() as f64;
        let mean = values.iter().map(|v| f64::from(*v)).sum::<f64>() / n;
        let var = values
            .iter()
            .map(|v| (f64::from(*v) - mean).powi(2))
            .sum::<f64>()
            / n;
        let std = var.sqrt();
        // Below ~1e-6 relative spread the image is constant up to rounding of its encoding.
        let scale = if std > 1e-6 * mean.abs().max(1e-30) && std > 1e-30 {
            1.0 / std
        } else {
            0.0
        };
        let base: Vec<f64> = values
            .iter()
            .map(|v| (f64::from(*v) - mean) * scale)
            .collect();
        let at = |x: usize, y: usize| base[(y % height) * width + (x % width)];
        let mut grad = Vec::with_capacity(width * height);
        let mut lip = DVec2::ZERO;
        for y in 0..height {
            for x in 0..width {
                let (f00, f10, f01, f11) = (at(x, y), at(x + 1, y), at(x, y + 1), at(x + 1, y + 1));
                let (a, b) = (f10 - f00, f11 - f01);
                let (c, d) = (f01 - f00, f11 - f10);
                lip = lip.max(DVec2::new(a.abs(), c.abs()));
                let (mx, my) = (0.5 * (a + b), 0.5 * (c + d));
                grad.push([
                    mx as f32,
                    my as f32,
                    ((a * a + a * b + b * b) / 3.0) as f32,
                    ((c * c + c * d + d * d) / 3.0) as f32,
                    (mx * my) as f32,
                ]);
            }
        }
        let max_abs = base.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // Standardized moments (base has mean 0 and std 1 unless constant, where both are 0).
        let (skewness, excess_kurtosis) = if scale > 0.0 {
            (
                base.iter().map(|v| v.powi(3)).sum::<f64>() / n,
                base.iter().map(|v| v.powi(4)).sum::<f64>() / n - 3.0,
            )
        } else {
            (0.0, 0.0)
        };
        let mut levels = vec![MipLevel {
            width,
            height,
            value: base.iter().map(|v| [*v as f32, (v * v) as f32]).collect(),
            grad,
            mean_variance: 0.0,
            lipschitz: DVec2::ZERO,
        }];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            levels.push(downsample(last));
        }
        for l in &mut levels {
            l.mean_variance = l
                .value
                .iter()
                .map(|v| (f64::from(v[1]) - f64::from(v[0]).powi(2)).max(0.0))
                .sum::<f64>()
                / l.value.len() as f64;
            l.lipschitz = level_lipschitz(l, (width, height));
        }
        Ok(Self {
            levels,
            original_mean: mean,
            original_std: std,
            max_abs,
            lipschitz: lip,
            skewness,
            excess_kurtosis,
        })
    }

    /// Width and height of level 0.
    pub fn size(&self) -> (usize, usize) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// The bilinear surface at texel coordinate `p` (texel centres at i + ½, wrapping): f and ∇f
    /// (per texel).
    pub fn value_and_gradient(&self, p: DVec2) -> (f64, DVec2) {
        let l = &self.levels[0];
        let (i, a) = cell(l, p);
        let f = |k: usize| f64::from(l.value[i[k]][0]);
        let (f00, f10, f01, f11) = (f(0), f(1), f(2), f(3));
        let top = f00 + a.x * (f10 - f00);
        let bot = f01 + a.x * (f11 - f01);
        let fx = (f10 - f00) + a.y * ((f11 - f01) - (f10 - f00));
        let fy = bot - top;
        (top + a.y * (bot - top), DVec2::new(fx, fy))
    }

    /// Visit the explicit surface at a regular sub-grid of every cell, `k × k` points per cell
    /// with `k = ⌊√(SURFACE_SAMPLES / texels)⌋` clamped to 1…4, row by row: `visit(f, ∇f)`
    /// ([`Self::value_and_gradient`], [`SURFACE_SAMPLES`]). The whole-image statistics
    /// (histogram, conditional slopes) sample it this way.
    pub fn for_each_surface_sample(&self, mut visit: impl FnMut(f64, DVec2)) {
        let (w, h) = self.size();
        let per_cell = ((SURFACE_SAMPLES / (w * h).max(1)) as f64)
            .sqrt()
            .floor()
            .clamp(1.0, 4.0) as usize;
        for y in 0..h {
            for x in 0..w {
                for j in 0..per_cell {
                    for i in 0..per_cell {
                        let p = DVec2::new(
                            x as f64 + 0.5 + (i as f64 + 0.5) / per_cell as f64,
                            y as f64 + 0.5 + (j as f64 + 0.5) / per_cell as f64,
                        );
                        let (f, g) = self.value_and_gradient(p);
                        visit(f, g);
                    }
                }
            }
        }
    }

    /// The sampling plan of a Gaussian footprint with covariance `cov` (texel units): the major axis
    /// σ₁ is covered by n = ⌈σ₁/σ₂⌉ ≤ [`Self::MAX_PROBES`] probes spaced by `√12·σ₁/n`, each a
    /// trilinear lookup whose kernel has std `max(σ₂, σ₁/n)` ([`lod_for_std`]); n kernels spaced by s
    /// add `s²(n² − 1)/12` along the axis, so both axes get the footprint's variance (checked against
    /// brute-force Gaussian averages in the tests).
    pub fn plan(&self, cov: DMat2) -> ProbePlan {
        let (xx, yy, xy) = (cov.x_axis.x, cov.y_axis.y, cov.x_axis.y);
        let tr = 0.5 * (xx + yy);
        let disc = (0.25 * (xx - yy).powi(2) + xy * xy).sqrt();
        let l1 = (tr + disc).max(0.0);
        let l2 = (tr - disc).max(0.0);
        let (s1, s2) = (l1.sqrt(), l2.sqrt());
        if !(s1 > 0.0) || !s1.is_finite() {
            return ProbePlan {
                lod: 0.0,
                probes: 1,
                step: DVec2::ZERO,
            };
        }
        let n = (s1 / s2.max(1e-300))
            .ceil()
            .clamp(1.0, f64::from(Self::MAX_PROBES));
        let max_lod = (self.levels.len() - 1) as f64;
        let lod = lod_for_std(s2.max(s1 / n)).min(max_lod);
        // Major axis: eigenvector of λ₁.
        let axis = if disc > 0.0 {
            let v = if (xx - yy) >= 0.0 {
                DVec2::new(l1 - yy, xy)
            } else {
                DVec2::new(xy, l1 - xx)
            };
            v.try_normalize().unwrap_or(DVec2::X)
        } else {
            DVec2::X
        };
        ProbePlan {
            lod,
            probes: n as u32,
            step: axis * (12f64.sqrt() * s1 / n),
        }
    }

    /// The two levels a trilinear lookup at `lod` blends and the blend weight of the coarser one
    /// (`lod` clamped to the pyramid; NaN reads level 0).
    fn split_lod(&self, lod: f64) -> (usize, usize, f64) {
        let last = self.levels.len() - 1;
        let lod = lod.clamp(0.0, last as f64);
        let l0 = (lod.floor() as usize).min(last);
        let l1 = (l0 + 1).min(last);
        let t = lod - l0 as f64;
        (l0, l1, if t.is_finite() { t } else { 0.0 })
    }

    /// Trilinear moments at texel coordinate `p` and level `lod`.
    pub fn moments_at(&self, p: DVec2, lod: f64) -> ImageMoments {
        let (l0, l1, t) = self.split_lod(lod);
        let mut m = level_moments(&self.levels[l0], self.size(), p);
        if t > 0.0 && l1 != l0 {
            let hi = level_moments(&self.levels[l1], self.size(), p);
            let mut out = ImageMoments::ZERO;
            out.accumulate(&m, 1.0 - t);
            out.accumulate(&hi, t);
            m = out;
        }
        m
    }

    /// Moments over the Gaussian footprint `cov` (texel units) centred at `p`: the average of the
    /// plan's probes ([`Self::plan`]).
    pub fn footprint_moments(&self, p: DVec2, cov: DMat2) -> ImageMoments {
        let plan = self.plan(cov);
        let n = plan.probes.max(1);
        let mut out = ImageMoments::ZERO;
        for i in 0..n {
            let o = plan.step * (f64::from(i) + 0.5 - 0.5 * f64::from(n));
            out.accumulate(&self.moments_at(p + o, plan.lod), 1.0 / f64::from(n));
        }
        out
    }

    /// f̄ alone over the footprint (what the level-of-detail surface needs at every march step).
    pub fn footprint_mean(&self, p: DVec2, plan: &ProbePlan) -> f64 {
        let n = plan.probes.max(1);
        let (l0, l1, t) = self.split_lod(plan.lod);
        let mut s = 0.0;
        for i in 0..n {
            let q = p + plan.step * (f64::from(i) + 0.5 - 0.5 * f64::from(n));
            let a = level_mean(&self.levels[l0], self.size(), q);
            let b = if t > 0.0 {
                level_mean(&self.levels[l1], self.size(), q)
            } else {
                a
            };
            s += a + t * (b - a);
        }
        s / f64::from(n)
    }

    /// The position-averaged footprint std at `lod`: √ of the levels' `mean_variance`, interpolated.
    pub fn mean_std(&self, lod: f64) -> f64 {
        let (l0, l1, t) = self.split_lod(lod);
        let v = self.levels[l0].mean_variance
            + t * (self.levels[l1].mean_variance - self.levels[l0].mean_variance);
        v.max(0.0).sqrt()
    }

    /// Lipschitz constants along x and y (per level-0 texel) of [`Self::footprint_mean`] under
    /// `plan`: the two blended levels' [`MipLevel::lipschitz`] mixed with the blend weight (a
    /// convex combination of two functions is Lipschitz with the combination of their constants;
    /// averaging shifted probes keeps it). Never above [`Self::lipschitz`] by more than f32
    /// rounding, and far below it at coarse levels: the far field's march takes long steps.
    pub fn lod_lipschitz(&self, plan: &ProbePlan) -> DVec2 {
        let (l0, l1, t) = self.split_lod(plan.lod);
        let (a, b) = (self.levels[l0].lipschitz, self.levels[l1].lipschitz);
        a * (1.0 - t) + b * t
    }
}

/// The mip level whose trilinear lookup has a kernel of std `sigma` (level-0 texels), on average over
/// positions. At integer level l a lookup averages boxes of 2^l texels weighted by the bilinear tent
/// between their centres: variance `4^l/12 + 4^l/6 = 4^l/4` on average over the position in the grid.
/// Between levels the variances mix linearly, `4^l₀(1 + 3t)/4`, which this inverts exactly (linear
/// interpolation in `log2` of the width overshoots the variance by up to 22%). 0 for σ ≤ ½.
pub fn lod_for_std(sigma: f64) -> f64 {
    let v = 4.0 * sigma * sigma;
    if !(v > 1.0) {
        return 0.0;
    }
    if !v.is_finite() {
        return 64.0;
    }
    let l0 = (v.log2() * 0.5).floor();
    let t = ((v / 4f64.powf(l0) - 1.0) / 3.0).clamp(0.0, 1.0);
    l0 + t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::colormap::tests::Rng;
    use crate::math::rounding::f32_up;

    fn random_image(w: usize, h: usize, seed: u64) -> ImageDriver {
        let mut rng = Rng(seed);
        let values: Vec<f32> = (0..w * h)
            .map(|_| (rng.normal() * 2.0 + 5.0) as f32)
            .collect();
        ImageDriver::new(w, h, &values).unwrap()
    }

    /// A smooth tiling image: a few low harmonics of the tile.
    fn smooth_image(w: usize, h: usize) -> ImageDriver {
        let values: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64 / w as f64, (i / w) as f64 / h as f64);
                let t = std::f64::consts::TAU;
                ((t * (2.0 * x + y)).sin() + 0.5 * (t * (3.0 * y - x) + 1.0).cos()) as f32
            })
            .collect();
        ImageDriver::new(w, h, &values).unwrap()
    }

    #[test]
    fn levels_are_exact_box_statistics() {
        let (w, h) = (64, 32);
        let d = random_image(w, h, 11);
        assert_eq!(d.levels.len(), 7);
        // Level 3: each texel is the box statistics of an 8×8 block of level 0, for values and cells.
        let (l0, l3) = (&d.levels[0], &d.levels[3]);
        for (bx, by) in [(0, 0), (3, 2), (7, 3)] {
            let (mut m, mut m2, mut gxx) = (0.0, 0.0, 0.0);
            for y in 0..8 {
                for x in 0..8 {
                    let i = (by * 8 + y) * w + bx * 8 + x;
                    let v = f64::from(l0.value[i][0]);
                    m += v / 64.0;
                    m2 += v * v / 64.0;
                    gxx += f64::from(l0.grad[i][2]) / 64.0;
                }
            }
            let t = &l3.value[by * l3.width + bx];
            assert!((f64::from(t[0]) - m).abs() < 1e-5);
            assert!((f64::from(t[1]) - m2).abs() < 1e-5);
            assert!((f64::from(l3.grad[by * l3.width + bx][2]) - gxx).abs() < 1e-4);
        }
        // The coarsest level holds the global statistics: mean 0, variance 1 after standardizing.
        let m = d.moments_at(DVec2::new(3.3, 7.1), 99.0);
        assert!(m.mean.abs() < 1e-5 && (m.std() - 1.0).abs() < 1e-4, "{m:?}");
        assert!((d.original_mean - 5.0).abs() < 0.2 && (d.original_std - 2.0).abs() < 0.1);
        assert!((d.mean_std(99.0) - 1.0).abs() < 1e-4);
        // Normal texels: skewness and excess kurtosis near 0 (2048 samples: s.e. 0.05 and 0.11).
        assert!(
            d.skewness.abs() < 0.2 && d.excess_kurtosis.abs() < 0.4,
            "{} {}",
            d.skewness,
            d.excess_kurtosis
        );
        // A two-valued image: skewness 0, excess kurtosis −2 exactly.
        let b = ImageDriver::new(2, 2, &[0.0, 1.0, 1.0, 0.0]).unwrap();
        assert!(b.skewness.abs() < 1e-12 && (b.excess_kurtosis + 2.0).abs() < 1e-12);
        assert!(d.mean_std(0.0) < 1e-3, "f32 rounding only");
    }

    #[test]
    fn cell_gradient_moments_are_exact_averages_of_the_bilinear_surface() {
        let d = random_image(8, 8, 3);
        // Brute force over cell (2, 5): texel centres 2.5..3.5 and 5.5..6.5.
        let n = 200;
        let mut acc = [0.0f64; 5];
        for j in 0..n {
            for i in 0..n {
                let p = DVec2::new(
                    2.5 + (i as f64 + 0.5) / n as f64,
                    5.5 + (j as f64 + 0.5) / n as f64,
                );
                let (_, g) = d.value_and_gradient(p);
                for (a, v) in acc
                    .iter_mut()
                    .zip([g.x, g.y, g.x * g.x, g.y * g.y, g.x * g.y])
                {
                    *a += v / (n * n) as f64;
                }
            }
        }
        let cellv = d.levels[0].grad[5 * 8 + 2];
        for k in 0..5 {
            assert!(
                (acc[k] - f64::from(cellv[k])).abs() < 2e-3 * (1.0 + acc[k].abs()),
                "{k}: brute force {} stored {}",
                acc[k],
                cellv[k]
            );
        }
        // At lod 0 the sampled gradient moments at the cell's centre are that cell's.
        let m = d.moments_at(DVec2::new(3.0, 6.0), 0.0);
        assert!((m.grad_sq.x_axis.x - f64::from(cellv[2])).abs() < 1e-5);
    }

    #[test]
    fn bilinear_surface_gradient_and_lipschitz_bound() {
        let d = random_image(16, 12, 5);
        let mut rng = Rng(9);
        for _ in 0..2000 {
            let p = DVec2::new(rng.uniform() * 40.0 - 20.0, rng.uniform() * 40.0 - 20.0);
            let dir = DVec2::from_angle(rng.uniform() * 7.0);
            let (f0, g) = d.value_and_gradient(p);
            let e = 1e-6;
            let (f1, _) = d.value_and_gradient(p + dir * e);
            let bound = d.lipschitz.x * dir.x.abs() + d.lipschitz.y * dir.y.abs();
            assert!(((f1 - f0) / e).abs() <= bound * (1.0 + 1e-6) + 1e-6);
            // Away from cell edges the gradient is the derivative.
            let frac = (p - DVec2::splat(0.5)).fract();
            if frac.min_element() > 1e-3 && frac.max_element() < 1.0 - 1e-3 {
                assert!(((f1 - f0) / e - g.dot(dir)).abs() < 1e-4);
            }
            assert!(f0.abs() <= d.max_abs + 1e-12);
        }
        // Wrapping: the tile repeats.
        let a = d.value_and_gradient(DVec2::new(3.2, 4.7)).0;
        let b = d
            .value_and_gradient(DVec2::new(3.2 + 16.0 * 3.0, 4.7 - 12.0 * 2.0))
            .0;
        assert!((a - b).abs() < 1e-9);
    }

    #[test]
    fn footprint_means_are_lipschitz_with_their_levels_constants() {
        // Non-power-of-two sides: levels 16×12, 8×6, 4×3, 2×2, 1×1.
        let d = random_image(16, 12, 5);
        assert_eq!(
            d.levels[0].lipschitz,
            d.lipschitz.map(|v| f64::from(f32_up(v)))
        );
        let coarse = d.levels[2].lipschitz;
        assert!(coarse.x < 0.7 * d.lipschitz.x && coarse.y < 0.7 * d.lipschitz.y);
        let last = d.levels.last().unwrap();
        assert_eq!(last.lipschitz, DVec2::ZERO);
        let mut rng = Rng(17);
        let mut tight: f64 = 0.0;
        for k in 0..3000 {
            let s1 = 0.2 + 8.0 * rng.uniform();
            let s2 = s1 * (0.1 + 0.9 * rng.uniform());
            let rot = DMat2::from_angle(rng.uniform() * 7.0);
            let cov = rot * DMat2::from_diagonal(DVec2::new(s1 * s1, s2 * s2)) * rot.transpose();
            let mut plan = d.plan(cov);
            if k % 3 == 0 {
                // Integer levels with one probe: at texel-centre rows the bound is attained.
                plan = ProbePlan {
                    lod: f64::from(k % 5),
                    probes: 1,
                    step: DVec2::ZERO,
                };
            }
            let lip = d.lod_lipschitz(&plan);
            let p = DVec2::new(rng.uniform() * 40.0 - 20.0, rng.uniform() * 40.0 - 20.0);
            let dir = DVec2::from_angle(rng.uniform() * 7.0);
            let e = 1e-5;
            let slope = (d.footprint_mean(p + dir * e, &plan) - d.footprint_mean(p, &plan)) / e;
            let bound = lip.x * dir.x.abs() + lip.y * dir.y.abs();
            assert!(
                slope.abs() <= bound * (1.0 + 1e-6) + 1e-6,
                "{slope} > {bound}"
            );
            if bound > 0.0 {
                tight = tight.max(slope.abs() / bound);
            }
        }
        assert!(tight > 0.95, "the bound is attained somewhere: {tight}");
    }

    #[test]
    fn probe_plans_follow_the_footprint() {
        let d = random_image(64, 64, 1);
        let iso = d.plan(DMat2::from_diagonal(DVec2::splat(4.0)));
        assert_eq!(iso.probes, 1);
        assert!((iso.lod - lod_for_std(2.0)).abs() < 1e-12);
        assert!((lod_for_std(2.0) - 2.0).abs() < 1e-12 && (lod_for_std(1.0) - 1.0).abs() < 1e-12);
        assert!((lod_for_std(1.5) - (1.0 + (9.0 / 4.0 - 1.0) / 3.0)).abs() < 1e-12);
        // 16:1 along the diagonal: 8 probes along (1, 1)/√2, lod from σ₁/8 = 2 texels.
        let r = DMat2::from_angle(std::f64::consts::FRAC_PI_4);
        let cov = r * DMat2::from_diagonal(DVec2::new(256.0, 1.0)) * r.transpose();
        let an = d.plan(cov);
        assert_eq!(an.probes, 8);
        assert!((an.lod - 2.0).abs() < 1e-9);
        assert_eq!(lod_for_std(0.3), 0.0);
        assert!(lod_for_std(f64::INFINITY).is_finite() && lod_for_std(f64::NAN) == 0.0);
        assert!((an.step.normalize().dot(DVec2::ONE.normalize()).abs() - 1.0).abs() < 1e-9);
        assert!((an.step.length() - 12f64.sqrt() * 2.0).abs() < 1e-9);
        let pt = d.plan(DMat2::ZERO);
        assert_eq!((pt.lod, pt.probes), (0.0, 1));
        let nan = d.plan(DMat2::from_diagonal(DVec2::new(f64::NAN, 1.0)));
        assert!(nan.lod.is_finite());
    }

    /// Footprint moments against brute-force Gaussian averages of the bilinear surface, averaged over
    /// 48 footprint centres (a mip lookup's kernel changes shape with the position inside the texel
    /// grid, as on any GPU; on average it has the footprint's variance): σ_f², slope variances within
    /// 12%; the mean within 0.03 of the image's unit std on average for isotropic footprints, 0.08
    /// along an 8:1 one, where the probes make a box of the Gaussian's variance (the box's sinc ringing
    /// against the Gaussian's decay is largest at σ₁ ≈ λ/3, as in this case).
    #[test]
    fn footprint_moments_match_gaussian_averages() {
        let d = smooth_image(128, 128);
        let mut rng = Rng(4);
        for (sx, sy) in [(3.0, 3.0), (8.0, 2.0), (1.5, 12.0)] {
            let cov = DMat2::from_diagonal(DVec2::new(sx * sx, sy * sy));
            let (mut var_bf, mut var_mip, mut gxx_bf, mut gxx_mip, mut gyy_bf, mut gyy_mip) =
                (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            let mut mean_err = 0.0;
            let centres = 48;
            for _ in 0..centres {
                let c = DVec2::new(rng.uniform() * 128.0, rng.uniform() * 128.0);
                let n = 4000;
                let (mut m, mut m2, mut gxx, mut gyy) = (0.0, 0.0, 0.0, 0.0);
                for _ in 0..n {
                    let p = c + DVec2::new(rng.normal() * sx, rng.normal() * sy);
                    let (f, g) = d.value_and_gradient(p);
                    m += f / n as f64;
                    m2 += f * f / n as f64;
                    gxx += g.x * g.x / n as f64;
                    gyy += g.y * g.y / n as f64;
                }
                let fm = d.footprint_moments(c, cov);
                var_bf += m2 - m * m;
                var_mip += fm.std().powi(2);
                gxx_bf += gxx;
                gxx_mip += fm.grad_sq.x_axis.x;
                gyy_bf += gyy;
                gyy_mip += fm.grad_sq.y_axis.y;
                mean_err += (fm.mean - m).abs() / centres as f64;
                assert!(
                    (d.footprint_mean(c, &d.plan(cov)) - fm.mean).abs() < 1e-9,
                    "the march's mean is the shading's"
                );
            }
            let rel = |a: f64, b: f64| (a - b).abs() / b;
            let tol = if sx == sy { 0.03 } else { 0.08 };
            assert!(mean_err < tol, "{sx},{sy}: mean error {mean_err}");
            assert!(
                rel(var_mip, var_bf) < 0.12,
                "{sx},{sy}: σ_f² {var_mip} vs {var_bf}"
            );
            assert!(
                rel(gxx_mip, gxx_bf) < 0.12,
                "{sx},{sy}: gxx {gxx_mip} vs {gxx_bf}"
            );
            assert!(
                rel(gyy_mip, gyy_bf) < 0.12,
                "{sx},{sy}: gyy {gyy_mip} vs {gyy_bf}"
            );
        }
    }

    #[test]
    fn constant_image_has_zero_variance_everywhere() {
        let d = ImageDriver::new(5, 3, &[0.25; 15]).unwrap();
        for s in [0.0, 0.7, 3.0, 100.0] {
            let m = d.footprint_moments(
                DVec2::new(0.41, 0.77),
                DMat2::from_diagonal(DVec2::splat(s)),
            );
            assert_eq!((m.mean, m.std()), (0.0, 0.0));
            assert_eq!(m.grad_cov(), DMat2::ZERO);
        }
        assert_eq!(d.original_std, 0.0);
        assert_eq!(d.lipschitz, DVec2::ZERO);
        // Non-finite positions give finite values.
        let (f, g) = d.value_and_gradient(DVec2::new(f64::NAN, f64::INFINITY));
        assert!(f.is_finite() && g.is_finite());
    }

    #[test]
    fn bad_images_are_errors() {
        assert!(matches!(
            ImageDriver::new(0, 4, &[]),
            Err(ImageDriverError::BadSize { .. })
        ));
        assert!(matches!(
            ImageDriver::new(2, 2, &[0.0; 3]),
            Err(ImageDriverError::BadSize { .. })
        ));
        assert_eq!(
            ImageDriver::new(2, 1, &[0.0, f32::NAN]),
            Err(ImageDriverError::NotFinite { x: 1, y: 0 })
        );
        assert!(matches!(
            ImageDriver::new(9000, 1, &vec![0.0; 9000]),
            Err(ImageDriverError::TooLarge { .. })
        ));
    }
}
