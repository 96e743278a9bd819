//! A tabulated driver: a grayscale image with mip-mapped first and second moments, `f̄` and `f²‾`
//! [HNPN14 Sec. 4.2]. The footprint variance is `σ_f² = f²‾ − f̄²` after linear interpolation of both
//! moments (numerics.md: the extracted text drops a square), clamped at 0.
//!
//! Values are standardized on construction (global mean 0, std 1) so colour maps and transfer
//! functions see the same N(0, 1) convention as the procedural driver; the original mean and std
//! are kept. Addressing wraps (the image tiles the plane); mip levels are 2×2 box averages (odd sizes
//! average the available texels), which makes every level's moments exact box statistics of level 0.

/// One mip level: per-texel mean of f and of f².
#[derive(Clone, Debug, PartialEq)]
pub struct MipLevel {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Mean of f over each texel's footprint in level 0.
    pub mean: Vec<f32>,
    /// Mean of f² over the same footprint.
    pub mean_sq: Vec<f32>,
}

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

/// A mip-mapped image driver.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageDriver {
    /// Levels, finest first.
    pub levels: Vec<MipLevel>,
    /// Mean of the original values.
    pub original_mean: f64,
    /// Standard deviation of the original values (0 for a constant image).
    pub original_std: f64,
}

impl ImageDriver {
    /// Largest accepted side, in texels.
    pub const MAX_SIDE: usize = 8192;

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
        let scale = if std > 1e-12 { 1.0 / std } else { 0.0 };
        let base: Vec<f32> = values
            .iter()
            .map(|v| ((f64::from(*v) - mean) * scale) as f32)
            .collect();
        let mut levels = vec![MipLevel {
            width,
            height,
            mean_sq: base.iter().map(|v| v * v).collect(),
            mean: base,
        }];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            levels.push(downsample(last));
        }
        Ok(Self {
            levels,
            original_mean: mean,
            original_std: std,
        })
    }

    /// Footprint mean and standard deviation at texture coordinate `uv` (wrapping, in units of the
    /// whole image) for a footprint of `radius_texels` level-0 texels: trilinear interpolation of the
    /// moments at `lod = log2(radius)`.
    pub fn filtered(&self, uv: [f64; 2], radius_texels: f64) -> (f64, f64) {
        let max_lod = (self.levels.len() - 1) as f64;
        let lod = if radius_texels > 1.0 {
            radius_texels.log2().min(max_lod)
        } else {
            0.0
        };
        let l0 = lod.floor() as usize;
        let l1 = (l0 + 1).min(self.levels.len() - 1);
        let t = lod - l0 as f64;
        let (m0, s0) = bilinear(&self.levels[l0], uv);
        let (m1, s1) = bilinear(&self.levels[l1], uv);
        let m = m0 + t * (m1 - m0);
        let sq = s0 + t * (s1 - s0);
        (m, (sq - m * m).max(0.0).sqrt())
    }
}

fn downsample(l: &MipLevel) -> MipLevel {
    let (w, h) = (l.width.div_ceil(2), l.height.div_ceil(2));
    let mut mean = vec![0.0; w * h];
    let mut mean_sq = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let (mut a, mut b, mut c) = (0.0f64, 0.0f64, 0.0f64);
            for dy in 0..2 {
                for dx in 0..2 {
                    let (sx, sy) = (2 * x + dx, 2 * y + dy);
                    if sx < l.width && sy < l.height {
                        a += f64::from(l.mean[sy * l.width + sx]);
                        b += f64::from(l.mean_sq[sy * l.width + sx]);
                        c += 1.0;
                    }
                }
            }
            mean[y * w + x] = (a / c) as f32;
            mean_sq[y * w + x] = (b / c) as f32;
        }
    }
    MipLevel {
        width: w,
        height: h,
        mean,
        mean_sq,
    }
}

/// Bilinear, wrapping lookup of both moments; texel centres at (i + ½)/size.
fn bilinear(l: &MipLevel, uv: [f64; 2]) -> (f64, f64) {
    let fx = uv[0].rem_euclid(1.0) * l.width as f64 - 0.5;
    let fy = uv[1].rem_euclid(1.0) * l.height as f64 - 0.5;
    let (x0, y0) = (fx.floor(), fy.floor());
    let (ax, ay) = (fx - x0, fy - y0);
    let wrap = |v: f64, n: usize| (v as i64).rem_euclid(n as i64) as usize;
    let (x0i, y0i) = (wrap(x0, l.width), wrap(y0, l.height));
    let (x1i, y1i) = ((x0i + 1) % l.width, (y0i + 1) % l.height);
    let at = |x: usize, y: usize| {
        (
            f64::from(l.mean[y * l.width + x]),
            f64::from(l.mean_sq[y * l.width + x]),
        )
    };
    let lerp =
        |a: (f64, f64), b: (f64, f64), t: f64| (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
    let top = lerp(at(x0i, y0i), at(x1i, y0i), ax);
    let bot = lerp(at(x0i, y1i), at(x1i, y1i), ax);
    lerp(top, bot, ay)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colormap::tests::Rng;

    #[test]
    fn levels_are_exact_box_statistics() {
        let mut rng = Rng(11);
        let (w, h) = (64, 32);
        let values: Vec<f32> = (0..w * h)
            .map(|_| (rng.normal() * 2.0 + 5.0) as f32)
            .collect();
        let d = ImageDriver::new(w, h, &values).unwrap();
        assert_eq!(d.levels.len(), 7);
        // Level 3: each texel is the box statistics of an 8×8 block of standardized level 0.
        let l0 = &d.levels[0];
        let l3 = &d.levels[3];
        for (bx, by) in [(0, 0), (3, 2), (7, 3)] {
            let (mut m, mut m2) = (0.0, 0.0);
            for y in 0..8 {
                for x in 0..8 {
                    let v = f64::from(l0.mean[(by * 8 + y) * w + bx * 8 + x]);
                    m += v / 64.0;
                    m2 += v * v / 64.0;
                }
            }
            assert!((f64::from(l3.mean[by * l3.width + bx]) - m).abs() < 1e-5);
            assert!((f64::from(l3.mean_sq[by * l3.width + bx]) - m2).abs() < 1e-5);
        }
        // The coarsest level holds the global statistics: mean 0, variance 1 after standardizing.
        let (m, s) = d.filtered([0.3, 0.6], 1e9);
        assert!(m.abs() < 1e-5 && (s - 1.0).abs() < 1e-4, "{m} {s}");
        assert!((d.original_mean - 5.0).abs() < 0.2 && (d.original_std - 2.0).abs() < 0.1);
    }

    #[test]
    fn constant_image_has_zero_variance_everywhere() {
        let d = ImageDriver::new(5, 3, &[0.25; 15]).unwrap();
        for r in [0.0, 0.7, 3.0, 100.0] {
            let (m, s) = d.filtered([0.41, 0.77], r);
            assert_eq!((m, s), (0.0, 0.0));
        }
        assert_eq!(d.original_std, 0.0);
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
