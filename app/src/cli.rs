//! Command-line interface (clap).

use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// Lodestone: a material and level-of-detail editor for procedural materials that must look right
/// at every distance. Without a subcommand it opens the editor on the default preset.
#[derive(Debug, Parser)]
#[command(name = "lodestone", version, about, long_about = None)]
pub struct Cli {
    /// Preset to open (RON); the built-in default when omitted.
    #[arg(long, global = true)]
    pub preset: Option<PathBuf>,
    /// What to do; the editor when omitted.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// Headless subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Mean linear-RGB colour of a far, flat, fully filtered patch under naive MIP, view-independent
    /// filtering, the filtered model and ray-traced ground truth (CPU reference evaluator).
    Eval {
        /// View angle from the normal, degrees (0 to 89.5).
        #[arg(long, default_value_t = 0.0)]
        view_deg: f64,
        /// View azimuth, degrees.
        #[arg(long, default_value_t = 0.0)]
        view_azimuth_deg: f64,
        /// Light angle from the normal, degrees.
        #[arg(long, default_value_t = 0.0)]
        light_deg: f64,
        /// Light azimuth, degrees.
        #[arg(long, default_value_t = 0.0)]
        light_azimuth_deg: f64,
        /// Ground-truth samples (eye rays) for the patch.
        #[arg(long, default_value_t = 40_000)]
        spp: usize,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Parse and validate a preset; exit code 2 and every problem on failure.
    Validate,
    /// Print the preset (the built-in default when --preset is omitted) as RON.
    Show,
    /// Describe the GPU adapter wgpu finds; exit code 3 when there is none.
    Adapter,
}
