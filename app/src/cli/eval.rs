//! `lodestone eval`: the CPU reference evaluation of a far patch under every method.

use crate::cli::Context;
use crate::cli::args;
use crate::preset_io::Resolved;
use anyhow::Result;
use lodestone_core::eval::FootprintQuery;
use lodestone_core::scene::direction::direction;
use serde::Serialize;

/// The arguments of `lodestone eval`.
#[derive(Debug, Clone, clap::Args)]
pub struct EvalArgs {
    /// View angle from the normal, degrees (0 to 89.5).
    #[arg(long, default_value_t = 0.0, value_parser = args::view_angle)]
    pub view_deg: f64,
    /// View azimuth, degrees.
    #[arg(long, default_value_t = 0.0, value_parser = args::azimuth)]
    pub view_azimuth_deg: f64,
    /// Light angle from the normal, degrees (0 to 180; past 90 the sun is below the horizon).
    #[arg(long, default_value_t = 0.0, value_parser = args::light_angle)]
    pub light_deg: f64,
    /// Light azimuth, degrees.
    #[arg(long, default_value_t = 0.0, value_parser = args::azimuth)]
    pub light_azimuth_deg: f64,
    /// Ground-truth samples (eye rays) for the patch (2 to 10⁸: its standard error needs two).
    #[arg(long, default_value_t = 40_000, value_parser = args::eval_samples)]
    pub spp: usize,
    /// The filtered model's masking of the visible slopes, overriding the preset's: Smith's
    /// (height alone), or conditioned on the facet's height and slope along the ray jointly
    /// (the default; noise drivers).
    #[arg(long, value_enum)]
    pub slope_masking: Option<args::SlopeMaskingArg>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Evaluate the far patch and print the table (or JSON).
pub fn run(args: EvalArgs, ctx: &Context) -> Result<()> {
    let mut preset = ctx.preset.clone();
    if let Some(sm) = args.slope_masking {
        preset.material.filtering.slope_masking = sm.into();
    }
    let r = eval(
        &preset,
        [
            args.view_deg,
            args.view_azimuth_deg,
            args.light_deg,
            args.light_azimuth_deg,
        ],
        args.spp,
    )?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        out!("{}", table(&r));
    }
    Ok(())
}

/// The result of `eval`, also its JSON form.
#[derive(Debug, Serialize)]
pub struct EvalReport {
    /// Material name.
    pub material: String,
    /// View angle (degrees from the normal).
    pub view_deg: f64,
    /// View azimuth (degrees).
    pub view_azimuth_deg: f64,
    /// Light angle (degrees from the normal).
    pub light_deg: f64,
    /// Light azimuth (degrees).
    pub light_azimuth_deg: f64,
    /// Naive MIP: colour map of the filtered driver, filtered normal.
    pub naive: [f64; 3],
    /// View-independent texture filtering.
    pub view_independent: [f64; 3],
    /// The filtered model.
    pub filtered: [f64; 3],
    /// Ground truth mean.
    pub ground_truth: [f64; 3],
    /// Ground truth standard error.
    pub ground_truth_std_error: [f64; 3],
    /// Ground truth samples.
    pub samples: usize,
    /// Rays before a glint as bright as the lobe's peak, carrying 1% of the mean, would have shown
    /// with 95% confidence (`Evaluator::glint_rays`); fewer samples may have missed the specular
    /// part, whatever the standard error says.
    pub glint_rays: f64,
    /// Largest per-channel relative error against ground truth, per method.
    pub relative_error: RelativeErrors,
}

/// Largest per-channel relative error of each method against ground truth.
#[derive(Debug, Serialize)]
pub struct RelativeErrors {
    /// Naive MIP.
    pub naive: f64,
    /// View-independent filtering.
    pub view_independent: f64,
    /// Filtered model.
    pub filtered: f64,
}

/// Evaluate the far patch.
pub fn eval(preset: &Resolved, angles: [f64; 4], samples: usize) -> Result<EvalReport> {
    let material = &preset.material;
    let [view_deg, view_azimuth_deg, light_deg, light_azimuth_deg] = angles;
    let prepared = preset.prepare()?;
    let wo = direction(
        view_deg.clamp(0.0, 89.5).to_radians(),
        view_azimuth_deg.to_radians(),
    );
    let wi = direction(
        light_deg.clamp(0.0, 90.0).to_radians(),
        light_azimuth_deg.to_radians(),
    );
    let cfg = FootprintQuery::far(&prepared, wo, wi);
    let gt = prepared.ground_truth(&cfg, samples, 1);
    let (naive, vi, filtered) = (
        prepared.naive(&cfg),
        prepared.view_independent(&cfg),
        prepared.filtered(&cfg),
    );
    let rel = |v: [f64; 3]| {
        (0..3)
            .map(|k| (v[k] - gt.mean[k]).abs() / gt.mean[k].abs().max(1e-12))
            .fold(0.0, f64::max)
    };
    Ok(EvalReport {
        material: material.name.clone(),
        view_deg,
        view_azimuth_deg,
        light_deg,
        light_azimuth_deg,
        naive,
        view_independent: vi,
        filtered,
        ground_truth: gt.mean,
        ground_truth_std_error: gt.std_error,
        samples: gt.samples,
        glint_rays: prepared.glint_rays(&cfg, gt.mean, 0.01),
        relative_error: RelativeErrors {
            naive: rel(naive),
            view_independent: rel(vi),
            filtered: rel(filtered),
        },
    })
}

/// A human-readable table.
pub fn table(r: &EvalReport) -> String {
    let c = |v: [f64; 3]| format!("{:>8.5} {:>8.5} {:>8.5}", v[0], v[1], v[2]);
    let glints = if (r.samples as f64) < r.glint_rays {
        format!(
            "warning: the specular lobe's peak needs {} rays before a glint carrying 1% would have shown; \
             with {} the truth may lack its glints (raise --spp)\n",
            if r.glint_rays.is_finite() {
                format!("{:.0}", r.glint_rays.ceil())
            } else {
                "unboundedly many".to_string()
            },
            r.samples
        )
    } else {
        String::new()
    };
    let table = format!(
        "{} — view {}° (azimuth {}°), light {}° (azimuth {}°), {} ground-truth samples\n\
         method              R        G        B   max rel. error\n\
         naive MIP        {}   {:>6.2}%\n\
         view-independent {}   {:>6.2}%\n\
         filtered         {}   {:>6.2}%\n\
         ground truth     {}\n\
         ± std. error     {}\n",
        r.material,
        r.view_deg,
        r.view_azimuth_deg,
        r.light_deg,
        r.light_azimuth_deg,
        r.samples,
        c(r.naive),
        100.0 * r.relative_error.naive,
        c(r.view_independent),
        100.0 * r.relative_error.view_independent,
        c(r.filtered),
        100.0 * r.relative_error.filtered,
        c(r.ground_truth),
        c(r.ground_truth_std_error),
    );
    table + &glints
}
