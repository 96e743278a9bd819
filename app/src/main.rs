//! The `lodestone` binary: the editor and the headless command line.
//!
//! Exit codes: 0 success, 1 other failure, 2 bad input (unreadable or invalid preset),
//! 3 no GPU adapter.

mod cli;
mod eval;
mod render_cmd;

use anyhow::{Context, Result};
use clap::Parser;
use cli::{Cli, Command};
use lodestone_core::material::{Material, MaterialError};
use std::path::Path;
use std::process::ExitCode;

/// The built-in default preset.
const DEFAULT_PRESET: &str = include_str!("../../presets/default.ron");

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

/// 2 for bad presets, 3 for a missing adapter, else 1.
fn exit_code(e: &anyhow::Error) -> u8 {
    if e.chain()
        .any(|c| c.is::<MaterialError>() || c.is::<PresetReadError>())
    {
        2
    } else if e.chain().any(|c| c.is::<lodestone_render::GpuError>()) {
        3
    } else {
        1
    }
}

/// A preset file that cannot be read.
#[derive(Debug)]
struct PresetReadError(String);

impl std::fmt::Display for PresetReadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PresetReadError {}

/// Load a preset (or the built-in default), naming the file in any error.
fn load(path: Option<&Path>) -> Result<Material> {
    match path {
        None => Material::from_ron(DEFAULT_PRESET).context("built-in default preset"),
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .map_err(|e| PresetReadError(format!("cannot read {}: {e}", p.display())))?;
            Material::from_ron(&text).with_context(|| format!("{}", p.display()))
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    let material = load(cli.preset.as_deref())?;
    match cli.command {
        None => {
            println!(
                "The interactive editor is not built yet (it is issue #4). Meanwhile, here is the preset \
                 evaluated by the CPU reference; see `lodestone --help` for the headless commands.\n"
            );
            let r = eval::eval(&material, [60.0, 0.0, 30.0, 90.0], 20_000)?;
            print!("{}", eval::table(&r));
        }
        Some(Command::Eval {
            view_deg,
            view_azimuth_deg,
            light_deg,
            light_azimuth_deg,
            spp,
            json,
        }) => {
            let r = eval::eval(
                &material,
                [view_deg, view_azimuth_deg, light_deg, light_azimuth_deg],
                spp,
            )?;
            if json {
                println!("{}", serde_json::to_string_pretty(&r)?);
            } else {
                print!("{}", eval::table(&r));
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
            spp,
            out,
            formats,
        }) => {
            let view = render_cmd::View {
                view_deg,
                view_azimuth_deg,
                light_deg,
                light_azimuth_deg,
                distance,
            };
            render_cmd::render(&material, view, mode, size, spp, &out, formats)?;
        }
        Some(Command::Bench { size, frames, json }) => {
            render_cmd::bench(&material, size, frames, json)?
        }
        Some(Command::Validate) => println!("ok: {} is a valid preset", material.name),
        Some(Command::Show) => println!("{}", material.to_ron()),
        Some(Command::Adapter) => {
            let ctx = lodestone_render::GpuContext::new_headless()?;
            println!("{}", ctx.describe());
        }
    }
    Ok(())
}
