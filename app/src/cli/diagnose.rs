//! `lodestone diagnose`: which term carries the filtered model's error [#17 item 1]. The far
//! patch of `eval`, for the material and for variants with one term switched off in both the
//! model and the ground truth (the same edit to the material, so both see it): the diffuse term
//! alone (specular 0), the specular lobe alone (albedo 0), the diffuse term in a constant grey
//! (colour model, slope and constant colour terms removed: masking, shadowing and the clamped
//! cosine without any colour), and under the sun alone or the environment alone where there is
//! one. Radiance is linear in the albedo and the specular weight, so the diffuse and specular
//! rows' absolute errors add up to the full one; each row's share is its truth over the full
//! truth.
//!
//! The truth is sampled in batches until its relative standard error is below `precision` and
//! enough rays were cast for the sharpest glint to have shown (`Evaluator::converged_truth`), or `max_samples` is
//! reached: glints make it noisy (the bumpy-specular preset needs ~10⁶ rays for 2%), and an
//! error within three standard errors is not an error.

use crate::cli::Context;
use crate::cli::args;
use crate::preset_io::Resolved;
use anyhow::Result;
use lodestone_core::eval::FootprintQuery;
use lodestone_core::material::color_terms::ColorTerms;
use lodestone_core::material::{ColorModel, Material};
use lodestone_core::scene::direction::direction;
use serde::Serialize;

/// The arguments of `lodestone diagnose`.
#[derive(Debug, Clone, clap::Args)]
pub struct DiagnoseArgs {
    /// View angles from the normal, degrees (0 to 89.5), comma-separated.
    #[arg(long, default_value = "0,45,75", value_delimiter = ',', value_parser = args::view_angle)]
    pub view_deg: Vec<f64>,
    /// Light angles from the normal, degrees (0 to 180), comma-separated.
    #[arg(long, default_value = "0,30", value_delimiter = ',', value_parser = args::light_angle)]
    pub light_deg: Vec<f64>,
    /// Light azimuths, degrees (the view's is 0: 0 puts the light on the viewer's side, 180
    /// opposite), comma-separated.
    #[arg(long, default_value = "0,180", value_delimiter = ',', value_parser = args::azimuth)]
    pub light_azimuth_deg: Vec<f64>,
    /// Sample the truth until its relative standard error is below this (0.0001 to 0.5).
    #[arg(long, default_value_t = 0.005, value_parser = args::precision)]
    pub precision: f64,
    /// At most this many ground-truth rays per variant and configuration (2 to 10⁸).
    #[arg(long, default_value_t = 2_000_000, value_parser = args::eval_samples)]
    pub max_spp: usize,
    /// Only the material itself, no variants (an accuracy grid over many configurations).
    #[arg(long)]
    pub full_only: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Diagnose the material over the grid and print the table (or JSON).
pub fn run(args: DiagnoseArgs, ctx: &Context) -> Result<()> {
    let preset = &ctx.preset;
    let rows = diagnose(
        preset,
        &Grid {
            views: &args.view_deg,
            lights: &args.light_deg,
            azimuths: &args.light_azimuth_deg,
        },
        args.precision,
        args.max_spp,
        args.full_only,
    )?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        out!("{}", table(&preset.material.name, &rows));
    }
    Ok(())
}

/// One variant at one configuration.
#[derive(Debug, Serialize)]
pub struct Row {
    /// The variant ("full", "diffuse only", …).
    pub variant: String,
    /// View angle from the normal (degrees).
    pub view_deg: f64,
    /// Light angle from the normal (degrees).
    pub light_deg: f64,
    /// Light azimuth (degrees; the view's is 0).
    pub light_azimuth_deg: f64,
    /// The filtered model.
    pub filtered: [f64; 3],
    /// Ground-truth mean.
    pub truth: [f64; 3],
    /// Its standard error.
    pub std_error: [f64; 3],
    /// (filtered − truth) / full truth, per channel: the variant's part of the full error (for
    /// the variants that are a part of the full material: not the grey one).
    pub error_of_full: Option<[f64; 3]>,
    /// (filtered − truth) / truth, per channel.
    pub relative_error: [f64; 3],
    /// The variant's truth over the full material's truth (mean over channels).
    pub share: f64,
    /// Ground-truth rays.
    pub samples: usize,
    /// The prototype mixture model's relative error where it applies (diffuse, sun, colour map:
    /// [`lodestone_core::eval::Evaluator::filtered_mixture`]).
    pub mixture_error: Option<[f64; 3]>,
    /// Whether |filtered − truth| exceeds three standard errors in some channel.
    pub significant: bool,
}

/// The variants of `m` that switch one term off (those that change something).
pub fn variants(m: &Material) -> Vec<(&'static str, Material)> {
    let mut out = vec![("full", m.clone())];
    // A measured BRDF has no diffuse/specular split to switch off (its table replaces albedo and
    // specular): only its colour and lighting are varied.
    let measured = m.brdf.measured.is_some();
    if m.brdf.specular > 0.0 && !measured {
        let mut d = m.clone();
        d.brdf.specular = 0.0;
        out.push(("diffuse only", d.clone()));
        let mut s = m.clone();
        s.brdf.albedo = 0.0;
        out.push(("specular only", s));
    }
    let mut grey = m.clone();
    grey.brdf.specular = 0.0;
    grey.color = ColorModel::Attribute {
        mean: [0.5; 3],
        correlation: [0.0; 3],
    };
    grey.terms = ColorTerms::default();
    out.push((if measured { "grey" } else { "diffuse, grey" }, grey));
    if m.lighting.environment.is_some() && m.lighting.sun > 0.0 {
        let mut sun = m.clone();
        sun.lighting.environment = None;
        out.push(("sun only", sun));
        let mut env = m.clone();
        env.lighting.sun = 0.0;
        out.push(("environment only", env));
    }
    out
}

/// The configurations: every combination of view angle, light angle and light azimuth (degrees;
/// the view's azimuth is 0).
#[derive(Clone, Copy, Debug)]
pub struct Grid<'a> {
    /// View angles from the normal.
    pub views: &'a [f64],
    /// Light angles from the normal.
    pub lights: &'a [f64],
    /// Light azimuths.
    pub azimuths: &'a [f64],
}

/// Diagnose the far patch at every configuration of `grid` (only the material itself with
/// `full_only`).
pub fn diagnose(
    preset: &Resolved,
    grid: &Grid,
    precision: f64,
    max_samples: usize,
    full_only: bool,
) -> Result<Vec<Row>> {
    let Grid {
        views,
        lights,
        azimuths,
    } = *grid;
    let mut rows = vec![];
    let prepared: Vec<_> = variants(&preset.material)
        .into_iter()
        .take(if full_only { 1 } else { usize::MAX })
        .map(|(name, material)| {
            let r = Resolved {
                material,
                ..preset.clone()
            };
            r.prepare().map(|p| (name, p))
        })
        .collect::<Result<_, _>>()?;
    for &view_deg in views {
        for &light_deg in lights {
            for &light_azimuth_deg in azimuths {
                let wo = direction(view_deg.to_radians(), 0.0);
                let wi = direction(light_deg.to_radians(), light_azimuth_deg.to_radians());
                let mut full = [0.0; 3];
                for (name, p) in &prepared {
                    let cfg = FootprintQuery::far(p, wo, wi);
                    let gt = p.converged_truth(&cfg, precision, max_samples);
                    let fi = p.filtered(&cfg);
                    if *name == "full" {
                        full = gt.mean;
                    }
                    let of = |v: f64, d: f64| if d.abs() > 0.0 { v / d } else { 0.0 };
                    rows.push(Row {
                        variant: (*name).to_string(),
                        view_deg,
                        light_deg,
                        light_azimuth_deg,
                        filtered: fi,
                        truth: gt.mean,
                        std_error: gt.std_error,
                        error_of_full: (*name != "diffuse, grey")
                            .then(|| [0, 1, 2].map(|k| of(fi[k] - gt.mean[k], full[k]))),
                        relative_error: [0, 1, 2].map(|k| of(fi[k] - gt.mean[k], gt.mean[k])),
                        share: (0..3).map(|k| of(gt.mean[k], full[k])).sum::<f64>() / 3.0,
                        samples: gt.samples,
                        mixture_error: p
                            .filtered_mixture(&cfg)
                            .map(|v| [0, 1, 2].map(|k| of(v[k] - gt.mean[k], gt.mean[k]))),
                        significant: (0..3)
                            .any(|k| (fi[k] - gt.mean[k]).abs() > 3.0 * gt.std_error[k]),
                    });
                }
            }
        }
    }
    Ok(rows)
}

/// The rows as a table: per configuration, each variant's error relative to itself and as a part
/// of the full truth, with the truth's standard error; `*` marks errors beyond three standard
/// errors, "—" a relative error of a variant whose truth is under 1% of the full one.
pub fn table(material: &str, rows: &[Row]) -> String {
    let pct = |v: [f64; 3]| {
        format!(
            "{:+6.2} {:+6.2} {:+6.2}",
            100.0 * v[0],
            100.0 * v[1],
            100.0 * v[2]
        )
    };
    let mut s = format!(
        "{material}: filtered − truth per channel (R G B, %), far patch; * beyond 3 s.e.\n\
         {:<5} {:<13} {:<16} {:>6} {:>21} {:>21} {:>7} {:>8}  {:>21}\n",
        "view",
        "light",
        "variant",
        "share",
        "of itself",
        "of the full truth",
        "s.e.%",
        "rays",
        "mixture (prototype)"
    );
    for r in rows {
        let se = (0..3)
            .map(|k| 100.0 * r.std_error[k] / r.truth[k].abs().max(1e-12))
            .fold(0.0f64, f64::max);
        let itself = if r.share < 0.01 {
            "—".to_string()
        } else {
            pct(r.relative_error)
        };
        let of_full = r.error_of_full.map_or_else(|| "—".to_string(), pct);
        // Under the same rule as `itself`: relative to a truth near 0 it is noise.
        let mixture = match r.mixture_error {
            Some(_) if r.share < 0.01 => "—".to_string(),
            m => m.map_or_else(String::new, pct),
        };
        s += &format!(
            "{:<5} {:<13} {:<16} {:>5.0}% {:>21} {:>21} {:>7.2} {:>8}{:2} {:>21}\n",
            format!("{}°", r.view_deg),
            format!("{}° az {}°", r.light_deg, r.light_azimuth_deg),
            r.variant,
            100.0 * r.share,
            itself,
            of_full,
            se,
            r.samples,
            if r.significant { " *" } else { "" },
            mixture
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The variants do what they say, and the diffuse and specular rows' errors add up to the
    /// full one (radiance is linear in albedo and specular weight, in the model and the truth).
    #[test]
    fn diffuse_and_specular_errors_add_up_to_the_full_error() {
        let m = lodestone_core::material::Material {
            brdf: lodestone_core::microfacet::brdf::BaseBrdf {
                albedo: 1.0,
                specular: 0.3,
                roughness: 0.1,
                measured: None,
            },
            ..lodestone_core::material::Material::default()
        };
        let names: Vec<_> = variants(&m).into_iter().map(|(n, _)| n).collect();
        assert_eq!(
            names,
            ["full", "diffuse only", "specular only", "diffuse, grey"]
        );
        let preset = Resolved::without_image(m);
        let grid = Grid {
            views: &[45.0],
            lights: &[30.0],
            azimuths: &[0.0],
        };
        let rows = diagnose(&preset, &grid, 1.0, 4000, false).expect("diagnose");
        assert_eq!(
            diagnose(&preset, &grid, 1.0, 4000, true)
                .expect("diagnose")
                .len(),
            1,
            "--full-only: the material alone"
        );
        let get = |n: &str| rows.iter().find(|r| r.variant == n).expect(n);
        let (full, d, s) = (get("full"), get("diffuse only"), get("specular only"));
        for k in 0..3 {
            // Same rays (same seed, same geometry): the sums agree to rounding.
            assert!((d.truth[k] + s.truth[k] - full.truth[k]).abs() < 1e-9 * full.truth[k]);
            assert!((d.filtered[k] + s.filtered[k] - full.filtered[k]).abs() < 1e-9);
            let sum = d.error_of_full.unwrap()[k] + s.error_of_full.unwrap()[k];
            assert!((sum - (full.filtered[k] - full.truth[k]) / full.truth[k]).abs() < 1e-9);
        }
        assert!((d.share + s.share - 1.0).abs() < 1e-9);
    }

    /// A variant whose truth is near 0 (the specular with the lobe out of reach) prints a dash for
    /// its relative errors, the prototype's included, instead of a ratio to noise (it printed
    /// 10¹³⁴%); a variant with a share prints both.
    #[test]
    fn relative_errors_of_a_vanishing_truth_print_a_dash() {
        let row = |share: f64| Row {
            variant: "specular only".into(),
            view_deg: 75.0,
            light_deg: 60.0,
            light_azimuth_deg: 0.0,
            filtered: [1e-3; 3],
            truth: [1e-300; 3],
            std_error: [0.0; 3],
            error_of_full: Some([0.0; 3]),
            relative_error: [1e297; 3],
            share,
            samples: 10,
            mixture_error: Some([2e297; 3]),
            significant: true,
        };
        let t = table("m", &[row(0.0)]);
        let last = t.lines().last().unwrap();
        assert!(!last.contains("e29") && !last.contains("000000"), "{last}");
        assert_eq!(last.matches('—').count(), 2, "{last}");
        let shown = table(
            "m",
            &[Row {
                relative_error: [0.01; 3],
                mixture_error: Some([0.02; 3]),
                ..row(0.5)
            }],
        );
        let last = shown.lines().last().unwrap();
        assert!(last.contains("+1.00") && last.contains("+2.00"), "{last}");
    }
}
