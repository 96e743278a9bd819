//! Adaptive ground truth on the GPU (#18 §1, [BSSBH13 Secs. 2.4, 3]): core predicts each pixel's
//! expected value and one ray's deviation ([`TruthPrediction`]), core's [`SamplingPlan`] decides
//! which pixels are shaded and with how many rays, [`Renderer::draw_planned`] traces exactly those
//! rays, and the image is reconstructed with the prediction as its guide.
//!
//! Two passes: a quarter of the budget on the a priori plan (the lattice, the pixels it cannot
//! interpolate, rays in proportion to the predicted deviation), then the a posteriori refinement
//! ([`SamplingPlan::refine`]: cells whose measured residual from the prediction is not smooth,
//! or where the realisation pooled over the neighbouring cells makes interpolating cost more than
//! shading, are shaded whole) with the rest, the corners' noise from their rays' own sample
//! variance pooled with the prediction ([`pixel_deviations`]). Uniform sampling is
//! `Renderer::draw` with the same total.

use crate::truth_noise::{SampleMoments, TruthEstimate};
use crate::{LinearImage, RenderError, Renderer, Scene, ViewTarget};
use lodestone_core::adaptive::sampling_plan::SamplingPlan;
use lodestone_core::adaptive::truth_prediction::TruthPrediction;
use lodestone_core::adaptive::windows::{
    WindowOptions, WindowReconstruction, WindowSample, reconstruct,
};
use lodestone_core::math::water_fill::water_fill;

/// The uniform share of an adaptive plan's allocation: rays go in proportion to
/// `σ̂ + DEFENSIVE·mean(σ̂)` (a defensive mixture, Hesterberg 1995), so no pixel gets less than
/// `DEFENSIVE/(1 + DEFENSIVE)` of the average however low its prediction.
pub const DEFENSIVE: f64 = 0.5;

/// How an adaptive ground truth spends its rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveOptions {
    /// Rays per pixel on average over the image (the budget).
    pub rays_per_pixel: f64,
    /// Lattice step in pixels: 1 shades every pixel (ray counts only), 2 or 4 also interpolates.
    pub step: usize,
    /// The most rays any one pixel gets (a pixel the prediction calls very noisy cannot take the
    /// whole budget).
    pub max_rays: u32,
}

/// An adaptive ground truth.
#[derive(Clone, Debug)]
pub struct AdaptiveTruth {
    /// The reconstructed image (weight 1 everywhere).
    pub image: LinearImage,
    /// The final plan: rays per pixel (0 where interpolated).
    pub plan: SamplingPlan,
}

impl AdaptiveTruth {
    /// Rays traced per pixel on average.
    pub fn rays_per_pixel(&self) -> f64 {
        self.plan.total_rays() as f64 / (self.plan.width * self.plan.height).max(1) as f64
    }
}

/// Render an adaptive ground truth of `scene` (the view `prediction` was made for, same size as
/// `target`) into `target` (overwritten) and reconstruct it.
pub fn render_adaptive(
    renderer: &Renderer,
    target: &mut ViewTarget,
    material: &crate::GpuMaterial,
    scene: &Scene,
    prediction: &TruthPrediction,
    opts: AdaptiveOptions,
) -> Result<AdaptiveTruth, RenderError> {
    let (w, h) = target.size();
    let (w, h) = (w as usize, h as usize);
    let guide = prediction.luminance();
    // Defensive mixture: rays in proportion to σ̂ + DEFENSIVE·mean(σ̂), so a pixel whose deviation
    // the model underestimates (a glint it calls shadowed) still gets a third of the average.
    let covered: Vec<f64> = prediction.sd.iter().copied().filter(|s| *s > 0.0).collect();
    let mean_sd = covered.iter().sum::<f64>() / covered.len().max(1) as f64;
    let sd: &Vec<f64> = &prediction
        .sd
        .iter()
        .map(|s| s + DEFENSIVE * mean_sd)
        .collect();
    target.reset();
    let first = SamplingPlan::new(
        w,
        h,
        &guide,
        sd,
        opts.rays_per_pixel / 4.0,
        opts.step,
        opts.max_rays,
    );
    renderer.draw_planned(target, material, scene, &first.rays);
    let traced = target.read(renderer)?;
    let est: Vec<f64> = luminance(&traced);
    // The refinement weighs each corner's residual against its noise: the rays' own sample
    // variance where they measured one, pooled with the prediction (as the progressive plan's).
    let measured = luminance_variances(&traced, &target.read_moments(renderer)?);
    let dev = pixel_deviations(sd, &measured);
    let plan = first.refine(&est, &dev, &guide, opts.rays_per_pixel, opts.max_rays);
    renderer.draw_planned(target, material, scene, &plan.rays);
    let shaded = target.read(renderer)?;
    let channels: Vec<Vec<f64>> = (0..3)
        .map(|k| {
            let values: Vec<f64> = (0..w * h).map(|p| rgb(&shaded, p)[k]).collect();
            plan.reconstruct(&values, Some(&prediction.channel(k)))
        })
        .collect();
    let image = LinearImage {
        width: w as u32,
        height: h as u32,
        pixels: (0..w * h)
            .map(|p| {
                let c = [0, 1, 2].map(|k| channels[k][p] as f32);
                [c[0], c[1], c[2], 1.0]
            })
            .collect(),
    };
    Ok(AdaptiveTruth { image, plan })
}

/// Pixel `p`'s linear RGB (divided by its weight; 0 where it has none).
fn rgb(img: &LinearImage, p: usize) -> [f64; 3] {
    let w = img.width.max(1) as usize;
    img.rgb((p % w) as u32, (p / w) as u32).map(f64::from)
}

/// Rec. 709 luminance per pixel.
fn luminance(img: &LinearImage) -> Vec<f64> {
    let n = (img.width * img.height) as usize;
    (0..n)
        .map(|p| crate::truth_noise::luminance(rgb(img, p)))
        .collect()
}

/// How many rays the prediction is worth when a pixel's deviation is estimated from its own rays
/// too ([`pixel_deviations`]): a pixel with `n` rays weighs its sample variance by `n − 1` against
/// the predicted one's `PRIOR_RAYS`, so two or three rays that happen to agree do not starve it.
pub const PRIOR_RAYS: f64 = 4.0;

/// Each pixel's deviation of one ray's luminance for allocating the next rays of a progressive
/// adaptive ground truth: the prediction `predicted` (per pixel, as
/// [`TruthPrediction::sd`]) pooled with what the pixel's own rays measured so far
/// (`measured[p] = (n, s²)`, the sample variance of its `n` rays' luminance),
/// `s_p² = (PRIOR_RAYS·σ̂_p² + (n − 1)·s²)/(PRIOR_RAYS + n − 1)` for `n ≥ 2`, the prediction
/// alone below. Non-finite or negative inputs count as 0; `measured` shorter than `predicted`
/// leaves the rest on the prediction.
pub fn pixel_deviations(predicted: &[f64], measured: &[(u32, f64)]) -> Vec<f64> {
    let clean = |v: f64| if v.is_finite() && v > 0.0 { v } else { 0.0 };
    predicted
        .iter()
        .enumerate()
        .map(|(p, &sd)| {
            let prior = clean(sd).powi(2);
            match measured.get(p) {
                Some(&(n, var)) if n >= 2 => {
                    let k = f64::from(n) - 1.0;
                    ((PRIOR_RAYS * prior + k * clean(var)) / (PRIOR_RAYS + k)).sqrt()
                }
                _ => prior.sqrt(),
            }
        })
        .collect()
}

/// Ray targets for the next round of a progressive adaptive ground truth: `mean_rays` rays per
/// pixel on average over the image, in proportion to `deviation + DEFENSIVE·mean(deviation)·
/// PRIOR_RAYS/(PRIOR_RAYS + n − 1)` with `n` the rays the pixel has (Neyman allocation
/// [BSSBH13 Sec. 2.4], with the defensive mixture of [`render_adaptive`], which fades as the
/// pixel's own rays replace the prediction in [`pixel_deviations`]),
/// divided by `√(cost/mean cost)` where `cost` (one ray's cost per pixel) is given: for a time
/// budget `Σ c_p n_p` the error `Σ σ_p²/n_p` is least at `n_p ∝ σ_p/√c_p` (an empty or short
/// `cost`, or an entry that is not finite and positive, counts as the mean of the known ones),
/// never fewer than a pixel has (`current`) nor than one, never more than `max_rays` (unless it
/// has them already). The total is `mean_rays × pixels` rounded, or what the floors force beyond
/// it; what the caps leave over goes to the others (water filling). Empty input gives an empty
/// plan; non-finite deviations count as 0.
pub fn progressive_counts(
    deviation: &[f64],
    cost: &[f64],
    current: &[u32],
    mean_rays: f64,
    max_rays: u32,
) -> Vec<u32> {
    let n = deviation.len();
    if n == 0 {
        return Vec::new();
    }
    let dev: Vec<f64> = deviation
        .iter()
        .map(|v| if v.is_finite() && *v > 0.0 { *v } else { 0.0 })
        .collect();
    let mean_dev = dev.iter().sum::<f64>() / n as f64;
    // All deviations 0 (or unknown): uniform.
    // The defensive share guards against a wrong prediction; as a pixel's own rays take over its
    // deviation (pixel_deviations: the prediction weighs PRIOR_RAYS against n − 1), it shrinks
    // in the same proportion, so sky and flat shadow stop taking a third of the average.
    let mut weight: Vec<f64> = if mean_dev > 0.0 {
        dev.iter()
            .enumerate()
            .map(|(p, d)| {
                let n = f64::from(current.get(p).copied().unwrap_or(0).max(1));
                d + DEFENSIVE * mean_dev * PRIOR_RAYS / (PRIOR_RAYS + n - 1.0)
            })
            .collect()
    } else {
        vec![1.0; n]
    };
    let known: Vec<f64> = cost
        .iter()
        .copied()
        .filter(|c| c.is_finite() && *c > 0.0)
        .collect();
    if !known.is_empty() {
        let mean_cost = known.iter().sum::<f64>() / known.len() as f64;
        for (p, w) in weight.iter_mut().enumerate() {
            let c = cost
                .get(p)
                .copied()
                .filter(|c| c.is_finite() && *c > 0.0)
                .unwrap_or(mean_cost);
            *w /= (c / mean_cost).sqrt();
        }
    }
    let floor: Vec<f64> = (0..n)
        .map(|p| f64::from(current.get(p).copied().unwrap_or(0).max(1)))
        .collect();
    let cap = vec![f64::from(max_rays.max(1)); n];
    let mean = if mean_rays.is_finite() {
        mean_rays.max(0.0)
    } else {
        0.0
    };
    water_fill(&weight, &floor, &cap, mean * n as f64)
}

/// Per pixel of a truth image and its squared sums: (rays, sample variance of their luminance),
/// the measurement [`pixel_deviations`] pools with the prediction.
/// ([`TruthEstimate::pixel`]'s variance of the mean times n; 0 below two rays, and for sizes
/// that do not match.)
pub fn luminance_variances(image: &LinearImage, moments: &SampleMoments) -> Vec<(u32, f64)> {
    let Some(est) = TruthEstimate::new(image, moments) else {
        return Vec::new();
    };
    let w = image.width.max(1);
    image
        .pixels
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let n = f64::from(p[3]).max(0.0);
            let v = est.pixel(i as u32 % w, i as u32 / w).var_mean_y * n;
            (n as u32, if v.is_finite() { v } else { 0.0 })
        })
        .collect()
}

/// One more ray's cost per pixel, `1 + work/rays` (one unit for the ray's setup and shading),
/// from a target's work ([`ViewTarget::read_work`]) and the rays each pixel has: what the
/// cost-aware plan weighs, and the editor's cost map.
pub fn ray_costs(work: &[u32], rays: &[u32]) -> Vec<f64> {
    work.iter()
        .zip(rays)
        .map(|(w, n)| 1.0 + f64::from(*w) / f64::from((*n).max(1)))
        .collect()
}

/// A ground truth (`image`, its squared sums `moments`) reconstructed over windows chosen per pixel
/// by the intersection of confidence intervals
/// ([`lodestone_core::adaptive::windows`], [BSSBH13 Sec. 3]): each pixel's value pools the rays
/// of the least noisy window around it whose mean stays within its noise. One ray's variance per pixel
/// is its measured sample variance pooled with the prediction `predicted` ([`pixel_deviations`];
/// a `predicted` of the wrong size counts as 0, which shrinks the measured variance and so the
/// windows). `guide`, the predicted luminance per pixel, refuses windows it predicts biased
/// ([`lodestone_core::adaptive::windows::reconstruct`]). Returns the image (weight 1) and the
/// windows.
pub fn reconstruct_truth(
    image: &LinearImage,
    moments: &SampleMoments,
    predicted: &[f64],
    guide: Option<&[f64]>,
    options: WindowOptions,
) -> (LinearImage, WindowReconstruction) {
    let n = (image.width as usize) * (image.height as usize);
    let predicted = if predicted.len() == n {
        predicted.to_vec()
    } else {
        vec![0.0; n]
    };
    let deviation = pixel_deviations(&predicted, &luminance_variances(image, moments));
    let samples: Vec<WindowSample> = (0..n.min(image.pixels.len()))
        .map(|p| WindowSample {
            rays: f64::from(image.pixels[p][3]),
            mean: rgb(image, p),
            ray_var: deviation[p] * deviation[p],
        })
        .collect();
    let r = reconstruct(
        image.width as usize,
        image.height as usize,
        &samples,
        guide,
        options,
    );
    let out = LinearImage {
        width: image.width,
        height: image.height,
        pixels: r
            .rgb
            .iter()
            .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, 1.0])
            .collect(),
    };
    (out, r)
}

/// What a progressive adaptive ground truth plans with ([`render_progressive`]).
#[derive(Clone, Copy, Debug)]
pub struct Progressive<'a> {
    /// One ray's predicted luminance deviation per pixel ([`TruthPrediction::sd`]).
    pub predicted: &'a [f64],
    /// Rays per pixel on average at the end.
    pub rays_per_pixel: f64,
    /// The most rays any one pixel gets.
    pub max_rays: u32,
    /// Weigh each pixel's share by `1/√(its cost per ray)` as measured by the rays so far
    /// ([`ViewTarget::read_work`]): the least error for the time rather than for the rays.
    pub cost_aware: bool,
}

/// Render a progressive adaptive ground truth into `target` (reset first): rounds of doubling
/// budgets, 1, 2, 4, … up to `plan.rays_per_pixel` rays per pixel on average, each giving the
/// pixels rays by [`progressive_counts`] (at most `plan.max_rays` each) from `plan.predicted`
/// pooled with what each pixel's rays measured by the
/// round's start ([`pixel_deviations`]). A round is traced in steps of about one ray per pixel;
/// after each, `on_step(target, rays, round_end)` may look at the target and returns whether to
/// go on. Returns the rays per pixel traced.
///
/// Unlike [`render_adaptive`]'s two passes, every pixel is shaded (no lattice: on noise-limited
/// images interpolation lost, docs/design/adaptive-truth.md), and the plan learns from each round, so a pixel
/// whose noise the model missed catches up at the next.
pub fn render_progressive(
    renderer: &Renderer,
    target: &mut ViewTarget,
    material: &crate::GpuMaterial,
    scene: &Scene,
    plan: Progressive,
    mut on_step: impl FnMut(&ViewTarget, &[u32], bool) -> Result<bool, RenderError>,
) -> Result<Vec<u32>, RenderError> {
    let (w, h) = target.size();
    let n = (w as usize) * (h as usize);
    target.reset();
    let goal_rpp = if plan.rays_per_pixel.is_finite() {
        plan.rays_per_pixel.max(1.0)
    } else {
        1.0
    };
    let mut have = vec![0_u32; n];
    let mut measured: Vec<(u32, f64)> = Vec::new();
    let mut cost: Vec<f64> = Vec::new();
    let mut budget = 1.0_f64.min(goal_rpp);
    loop {
        let goal = progressive_counts(
            &pixel_deviations(plan.predicted, &measured),
            &cost,
            &have,
            budget,
            plan.max_rays,
        );
        let extra: u64 = goal
            .iter()
            .zip(&have)
            .map(|(g, h)| u64::from(g.saturating_sub(*h)))
            .sum();
        let steps = extra.div_ceil(n.max(1) as u64).max(1);
        let start = have.clone();
        for step in 1..=steps {
            for (p, h) in have.iter_mut().enumerate() {
                let add = u64::from(goal[p].saturating_sub(start[p]));
                *h = start[p] + (add * step).div_ceil(steps) as u32;
            }
            renderer.draw_planned(target, material, scene, &have);
            if !on_step(target, &have, step == steps)? {
                return Ok(have);
            }
        }
        if budget >= goal_rpp {
            return Ok(have);
        }
        measured = luminance_variances(&target.read(renderer)?, &target.read_moments(renderer)?);
        if plan.cost_aware {
            cost = ray_costs(&target.read_work(renderer)?, &have);
        }
        budget = (budget * 2.0).min(goal_rpp);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_follow_the_deviation_and_spend_the_budget() {
        // Deviations 1 and 3 (mean 2): weights 2 and 4, so 16 rays a pixel on average go 2:4.
        let dev = [1.0, 3.0, 1.0, 3.0];
        let c = progressive_counts(&dev, &[], &[0; 4], 16.0, 1000);
        assert_eq!(c.iter().sum::<u32>(), 64);
        assert!(c[0].abs_diff(11) <= 1 && c[1].abs_diff(21) <= 1, "{c:?}");
        // Equal deviations (or none known) are uniform.
        assert_eq!(
            progressive_counts(&[0.5; 6], &[], &[0; 6], 4.0, 100),
            vec![4; 6]
        );
        assert_eq!(
            progressive_counts(&[0.0; 3], &[], &[0; 3], 2.0, 100),
            vec![2; 3]
        );
    }

    #[test]
    fn costly_pixels_get_fewer_rays_by_the_square_root() {
        // Equal deviations, one pixel four times as costly: half the rays of the others
        // (n ∝ σ/√c); unknown costs count as the mean of the known ones.
        let c = progressive_counts(&[1.0; 4], &[4.0, 1.0, 1.0], &[0; 4], 14.0, 1000);
        assert_eq!(c.iter().sum::<u32>(), 56);
        let mean_cost: f64 = 2.0;
        let w = [
            1.0 / (4.0 / mean_cost).sqrt(),
            1.0 / (1.0 / mean_cost).sqrt(),
            1.0 / (1.0 / mean_cost).sqrt(),
            1.0,
        ];
        let sum: f64 = w.iter().sum();
        for (got, w) in c.iter().zip(w) {
            assert!((f64::from(*got) - 56.0 * w / sum).abs() <= 1.0, "{c:?}");
        }
    }

    #[test]
    fn the_defensive_share_fades_with_a_pixels_own_rays() {
        // Pixel 0 is quiet (deviation 0) and has 4 rays: its defensive weight is
        // 0.5·0.75·4/7 = 0.21 against 0.375 before it had any, so it gets about 5 of 100 rays
        // instead of 8.
        let c = progressive_counts(&[0.0, 1.0, 1.0, 1.0], &[], &[4, 1, 1, 1], 25.0, 1000);
        assert_eq!(c.iter().sum::<u32>(), 100);
        assert!((4..=6).contains(&c[0]), "{c:?}");
        let fresh = progressive_counts(&[0.0, 1.0, 1.0, 1.0], &[], &[0; 4], 25.0, 1000);
        assert!((7..=9).contains(&fresh[0]), "{fresh:?}");
    }

    #[test]
    fn counts_respect_floors_and_caps() {
        // One pixel far noisier than the rest is capped; the rays it cannot take go elsewhere.
        let mut dev = vec![0.1; 10];
        dev[3] = 100.0;
        let c = progressive_counts(&dev, &[], &[0; 10], 8.0, 20);
        assert_eq!(c[3], 20);
        assert_eq!(c.iter().sum::<u32>(), 80);
        assert!(c.iter().all(|&r| r >= 1));
        // A pixel never loses rays it has, and every pixel gets one.
        let cur = [9, 0, 0, 0];
        let c = progressive_counts(&[0.0, 1.0, 1.0, 1.0], &[], &cur, 2.0, 100);
        assert!(c[0] >= 9 && c.iter().all(|&r| r >= 1), "{c:?}");
        // The floors may exceed the budget: then they are the plan.
        assert_eq!(
            progressive_counts(&[1.0; 2], &[], &[5, 7], 1.0, 100),
            vec![5, 7]
        );
    }

    #[test]
    fn hostile_inputs_still_give_a_plan() {
        assert!(progressive_counts(&[], &[], &[], 4.0, 10).is_empty());
        let c = progressive_counts(
            &[f64::NAN, f64::INFINITY, -1.0, 1.0],
            &[f64::NAN, -1.0],
            &[],
            f64::NAN,
            0,
        );
        assert_eq!(c, vec![1; 4]);
        let c = progressive_counts(&[1.0, 2.0], &[], &[], f64::INFINITY, 1 << 20);
        assert_eq!(c, vec![1, 1]);
        let c = progressive_counts(&[1e300, 1e-300], &[1e300, 1e-300], &[], 1e6, u32::MAX);
        assert!(c.iter().all(|&r| r >= 1));
    }

    #[test]
    fn measured_variances_and_costs_per_pixel() {
        // Pixel 0: two grey rays of luminance 0 and 1 (s² = 0.5); pixel 1: one ray (unknown: 0).
        let image = LinearImage {
            width: 2,
            height: 1,
            pixels: vec![[1.0, 1.0, 1.0, 2.0], [0.5, 0.5, 0.5, 1.0]],
        };
        let moments = SampleMoments {
            width: 2,
            height: 1,
            sum_sq: vec![[1.0; 4], [0.25; 4]],
        };
        let v = luminance_variances(&image, &moments);
        assert_eq!((v[0].0, v[1]), (2, (1, 0.0)));
        assert!((v[0].1 - 0.5).abs() < 1e-6, "{v:?}");
        assert_eq!(ray_costs(&[30, 0, 7], &[3, 0, 1]), vec![11.0, 1.0, 8.0]);
    }

    #[test]
    fn deviations_pool_prediction_and_measurement() {
        // No rays yet, or one: the prediction.
        assert_eq!(pixel_deviations(&[0.3, 0.4], &[(1, 9.0)]), vec![0.3, 0.4]);
        // Many rays: the measurement dominates; PRIOR_RAYS + 1 rays weigh them evenly.
        let d = pixel_deviations(&[0.0], &[(10_001, 4.0)]);
        assert!((d[0] - 2.0).abs() < 1e-3, "{d:?}");
        let d = pixel_deviations(&[1.0], &[(PRIOR_RAYS as u32 + 1, 9.0)]);
        assert!((d[0] - 5.0_f64.sqrt()).abs() < 1e-12);
        // Hostile values count as 0.
        let d = pixel_deviations(&[f64::NAN, -2.0], &[(5, f64::INFINITY), (0, 1.0)]);
        assert_eq!(d, vec![0.0, 0.0]);
    }
}
