//! One level of an image driver's mip pyramid [HNPN14 Sec. 4.2] (see [`crate::driver::image`] for
//! the pyramid and its conventions): its texel grids of value and gradient moments, their wrapped
//! bilinear lookups at a level-0 texel coordinate, the 2×2 box average that builds the next level,
//! and the level's Lipschitz constants.

use crate::math::rounding::f32_up;
use glam::{DMat2, DVec2};

/// One mip level.
#[derive(Clone, Debug, PartialEq)]
pub struct MipLevel {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Per texel: mean of f and of f² over its footprint in level 0 (texel grid).
    pub value: Vec<[f32; 2]>,
    /// Per texel of the cell grid: mean of f_x, f_y, f_x², f_y², f_x·f_y (level-0 texel units).
    pub grad: Vec<[f32; 5]>,
    /// Mean of `f²‾ − f̄²` over the level's texels: the footprint variance of f averaged over
    /// position (the image's analogue of the noise's phase-averaged σ_f²).
    pub mean_variance: f64,
    /// Lipschitz constants of the level's bilinear interpolant of f̄ along x and y, per level-0
    /// texel: its largest wrapped neighbour differences times the level's texel size (the
    /// level-of-detail march's rate at this level, [`crate::driver::image::ImageDriver::lod_lipschitz`]). Coarser levels
    /// are smoother: at level 0 it is [`crate::driver::image::ImageDriver::lipschitz`].
    pub lipschitz: DVec2,
}

/// Footprint moments of the driver (texel units): what every filtered view needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageMoments {
    /// f̄.
    pub mean: f64,
    /// f²‾.
    pub mean_sq: f64,
    /// ∇f‾.
    pub grad_mean: DVec2,
    /// ∇f∇fᵀ‾.
    pub grad_sq: DMat2,
}

impl ImageMoments {
    /// σ_f = √(f²‾ − f̄²), clamped at 0.
    pub fn std(&self) -> f64 {
        (self.mean_sq - self.mean * self.mean).max(0.0).sqrt()
    }

    /// The unresolved gradient covariance `∇f∇fᵀ‾ − ∇f‾∇f‾ᵀ`, with its diagonal clamped at 0 and its
    /// off-diagonal clamped to keep it positive semi-definite.
    pub fn grad_cov(&self) -> DMat2 {
        let g = self.grad_mean;
        let xx = (self.grad_sq.x_axis.x - g.x * g.x).max(0.0);
        let yy = (self.grad_sq.y_axis.y - g.y * g.y).max(0.0);
        let lim = (xx * yy).sqrt();
        let xy = (self.grad_sq.x_axis.y - g.x * g.y).clamp(-lim, lim);
        DMat2::from_cols(DVec2::new(xx, xy), DVec2::new(xy, yy))
    }

    pub(crate) fn accumulate(&mut self, o: &ImageMoments, w: f64) {
        self.mean += w * o.mean;
        self.mean_sq += w * o.mean_sq;
        self.grad_mean += w * o.grad_mean;
        self.grad_sq += o.grad_sq * w;
    }

    pub(crate) const ZERO: Self = Self {
        mean: 0.0,
        mean_sq: 0.0,
        grad_mean: DVec2::ZERO,
        grad_sq: DMat2::ZERO,
    };
}

/// The four wrapped texel indices around texel coordinate p (for a grid whose texel i is centred at
/// i + ½ in units of this level's texels) and the fractions.
pub(crate) fn cell(l: &MipLevel, p: DVec2) -> ([usize; 4], DVec2) {
    let fx = p.x - 0.5;
    let fy = p.y - 0.5;
    let (x0, y0) = (fx.floor(), fy.floor());
    let a = DVec2::new(fx - x0, fy - y0);
    let wrap = |v: f64, n: usize| {
        if v.is_finite() {
            (v.rem_euclid(n as f64) as usize).min(n - 1)
        } else {
            0
        }
    };
    let (x0i, y0i) = (wrap(x0, l.width), wrap(y0, l.height));
    let (x1i, y1i) = ((x0i + 1) % l.width, (y0i + 1) % l.height);
    let w = l.width;
    (
        [y0i * w + x0i, y0i * w + x1i, y1i * w + x0i, y1i * w + x1i],
        if a.is_finite() { a } else { DVec2::ZERO },
    )
}

pub(crate) fn bilerp<const N: usize>(v: &[[f32; N]], i: [usize; 4], a: DVec2) -> [f64; N] {
    std::array::from_fn(|k| {
        let f = |j: usize| f64::from(v[i[j]][k]);
        let top = f(0) + a.x * (f(1) - f(0));
        let bot = f(2) + a.x * (f(3) - f(2));
        top + a.y * (bot - top)
    })
}

/// Level-0 texel coordinate p in the texel units of level `l` (the tile maps onto every level
/// exactly, also for sides that are not powers of two).
pub(crate) fn at_level(l: &MipLevel, base: (usize, usize), p: DVec2) -> DVec2 {
    DVec2::new(
        p.x * l.width as f64 / base.0 as f64,
        p.y * l.height as f64 / base.1 as f64,
    )
}

pub(crate) fn level_mean(l: &MipLevel, base: (usize, usize), p: DVec2) -> f64 {
    let (i, a) = cell(l, at_level(l, base, p));
    let f = |j: usize| f64::from(l.value[i[j]][0]);
    let top = f(0) + a.x * (f(1) - f(0));
    let bot = f(2) + a.x * (f(3) - f(2));
    top + a.y * (bot - top)
}

pub(crate) fn level_moments(l: &MipLevel, base: (usize, usize), p: DVec2) -> ImageMoments {
    let (i, a) = cell(l, at_level(l, base, p));
    let v = bilerp(&l.value, i, a);
    let (j, b) = cell(l, at_level(l, base, p - DVec2::splat(0.5)));
    let g = bilerp(&l.grad, j, b);
    ImageMoments {
        mean: v[0],
        mean_sq: v[1],
        grad_mean: DVec2::new(g[0], g[1]),
        grad_sq: DMat2::from_cols(DVec2::new(g[2], g[4]), DVec2::new(g[4], g[3])),
    }
}

pub(crate) fn downsample(l: &MipLevel) -> MipLevel {
    let (w, h) = (l.width.div_ceil(2), l.height.div_ceil(2));
    let mut value = vec![[0.0f32; 2]; w * h];
    let mut grad = vec![[0.0f32; 5]; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut v = [0.0f64; 2];
            let mut g = [0.0f64; 5];
            let mut c = 0.0;
            for dy in 0..2 {
                for dx in 0..2 {
                    let (sx, sy) = (2 * x + dx, 2 * y + dy);
                    if sx < l.width && sy < l.height {
                        let i = sy * l.width + sx;
                        for k in 0..2 {
                            v[k] += f64::from(l.value[i][k]);
                        }
                        for k in 0..5 {
                            g[k] += f64::from(l.grad[i][k]);
                        }
                        c += 1.0;
                    }
                }
            }
            value[y * w + x] = v.map(|s| (s / c) as f32);
            grad[y * w + x] = g.map(|s| (s / c) as f32);
        }
    }
    MipLevel {
        width: w,
        height: h,
        value,
        grad,
        mean_variance: 0.0,
        lipschitz: DVec2::ZERO,
    }
}

/// [`MipLevel::lipschitz`]: the largest wrapped neighbour differences of the level's f̄ along x
/// and y (a bilinear interpolant's slope along an axis is a convex combination of them), scaled
/// from the level's texels to level-0 texels (`image_driver::at_level`), rounded up to f32 so the
/// GPU's copy is no tighter. A level one texel wide wraps onto itself: 0 along that axis.
pub(crate) fn level_lipschitz(l: &MipLevel, base: (usize, usize)) -> DVec2 {
    let (w, h) = (l.width, l.height);
    let f = |x: usize, y: usize| f64::from(l.value[(y % h) * w + (x % w)][0]);
    let mut lip = DVec2::ZERO;
    for y in 0..h {
        for x in 0..w {
            let f00 = f(x, y);
            lip = lip.max(DVec2::new(
                (f(x + 1, y) - f00).abs(),
                (f(x, y + 1) - f00).abs(),
            ));
        }
    }
    let scale = DVec2::new(w as f64 / base.0 as f64, h as f64 / base.1 as f64);
    let v = lip * scale;
    DVec2::new(f64::from(f32_up(v.x)), f64::from(f32_up(v.y)))
}
