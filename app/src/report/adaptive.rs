//! The adaptive ground truth's part of `lodestone report` (#18 §1): per configuration, uniform
//! ground truth and adaptive ground truth ([`lodestone_render::adaptive_truth`]) at several ray
//! budgets, each as its error against the true image, rays per pixel and time; and the uniform ray
//! count that reaches the same error (the rays an adaptive plan saves at equal error).
//!
//! **Error against the true image.** Every truth here shares the reference's low-discrepancy
//! sequence: a pixel with n rays holds the first n of the reference's R. For such a prefix,
//! `E[(x̂_n − x̂_R)²] = σ²(1/n − 1/R)`, so its error against the truth is the error against the
//! reference plus `σ²/R`; a pixel filled by interpolation is independent of the reference there and
//! its error against the truth is the error against the reference minus `σ²/R`. `σ²/R` per pixel
//! comes from the reference's squared sums ([`TruthEstimate`]). Pixels given more than R/2 rays are
//! capped at R/2 so that every shaded pixel is a prefix.

use crate::report::chart::{Chart, Series};
use lodestone_core::math::correlation::{pearson, spearman};
use lodestone_render::LinearImage;
use lodestone_render::truth_noise::TruthEstimate;
use serde::Serialize;
use std::fmt::Write as _;

/// Ray budgets (rays per pixel on average) of the adaptive ground truth, by default.
pub const ADAPTIVE_RPP: [f64; 3] = [4.0, 16.0, 64.0];

/// How an adaptive ground truth spends its budget.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// [`lodestone_render::adaptive_truth::render_adaptive`]'s two passes on a lattice of this
    /// step (1: ray counts only, superseded by the progressive counts and no longer reported).
    TwoPass(usize),
    /// [`lodestone_render::adaptive_truth::render_progressive`]'s doubling rounds (the editor's),
    /// cost-aware or not.
    Progressive {
        /// Shares divided by √(measured cost per ray).
        cost_aware: bool,
    },
    /// The same rays everywhere (`progressive: false`) or progressive counts, then each pixel
    /// pools the rays of the window around it that ICI chooses
    /// ([`lodestone_render::adaptive_truth::reconstruct_truth`]).
    Reconstructed {
        /// Progressive counts rather than uniform rays.
        progressive: bool,
        /// The prediction's luminance refuses windows it predicts biased.
        guided: bool,
    },
}

/// The adaptive strategies compared, by name.
pub const STRATEGIES: [(&str, Strategy); 6] = [
    ("lattice 4, refined", Strategy::TwoPass(4)),
    (
        "progressive counts",
        Strategy::Progressive { cost_aware: false },
    ),
    (
        "progressive, cost-aware",
        Strategy::Progressive { cost_aware: true },
    ),
    (
        "uniform, reconstructed",
        Strategy::Reconstructed {
            progressive: false,
            guided: false,
        },
    ),
    (
        "uniform, guided reconstruction",
        Strategy::Reconstructed {
            progressive: false,
            guided: true,
        },
    ),
    (
        "progressive, guided reconstruction",
        Strategy::Reconstructed {
            progressive: true,
            guided: true,
        },
    ),
];

/// Uniform ground truth at one ray count.
#[derive(Clone, Debug, Serialize)]
pub struct UniformPoint {
    /// Rays per pixel.
    pub spp: u32,
    /// RMSE against the true image (linear RGB; see the module docs).
    pub rmse_true: f64,
    /// Time (ms), synchronised wall time.
    pub ms: f64,
}

/// Adaptive ground truth at one budget.
#[derive(Clone, Debug, Serialize)]
pub struct AdaptiveResult {
    /// The strategy (see [`STRATEGIES`]).
    pub strategy: String,
    /// The budget, rays per pixel.
    pub budget: f64,
    /// Rays traced per pixel on average.
    pub rays_per_pixel: f64,
    /// Fraction of pixels traced (the rest interpolated).
    pub shaded_fraction: f64,
    /// RMSE against the true image (linear RGB; see the module docs).
    pub rmse_true: f64,
    /// Uniform rays per pixel that reach `rmse_true` (log–log interpolation of the uniform
    /// curve, extrapolated as 1/√n beyond its ends).
    pub uniform_rays_equal: f64,
    /// GPU passes, readbacks and reconstruction (ms).
    pub ms: f64,
    /// The model's prediction on the CPU (ms; shared by every budget of the configuration).
    pub predict_ms: f64,
}

impl AdaptiveResult {
    /// Uniform rays over adaptive rays at equal error.
    pub fn ray_gain(&self) -> f64 {
        self.uniform_rays_equal / self.rays_per_pixel.max(1e-12)
    }

    /// Uniform time over adaptive time (prediction included) at equal error, from the uniform
    /// curve's time per ray.
    pub fn time_gain(&self, uniform: &[UniformPoint]) -> f64 {
        let per_ray = uniform
            .iter()
            .map(|u| u.ms / f64::from(u.spp.max(1)))
            .fold(f64::NAN, f64::min);
        per_ray * self.uniform_rays_equal / (self.ms + self.predict_ms).max(1e-12)
    }
}

/// RMSE of `img` against the true image, from its error against `reference` and the
/// reference's own noise. Pixel p's value is `w_p` times a prefix of the reference's ray sequence
/// at p (its own first rays) plus what is independent of the reference there (other pixels'
/// rays, or an interpolation): `x̂ = w_p·x̄_n + (1 − w_p)·y`, so `Cov(x̂, x̂_R) = w_p·σ²/R` and
/// `E[(x̂ − x̂_R)²] = E[(x̂ − μ)²] + σ²/R − 2·w_p·σ²/R`. The true squared error is therefore the
/// squared error against the reference `+(2w_p − 1)·σ²/R`: `+σ²/R` for a prefix (`w_p = 1`),
/// `−σ²/R` for an interpolated pixel (`w_p = 0`). `own(p)` gives `w_p` (clamped to [0, 1]);
/// the result is clamped at 0.
pub fn rmse_true(img: &LinearImage, reference: &TruthEstimate, own: &dyn Fn(usize) -> f64) -> f64 {
    let r = reference.image();
    let (w, h) = (r.width, r.height);
    let (mut sum, mut n) = (0.0, 0.0f64);
    for y in 0..h {
        for x in 0..w {
            let p = (y * w + x) as usize;
            let a = img.rgb(x, y).map(f64::from);
            let e = reference.pixel(x, y);
            let w_own = own(p);
            let sign = if w_own.is_finite() {
                2.0 * w_own.clamp(0.0, 1.0) - 1.0
            } else {
                -1.0
            };
            for k in 0..3 {
                let v = if e.var_mean[k].is_finite() {
                    e.var_mean[k]
                } else {
                    0.0
                };
                sum += (a[k] - e.mean[k]).powi(2) + sign * v;
                n += 1.0;
            }
        }
    }
    (sum / n.max(1.0)).max(0.0).sqrt()
}

/// The uniform rays per pixel at which `uniform` (sorted by rays) reaches `error`: log–log
/// interpolation between the bracketing points, 1/√n extrapolation beyond the ends.
pub fn uniform_rays_at(uniform: &[UniformPoint], error: f64) -> f64 {
    let pts: Vec<(f64, f64)> = uniform
        .iter()
        .filter(|u| u.rmse_true > 0.0 && u.rmse_true.is_finite())
        .map(|u| (f64::from(u.spp).ln(), u.rmse_true.ln()))
        .collect();
    if pts.is_empty() || !(error > 0.0) {
        return f64::NAN;
    }
    let e = error.ln();
    for pair in pts.windows(2) {
        let ((n0, e0), (n1, e1)) = (pair[0], pair[1]);
        if (e <= e0 && e >= e1) || (e >= e0 && e <= e1) {
            let t = if e1 != e0 { (e - e0) / (e1 - e0) } else { 0.0 };
            return (n0 + t * (n1 - n0)).exp();
        }
    }
    // Beyond the curve: error ∝ n^(−1/2) from the nearer end.
    let (first, last) = (pts[0], pts[pts.len() - 1]);
    let (n0, e0) = if e > first.1 { first } else { last };
    (n0 - 2.0 * (e - e0)).exp()
}

/// How well the model's predicted deviation of one ray (`TruthPrediction::sd`) matches what the
/// reference's rays measured, over the pixels where both are known and positive.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct PredictionCheck {
    /// Pixels compared (the reference has at least two rays there and both deviations are
    /// positive).
    pub pixels: usize,
    /// Spearman's rank correlation of predicted and measured deviations (what the ray counts
    /// need: which pixels are noisier).
    pub rank_correlation: f64,
    /// Pearson's correlation of their logarithms.
    pub log_correlation: f64,
    /// Median of predicted over measured (1: unbiased in scale).
    pub median_ratio: f64,
    /// The most any per-pixel ray counts can buy ([`allocation_gains`]): uniform rays over the
    /// best allocation's at equal error, from the reference's measured deviations.
    pub best_allocation_gain: f64,
    /// What the model's counts buy on the same measure ([`allocation_gains`]).
    pub predicted_allocation_gain: f64,
}

/// Uniform rays over adaptive rays at equal error for per-pixel ray counts, if each pixel's error
/// were its Monte Carlo variance: with `s_p²` the variance of one ray at pixel p (summed over RGB,
/// as the report's RMSE sums them) and `n_p` its rays, the error is `Σ s_p²/n_p`, so at equal total
/// rays the gain of counts `n_p ∝ w_p` over uniform ones is `P · Σ s_p² / (Σ w_p · Σ s_p²/w_p)`.
/// Returns `(best, predicted)`: the best is Neyman's `w_p = s_p` (BSSBH13 Sec. 2.4 with the true
/// deviations), `P Σ s² / (Σ s)²`, which no per-pixel allocation exceeds on this measure; the
/// predicted is the model's first-round weights, `ŝ_p + DEFENSIVE·mean ŝ` (as
/// [`lodestone_render::adaptive_truth::progressive_counts`] starts). It reads the noise as
/// independent rays: the truth's stratified rays converge faster than `1/n` on smooth pixels, and a
/// pixel that glints converges slower, so it bounds what counts buy where the error is noise, not
/// what a reconstruction across pixels buys. Pixels the reference gave fewer than two rays are left
/// out; `None` without any variance or with sizes that do not match.
pub fn allocation_gains(predicted: &[f64], reference: &TruthEstimate) -> Option<(f64, f64)> {
    use lodestone_render::adaptive_truth::DEFENSIVE;
    let img = reference.image();
    let w = img.width;
    if predicted.len() != img.pixels.len() {
        return None;
    }
    let clean = |x: f64| if x.is_finite() && x > 0.0 { x } else { 0.0 };
    let mean_pred =
        predicted.iter().map(|x| clean(*x)).sum::<f64>() / predicted.len().max(1) as f64;
    let (mut pixels, mut s2, mut s1) = (0.0, 0.0, 0.0);
    let (mut w_sum, mut s2_over_w) = (0.0, 0.0);
    for (i, (sd, px)) in predicted.iter().zip(&img.pixels).enumerate() {
        let n = f64::from(px[3]);
        if n < 2.0 {
            continue;
        }
        let e = reference.pixel(i as u32 % w, i as u32 / w);
        let var: f64 = e.var_mean.iter().map(|v| clean(*v) * n).sum();
        let weight = if mean_pred > 0.0 {
            clean(*sd) + DEFENSIVE * mean_pred
        } else {
            1.0
        };
        pixels += 1.0;
        s2 += var;
        s1 += var.sqrt();
        w_sum += weight;
        s2_over_w += var / weight;
    }
    if !(s2 > 0.0 && s2_over_w > 0.0) {
        return None;
    }
    Some((pixels * s2 / (s1 * s1), pixels * s2 / (w_sum * s2_over_w)))
}

/// [`PredictionCheck`] of `predicted` (per pixel, row-major) against the reference's per-pixel
/// sample deviation of one ray's luminance, `√(n · Var(mean))` from its squared sums. `None` with
/// fewer than three pixels to compare or sizes that do not match.
pub fn prediction_check(predicted: &[f64], reference: &TruthEstimate) -> Option<PredictionCheck> {
    let img = reference.image();
    let w = img.width;
    if predicted.len() != img.pixels.len() {
        return None;
    }
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for (i, (sd, px)) in predicted.iter().zip(&img.pixels).enumerate() {
        let n = f64::from(px[3]);
        let measured = (reference.pixel(i as u32 % w, i as u32 / w).var_mean_y * n).sqrt();
        if n >= 2.0 && *sd > 0.0 && sd.is_finite() && measured > 0.0 && measured.is_finite() {
            a.push(*sd);
            b.push(measured);
        }
    }
    if a.len() < 3 {
        return None;
    }
    let mut ratios: Vec<f64> = a.iter().zip(&b).map(|(p, m)| p / m).collect();
    ratios.sort_by(f64::total_cmp);
    let log = |v: &[f64]| v.iter().map(|x| x.ln()).collect::<Vec<_>>();
    let (best, model) = allocation_gains(predicted, reference).unwrap_or((f64::NAN, f64::NAN));
    Some(PredictionCheck {
        pixels: a.len(),
        rank_correlation: spearman(&a, &b),
        log_correlation: pearson(&log(&a), &log(&b)),
        median_ratio: ratios[ratios.len() / 2],
        best_allocation_gain: best,
        predicted_allocation_gain: model,
    })
}

/// Every budget any configuration ran, ascending.
fn budgets(configs: &[(String, &[UniformPoint], &[AdaptiveResult])]) -> Vec<f64> {
    let mut b: Vec<f64> = configs
        .iter()
        .flat_map(|c| c.2.iter().map(|a| a.budget))
        .collect();
    b.sort_by(f64::total_cmp);
    b.dedup();
    b
}

/// The Markdown section: per configuration and budget, the uniform rays at equal error and the
/// gains; then the averages per strategy and budget.
pub fn markdown(configs: &[(String, &[UniformPoint], &[AdaptiveResult])]) -> String {
    let mut s = String::new();
    if configs.iter().all(|c| c.2.is_empty()) {
        return s;
    }
    let _ = writeln!(
        s,
        "## Adaptive ground truth\n\nRMSE against the true image (the reference's noise \
         accounted per pixel), rays a pixel on average, the uniform rays a pixel that reach the same \
         error, and the gains in rays and in time (the model's CPU prediction included).\n"
    );
    let _ = writeln!(
        s,
        "| configuration | strategy | budget | rays/px | shaded | RMSE | uniform rays at equal RMSE | ray gain | time gain |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    for (name, uniform, adaptive) in configs {
        for a in adaptive.iter() {
            let _ = writeln!(
                s,
                "| {name} | {} | {} | {:.1} | {:.0}% | {:.4} | {:.1} | {:.2} | {:.2} |",
                a.strategy,
                a.budget,
                a.rays_per_pixel,
                100.0 * a.shaded_fraction,
                a.rmse_true,
                a.uniform_rays_equal,
                a.ray_gain(),
                a.time_gain(uniform)
            );
        }
    }
    let _ = writeln!(
        s,
        "\nGeometric means over the configurations:\n\n| strategy | budget | ray gain | time gain |\n|---|---|---|---|"
    );
    for (strategy, _) in STRATEGIES {
        for b in budgets(configs) {
            let (mut rg, mut tg, mut n) = (0.0, 0.0, 0.0);
            for (_, uniform, adaptive) in configs {
                for a in adaptive
                    .iter()
                    .filter(|a| a.strategy == strategy && a.budget == b)
                {
                    let (r, t) = (a.ray_gain(), a.time_gain(uniform));
                    if r > 0.0 && t > 0.0 && r.is_finite() && t.is_finite() {
                        rg += r.ln();
                        tg += t.ln();
                        n += 1.0;
                    }
                }
            }
            if n > 0.0 {
                let _ = writeln!(
                    s,
                    "| {strategy} | {b} | {:.2} | {:.2} |",
                    (rg / n).exp(),
                    (tg / n).exp()
                );
            }
        }
    }
    s.push('\n');
    s
}

/// Error against rays per pixel (log–log), averaged over the configurations: the uniform curve
/// and one curve per strategy.
pub fn chart(
    preset: &str,
    configs: &[(String, &[UniformPoint], &[AdaptiveResult])],
) -> Option<(Chart, Vec<Series>)> {
    let n = configs.len() as f64;
    if configs.iter().all(|c| c.2.is_empty()) {
        return None;
    }
    let mut spps: Vec<u32> = configs
        .iter()
        .flat_map(|c| c.1.iter().map(|u| u.spp))
        .collect();
    spps.sort_unstable();
    spps.dedup();
    let uniform: Vec<(f64, f64)> = spps
        .iter()
        .map(|s| {
            let e = configs
                .iter()
                .filter_map(|c| c.1.iter().find(|u| u.spp == *s))
                .map(|u| u.rmse_true)
                .sum::<f64>()
                / n;
            (f64::from(*s), e)
        })
        .collect();
    let mut series = vec![("uniform".to_owned(), "#555555", uniform, true)];
    for (i, (strategy, _)) in STRATEGIES.iter().enumerate() {
        let pts: Vec<(f64, f64)> = budgets(configs)
            .iter()
            .map(|b| {
                let hits: Vec<&AdaptiveResult> = configs
                    .iter()
                    .flat_map(|c| c.2.iter())
                    .filter(|a| a.strategy == *strategy && a.budget == *b)
                    .collect();
                let k = hits.len().max(1) as f64;
                (
                    hits.iter().map(|a| a.rays_per_pixel).sum::<f64>() / k,
                    hits.iter().map(|a| a.rmse_true).sum::<f64>() / k,
                )
            })
            .collect();
        series.push((
            format!("adaptive, {strategy}"),
            [
                "#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf",
            ][i % 6],
            pts,
            true,
        ));
    }
    Some((
        Chart {
            title: format!("{preset}: ground truth error against rays, uniform and adaptive"),
            x_label: "rays per pixel (log)".into(),
            y_label: "RMSE against the true image (log)".into(),
            log_x: true,
            log_y: true,
        },
        series,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve() -> Vec<UniformPoint> {
        [1u32, 4, 16, 64]
            .iter()
            .map(|n| UniformPoint {
                spp: *n,
                rmse_true: 0.2 / f64::from(*n).sqrt(),
                ms: 2.0 * f64::from(*n),
            })
            .collect()
    }

    /// On an exact 1/√n curve, interpolation and extrapolation both invert it.
    #[test]
    fn equal_error_rays_invert_the_uniform_curve() {
        let u = curve();
        for n in [0.5, 1.0, 2.0, 10.0, 64.0, 300.0] {
            let e = 0.2 / f64::sqrt(n);
            let got = uniform_rays_at(&u, e);
            assert!((got / n - 1.0).abs() < 1e-9, "{n}: {got}");
        }
        assert!(uniform_rays_at(&u, 0.0).is_nan());
        assert!(uniform_rays_at(&[], 0.1).is_nan());
        let a = AdaptiveResult {
            strategy: "x".into(),
            budget: 4.0,
            rays_per_pixel: 4.0,
            shaded_fraction: 1.0,
            rmse_true: 0.2 / 32f64.sqrt(),
            uniform_rays_equal: uniform_rays_at(&u, 0.2 / 32f64.sqrt()),
            ms: 6.0,
            predict_ms: 2.0,
        };
        assert!((a.ray_gain() - 8.0).abs() < 1e-9);
        // Uniform: 2 ms a ray, 32 rays = 64 ms, against 8 ms.
        assert!((a.time_gain(&u) - 8.0).abs() < 1e-9);
    }

    /// Grey pixels of 4 rays with per-ray deviations `sds` (sums 4·0.5, squared sums 3s² +
    /// 4·0.25), then one pixel of one ray: a truth image and its squared sums.
    fn grey_pixels(sds: &[f64]) -> (LinearImage, lodestone_render::truth_noise::SampleMoments) {
        let mut pixels: Vec<[f32; 4]> = vec![[2.0, 2.0, 2.0, 4.0]; sds.len()];
        let mut sum_sq: Vec<[f32; 4]> = sds
            .iter()
            .map(|s| [(3.0 * s * s + 1.0) as f32; 4])
            .collect();
        pixels.push([0.5, 0.5, 0.5, 1.0]);
        sum_sq.push([0.25; 4]);
        let width = sds.len() as u32 + 1;
        (
            LinearImage {
                width,
                height: 1,
                pixels,
            },
            lodestone_render::truth_noise::SampleMoments {
                width,
                height: 1,
                sum_sq,
            },
        )
    }

    #[test]
    fn the_prediction_check_ranks_and_scales() {
        // Deviations 0.1–0.4, predicted twice those in the same order, and one pixel with one
        // ray (left out).
        let (img, moments) = grey_pixels(&[0.1, 0.2, 0.3, 0.4]);
        let est = TruthEstimate::new(&img, &moments).unwrap();
        let predicted = [0.2, 0.4, 0.6, 0.8, 1.0];
        let c = prediction_check(&predicted, &est).unwrap();
        assert_eq!(c.pixels, 4);
        assert!((c.rank_correlation - 1.0).abs() < 1e-12, "{c:?}");
        assert!((c.log_correlation - 1.0).abs() < 1e-6, "{c:?}");
        assert!((c.median_ratio - 2.0).abs() < 1e-3, "{c:?}");
        // Reversed order: rank correlation −1.
        let reversed = [0.8, 0.6, 0.4, 0.2, 1.0];
        let c = prediction_check(&reversed, &est).unwrap();
        assert!((c.rank_correlation + 1.0).abs() < 1e-12, "{c:?}");
        assert!(prediction_check(&predicted[..3], &est).is_none());
    }

    /// The allocation gains on pixels of known per-ray variances: equal deviations gain nothing;
    /// deviations 0.1–0.4 (one pixel of one ray left out) give Neyman's `P Σ s²/(Σ s)²` exactly,
    /// here ×3 for the three channels in both sums: 4·0.3/1 = 1.2; and a perfect prediction
    /// gains less than the best by its defensive share, a flat one nothing.
    #[test]
    fn allocation_gains_follow_neyman() {
        let (img, moments) = grey_pixels(&[0.2; 4]);
        let flat = TruthEstimate::new(&img, &moments).unwrap();
        let (best, model) = allocation_gains(&[0.2, 0.2, 0.2, 0.2, 0.0], &flat).unwrap();
        assert!(
            (best - 1.0).abs() < 1e-4 && (model - 1.0).abs() < 1e-4,
            "{best} {model}"
        );
        let (img, moments) = grey_pixels(&[0.1, 0.2, 0.3, 0.4]);
        let est = TruthEstimate::new(&img, &moments).unwrap();
        let (best, model) = allocation_gains(&[0.1, 0.2, 0.3, 0.4, 0.0], &est).unwrap();
        assert!((best - 1.2).abs() < 1e-3, "{best}");
        assert!(model > 1.0 && model < best, "{model}");
        // The model's weights s + ½·mean(s), the fifth pixel's 0 in the mean:
        let mean = 1.0 / 5.0;
        let w: Vec<f64> = [0.1, 0.2, 0.3, 0.4]
            .iter()
            .map(|s| s + 0.5 * mean)
            .collect();
        let s2: Vec<f64> = [0.1f64, 0.2, 0.3, 0.4].iter().map(|s| s * s).collect();
        let expect = 4.0 * s2.iter().sum::<f64>()
            / (w.iter().sum::<f64>() * s2.iter().zip(&w).map(|(a, b)| a / b).sum::<f64>());
        assert!((model - expect).abs() < 1e-3, "{model} {expect}");
        let (_, none) = allocation_gains(&[0.3; 5], &est).unwrap();
        assert!((none - 1.0).abs() < 1e-4, "{none}");
        assert!(allocation_gains(&[0.1; 3], &est).is_none());
    }
}
