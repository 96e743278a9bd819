//! `lodestone stability`: core's stiff and extreme cases (f64 and the f32 mirror, see
//! [`crate::cli::stability::cases`]) plus the same cases through the WGSL on the GPU adapter.
//!
//! WGSL rows: the special functions on the same arguments (bound 1e-5·(1 + κ) relative, κ the
//! condition number, [`crate::cli::stability::cases::f32_deviation`]: WGSL lets
//! `exp`/`log` be off by a few ULP more than Rust's), and every material case rendered far away
//! (8×8 pixels, camera at the listed angles from the normal plus 60°, every mode, the ground truth
//! with 1 ray where core traces it too, [`stability::truth_traceable`]): non-finite or negative pixels
//! are failures; the deviation is the fraction of pixels
//! below 89.9° whose analytic value differs from core's evaluation of that pixel by more than
//! 0.5% + 2e-4 (bound 2%: f32 against f64 rays may cross a shadow edge differently).
//! `RUST_LOG=lodestone=debug` logs every failing WGSL pixel.

pub mod cases;
pub mod inputs;
pub mod materials;
pub mod row;

use crate::cli::Context;
use crate::cli::stability::cases::SpecialFunction;
use crate::cli::stability::materials::{self as stability, material_cases};
use crate::cli::stability::row::{Path, Row};
use anyhow::Result;
use glam::DVec2;
use lodestone_core::eval::{Evaluator, Method};
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::shape::Shape;
use lodestone_render::{GpuContext, GpuMaterial, Renderer, Scene, ViewMode, compute, shaders};

/// The arguments of `lodestone stability`.
#[derive(Debug, Clone, clap::Args)]
pub struct StabilityArgs {
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Only core's f64 and f32 rows (without it, no GPU adapter is exit code 3: the WGSL rows
    /// did not run).
    #[arg(long)]
    pub cpu_only: bool,
}

/// Run every case and print the table (or JSON); exit code 1 when a row fails.
pub fn run_command(args: StabilityArgs, _ctx: &Context) -> Result<()> {
    run(args.json, args.cpu_only)
}

fn wgsl_special_rows(ctx: &GpuContext) -> Vec<Row> {
    SpecialFunction::ALL
        .iter()
        .map(|&function| {
            let name = function.name();
            let xs = function.inputs();
            let xf: Vec<f32> = xs.iter().map(|x| *x as f32).collect();
            let got = compute::eval_unary(ctx, shaders::SPECIAL, name, &xf);
            let (mut dev, mut bad) = (0.0f64, 0);
            for (g, xs32) in got.iter().zip(&xf) {
                let g = f64::from(*g);
                if !g.is_finite() {
                    bad += 1;
                }
                dev = dev.max(crate::cli::stability::cases::f32_deviation(
                    function, *xs32, g,
                ));
            }
            Row {
                case: format!("{name} at {} extreme arguments", xs.len()),
                path: Path::Wgsl,
                outputs: xs.len(),
                max_deviation: dev,
                bound: 1e-5,
                non_finite: bad,
                reference: "quadrature at the f32 argument (relative / (1 + condition number))"
                    .into(),
            }
        })
        .collect()
}

fn wgsl_material_rows(r: &Renderer) -> Vec<Row> {
    let (w, h) = (8u32, 8u32);
    let mut degs: Vec<f64> = stability::angles().iter().map(|a| a.to_degrees()).collect();
    degs.push(60.0);
    let light = direction(0.7, 2.0);
    material_cases()
        .into_iter()
        .map(|case| {
            let p = match Evaluator::with_image(&case.material, case.image.clone(), None) {
                Ok(p) => p,
                Err(e) => {
                    return Row {
                        case: format!("{}: {e}", case.name),
                        path: Path::Wgsl,
                        outputs: 0,
                        max_deviation: f64::INFINITY,
                        bound: 0.0,
                        non_finite: 1,
                        reference: String::new(),
                    };
                }
            };
            let (mut outputs, mut bad, mut compared, mut off) = (0, 0, 0, 0);
            for deg in &degs {
                let camera = Camera {
                    elevation_deg: *deg,
                    azimuth_deg: 30.0,
                    distance: 50.0,
                    target: [3.0, -2.0],
                    fov_deg: 20.0,
                };
                let scene = Scene {
                    camera,
                    light,
                    shape: Shape::Plane,
                };
                let Ok(gm) = GpuMaterial::new(r.context(), &p, camera.target) else {
                    bad += 1;
                    continue;
                };
                for mode in [
                    ViewMode::Naive,
                    ViewMode::ViewIndependent,
                    ViewMode::Filtered,
                    ViewMode::Truth,
                ] {
                    if mode == ViewMode::Truth && !stability::truth_traceable(&p) {
                        continue;
                    }
                    let Ok(img) = r.render(&gm, &scene, mode, (w, h), 1) else {
                        bad += (w * h) as usize;
                        continue;
                    };
                    for y in 0..h {
                        for x in 0..w {
                            let got = img.rgb(x, y);
                            outputs += 3;
                            let nb = got.iter().filter(|v| !v.is_finite() || **v < 0.0).count();
                            if nb > 0 {
                                log::debug!("{} {mode:?} {deg}° ({x},{y}): {got:?}", case.name);
                            }
                            bad += nb;
                            let method = match mode {
                                ViewMode::Naive => Method::Naive,
                                ViewMode::ViewIndependent => Method::ViewIndependent,
                                ViewMode::Filtered => Method::Filtered,
                                ViewMode::Truth => continue,
                            };
                            // Beyond truth_traceable the f32 march cannot place hits in the slab (a
                            // 1e6-unit relief seen from 50 units); without an environment such
                            // pixels are still comparable (the sun leaves them black on both
                            // sides), with one they show the misplaced hit: finite only.
                            if *deg >= 89.9
                                || (p.environment.is_some() && !stability::truth_traceable(&p))
                            {
                                continue;
                            }
                            let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                            if camera.plane_footprint(c, w, h).is_none() {
                                continue;
                            }
                            let want = p.plane_pixel(method, &camera, c, (w, h), light);
                            compared += 1;
                            if (0..3).any(|k| {
                                (f64::from(got[k]) - want[k]).abs() > 5e-3 * want[k].abs() + 2e-4
                            }) {
                                if off < 3 {
                                    log::debug!(
                                        "{} {mode:?} {deg}° ({x},{y}): GPU {got:?} core {want:?}",
                                        case.name
                                    );
                                }
                                off += 1;
                            }
                        }
                    }
                }
            }
            Row {
                case: case.name,
                path: Path::Wgsl,
                outputs,
                max_deviation: if compared > 0 {
                    off as f64 / compared as f64
                } else {
                    0.0
                },
                bound: 0.02,
                non_finite: bad,
                reference: if compared > 0 {
                    "core's pixel (fraction of pixels off by > 0.5%)".into()
                } else {
                    "finite and ≥ 0 only (f32 cannot place hits in this slab)".into()
                },
            }
        })
        .collect()
}

/// Every row: CPU, then (unless `cpu_only`) WGSL on the adapter, and the reason there are no WGSL
/// rows when no adapter was found.
pub fn rows(cpu_only: bool) -> (Vec<Row>, Option<lodestone_render::GpuError>) {
    let mut rows = crate::cli::stability::cases::cpu_rows();
    if cpu_only {
        return (rows, None);
    }
    match GpuContext::new_headless() {
        Ok(ctx) => {
            rows.extend(wgsl_special_rows(&ctx));
            rows.extend(wgsl_material_rows(&Renderer::new(ctx)));
            (rows, None)
        }
        Err(e) => (rows, Some(e)),
    }
}

/// The table.
pub fn table(rows: &[Row]) -> String {
    let mut s = format!(
        "{:<62} {:<9} {:>7} {:>12} {:>9} {:>10}  {}\n",
        "case", "path", "outputs", "max dev.", "bound", "non-finite", "result"
    );
    for r in rows {
        s += &format!(
            "{:<62} {:<9} {:>7} {:>12.3e} {:>9.1e} {:>10}  {}\n",
            r.case,
            r.path.name(),
            r.outputs,
            r.max_deviation,
            r.bound,
            r.non_finite,
            if r.passed() { "ok" } else { "FAIL" }
        );
    }
    s
}

/// `lodestone stability [--json] [--cpu-only]`: prints the table (or JSON) and fails when a row
/// fails, or (exit code 3) when the WGSL rows could not run for want of an adapter: a run without
/// them is not a pass unless `--cpu-only` asked for core alone.
pub fn run(json: bool, cpu_only: bool) -> Result<()> {
    let (rows, no_gpu) = rows(cpu_only);
    if json {
        outln!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        out!("{}", table(&rows));
        outln!("reference and unit of each deviation:");
        for r in &rows {
            outln!("  {} [{}]: {}", r.case, r.path.name(), r.reference);
        }
    }
    let failed = rows.iter().filter(|r| !r.passed()).count();
    if failed > 0 {
        anyhow::bail!("{failed} of {} stability rows failed", rows.len());
    }
    if let Some(e) = no_gpu {
        return Err(anyhow::Error::new(e).context(
            "the WGSL rows did not run (the CPU rows above passed; --cpu-only checks core alone)",
        ));
    }
    Ok(())
}
