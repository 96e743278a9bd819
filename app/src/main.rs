//! The `lodestone` binary: the editor and the headless command line.
//!
//! Exit codes: 0 success, 1 other failure, 2 bad input (unreadable or invalid preset),
//! 3 no GPU adapter. Output piped into a command that stops reading (`| head`) ends the program
//! quietly with 0, like other command-line tools, instead of panicking.

/// `print!` to stdout that exits quietly when the reader has gone (broken pipe).
macro_rules! out {
    ($($t:tt)*) => { $crate::write_stdout(format_args!($($t)*), false) };
}

/// `println!` to stdout that exits quietly when the reader has gone (broken pipe).
macro_rules! outln {
    ($($t:tt)*) => { $crate::write_stdout(format_args!($($t)*), true) };
}

mod adaptive_report;
mod chart;
mod cielab;
mod cli;
mod diagnose;
mod dolly;
mod editor;
mod eval;
mod inspect;
mod object_cmd;
mod object_scene;
mod preset_io;
mod render_cmd;
mod report;
mod stability;
mod stability_cases;
mod stability_materials;

use anyhow::{Context, Result};
use clap::Parser;
use cli::{Cli, Command};
use lodestone_core::material::{Material, MaterialError};
use std::path::Path;
use std::process::ExitCode;

/// Write to stdout; a closed pipe ends the process with 0, other errors are logged.
fn write_stdout(args: std::fmt::Arguments<'_>, newline: bool) {
    use std::io::Write;
    let mut o = std::io::stdout().lock();
    let r = o
        .write_fmt(args)
        .and_then(|()| if newline { o.write_all(b"\n") } else { Ok(()) });
    if let Err(e) = r {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        log::error!("writing to stdout: {e}");
    }
}

fn main() -> ExitCode {
    env_logger::Builder::from_env(
        env_logger::Env::default().default_filter_or("warn,wgpu_hal::gles::egl=off"),
    )
    .init();
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(exit_code(&e))
        }
    }
}

/// 2 for bad presets and sizes or materials beyond the adapter's limits, 3 for a missing adapter,
/// else 1.
/// A command-line argument that cannot work, found before any work starts (exit code 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// Where `render` or `report` would write, checked before rendering (#16: a `.txt` output or an
/// existing file in the way used to fail only after minutes of work): a single image needs a `.png`
/// or `.exr` name in an existing folder; a folder output must not be an existing file.
fn check_output(out: &Path, folder: bool) -> Result<(), UsageError> {
    if folder {
        if out.exists() && !out.is_dir() {
            return Err(UsageError(format!(
                "--out {}: exists and is not a folder",
                out.display()
            )));
        }
        return Ok(());
    }
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if ext != "png" && ext != "exr" {
        return Err(UsageError(format!(
            "--out {}: unsupported output (use .png or .exr)",
            out.display()
        )));
    }
    if out.is_dir() {
        return Err(UsageError(format!("--out {}: is a folder", out.display())));
    }
    match out.parent() {
        Some(dir) if !dir.as_os_str().is_empty() && !dir.is_dir() => Err(UsageError(format!(
            "--out {}: the folder {} does not exist",
            out.display(),
            dir.display()
        ))),
        _ => Ok(()),
    }
}

fn exit_code(e: &anyhow::Error) -> u8 {
    let too_large = |c: &(dyn std::error::Error + 'static)| {
        matches!(
            c.downcast_ref::<lodestone_render::RenderError>(),
            Some(lodestone_render::RenderError::TooLarge { .. })
        )
    };
    if e.chain().any(|c| {
        c.is::<MaterialError>()
            || c.is::<preset_io::PresetError>()
            || c.is::<UsageError>()
            || too_large(c)
    }) {
        2
    } else if e.chain().any(|c| c.is::<lodestone_render::GpuError>()) {
        3
    } else {
        1
    }
}

/// Load a preset (or the built-in default), naming the file in any error.
fn load(path: Option<&Path>) -> Result<preset_io::Resolved> {
    match path {
        None => Ok(preset_io::Resolved::without_image(
            Material::from_ron(preset_io::DEFAULT_PRESET).context("built-in default preset")?,
        )),
        Some(p) => Ok(preset_io::load_resolved(p)?),
    }
}

/// Open the editor window.
fn run_editor(preset: Option<(std::path::PathBuf, Material)>) -> Result<()> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("Lodestone")
            .with_inner_size([1600.0, 900.0])
            .with_min_inner_size([960.0, 600.0])
            .with_drag_and_drop(true),
        ..Default::default()
    };
    let opts = editor::Options {
        preset,
        ..editor::Options::default()
    };
    eframe::run_native(
        "Lodestone",
        options,
        Box::new(move |cc| Ok(Box::new(editor::EditorApp::new(cc, opts)))),
    )
    .map_err(|e| anyhow::anyhow!("cannot open the editor window: {e}"))
}

fn run(cli: Cli) -> Result<()> {
    let preset = load(cli.preset.as_deref())?;
    let material = &preset.material;
    match cli.command {
        None => run_editor(cli.preset.clone().map(|p| (p, material.clone())))?,
        Some(Command::Eval {
            view_deg,
            view_azimuth_deg,
            light_deg,
            light_azimuth_deg,
            spp,
            slope_masking,
            json,
        }) => {
            let mut preset = preset.clone();
            if let Some(sm) = slope_masking {
                preset.material.filtering.slope_masking = sm.into();
            }
            let r = eval::eval(
                &preset,
                [view_deg, view_azimuth_deg, light_deg, light_azimuth_deg],
                spp,
            )?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&r)?);
            } else {
                out!("{}", eval::table(&r));
            }
        }
        Some(Command::Diagnose {
            view_deg,
            light_deg,
            light_azimuth_deg,
            precision,
            max_spp,
            full_only,
            json,
        }) => {
            let rows = diagnose::diagnose(
                &preset,
                &diagnose::Grid {
                    views: &view_deg,
                    lights: &light_deg,
                    azimuths: &light_azimuth_deg,
                },
                precision,
                max_spp,
                full_only,
            )?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&rows)?);
            } else {
                out!("{}", diagnose::table(&preset.material.name, &rows));
            }
        }
        Some(Command::Render {
            mode,
            view_deg,
            view_azimuth_deg,
            light_deg,
            light_azimuth_deg,
            distance,
            size,
            shape,
            radius,
            spp,
            out,
            formats,
            march,
            error_block,
            retry_cut_rays,
        }) => {
            let shape = shape.shape(radius).map_err(UsageError)?;
            check_output(&out, mode == cli::RenderMode::All)?;
            let view = render_cmd::View {
                view_deg,
                view_azimuth_deg,
                light_deg,
                light_azimuth_deg,
                distance,
                shape,
                march: march.march(),
                error_block,
                retry_cut_rays,
            };
            render_cmd::render(&preset, view, mode, size, spp, &out, formats)?;
        }
        Some(Command::Bench {
            size,
            frames,
            json,
            view_deg,
            distance,
            presets,
            modes,
            no_reference,
            interception,
        }) => {
            let mut sweep = vec![];
            if presets.is_empty() {
                let name = cli
                    .preset
                    .as_ref()
                    .map_or("default".to_owned(), |p| p.display().to_string());
                sweep.push((name, preset));
            } else {
                for p in &presets {
                    sweep.push((p.display().to_string(), load(Some(p))?));
                }
            }
            let cfg = render_cmd::BenchSweep {
                view_deg,
                distance,
                size,
                frames,
                modes: modes.iter().map(|m| m.name()).collect(),
                reference: !no_reference,
                interception: interception.interception(),
            };
            render_cmd::bench(&sweep, &cfg, json)?
        }
        Some(Command::Dolly {
            view_deg,
            from,
            to,
            frames,
            size,
            json,
        }) => {
            let opts = dolly::Options {
                view_deg,
                range: (from, to),
                frames,
                size,
            };
            let (adapter, rows) = dolly::run(&preset, &opts)?;
            if json {
                outln!(
                    "{}",
                    serde_json::to_string_pretty(&dolly::to_json(&rows, &opts, &adapter))?
                );
            } else {
                out!("{}", dolly::table(&rows, &opts, &adapter));
            }
        }
        Some(Command::Export { out }) => {
            let written = preset_io::export_bundle(&preset, cli.preset.as_deref(), &out)?;
            outln!(
                "wrote {} files to {} (see manifest.json)",
                written.len(),
                out.display()
            );
        }
        Some(Command::Inspect {
            json,
            light_deg,
            light_azimuth_deg,
            shape,
            time,
            size,
            frames,
        }) => {
            let view = render_cmd::View {
                view_deg: 60.0,
                view_azimuth_deg: 0.0,
                light_deg,
                light_azimuth_deg,
                distance: 6.0,
                shape: shape.shape(2.0).map_err(anyhow::Error::msg)?,
                march: lodestone_core::scene::march::March::default(),
                error_block: 8,
                retry_cut_rays: false,
            };
            let opts = inspect::Options {
                view,
                time,
                size,
                frames,
            };
            let i = inspect::inspect(&preset, opts)?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&i.to_json())?);
            } else {
                out!("{}", i.to_text());
            }
        }
        Some(Command::Merl {
            out,
            diffuse,
            f0,
            alpha,
        }) => {
            use lodestone_core::material::merl::{MerlBrdf, ggx_reference};
            let [r, g, b] = diffuse[..] else {
                return Err(UsageError(format!(
                    "--diffuse takes three values (red, green, blue), got {}",
                    diffuse.len()
                ))
                .into());
            };
            if out.is_dir() {
                return Err(UsageError(format!("--out {}: is a folder", out.display())).into());
            }
            if let Some(dir) = out
                .parent()
                .filter(|d| !d.as_os_str().is_empty() && !d.is_dir())
            {
                return Err(UsageError(format!(
                    "--out {}: the folder {} does not exist",
                    out.display(),
                    dir.display()
                ))
                .into());
            }
            let table = MerlBrdf::tabulate(ggx_reference([r, g, b], [f0; 3], alpha));
            preset_io::write_atomic_bytes(&out, &table.to_bytes())?;
            outln!(
                "wrote {} (MERL BRDF: diffuse {r}, {g}, {b}; F0 {f0}; GGX α {alpha})",
                out.display()
            );
        }
        Some(Command::Validate) => outln!("ok: {} is a valid preset", material.name),
        Some(Command::Show) => outln!("{}", material.to_ron()),
        Some(Command::Stability { json, cpu_only }) => stability::run(json, cpu_only)?,
        Some(Command::Report {
            out,
            size,
            reference_spp,
            views,
            zooms,
            repeats,
            march,
            adaptive_rpp,
            retry_cut_rays,
            shape,
            radius,
            object_distances,
            object_depth,
        }) => {
            check_output(&out, true)?;
            let shape = shape.shape(radius).map_err(anyhow::Error::msg)?;
            let opts = report::Options {
                size,
                reference_spp,
                views,
                zooms,
                repeats,
                march: march.march(),
                adaptive: adaptive_rpp.into_iter().filter(|b| *b > 0.0).collect(),
                retry_cut_rays,
                shape,
            };
            let rep = report::run(&preset, &opts)?;
            report::write(&rep, &out)?;
            out!("{}", report::markdown(&rep));
            if !object_distances.is_empty() {
                // The whole object (#19): `lodestone object`'s sweep on the unit sphere, its
                // table appended to report.md.
                let sweep = object_cmd::Options {
                    depth: object_depth,
                    size,
                    distances: object_distances,
                    out: Some(out.join("objects")),
                    ..object_cmd::Options::sphere_defaults()?
                };
                let table = object_cmd::run(material, &sweep)?;
                let section = format!(
                    "\n## Whole object: voxel views against ground truth\n\n\
                     `lodestone object` on the unit sphere, octree depth {object_depth}, at the \
                     report's size (strips in `objects/`).\n\n{table}\n"
                );
                let md = out.join("report.md");
                let mut text = std::fs::read_to_string(&md)?;
                text.push_str(&section);
                preset_io::write_atomic(&md, &text)?;
                out!("{section}");
            }
            outln!(
                "wrote report.json, report.md and the charts (error_vs_time, error_vs_view, error_vs_rays; SVG and PNG) to {}",
                out.display()
            );
        }
        Some(cmd @ Command::Object { .. }) => {
            let opts = object_cmd::Options::from_command(cmd)?;
            out!("{}", object_cmd::run(material, &opts)?);
        }
        Some(Command::Adapter) => {
            let ctx = lodestone_render::GpuContext::new_headless()?;
            outln!("{}", ctx.describe());
        }
    }
    Ok(())
}
