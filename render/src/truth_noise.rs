//! Ground truth's own Monte Carlo noise, and errors against the truth with that noise taken out
//! (#18 §3).
//!
//! A ground-truth pixel is the mean of `n` rays. At grazing angles a few bright glints carry most
//! of its value, so at tens of rays its distribution is heavy-tailed: the typical pixel lies far
//! below its expectation μ. An estimate `e` compared pixel by pixel with such a truth `T` measures
//! `E[(e − T)²] = (e − μ)² + Var(T)`: the truth's variance is added to every view alike, and what is
//! left, `(e − μ)²`, is drowned in the noise of the estimate of it (for one glint pixel,
//! `(e_a − T)² − (e_b − T)² = (e_a − e_b)(e_a + e_b − 2T)` swings with T and rewards the darker
//! view wherever T happens to be small).
//!
//! Here the truth keeps a per-pixel sum of squared samples beside its sum ([`SampleMoments`],
//! written by `view.wgsl`), so each pixel's mean comes with the variance of that mean,
//! `s²/n` with `s² = (Σx² − n·x̄²)/(n − 1)` ([`TruthEstimate`]). Errors are then measured on block
//! means of `b × b` pixels ([`BlockErrors`]): a block's mean difference `d = ē − T̄` has
//! `E[d²] = (ē − μ̄)² + Var(T̄)`, with `Var(T̄) = Σ Var(T_i) / m²` over its m pixels, so
//! - `d² − Var(T̄)` is an unbiased estimate of the squared bias at the block's scale, and its mean
//!   over blocks is the excess mean squared error [`BlockErrors::excess_mse`], with a standard
//!   error from its spread over blocks ([`BlockErrors::excess_mse_se`]);
//! - `z = |d_Y| / √Var(T̄_Y)` on luminance says whether a block's difference stands out of the
//!   truth's noise ([`Z_SIGNIFICANT`]), with the per-pixel variance pooled over the 3×3 blocks
//!   around: a block's own estimate is tied to its mean for skewed data (a block that drew fewer
//!   glints has both a lower mean and a lower sample variance), which flagged twice the nominal
//!   share of an unbiased view's blocks (10.2%; pooled 4.7%, tested).
//!
//! Block means matter because the filtered model predicts a footprint's expectation: over one
//! pixel the micro-geometry's own realisation (which crests the pixel happens to hold) differs from
//! that expectation, over a block it averages out, while a biased view stays biased at every scale.
//!
//! Caveat: the truth's rays follow a low-discrepancy sequence, which converges faster than
//! independent rays on smooth integrands, so `s²/n` overestimates the variance of its mean there.
//! The estimates err on the safe side: fewer blocks flagged significant, an excess error a little
//! low (the same amount is removed from every view, so their ranking does not depend on it).

use crate::image::LinearImage;
use lodestone_core::material::colormap::Gradient;

/// Rec. 709 luminance weights (linear RGB), core's. `view.wgsl` accumulates `Y²` with the same weights.
pub use lodestone_core::material::colormap::LUMINANCE;

/// A block difference counts as significant from this many standard errors of the truth's block
/// mean (two-sided, about 5% of blocks without bias for Gaussian noise).
pub const Z_SIGNIFICANT: f64 = 2.0;

/// Rec. 709 luminance of linear RGB.
pub fn luminance(c: [f64; 3]) -> f64 {
    LUMINANCE[0] * c[0] + LUMINANCE[1] * c[1] + LUMINANCE[2] * c[2]
}

/// Ground truth's per-pixel sums of squared samples, read back beside its sums
/// ([`crate::ViewTarget::read_moments`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SampleMoments {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Row-major `(Σr², Σg², Σb², ΣY²)`, Y the luminance ([`LUMINANCE`]).
    pub sum_sq: Vec<[f32; 4]>,
}

/// One ground-truth pixel as an estimate: its mean and the variance of that mean.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelEstimate {
    /// Mean linear RGB.
    pub mean: [f64; 3],
    /// Variance of the mean per channel, `s²/n` (infinite below two samples: unknown).
    pub var_mean: [f64; 3],
    /// Variance of the mean luminance.
    pub var_mean_y: f64,
}

/// Ground truth with its own noise: the accumulated sums and sums of squares of one target.
#[derive(Clone, Copy, Debug)]
pub struct TruthEstimate<'a> {
    image: &'a LinearImage,
    moments: &'a SampleMoments,
}

impl<'a> TruthEstimate<'a> {
    /// The truth in `image` with the squared sums in `moments`; `None` when their sizes differ.
    pub fn new(image: &'a LinearImage, moments: &'a SampleMoments) -> Option<Self> {
        let n = (image.width as usize) * (image.height as usize);
        ((image.width, image.height) == (moments.width, moments.height)
            && image.pixels.len() == n
            && moments.sum_sq.len() == n)
            .then_some(Self { image, moments })
    }

    /// The truth's image (sums and sample counts).
    pub fn image(&self) -> &'a LinearImage {
        self.image
    }

    /// Pixel (x, y): mean and variance of the mean. A pixel of `n` samples with sums `S` and
    /// squared sums `Q` has `s² = (Q − S²/n)/(n − 1)` (clamped at 0 against rounding) and a mean of
    /// variance `s²/n`; with fewer than two samples the variance is unknown (infinite).
    pub fn pixel(&self, x: u32, y: u32) -> PixelEstimate {
        let i = (y * self.image.width + x) as usize;
        let p = self.image.pixels[i];
        let q = self.moments.sum_sq[i];
        let n = f64::from(p[3]);
        let var_mean = |sum: f32, sq: f32| {
            if n < 2.0 {
                return f64::INFINITY;
            }
            let (s, q) = (f64::from(sum), f64::from(sq));
            ((q - s * s / n) / (n - 1.0)).max(0.0) / n
        };
        let w = if n > 0.0 { n } else { 1.0 };
        let mean = [0, 1, 2].map(|k| f64::from(p[k]) / w);
        let sum_y = luminance([0, 1, 2].map(|k| f64::from(p[k])));
        PixelEstimate {
            mean,
            var_mean: [0, 1, 2].map(|k| var_mean(p[k], q[k])),
            var_mean_y: var_mean(sum_y as f32, q[3]),
        }
    }
}

/// One block's difference from the truth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Pixels in it (edge blocks have fewer).
    pub pixels: u32,
    /// Mean of (estimate − truth) per channel.
    pub diff: [f64; 3],
    /// Variance of the truth's block mean per channel (from the block's own pixels).
    pub var: [f64; 3],
    /// `|d_Y| / √Var(T̄_Y)` on luminance, the variance pooled over the 3×3 blocks around (0 for no
    /// difference, infinite for a difference from an exact truth).
    pub z: f64,
}

impl Block {
    /// Largest absolute channel difference.
    pub fn max_abs(&self) -> f64 {
        self.diff.iter().fold(0.0f64, |m, d| m.max(d.abs()))
    }

    /// Whether the difference stands out of the truth's noise (`z ≥` [`Z_SIGNIFICANT`]).
    pub fn significant(&self) -> bool {
        self.z >= Z_SIGNIFICANT
    }

    /// `mean_c (d_c² − Var_c)`: this block's unbiased estimate of its squared bias (may be < 0).
    fn excess(&self) -> f64 {
        (0..3)
            .map(|k| self.diff[k] * self.diff[k] - self.var[k])
            .sum::<f64>()
            / 3.0
    }
}

/// An image's differences from a noisy truth on block means ([module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct BlockErrors {
    /// Block side in pixels.
    pub block: u32,
    /// The blocks, row-major.
    pub blocks: Vec<Block>,
}

impl BlockErrors {
    /// Differences of `image` from `truth` on `block × block` means (`block` ≥ 1; 1 is per
    /// pixel). `None` when the sizes differ, or when the truth has fewer than two samples per
    /// pixel somewhere (its noise is then unknown).
    pub fn new(image: &LinearImage, truth: &TruthEstimate, block: u32) -> Option<Self> {
        let t = truth.image();
        if (image.width, image.height) != (t.width, t.height)
            || image.pixels.len() != t.pixels.len()
        {
            return None;
        }
        let b = block.max(1);
        let (nx, ny) = (t.width.div_ceil(b), t.height.div_ceil(b));
        // Per block: sums of the differences and of the pixels' variances, luminance last.
        let mut sums = Vec::with_capacity((nx * ny) as usize);
        for by in (0..t.height).step_by(b as usize) {
            for bx in (0..t.width).step_by(b as usize) {
                let (mut d, mut v, mut m) = ([0.0; 4], [0.0; 4], 0u32);
                for y in by..(by + b).min(t.height) {
                    for x in bx..(bx + b).min(t.width) {
                        let p = truth.pixel(x, y);
                        if !p.var_mean_y.is_finite() {
                            return None;
                        }
                        let e = image.rgb(x, y).map(f64::from);
                        for k in 0..3 {
                            d[k] += e[k] - p.mean[k];
                            v[k] += p.var_mean[k];
                        }
                        d[3] += luminance(e) - luminance(p.mean);
                        v[3] += p.var_mean_y;
                        m += 1;
                    }
                }
                sums.push((bx, by, d, v, m));
            }
        }
        let mut blocks = Vec::with_capacity(sums.len());
        for (i, &(bx, by, d, v, m)) in sums.iter().enumerate() {
            let mf = f64::from(m);
            // The luminance variance for z pooled over the 3×3 blocks around: a block's own
            // estimate is noisy and, for skewed data, low exactly where its mean is low (fewer
            // glints: a lower mean and a lower sample variance), which would flag unbiased views.
            let (ix, iy) = ((i as u32) % nx, (i as u32) / nx);
            let (mut pv, mut pm) = (0.0, 0.0);
            for jy in iy.saturating_sub(1)..(iy + 2).min(ny) {
                for jx in ix.saturating_sub(1)..(ix + 2).min(nx) {
                    let s = &sums[(jy * nx + jx) as usize];
                    pv += s.3[3];
                    pm += f64::from(s.4);
                }
            }
            let (dy, vy) = (d[3] / mf, pv / pm / mf);
            let z = if dy == 0.0 {
                0.0
            } else if vy > 0.0 {
                dy.abs() / vy.sqrt()
            } else {
                f64::INFINITY
            };
            blocks.push(Block {
                x: bx,
                y: by,
                pixels: m,
                diff: [d[0], d[1], d[2]].map(|s| s / mf),
                var: [v[0], v[1], v[2]].map(|s| s / (mf * mf)),
                z,
            });
        }
        Some(Self { block: b, blocks })
    }

    fn weights(&self) -> f64 {
        self.blocks.iter().map(|b| f64::from(b.pixels)).sum()
    }

    /// RMSE of the block means as measured, the truth's noise included (at block 1: the plain
    /// per-pixel RMSE over pixels and channels).
    pub fn rmse_raw(&self) -> f64 {
        let s: f64 = self
            .blocks
            .iter()
            .map(|b| f64::from(b.pixels) * b.diff.iter().map(|d| d * d).sum::<f64>() / 3.0)
            .sum();
        (s / self.weights()).sqrt()
    }

    /// The mean squared error left when the truth's own noise is taken out: the pixel-weighted
    /// mean of `mean_c (d_c² − Var(T̄_c))` over blocks. Unbiased; negative when the image is
    /// within the truth's noise and the draw fell low.
    pub fn excess_mse(&self) -> f64 {
        self.blocks
            .iter()
            .map(|b| f64::from(b.pixels) * b.excess())
            .sum::<f64>()
            / self.weights()
    }

    /// Standard error of [`excess_mse`](Self::excess_mse), from the spread of the blocks' terms
    /// (the blocks taken as independent).
    pub fn excess_mse_se(&self) -> f64 {
        let w = self.weights();
        let mean = self.excess_mse();
        let s: f64 = self
            .blocks
            .iter()
            .map(|b| {
                let wb = f64::from(b.pixels);
                (wb * (b.excess() - mean)).powi(2)
            })
            .sum();
        s.sqrt() / w
    }

    /// RMSE beyond the truth's noise, `√max(excess, 0)`.
    pub fn rmse(&self) -> f64 {
        self.excess_mse().max(0.0).sqrt()
    }

    /// [`rmse`](Self::rmse)'s range for `excess ± k·se`.
    pub fn rmse_range(&self, k: f64) -> (f64, f64) {
        let (m, se) = (self.excess_mse(), self.excess_mse_se());
        ((m - k * se).max(0.0).sqrt(), (m + k * se).max(0.0).sqrt())
    }

    /// Fraction of pixels in blocks whose difference is significant.
    pub fn significant_fraction(&self) -> f64 {
        self.blocks
            .iter()
            .filter(|b| b.significant())
            .map(|b| f64::from(b.pixels))
            .sum::<f64>()
            / self.weights()
    }

    /// Heat map of the blocks' largest channel difference (`scale` at the top of `gradient`),
    /// each block filling its pixels; blocks within the truth's noise are drawn in grey at a
    /// third of their colour's luminance, so what is left in colour is what the truth can tell.
    pub fn heat(&self, width: u32, height: u32, gradient: &Gradient, scale: f64) -> LinearImage {
        let scale = if scale > 0.0 { scale } else { 1.0 };
        let mut pixels = vec![[0.0f32, 0.0, 0.0, 1.0]; (width as usize) * (height as usize)];
        let b = self.block;
        for blk in &self.blocks {
            let c = gradient.sample((blk.max_abs() / scale).min(1.0));
            let c = if blk.significant() {
                c
            } else {
                let g = luminance(c) / 3.0;
                [g; 3]
            };
            for y in blk.y..(blk.y + b).min(height) {
                for x in blk.x..(blk.x + b).min(width) {
                    pixels[(y * width + x) as usize] = [c[0] as f32, c[1] as f32, c[2] as f32, 1.0];
                }
            }
        }
        LinearImage {
            width,
            height,
            pixels,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Core's reproducible generator (SplitMix64, Box–Muller).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            lodestone_core::math::random::splitmix(&mut self.0)
        }
        fn gauss(&mut self) -> f64 {
            lodestone_core::math::random::standard_normal(&mut self.0)
        }
    }

    /// A truth of `n` grey samples per pixel drawn by `sample`, as the GPU accumulates it.
    fn truth(
        w: u32,
        h: u32,
        n: u32,
        mut sample: impl FnMut() -> f64,
    ) -> (LinearImage, SampleMoments) {
        let mut pixels = Vec::new();
        let mut sum_sq = Vec::new();
        for _ in 0..w * h {
            let (mut s, mut q) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let x = sample();
                s += x;
                q += x * x;
            }
            pixels.push([s as f32, s as f32, s as f32, n as f32]);
            // Grey: Y = x, so ΣY² = Σx².
            sum_sq.push([q as f32; 4]);
        }
        (
            LinearImage {
                width: w,
                height: h,
                pixels,
            },
            SampleMoments {
                width: w,
                height: h,
                sum_sq,
            },
        )
    }

    fn flat(w: u32, h: u32, v: f32) -> LinearImage {
        LinearImage {
            width: w,
            height: h,
            pixels: vec![[v, v, v, 1.0]; (w * h) as usize],
        }
    }

    #[test]
    fn pixel_variance_is_the_sample_variance_over_n() {
        let xs = [0.1, 0.4, 0.2, 0.9, 0.0];
        let mut it = xs.iter().copied();
        let (img, mom) = truth(1, 1, 5, || it.next().expect("five samples"));
        let t = TruthEstimate::new(&img, &mom).expect("same size");
        let p = t.pixel(0, 0);
        let mean = xs.iter().sum::<f64>() / 5.0;
        let s2 = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 4.0;
        assert!((p.mean[1] - mean).abs() < 1e-6, "{p:?}");
        assert!((p.var_mean[0] - s2 / 5.0).abs() < 1e-6, "{p:?}");
        assert!((p.var_mean_y - s2 / 5.0).abs() < 1e-6, "{p:?}");
        let (one, mom1) = truth(1, 1, 1, || 0.5);
        let p1 = TruthEstimate::new(&one, &mom1)
            .expect("same size")
            .pixel(0, 0);
        assert!(p1.var_mean[0].is_infinite(), "one sample: unknown noise");
        let other = flat(2, 1, 0.0);
        assert!(TruthEstimate::new(&other, &mom).is_none(), "sizes differ");
    }

    #[test]
    fn excess_error_recovers_a_known_bias_under_gaussian_noise() {
        // Truth: μ = 0.5 per pixel, σ = 0.3, 16 samples: per-pixel noise 0.075, far above the
        // biases tested.
        let mut rng = Rng(7);
        let (img, mom) = truth(64, 64, 16, || 0.5 + 0.3 * rng.gauss());
        let t = TruthEstimate::new(&img, &mom).expect("same size");
        for (bias, block) in [(0.0, 1), (0.0, 8), (0.02, 1), (0.02, 4), (0.05, 8)] {
            let e = BlockErrors::new(&flat(64, 64, (0.5 + bias) as f32), &t, block).expect("sizes");
            let (m, se) = (e.excess_mse(), e.excess_mse_se());
            assert!(
                (m - bias * bias).abs() < 3.0 * se + 1e-9,
                "bias {bias} block {block}: excess {m} ± {se}"
            );
            // The raw RMSE carries the noise: at one pixel √(b² + σ²/n).
            if block == 1 {
                let want = (bias * bias + 0.09 / 16.0).sqrt();
                assert!(
                    (e.rmse_raw() - want).abs() < 0.05 * want,
                    "{} vs {want}",
                    e.rmse_raw()
                );
            }
            let sig = e.significant_fraction();
            if bias == 0.0 {
                assert!(sig < 0.1, "no bias, block {block}: {sig} significant");
            }
            if bias == 0.05 {
                // 8×8 blocks: noise of the block mean 0.075/8 ≈ 0.009, so z ≈ 5.
                assert!(sig > 0.95, "bias {bias} block {block}: {sig} significant");
            }
        }
    }

    #[test]
    fn block_means_rank_the_unbiased_view_ahead_under_glints() {
        // A grazing ground-truth pixel: mostly dark, a rare bright glint (mean 0.1, of which 0.08
        // from glints of value 20 with probability 0.004), 32 rays. A view that drops the glints
        // (0.02, biased by −0.08) matches most truth pixels exactly (88% saw no glint), so a
        // per-pixel |e − T| map shows it black there; on block means with the noise taken out the
        // exact mean wins, and only the dark view's blocks stand out of the noise.
        let mut rng = Rng(11);
        let (img, mom) = truth(
            128,
            128,
            32,
            || {
                if rng.next() < 0.004 { 20.0 } else { 0.02 }
            },
        );
        let t = TruthEstimate::new(&img, &mom).expect("same size");
        let exact = flat(128, 128, 0.1);
        let dark = flat(128, 128, 0.02);
        let per_pixel = |v: &LinearImage| BlockErrors::new(v, &t, 1).expect("sizes");
        let (pe, pd) = (per_pixel(&exact), per_pixel(&dark));
        assert!(
            pd.blocks.iter().filter(|b| b.max_abs() < 1e-3).count() > pe.blocks.len() / 2,
            "most truth pixels saw no glint"
        );
        let (be, bd) = (
            BlockErrors::new(&exact, &t, 8).expect("sizes"),
            BlockErrors::new(&dark, &t, 8).expect("sizes"),
        );
        // Unbiased: the exact view's excess is zero within its error, the dark view's is 0.08².
        assert!(be.excess_mse().abs() < 3.0 * be.excess_mse_se(), "{be:?}");
        assert!(
            (bd.excess_mse() - 0.0064).abs() < 3.0 * bd.excess_mse_se(),
            "{} ± {}",
            bd.excess_mse(),
            bd.excess_mse_se()
        );
        assert!(be.rmse() < bd.rmse(), "{} vs {}", be.rmse(), bd.rmse());
        // 8×8 blocks of 32 rays: the truth's block mean has a deviation of 0.028, the dark view's
        // bias is 2.9 of them.
        let (se, sd) = (be.significant_fraction(), bd.significant_fraction());
        // Measured: 4.7% of the exact view's blocks (10.2% with each block's own variance), 82%
        // of the dark view's.
        assert!(se < 0.08 && sd > 0.6, "significant: exact {se}, dark {sd}");
    }

    #[test]
    fn an_exact_truth_makes_every_difference_significant() {
        // Two samples of the same value: zero variance.
        let (img, mom) = truth(4, 4, 2, || 0.25);
        let t = TruthEstimate::new(&img, &mom).expect("same size");
        let e = BlockErrors::new(&flat(4, 4, 0.26), &t, 2).expect("sizes");
        assert_eq!(e.significant_fraction(), 1.0);
        assert!((e.rmse() - 0.01).abs() < 1e-6, "{}", e.rmse());
        let same = BlockErrors::new(&flat(4, 4, 0.25), &t, 2).expect("sizes");
        assert_eq!(same.significant_fraction(), 0.0);
        assert_eq!(same.blocks.len(), 4);
    }

    #[test]
    fn heat_greys_out_blocks_within_the_noise() {
        let mut rng = Rng(3);
        let (img, mom) = truth(8, 8, 16, || 0.5 + 0.3 * rng.gauss());
        let t = TruthEstimate::new(&img, &mom).expect("same size");
        let g = crate::error_map::heat_gradient();
        // Far off: every block significant and coloured like error_heat's top.
        let far = BlockErrors::new(&flat(8, 8, 2.0), &t, 4).expect("sizes");
        let h = far.heat(8, 8, &g, 0.5);
        let top = g.sample(1.0);
        assert!((f64::from(h.rgb(7, 7)[0]) - top[0]).abs() < 1e-6);
        // Within the noise: grey.
        let near = BlockErrors::new(&flat(8, 8, 0.5), &t, 4).expect("sizes");
        let h = near.heat(8, 8, &g, 0.5);
        for y in 0..8 {
            for x in 0..8 {
                let c = h.rgb(x, y);
                let b = &near.blocks[((y / 4) * 2 + x / 4) as usize];
                assert_eq!(c[0] == c[1] && c[1] == c[2], !b.significant(), "{b:?}");
            }
        }
    }
}
