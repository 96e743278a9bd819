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
mod tests;
