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

mod cli;
mod editor;
mod object;
mod preset_io;
mod report;

use anyhow::Result;
use clap::Parser;
use cli::Cli;
use lodestone_core::material::Material;
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
            ExitCode::from(cli::exit_code(&e))
        }
    }
}

/// A command-line argument that cannot work, found before any work starts (exit code 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

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
    let ctx = cli::Context {
        preset: cli::load(cli.preset.as_deref())?,
        path: cli.preset.clone(),
    };
    match cli.command {
        None => run_editor(cli.preset.map(|p| (p, ctx.preset.material.clone()))),
        Some(command) => cli::run(command, &ctx),
    }
}
