//! Adaptive ground truth on the GPU (#18 §1, [BSSBH13 Secs. 2.4, 3]): core predicts each pixel's
//! expected value and one ray's deviation ([`TruthPrediction`]), core's [`SamplingPlan`] decides
//! which pixels are shaded and with how many rays, [`Renderer::draw_planned`] traces exactly those
//! rays, and the image is reconstructed with the prediction as its guide.
//!
//! Two passes: a quarter of the budget on the a priori plan (the lattice, the pixels it cannot
//! interpolate, rays in proportion to the predicted deviation), then the a posteriori refinement
//! ([`SamplingPlan::refine`]: cells whose measured residual from the prediction is not smooth are
//! shaded whole) with the rest. Uniform sampling is `Renderer::draw` with the same total.

use crate::{LinearImage, RenderError, Renderer, Scene, ViewTarget};
use lodestone_core::eval::sampling_plan::SamplingPlan;
use lodestone_core::eval::truth_prediction::TruthPrediction;

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
    let cap = |mut plan: SamplingPlan| {
        for r in &mut plan.rays {
            *r = (*r).min(opts.max_rays.max(1));
        }
        plan
    };
    target.reset();
    let first = cap(SamplingPlan::new(
        w,
        h,
        &guide,
        sd,
        opts.rays_per_pixel / 4.0,
        opts.step,
    ));
    renderer.draw_planned(target, material, scene, &first.rays);
    let est: Vec<f64> = luminance(&target.read(renderer)?);
    let plan = cap(first.refine(&est, sd, &guide, opts.rays_per_pixel));
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
