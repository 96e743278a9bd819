//! `lodestone report`: error against run time for one preset. Over view/light configurations and
//! zoom levels it renders naive MIP, view-independent filtering, the filtered model with the paper's
//! fits and uncorrelated masking, the filtered model with exact tables and correlated masking, and
//! ground truth at 1…256 rays per pixel, each against a ground-truth reference (1024 rays per pixel by
//! default), and reports RMSE (linear RGB), mean and 95th-percentile ΔE*ab and the time per frame.
//!
//! Honesty notes, also written into the report:
//! * Ground truth at N rays is the first N rays of the reference's own low-discrepancy sequence, so
//!   its RMSE against the reference is its noise with the reference's shared part removed,
//!   `σ·√(1/N − 1/R)` for R reference rays (×0.87 at N = R/4).
//! * The reference's own noise is `RMSE(first R/2 rays, all R)`, which estimates `σ/√R` exactly for
//!   independent rays.
//! * Every method's RMSE is also given with the reference's noise taken out (`rmse_beyond_noise`,
//!   from the reference's per-pixel squared sums: `lodestone_render::truth_noise`), with its range
//!   for ±2 standard errors. Its ray-to-ray variance overestimates the noise of a low-discrepancy
//!   mean, so the figure errs low, by the same amount for every method.
//! * Times are synchronised wall times (submit, then wait for the device), medians of `repeats` runs;
//!   timestamp queries are not used. On the software adapter they are CPU times.

pub mod adaptive;
pub mod chart;
pub mod cielab;

mod output;
use crate::preset_io::Resolved;
use crate::report::adaptive::{
    ADAPTIVE_RPP, AdaptiveResult, PredictionCheck, STRATEGIES, Strategy, UniformPoint,
    prediction_check, rmse_true, uniform_rays_at,
};
use crate::report::chart::{Chart, Series};
use crate::report::cielab::delta_e76;
use anyhow::{Context, Result};
use glam::DVec3;
use lodestone_core::adaptive::sampling_plan::SamplingPlan;
use lodestone_core::adaptive::windows::WindowOptions;
use lodestone_core::microfacet::effective_height::HeightFilter;
use lodestone_core::microfacet::masking_shadowing::Correlation;
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::shape::Shape;
use lodestone_render::adaptive_truth::{
    AdaptiveOptions, AdaptiveTruth, Progressive, reconstruct_truth, render_adaptive,
    render_progressive,
};
use lodestone_render::truth_noise::{BlockErrors, TruthEstimate};
use lodestone_render::{
    GpuContext, GpuMaterial, LinearImage, Renderer, Scene, ViewMode, ViewTarget,
};
pub use output::{markdown, write};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// What to measure.
#[derive(Clone, Debug)]
pub struct Options {
    /// Image size of every rendering.
    pub size: (u32, u32),
    /// Rays per pixel of the reference.
    pub reference_spp: u32,
    /// View angles from the normal (degrees).
    pub views: Vec<f64>,
    /// Camera distances (zoom levels).
    pub zooms: Vec<f64>,
    /// Timing repeats (median).
    pub repeats: u32,
    /// How every march steps and refines (the fast march, or the reference for comparison).
    pub march: lodestone_core::scene::march::March,
    /// Ray budgets of the adaptive ground truth (rays per pixel on average; empty: none).
    pub adaptive: Vec<f64>,
    /// Trace cut ground-truth rays again alone (`Renderer::set_retry_cut`).
    pub retry_cut_rays: bool,
    /// The object every configuration views.
    pub shape: Shape,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            size: (64, 40),
            reference_spp: 1024,
            views: vec![0.0, 30.0, 60.0, 75.0, 85.0, 89.0],
            zooms: vec![1.5, 6.0, 40.0],
            repeats: 5,
            march: lodestone_core::scene::march::March::Fast,
            adaptive: ADAPTIVE_RPP.to_vec(),
            retry_cut_rays: false,
            shape: Shape::Plane,
        }
    }
}

/// One method in one configuration.
#[derive(Clone, Debug, Serialize)]
pub struct MethodResult {
    /// Method name.
    pub method: String,
    /// Rays per pixel (ground truth only).
    pub spp: Option<u32>,
    /// RMSE against the reference, linear RGB.
    pub rmse: f64,
    /// RMSE with the reference's own Monte Carlo noise taken out, per pixel
    /// (`lodestone_render::truth_noise`: `√max(mean(d² − Var(ref)), 0)`, the reference's variance
    /// from its per-pixel squared sums).
    pub rmse_beyond_noise: f64,
    /// [`rmse_beyond_noise`](Self::rmse_beyond_noise)'s range for ±2 standard errors.
    pub rmse_beyond_noise_range: (f64, f64),
    /// Mean ΔE*ab over the pixels that are not black in both.
    pub delta_e_mean: f64,
    /// 95th percentile of ΔE*ab.
    pub delta_e_p95: f64,
    /// Time per frame (ms), synchronised wall time, median.
    pub ms: f64,
}

/// One view/light/zoom configuration.
#[derive(Clone, Debug, Serialize)]
pub struct ConfigResult {
    /// Camera distance.
    pub distance: f64,
    /// View angle from the normal (degrees).
    pub view_deg: f64,
    /// Light: "normal", "view" or "opposite".
    pub light: String,
    /// RMSE of the reference's own noise (see the module docs).
    pub reference_noise: f64,
    /// Rays of the reference whose loops the adapter cut (`ViewTarget::cut_count`; 0 on real
    /// GPUs and with `retry_cut_rays`, bar rays that need more than the limit alone).
    pub reference_cut_rays: u32,
    /// Every method.
    pub methods: Vec<MethodResult>,
    /// Uniform ground truth's error against the true image per ray count.
    pub uniform: Vec<UniformPoint>,
    /// Adaptive ground truth per strategy and budget.
    pub adaptive: Vec<AdaptiveResult>,
    /// The model's predicted deviation of one ray against the reference's measured one (with
    /// adaptive ground truth; `None` without, or with too few pixels).
    pub prediction: Option<PredictionCheck>,
}

/// The report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Preset name.
    pub preset: String,
    /// The adapter.
    pub adapter: String,
    /// How times were taken.
    pub timing: String,
    /// Image size.
    pub size: (u32, u32),
    /// Reference rays per pixel.
    pub reference_spp: u32,
    /// The object viewed: "plane" or "cylinder of radius R".
    pub object: String,
    /// The configurations.
    pub configs: Vec<ConfigResult>,
}

/// Ground-truth sample counts compared against the reference.
pub const TRUTH_SPP: [u32; 5] = [1, 4, 16, 64, 256];

fn errors(img: &LinearImage, reference: &LinearImage) -> (f64, f64, f64) {
    let (w, h) = (reference.width, reference.height);
    let (mut sq, mut n) = (0.0, 0.0);
    let mut de = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let a = img.rgb(x, y).map(f64::from);
            let b = reference.rgb(x, y).map(f64::from);
            for k in 0..3 {
                sq += (a[k] - b[k]).powi(2);
            }
            n += 3.0;
            if a != [0.0; 3] || b != [0.0; 3] {
                de.push(delta_e76(a, b));
            }
        }
    }
    de.sort_by(f64::total_cmp);
    let mean = if de.is_empty() {
        0.0
    } else {
        de.iter().sum::<f64>() / de.len() as f64
    };
    let p95 = de
        .get(((de.len() as f64 * 0.95) as usize).min(de.len().saturating_sub(1)))
        .copied()
        .unwrap_or(0.0);
    ((sq / n).sqrt(), mean, p95)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { 0.0 } else { v[v.len() / 2] }
}

fn timed(r: &Renderer, f: impl FnOnce()) -> f64 {
    let t = Instant::now();
    f();
    r.wait();
    t.elapsed().as_secs_f64() * 1e3
}

/// Run the report with a progress bar on stderr.
pub fn run(preset: &Resolved, opts: &Options) -> Result<Report> {
    let r = run_with(
        preset,
        opts,
        &|done, total, c| {
            let width = 30;
            let filled = done * width / total.max(1);
            eprint!(
                "\r[{}{}] {done}/{total}: distance {}, view {}°, light {}        ",
                "#".repeat(filled),
                "-".repeat(width - filled),
                c.distance,
                c.view_deg,
                c.light
            );
        },
        &|| false,
    );
    eprintln!();
    r
}

/// Why a report stopped early.
#[derive(Debug, thiserror::Error)]
#[error("the report was cancelled")]
pub struct Cancelled;

/// Run the report; `progress(done, total, finished configuration)` after each configuration,
/// `cancel()` checked between configurations and between truth passes (returns [`Cancelled`]).
pub fn run_with(
    preset: &Resolved,
    opts: &Options,
    progress: &dyn Fn(usize, usize, &ConfigResult),
    cancel: &dyn Fn() -> bool,
) -> Result<Report> {
    let ctx = GpuContext::new_headless()?;
    let adapter = ctx.describe();
    let mut r = Renderer::new(ctx);
    r.set_retry_cut(opts.retry_cut_rays);
    let mut exact = preset.material.clone();
    exact.filtering.height_filter = HeightFilter::Exact;
    exact.filtering.correlation = Correlation::HeightDirection;
    let mut paper = preset.material.clone();
    paper.filtering.height_filter = HeightFilter::PaperFit;
    paper.filtering.correlation = Correlation::Uncorrelated;
    let prepare = |m: &lodestone_core::material::Material| {
        crate::preset_io::Resolved {
            material: m.clone(),
            ..preset.clone()
        }
        .prepare()
        .map(|mut e| {
            e.surface.march = opts.march;
            e
        })
    };
    let (p_exact, p_paper) = (prepare(&exact)?, prepare(&paper)?);
    let target = [0.3, 0.7];
    let gm_exact = GpuMaterial::new(r.context(), &p_exact, target)?;
    let gm_paper = GpuMaterial::new(r.context(), &p_paper, target)?;
    let total = opts.zooms.len() * opts.views.len() * 3;
    let mut configs = Vec::new();
    let mut done = 0;
    let ref_spp = opts.reference_spp.max(2);
    for &distance in &opts.zooms {
        for &view in &opts.views {
            for light_name in ["normal", "view", "opposite"] {
                if cancel() {
                    return Err(Cancelled.into());
                }
                done += 1;
                let light = match light_name {
                    "normal" => DVec3::Z,
                    "view" => direction(view.to_radians(), 0.0),
                    _ => direction(view.to_radians(), std::f64::consts::PI),
                };
                let scene = Scene {
                    camera: Camera {
                        elevation_deg: view,
                        azimuth_deg: 0.0,
                        distance,
                        target,
                        fov_deg: 30.0,
                    },
                    light,
                    shape: opts.shape,
                };
                // Ground truth: one progressive accumulation gives every N and the reference.
                let mut milestones: Vec<u32> =
                    TRUTH_SPP.iter().copied().filter(|n| *n < ref_spp).collect();
                milestones.push(ref_spp / 2);
                milestones.push(ref_spp);
                milestones.sort_unstable();
                milestones.dedup();
                let mut tgt = ViewTarget::new(&r, opts.size.0, opts.size.1)?;
                let mut truth = Vec::new();
                let mut frame_ms = Vec::new();
                let mut have = 0;
                for n in milestones {
                    if cancel() {
                        return Err(Cancelled.into());
                    }
                    let add = n - have;
                    let ms = timed(&r, || {
                        r.draw(&mut tgt, &gm_exact, &scene, ViewMode::Truth, add)
                    });
                    frame_ms.push(ms / f64::from(add));
                    have = n;
                    truth.push((n, tgt.read(&r)?));
                }
                let reference = &truth.last().expect("reference").1;
                let reference_moments = tgt.read_moments(&r)?;
                let reference_cut_rays = tgt.cut_count(&r)?;
                tgt.warn_if_cut(&r, ViewMode::Truth);
                let reference_est = TruthEstimate::new(reference, &reference_moments)
                    .context("the reference's squared sums do not match its image")?;
                let beyond_noise = |img: &LinearImage| {
                    BlockErrors::new(img, &reference_est, 1)
                        .map_or((f64::NAN, (f64::NAN, f64::NAN)), |b| {
                            (b.rmse(), b.rmse_range(2.0))
                        })
                };
                let half = &truth
                    .iter()
                    .find(|(n, _)| *n == ref_spp / 2)
                    .expect("half")
                    .1;
                let reference_noise = errors(half, reference).0;
                let ray_ms = median(frame_ms);
                let mut methods = Vec::new();
                for (name, mode, gm) in [
                    ("naive MIP", ViewMode::Naive, &gm_exact),
                    ("view-independent", ViewMode::ViewIndependent, &gm_exact),
                    (
                        "filtered (paper fits, uncorrelated)",
                        ViewMode::Filtered,
                        &gm_paper,
                    ),
                    (
                        "filtered (exact, correlated)",
                        ViewMode::Filtered,
                        &gm_exact,
                    ),
                ] {
                    let mut img = None;
                    let mut times = Vec::new();
                    for _ in 0..opts.repeats.max(1) {
                        let mut t = ViewTarget::new(&r, opts.size.0, opts.size.1)?;
                        times.push(timed(&r, || r.draw(&mut t, gm, &scene, mode, 1)));
                        img = Some(t.read(&r)?);
                    }
                    let img = img.as_ref().expect("rendered");
                    let (rmse, de, p95) = errors(img, reference);
                    let (rmse_beyond_noise, rmse_beyond_noise_range) = beyond_noise(img);
                    methods.push(MethodResult {
                        method: name.into(),
                        spp: None,
                        rmse,
                        rmse_beyond_noise,
                        rmse_beyond_noise_range,
                        delta_e_mean: de,
                        delta_e_p95: p95,
                        ms: median(times),
                    });
                }
                for (n, img) in &truth {
                    if !TRUTH_SPP.contains(n) || *n >= ref_spp {
                        continue;
                    }
                    let (rmse, de, p95) = errors(img, reference);
                    let (rmse_beyond_noise, rmse_beyond_noise_range) = beyond_noise(img);
                    methods.push(MethodResult {
                        method: format!("ground truth {n} spp"),
                        spp: Some(*n),
                        rmse,
                        rmse_beyond_noise,
                        rmse_beyond_noise_range,
                        delta_e_mean: de,
                        delta_e_p95: p95,
                        ms: ray_ms * f64::from(*n),
                    });
                }
                let uniform: Vec<UniformPoint> = truth
                    .iter()
                    .filter(|(n, _)| TRUTH_SPP.contains(n) && *n < ref_spp)
                    .map(|(n, img)| UniformPoint {
                        spp: *n,
                        rmse_true: rmse_true(img, &reference_est, &|_| 1.0),
                        ms: ray_ms * f64::from(*n),
                    })
                    .collect();
                let (adaptive, prediction) = if opts.adaptive.is_empty() {
                    (Vec::new(), None)
                } else {
                    adaptive_truth(
                        &r,
                        &p_exact,
                        &gm_exact,
                        &scene,
                        opts,
                        &reference_est,
                        &uniform,
                    )?
                };
                let c = ConfigResult {
                    distance,
                    view_deg: view,
                    light: light_name.into(),
                    reference_noise,
                    reference_cut_rays,
                    methods,
                    uniform,
                    adaptive,
                    prediction,
                };
                progress(done, total, &c);
                configs.push(c);
            }
        }
    }
    Ok(Report {
        preset: preset.material.name.clone(),
        adapter,
        timing: format!(
            "synchronised wall time (submit + wait), median of {} runs; no timestamp queries",
            opts.repeats.max(1)
        ),
        size: opts.size,
        reference_spp: ref_spp,
        object: match opts.shape {
            Shape::Plane => "plane".into(),
            Shape::Cylinder { radius } => format!("cylinder of radius {radius}"),
        },
        configs,
    })
}

/// The adaptive ground truth of one configuration at every budget and strategy of `opts`.
fn adaptive_truth(
    r: &Renderer,
    evaluator: &lodestone_core::eval::Evaluator,
    gm: &GpuMaterial,
    scene: &Scene,
    opts: &Options,
    reference: &TruthEstimate,
    uniform: &[UniformPoint],
) -> Result<(Vec<AdaptiveResult>, Option<PredictionCheck>)> {
    let t = Instant::now();
    let prediction = evaluator.predict_truth_of(scene.shape, &scene.camera, opts.size, scene.light);
    let predict_ms = t.elapsed().as_secs_f64() * 1e3;
    let guide = prediction.luminance();
    let check = prediction_check(&prediction.sd, reference);
    let mut out = Vec::new();
    let mut tgt = ViewTarget::new(r, opts.size.0, opts.size.1)?;
    let (size_w, size_h) = (opts.size.0 as usize, opts.size.1 as usize);
    // At most half the reference's rays a pixel, so every shaded pixel is a prefix of it.
    let max_rays = opts.reference_spp.max(2) / 2;
    for &budget in &opts.adaptive {
        let progressive = |cost_aware: bool, tgt: &mut ViewTarget| {
            let plan = Progressive {
                predicted: &prediction.sd,
                rays_per_pixel: budget,
                max_rays,
                cost_aware,
            };
            render_progressive(r, tgt, gm, scene, plan, |_, _, _| Ok(true))
        };
        for (strategy, how) in STRATEGIES {
            // One run, as the uniform truth's milestones: its passes are long enough to time once.
            let t = Instant::now();
            let (a, own): (AdaptiveTruth, Vec<f64>) = match how {
                Strategy::TwoPass(step) => {
                    let a_opts = AdaptiveOptions {
                        rays_per_pixel: budget,
                        step,
                        max_rays,
                    };
                    let a = render_adaptive(r, &mut tgt, gm, scene, &prediction, a_opts)?;
                    let own = a
                        .plan
                        .rays
                        .iter()
                        .map(|n| f64::from(u8::from(*n > 0)))
                        .collect();
                    (a, own)
                }
                Strategy::Progressive { cost_aware } => {
                    let rays = progressive(cost_aware, &mut tgt)?;
                    let own = vec![1.0; rays.len()];
                    let plan = SamplingPlan {
                        width: size_w,
                        height: size_h,
                        step: 1,
                        rays,
                    };
                    (
                        AdaptiveTruth {
                            image: tgt.read(r)?,
                            plan,
                        },
                        own,
                    )
                }
                Strategy::Reconstructed {
                    progressive: prog,
                    guided,
                } => {
                    let rays = if prog {
                        progressive(false, &mut tgt)?
                    } else {
                        let rays = vec![
                            (budget.round() as u32).clamp(1, max_rays.max(1));
                            size_w * size_h
                        ];
                        tgt.reset();
                        r.draw_planned(&mut tgt, gm, scene, &rays);
                        rays
                    };
                    let (image, windows) = reconstruct_truth(
                        &tgt.read(r)?,
                        &tgt.read_moments(r)?,
                        &prediction.sd,
                        guided.then_some(guide.as_slice()),
                        WindowOptions::default(),
                    );
                    let plan = SamplingPlan {
                        width: size_w,
                        height: size_h,
                        step: 1,
                        rays,
                    };
                    (AdaptiveTruth { image, plan }, windows.own_weight)
                }
            };
            let ms = t.elapsed().as_secs_f64() * 1e3;
            let err = rmse_true(&a.image, reference, &|p| own.get(p).copied().unwrap_or(0.0));
            out.push(AdaptiveResult {
                strategy: strategy.into(),
                budget,
                rays_per_pixel: a.rays_per_pixel(),
                shaded_fraction: a.plan.rays.iter().filter(|r| **r > 0).count() as f64
                    / a.plan.rays.len().max(1) as f64,
                rmse_true: err,
                uniform_rays_equal: uniform_rays_at(uniform, err),
                ms,
                predict_ms,
            });
        }
    }
    Ok((out, check))
}
