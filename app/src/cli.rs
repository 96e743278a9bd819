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
    /// Render the plane scene under one mode (or all of them) to PNG (8-bit sRGB) or EXR (linear).
    Render {
        /// naive, view-independent, filtered, truth, error (filtered against truth) or all.
        #[arg(long, value_enum, default_value_t = RenderMode::All)]
        mode: RenderMode,
        /// Camera angle from the normal, degrees (0 to 89.5).
        #[arg(long, default_value_t = 60.0)]
        view_deg: f64,
        /// Camera azimuth, degrees.
        #[arg(long, default_value_t = 0.0)]
        view_azimuth_deg: f64,
        /// Light angle from the normal, degrees.
        #[arg(long, default_value_t = 30.0)]
        light_deg: f64,
        /// Light azimuth, degrees.
        #[arg(long, default_value_t = 90.0)]
        light_azimuth_deg: f64,
        /// Camera distance to its target (world units); features are about 1 unit across.
        #[arg(long, default_value_t = 6.0)]
        distance: f64,
        /// Image size, WxH.
        #[arg(long, default_value = "512x384", value_parser = parse_size)]
        size: (u32, u32),
        /// The object: the plane, or a cylinder whose top line passes through the camera target.
        #[arg(long, value_enum, default_value_t = ShapeArg::Plane)]
        shape: ShapeArg,
        /// Radius of the cylinder (world units).
        #[arg(long, default_value_t = 2.0)]
        radius: f64,
        /// Ground-truth rays per pixel.
        #[arg(long, default_value_t = 64)]
        spp: u32,
        /// Output: a .png or .exr file, or a directory for `--mode all`.
        #[arg(long)]
        out: PathBuf,
        /// Formats written by `--mode all`.
        #[arg(long, value_enum, default_value_t = Formats::Both)]
        formats: Formats,
        /// How the ray marches step and refine a crossing (the reference stays selectable).
        #[arg(long, value_enum, default_value_t = MarchArg::Fast)]
        march: MarchArg,
    },
    /// Time each mode's frame on the GPU adapter (medians of repeated frames) over presets × view
    /// angles × distances, against a "flat" reference (the same camera and colour with σ_h = 0: the
    /// cost of a textured plane), with the filtered/naive cost ratio.
    Bench {
        /// Image size, WxH.
        #[arg(long, default_value = "512x512", value_parser = parse_size)]
        size: (u32, u32),
        /// Camera angles from the normal to sweep, degrees (comma-separated).
        #[arg(long, default_value = "60", value_delimiter = ',')]
        view_deg: Vec<f64>,
        /// Camera distances to sweep, world units (comma-separated).
        #[arg(long, default_value = "6", value_delimiter = ',')]
        distance: Vec<f64>,
        /// Presets to sweep (comma-separated RON files); the global --preset (or the built-in
        /// default) when omitted.
        #[arg(long, value_delimiter = ',')]
        presets: Vec<PathBuf>,
        /// Timed frames per mode (after one warm-up frame).
        #[arg(long, default_value_t = 5)]
        frames: u32,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Write the engine bundle: the pre-convolved tables (EXR), a manifest (JSON), and self-contained
    /// WGSL and GLSL snippets that evaluate the filtered material from them.
    Export {
        /// Output directory (created if needed).
        #[arg(long)]
        out: PathBuf,
    },
    /// What the preset needs in a scene: its feature set and why each other feature is left out,
    /// the view shader specialised to it against the all-features shader (naga statements), the
    /// GPU data by part, and with --time compile and frame times of both pipelines.
    Inspect {
        /// Print JSON.
        #[arg(long)]
        json: bool,
        /// Light angle from the normal, degrees (0 puts it at the normal: no shadow rays).
        #[arg(long, default_value_t = 30.0)]
        light_deg: f64,
        /// Light azimuth, degrees.
        #[arg(long, default_value_t = 90.0)]
        light_azimuth_deg: f64,
        /// The object: the plane, or a cylinder of radius 2.
        #[arg(long, value_enum, default_value_t = ShapeArg::Plane)]
        shape: ShapeArg,
        /// Also compile and time both pipelines on the GPU adapter (view 60°, distance 6).
        #[arg(long)]
        time: bool,
        /// Image size for --time, WxH.
        #[arg(long, default_value = "256x192", value_parser = parse_size)]
        size: (u32, u32),
        /// Timed batches of 8 frames per mode for --time.
        #[arg(long, default_value_t = 5)]
        frames: u32,
    },
    /// Parse and validate a preset; exit code 2 and every problem on failure.
    Validate,
    /// Print the preset (the built-in default when --preset is omitted) as RON.
    Show,
    /// Describe the GPU adapter wgpu finds; exit code 3 when there is none.
    Adapter,
    /// Error against run time: naive, view-independent, both filtered variants and ground truth at
    /// 1…256 rays against a ground-truth reference over view/light configurations and zoom levels;
    /// writes report.json, report.md and SVG charts into --out.
    Report {
        /// Output folder.
        #[arg(long)]
        out: std::path::PathBuf,
        /// Image size WIDTHxHEIGHT of every rendering.
        #[arg(long, default_value = "64x40", value_parser = parse_size)]
        size: (u32, u32),
        /// Rays per pixel of the reference.
        #[arg(long, default_value_t = 1024)]
        reference_spp: u32,
        /// View angles from the normal, degrees (comma-separated).
        #[arg(long, default_value = "0,30,60,75,85,89", value_delimiter = ',')]
        views: Vec<f64>,
        /// Camera distances, one per zoom level (comma-separated).
        #[arg(long, default_value = "1.5,6,40", value_delimiter = ',')]
        zooms: Vec<f64>,
        /// Timing repeats (the median is reported).
        #[arg(long, default_value_t = 5)]
        repeats: u32,
        /// How the ray marches step and refine a crossing (the reference stays selectable).
        #[arg(long, value_enum, default_value_t = MarchArg::Fast)]
        march: MarchArg,
    },
    /// Run stiff and extreme cases (grazing angles, σ → 0 and 1e6, anisotropy 1e±6, L to 1e12, step
    /// maps, vertical transfer segments, constant images) through core f64, its f32 mirror and the
    /// WGSL; exit code 1 if any output is non-finite or exceeds its documented bound.
    Stability {
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
}

/// What `render` draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RenderMode {
    /// Naive MIP.
    Naive,
    /// View-independent texture filtering.
    ViewIndependent,
    /// The filtered model.
    Filtered,
    /// Ray-traced ground truth.
    Truth,
    /// Heat map of |filtered − truth|.
    Error,
    /// Every mode and every error map, into a directory.
    All,
}

/// How marches step and refine the crossing they find (`lodestone_core::scene::march::March`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MarchArg {
    /// Global Lipschitz steps and bisection, 48 halvings on the CPU and 24 on the GPU (the reference).
    Reference,
    /// The octave march (noise drivers) and the Illinois method to the same bracket width.
    Fast,
}

impl MarchArg {
    /// The core value.
    pub fn march(self) -> lodestone_core::scene::march::March {
        match self {
            Self::Reference => lodestone_core::scene::march::March::Reference,
            Self::Fast => lodestone_core::scene::march::March::Fast,
        }
    }
}

/// The object `render` draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ShapeArg {
    /// The unbounded plane.
    Plane,
    /// A cylinder around an axis parallel to x.
    Cylinder,
}

impl ShapeArg {
    /// The object, with `radius` for the cylinder (which must be positive and finite).
    pub fn shape(self, radius: f64) -> Result<lodestone_core::scene::shape::Shape, String> {
        match self {
            ShapeArg::Plane => Ok(lodestone_core::scene::shape::Shape::Plane),
            ShapeArg::Cylinder if radius > 0.0 && radius.is_finite() => {
                Ok(lodestone_core::scene::shape::Shape::Cylinder { radius })
            }
            ShapeArg::Cylinder => Err(format!("--radius must be a positive number, got {radius}")),
        }
    }
}

/// Parse "WxH".
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got {s:?}"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in {s:?}"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in {s:?}"))?;
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        return Err(format!("size must be between 1x1 and 8192x8192, got {s:?}"));
    }
    Ok((w, h))
}

/// Image formats `render --mode all` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Formats {
    /// 8-bit sRGB PNG only.
    Png,
    /// Linear EXR only (views as EXR; error maps as PNG heat maps and EXR |mode − truth|).
    Exr,
    /// Both (error maps as PNG heat maps and as linear EXR |mode − truth| per channel).
    Both,
}
