//! Reconstruction of a noisy ground truth over windows chosen per pixel by the intersection of
//! confidence intervals (ICI) [Katkovnik 1999; Goldenshluger & Nemirovski 1997], the a posteriori
//! half of an adaptive ground truth's reconstruction [BSSBH13 Sec. 3] (#18 §1).
//!
//! A pixel's mean of `n` rays has variance `σ²/n`. Where the image is smooth at a larger scale
//! than a pixel (the far field, where every pixel's footprint already averages many crests), the
//! pixels around it estimate the same expectation, and pooling their rays divides that variance by
//! the window's ray count at the price of a bias: the window's expectation minus the pixel's. BSSBH13
//! choose the scale from a predicted bandwidth; here it is chosen from the rays themselves, so the
//! reconstruction never depends on the statistical model the ground truth is there to judge (the
//! model only supplies a prior for each pixel's variance, through the caller's `ray_var`).
//!
//! For nested square windows of radius `r_0 = 0 < r_1 < … ≤ max_radius` around pixel `p`, window
//! `k` estimates `m_k = Σ n_i Y_i / Σ n_i` (ray-weighted mean luminance over its pixels) with
//! standard error `s_k = √(Σ n_i v_i) / Σ n_i` (`v_i` one ray's variance at pixel i). ICI keeps
//! the largest `k` for which the intervals `[m_j − Γ s_j, m_j + Γ s_j]`, `j ≤ k`, still share a
//! point: while the windows' biases stay below about `Γ s_j` their intervals overlap; once a
//! window reaches an edge or a slope its mean leaves the earlier intervals. The estimate's mean
//! squared error is then within a constant factor of the best window's (the oracle inequality of
//! Goldenshluger & Nemirovski). The chosen window's RGB mean is the pixel's value.
//!
//! Windows are clipped at the image's border. A pixel with no rays of its own starts at the first
//! window that has some (its value is interpolated from its neighbours). Noise differs between
//! pixels, so a larger window need not have a smaller `s_k` (a sky pixel, exactly 0 with no
//! variance, beside a glinting horizon): among the windows that pass, the pixel takes the one of
//! least standard error (the largest on ties), which on evenly noisy images is the largest.
//!
//! The decision uses luminance, the quantity the rays' variance is known for; the three channels
//! follow the same window.

use crate::material::colormap::LUMINANCE;

/// One pixel of a ground truth: its rays, their mean and one ray's luminance variance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WindowSample {
    /// Rays traced at this pixel (0: none; non-finite or negative counts as 0).
    pub rays: f64,
    /// Mean linear RGB of its rays (ignored without rays; a non-finite mean drops the pixel).
    pub mean: [f64; 3],
    /// Variance of one ray's luminance (non-finite or negative counts as 0: the pixel's own
    /// interval is then a point, so an unknown variance never licenses a wider window).
    pub ray_var: f64,
}

/// The windows ICI chooses among.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowOptions {
    /// The largest radius (pixels; 0 returns every pixel's own mean).
    pub max_radius: u32,
    /// Half-width of each confidence interval in standard errors, Γ. Larger widens the windows
    /// (less noise, more bias). Katkovnik's range is 1.5–2.5; the default is 2. Below about 1.5
    /// the intervals of a flat image's nested windows stop intersecting by chance and ICI pools
    /// little (Γ = 1 leaves 0.11 of a flat image's raw 0.15 RMSE in the test below, Γ = 2 under
    /// 0.025).
    pub gamma: f64,
}

impl Default for WindowOptions {
    fn default() -> Self {
        Self {
            max_radius: 8,
            gamma: 2.0,
        }
    }
}

/// A reconstructed image.
#[derive(Clone, Debug, PartialEq)]
pub struct WindowReconstruction {
    /// Row-major linear RGB.
    pub rgb: Vec<[f64; 3]>,
    /// The radius chosen per pixel (0: the pixel's own rays; the measured scale over which the
    /// image is flat within its noise, a bandwidth of about `1/(2r + 1)` cycles per pixel).
    pub radius: Vec<u32>,
    /// The share of each pixel's value that is its own rays, `n_p / Σ_window n_i` (1 for its own
    /// mean, 0 for an interpolated pixel): what an error against a reference that shares the
    /// pixel's ray sequence must account for.
    pub own_weight: Vec<f64>,
}

/// The radii tried up to `max_radius`: 0, 1, 2, 3, 4, then growing by about a third
/// (6, 8, 11, 15, …) so that each window holds at least ~1.7× the rays of the last.
pub fn window_radii(max_radius: u32) -> Vec<u32> {
    let mut radii = Vec::new();
    let mut r = 0_u32;
    while r <= max_radius {
        radii.push(r);
        r = if r < 4 { r + 1 } else { r + r.div_ceil(3) };
    }
    radii
}

/// Summed-area table of one per-pixel quantity, with a zero first row and column.
struct Table {
    width: usize,
    sums: Vec<f64>,
}

impl Table {
    fn new(width: usize, height: usize, value: impl Fn(usize) -> f64) -> Self {
        let stride = width + 1;
        let mut sums = vec![0.0; stride * (height + 1)];
        for y in 0..height {
            let mut row = 0.0;
            for x in 0..width {
                row += value(y * width + x);
                sums[(y + 1) * stride + x + 1] = sums[y * stride + x + 1] + row;
            }
        }
        Self { width, sums }
    }

    /// Sum over columns `x0..x1`, rows `y0..y1` (half-open).
    fn sum(&self, x0: usize, x1: usize, y0: usize, y1: usize) -> f64 {
        let s = self.width + 1;
        self.sums[y1 * s + x1] - self.sums[y0 * s + x1] - self.sums[y1 * s + x0]
            + self.sums[y0 * s + x0]
    }
}

/// How far a guide's predicted bias may go, in standard errors of the window's mean: a window is
/// kept only while `|Σ n_i F_i / Σ n_i − F_p| ≤ GUIDE_BIAS·s_k`, so the bias it adds costs at most
/// `GUIDE_BIAS²` of its variance.
pub const GUIDE_BIAS: f64 = 0.5;

/// Reconstruct a `width × height` ground truth from its per-pixel `samples` (row-major) by ICI
/// over square windows (module docs). A `samples` of the wrong length is read as far as it goes,
/// the rest as pixels without rays; every output is finite.
///
/// With a `guide` (the truth's predicted luminance per pixel, e.g. the filtered view), a window is
/// also refused where the guide predicts it biased ([`GUIDE_BIAS`]): the prediction says where an
/// image is textured at the pixel scale, which ICI's intervals cannot see through the noise of a
/// few rays, and the rays' intervals veto what the prediction gets wrong. The guide only chooses
/// windows; the values are the rays'. A guide of the wrong length, or non-finite entries, count as
/// no prediction there.
pub fn reconstruct(
    width: usize,
    height: usize,
    samples: &[WindowSample],
    guide: Option<&[f64]>,
    options: WindowOptions,
) -> WindowReconstruction {
    let n = width * height;
    let sample = |p: usize| -> WindowSample {
        let s = samples.get(p).copied().unwrap_or_default();
        let rays = if s.rays.is_finite() && s.rays > 0.0 && s.mean.iter().all(|c| c.is_finite()) {
            s.rays
        } else {
            0.0
        };
        let ray_var = if s.ray_var.is_finite() && s.ray_var > 0.0 {
            s.ray_var
        } else {
            0.0
        };
        let mean = if rays > 0.0 { s.mean } else { [0.0; 3] };
        WindowSample {
            rays,
            mean,
            ray_var,
        }
    };
    let clean: Vec<WindowSample> = (0..n).map(sample).collect();
    let table = |value: &dyn Fn(&WindowSample, usize) -> f64| {
        Table::new(width, height, |p| clean[p].rays * value(&clean[p], p))
    };
    let weights = table(&|_, _| 1.0);
    let channels = [0, 1, 2].map(|k| table(&|s, _| s.mean[k]));
    let lum = table(&|s, _| (0..3).map(|k| LUMINANCE[k] * s.mean[k]).sum::<f64>());
    let var = table(&|s, _| s.ray_var);
    // The guide with its ray-weighted table, where it is usable.
    let guide = guide
        .filter(|g| g.len() == n && g.iter().all(|v| v.is_finite()))
        .map(|g| (g, table(&|_, p| g[p])));
    let gamma = if options.gamma.is_finite() {
        options.gamma.max(0.0)
    } else {
        WindowOptions::default().gamma
    };
    let radii = window_radii(options.max_radius);

    let mut out = WindowReconstruction {
        rgb: vec![[0.0; 3]; n],
        radius: vec![options.max_radius; n],
        own_weight: vec![0.0; n],
    };
    for y in 0..height {
        for x in 0..width {
            let p = y * width + x;
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            let mut chosen = None;
            let mut best_s = f64::INFINITY;
            for &r in &radii {
                let r = r as usize;
                let (x0, x1) = (x.saturating_sub(r), (x + r + 1).min(width));
                let (y0, y1) = (y.saturating_sub(r), (y + r + 1).min(height));
                let total = weights.sum(x0, x1, y0, y1);
                if !(total > 0.0) {
                    continue;
                }
                let m = lum.sum(x0, x1, y0, y1) / total;
                let s = var.sum(x0, x1, y0, y1).max(0.0).sqrt() / total;
                lo = lo.max(m - gamma * s);
                hi = hi.min(m + gamma * s);
                if lo > hi {
                    break;
                }
                if let Some((g, t)) = &guide
                    && r > 0
                    && (t.sum(x0, x1, y0, y1) / total - g[p]).abs() > GUIDE_BIAS * s
                {
                    break;
                }
                // Noise is not the same everywhere: a window that takes in noisier pixels can
                // have a larger standard error than a smaller one (a sky pixel, exactly 0, beside
                // a glinting horizon). Keep the consistent window of least error.
                if s <= best_s {
                    best_s = s;
                    chosen = Some((r, x0, x1, y0, y1, total));
                }
            }
            if let Some((r, x0, x1, y0, y1, total)) = chosen {
                out.rgb[p] = if r == 0 {
                    clean[p].mean
                } else {
                    [0, 1, 2].map(|k| channels[k].sum(x0, x1, y0, y1) / total)
                };
                out.radius[p] = r as u32;
                out.own_weight[p] = (clean[p].rays / total).clamp(0.0, 1.0);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::standard_normal;

    /// A `w × h` truth whose pixel expectations are `f(x, y)` (grey), `rays` rays a pixel of
    /// standard deviation `sd` each: per pixel the mean of its rays.
    fn noisy(
        w: usize,
        h: usize,
        rays: f64,
        sd: f64,
        f: impl Fn(usize, usize) -> f64,
        seed: u64,
    ) -> Vec<WindowSample> {
        let mut state = seed;
        (0..w * h)
            .map(|p| {
                let v = f(p % w, p / w) + sd / rays.sqrt() * standard_normal(&mut state);
                WindowSample {
                    rays,
                    mean: [v; 3],
                    ray_var: sd * sd,
                }
            })
            .collect()
    }

    fn rmse(rgb: &[[f64; 3]], w: usize, f: impl Fn(usize, usize) -> f64) -> f64 {
        let s: f64 = rgb
            .iter()
            .enumerate()
            .map(|(p, c)| (c[0] - f(p % w, p / w)).powi(2))
            .sum();
        (s / rgb.len() as f64).sqrt()
    }

    #[test]
    fn radii_start_at_the_pixel_and_grow() {
        assert_eq!(window_radii(0), vec![0]);
        assert_eq!(window_radii(8), vec![0, 1, 2, 3, 4, 6, 8]);
        assert_eq!(window_radii(20), vec![0, 1, 2, 3, 4, 6, 8, 11, 15, 20]);
    }

    #[test]
    fn a_flat_image_pools_the_largest_window() {
        // Expectation 0.5 everywhere, 4 rays of deviation 0.3: the raw RMSE is 0.15; a 17×17
        // window (interior) has 289 times the rays, so ~17× less error. Clipped border windows
        // and ICI stopping early on a few unlucky pixels keep the whole image above that.
        let (w, h) = (48, 40);
        let s = noisy(w, h, 4.0, 0.3, |_, _| 0.5, 7);
        let raw: Vec<[f64; 3]> = s.iter().map(|s| s.mean).collect();
        let r = reconstruct(w, h, &s, None, WindowOptions::default());
        let (e_raw, e) = (rmse(&raw, w, |_, _| 0.5), rmse(&r.rgb, w, |_, _| 0.5));
        assert!((e_raw - 0.15).abs() < 0.01, "{e_raw}");
        assert!(e < e_raw / 6.0, "{e} against {e_raw}");
        let widest = r.radius.iter().filter(|r| **r == 8).count();
        assert!(widest as f64 > 0.8 * (w * h) as f64, "{widest}");
        // Own weights: 1/(window's pixels) where the window is widest and inside.
        let p = 20 * w + 24;
        assert!(
            (r.own_weight[p] - 1.0 / 289.0).abs() < 1e-12,
            "{}",
            r.own_weight[p]
        );
    }

    #[test]
    fn an_edge_stays_sharp() {
        // A step of 1.0 at x = 24 under noise 0.3/√16 = 0.075 a pixel: a window that crosses the
        // edge by one column moves the mean by ≥ 1/17 ≈ 0.06 ≫ its standard error, so ICI stops
        // before. The error next to the edge stays near the raw noise, the rest is pooled.
        let (w, h) = (48, 40);
        let f = |x: usize, _y: usize| if x < 24 { 0.2 } else { 1.2 };
        let s = noisy(w, h, 16.0, 0.3, f, 11);
        let raw: Vec<[f64; 3]> = s.iter().map(|s| s.mean).collect();
        let r = reconstruct(w, h, &s, None, WindowOptions::default());
        let e_raw = rmse(&raw, w, f);
        let e = rmse(&r.rgb, w, f);
        assert!(e < e_raw / 2.0, "{e} against {e_raw}");
        // The columns beside the edge: within about the raw noise (ICI's bias is bounded by a
        // few Γ·s₀ on unlucky pixels, not by the step).
        let beside: Vec<usize> = (0..h).flat_map(|y| [y * w + 23, y * w + 24]).collect();
        let e_edge = (beside
            .iter()
            .map(|p| (r.rgb[*p][0] - f(p % w, 0)).powi(2))
            .sum::<f64>()
            / beside.len() as f64)
            .sqrt();
        assert!(e_edge < 2.0 * 0.075, "{e_edge}");
        // Without ICI (the widest window everywhere), the edge columns would be off by ~0.5.
        let always = reconstruct(
            w,
            h,
            &s,
            None,
            WindowOptions {
                max_radius: 8,
                gamma: 1e9,
            },
        );
        let p = 20 * w + 23;
        assert!(
            (always.rgb[p][0] - f(23, 20)).abs() > 0.4,
            "{:?}",
            always.rgb[p]
        );
    }

    #[test]
    fn a_linear_ramp_is_pooled_without_bias() {
        // A symmetric window's mean of a linear ramp is the centre's value: interior pixels pool
        // widely and stay unbiased.
        let (w, h) = (48, 40);
        let f = |x: usize, y: usize| 0.2 + 0.01 * x as f64 + 0.005 * y as f64;
        let s = noisy(w, h, 4.0, 0.3, f, 3);
        let raw: Vec<[f64; 3]> = s.iter().map(|s| s.mean).collect();
        let r = reconstruct(w, h, &s, None, WindowOptions::default());
        assert!(rmse(&r.rgb, w, f) < rmse(&raw, w, f) / 3.0);
    }

    #[test]
    fn radius_zero_is_the_identity_and_empty_pixels_are_filled() {
        let (w, h) = (6, 5);
        let mut s = noisy(w, h, 3.0, 0.1, |x, _| x as f64, 5);
        let r = reconstruct(
            w,
            h,
            &s,
            None,
            WindowOptions {
                max_radius: 0,
                gamma: 2.0,
            },
        );
        for (p, c) in r.rgb.iter().enumerate() {
            assert_eq!(*c, s[p].mean);
            assert_eq!(r.own_weight[p], 1.0);
            assert_eq!(r.radius[p], 0);
        }
        // A pixel without rays takes the first window that has some, with own weight 0.
        s[2 * w + 3].rays = 0.0;
        let r = reconstruct(w, h, &s, None, WindowOptions::default());
        let p = 2 * w + 3;
        assert_eq!(r.own_weight[p], 0.0);
        assert!(r.radius[p] >= 1);
        assert!((r.rgb[p][0] - 3.0).abs() < 0.5, "{:?}", r.rgb[p]);
    }

    #[test]
    fn a_guide_keeps_texture_that_the_noise_hides() {
        // A checkerboard of ±0.05 under 4 rays of deviation 0.3 (0.15 a pixel): ICI cannot see
        // the pattern through the noise and pools it away, leaving its whole amplitude as error
        // (0.05); a guide that knows the pattern keeps each pixel's own rays where pooling would
        // bias it, and pools the flat half of the image.
        let (w, h) = (48, 40);
        let f = |x: usize, y: usize| {
            if x < 24 {
                0.5 + if (x + y).is_multiple_of(2) {
                    0.05
                } else {
                    -0.05
                }
            } else {
                0.5
            }
        };
        let s = noisy(w, h, 64.0, 0.3, f, 13);
        let guide: Vec<f64> = (0..w * h).map(|p| f(p % w, p / w)).collect();
        let blind = reconstruct(w, h, &s, None, WindowOptions::default());
        let guided = reconstruct(w, h, &s, Some(&guide), WindowOptions::default());
        let textured = |r: &WindowReconstruction| {
            let e: f64 = (0..h)
                .flat_map(|y| (2..22).map(move |x| (x, y)))
                .map(|(x, y)| (r.rgb[y * w + x][0] - f(x, y)).powi(2))
                .sum();
            (e / (20 * h) as f64).sqrt()
        };
        // Raw noise 0.3/8 = 0.0375 a pixel.
        assert!(textured(&blind) > 0.045, "{}", textured(&blind));
        assert!(textured(&guided) < 0.042, "{}", textured(&guided));
        // The flat half is pooled either way.
        let flat = 20 * w + 36;
        assert!(guided.radius[flat] >= 4, "{}", guided.radius[flat]);
        assert_eq!(guided.radius[20 * w + 10], 0);
    }

    #[test]
    fn an_exact_pixel_is_not_pooled_with_noisier_ones() {
        // A row of sky (0, known exactly: no variance) above rows of glinting surface (mean 0.1,
        // one ray's deviation 1, 8 rays): a window reaching into the surface has a mean within
        // its wide interval of 0, so plain ICI would pool it and bleed the glints into the sky.
        let (w, h) = (24, 12);
        let mut s = noisy(w, h, 8.0, 1.0, |_, _| 0.1, 21);
        for x in 0..w {
            s[x] = WindowSample {
                rays: 8.0,
                mean: [0.0; 3],
                ray_var: 0.0,
            };
        }
        let r = reconstruct(w, h, &s, None, WindowOptions::default());
        for x in 0..w {
            assert_eq!(r.rgb[x], [0.0; 3], "sky pixel {x}: {:?}", r.rgb[x]);
            assert_eq!(r.radius[x], 0);
        }
        // The surface below still pools.
        let p = 8 * w + 12;
        assert!(r.radius[p] >= 2, "{}", r.radius[p]);
    }

    #[test]
    fn hostile_samples_give_finite_images() {
        let bad = [
            WindowSample {
                rays: f64::NAN,
                mean: [1.0; 3],
                ray_var: 1.0,
            },
            WindowSample {
                rays: -3.0,
                mean: [1.0; 3],
                ray_var: 1.0,
            },
            WindowSample {
                rays: 2.0,
                mean: [f64::INFINITY, 0.0, 0.0],
                ray_var: 1.0,
            },
            WindowSample {
                rays: 2.0,
                mean: [0.5; 3],
                ray_var: f64::NAN,
            },
            WindowSample {
                rays: f64::INFINITY,
                mean: [0.5; 3],
                ray_var: f64::INFINITY,
            },
        ];
        for options in [
            WindowOptions::default(),
            WindowOptions {
                max_radius: 100,
                gamma: f64::NAN,
            },
        ] {
            let r = reconstruct(3, 2, &bad, Some(&[f64::NAN; 6]), options);
            assert_eq!(r.rgb.len(), 6);
            assert!(r.rgb.iter().flatten().all(|c| c.is_finite()), "{r:?}");
            assert!(r.own_weight.iter().all(|w| (0.0..=1.0).contains(w)));
        }
        assert!(
            reconstruct(0, 0, &[], None, WindowOptions::default())
                .rgb
                .is_empty()
        );
        // No rays anywhere: black, nothing of its own.
        let r = reconstruct(2, 2, &[], None, WindowOptions::default());
        assert_eq!(r.rgb, vec![[0.0; 3]; 4]);
    }
}
