//! The command line: the parser (clap) and one module per subcommand, each with its own
//! arguments and its `run`. [`run`] dispatches a parsed command; without one, `main` opens the
//! editor. `docs/cli.md` is generated from these definitions ([`reference`]).

use crate::UsageError;
use crate::preset_io::{self, Resolved};
use anyhow::{Context as _, Result};
use clap::{Parser, Subcommand};
use lodestone_core::material::{Material, MaterialError};
use std::path::{Path, PathBuf};

pub mod args;
pub mod bench;
pub mod diagnose;
pub mod dolly;
pub mod eval;
pub mod export;
pub mod inspect;
pub mod merl;
pub mod object;
#[cfg(test)]
mod reference;
pub mod render;
pub mod report;
pub mod stability;

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
    Eval(eval::EvalArgs),
    /// Which term carries the filtered model's error: the far patch of `eval` for the material and
    /// for variants with one term switched off in the model and the ground truth alike (diffuse
    /// only, specular only, diffuse in constant grey, sun or environment alone), at every
    /// combination of the listed view and light angles.
    Diagnose(diagnose::DiagnoseArgs),
    /// Render the plane scene under one mode (or all of them) to PNG (8-bit sRGB) or EXR (linear).
    ///
    /// The plane (or, with `--shape cylinder`, a cylinder around an axis parallel to x whose top line
    /// passes through the camera target; `--view-azimuth-deg 90` sees it side-on) under an orbit camera
    /// and a directional light. `--mode all` writes every view, its EXR, and an error heat map per method
    /// against the ground truth on means of `--error-block` blocks (grey where a block is within the
    /// truth's own noise; one shared legend along the bottom), with the raw |mode − truth| as EXR, and
    /// prints RMSE, max, and the RMSE beyond the truth's noise with its ±2 standard-error range. The
    /// ground truth accumulates `--spp` low-discrepancy rays per pixel. On Mesa's software adapter a few
    /// rays skimming the relief near the horizon can run out of its loop budget: they are counted and
    /// warned about, and `--retry-cut-rays` traces them again alone (slowly).
    Render(render::RenderArgs),
    /// Time each mode's frame on the GPU adapter (medians of repeated frames) over presets × view
    /// angles × distances, against a "flat" reference (the same camera and colour with σ_h = 0: the
    /// cost of a textured plane), with the filtered/naive cost ratio.
    Bench(bench::BenchArgs),
    /// The popping figure: a slow dolly (the editor's zoom sweep, geometric in distance) with the
    /// fast and the reference march; per pixel, the jump between consecutive frames of each
    /// analytic view, and how much more any pixel jumps under the fast march.
    Dolly(dolly::DollyArgs),
    /// Write the engine bundle: the pre-convolved tables (EXR), a manifest (JSON), and self-contained
    /// WGSL and GLSL snippets that evaluate the filtered material from them.
    ///
    /// The bundle: `lodestone_filtered.wgsl` (self-contained: the renderer's own special-function and
    /// material WGSL, plus an example compute entry point) and `lodestone_filtered.glsl` (the same,
    /// translated to GLSL 4.50 by naga), `params.bin` and `data.bin` (the buffers they bind), the
    /// pre-convolved tables as EXR, `manifest.json` (table sizes, ranges and indexing, every parameter by
    /// name and offset, the API `eval_filtered(x0, footprint, wo, wi)`), the preset and the files it
    /// names. Every file is written under a temporary name first, the manifest last.
    Export(export::ExportArgs),
    /// What the preset needs in a scene: its feature set and why each other feature is left out,
    /// the view shader specialised to it against the all-features shader (naga statements), the
    /// GPU data by part, and with --time compile and frame times of both pipelines.
    Inspect(inspect::InspectArgs),
    /// Write a MERL-format isotropic BRDF table (`.binary`, 90×90×180 half/difference angles, 35
    /// MB) of an analytic plastic: Lambert diffuse plus a GGX lobe with Schlick's Fresnel. For a
    /// preset that references a measured BRDF without the MERL database at hand (the library's
    /// `presets/measured/red-plastic.ron` is written with the defaults).
    Merl(merl::MerlArgs),
    /// Parse and validate a preset; exit code 2 and every problem on failure.
    Validate,
    /// Print the preset (the built-in default when --preset is omitted) as RON.
    Show,
    /// Describe the GPU adapter wgpu finds; exit code 3 when there is none.
    Adapter,
    /// A whole object (sphere, torus or a closed OBJ mesh) displaced by the preset's relief,
    /// voxelised into a sparse octree and cone traced on the CPU [HN12] beside its ray-traced
    /// ground truth, over a zoom sweep: per distance a PNG strip (nearest voxels | alpha blended |
    /// masks | ground truth, and with --gpu the WGSL masks) and the colour error of covered pixels,
    /// the silhouette's coverage error and the time per pixel. Noise drivers only; a bad mesh is
    /// exit code 2.
    Object(object::ObjectArgs),
    /// Error against run time: naive, view-independent, both filtered variants and ground truth at
    /// 1…256 rays against a ground-truth reference over view/light configurations and zoom levels;
    /// writes report.json, report.md and SVG charts into --out.
    ///
    /// Every method is compared with a ground-truth reference: RMSE in linear RGB (also beyond the
    /// reference's own noise), mean and 95th-percentile CIELAB ΔE, and time per frame (synchronised wall
    /// time, median). The adaptive ground truth is rendered at the budgets of `--adaptive-rpp` (rays a
    /// pixel on average): a lattice refined after a first quarter of the budget, progressive per-pixel
    /// counts, and windowed reconstructions of uniform and progressive truths; report.md gives each one's
    /// RMSE, the uniform rays that reach it and the gains in rays and time, and checks the predicted
    /// deviation of one ray against the reference's per configuration. The defaults are sized for a GPU;
    /// on a software adapter use e.g. `--size 24x16 --reference-spp 256`.
    Report(report::ReportArgs),
    /// Run stiff and extreme cases (grazing angles, σ → 0 and 1e6, anisotropy 1e±6, L to 1e12, step
    /// maps, vertical transfer segments, constant images) through core f64, its f32 mirror and the
    /// WGSL; exit code 1 if any output is non-finite or exceeds its documented bound, 3 if the WGSL
    /// rows could not run.
    ///
    /// Every CPU row has an independent reference and a documented bound: quadrature of the defining
    /// integral (special functions, D_h, Smith Λ over anisotropic slopes), an exact identity computed
    /// through other materials (σ_h's scale drops out, transposed anisotropy seen mirrored, filtered =
    /// view-independent without micro-slopes, a step map = its 1e-7 ramp) or a limit. The f32 and WGSL
    /// special functions are bounded relative to their condition number. WGSL material rows compare
    /// with core's pixel.
    Stability(stability::StabilityArgs),
}

/// What every subcommand starts from: the preset (or the built-in default) and the file it came
/// from.
pub struct Context {
    /// The preset, with its image loaded.
    pub preset: Resolved,
    /// Its file (`--preset`), if any.
    pub path: Option<PathBuf>,
}

/// Run one subcommand on the preset `ctx` holds.
pub fn run(command: Command, ctx: &Context) -> Result<()> {
    match command {
        Command::Eval(a) => eval::run(a, ctx),
        Command::Diagnose(a) => diagnose::run(a, ctx),
        Command::Render(a) => render::run(a, ctx),
        Command::Bench(a) => bench::run(a, ctx),
        Command::Dolly(a) => dolly::run_command(a, ctx),
        Command::Export(a) => export::run(a, ctx),
        Command::Inspect(a) => inspect::run(a, ctx),
        Command::Merl(a) => merl::run(a),
        Command::Validate => {
            outln!("ok: {} is a valid preset", ctx.preset.material.name);
            Ok(())
        }
        Command::Show => {
            outln!("{}", ctx.preset.material.to_ron());
            Ok(())
        }
        Command::Adapter => {
            let gpu = lodestone_render::GpuContext::new_headless()?;
            outln!("{}", gpu.describe());
            Ok(())
        }
        Command::Object(a) => object::run(a, ctx),
        Command::Report(a) => report::run(a, ctx),
        Command::Stability(a) => stability::run_command(a, ctx),
    }
}

/// Load a preset (or the built-in default), naming the file in any error.
pub fn load(path: Option<&Path>) -> Result<Resolved> {
    match path {
        None => Ok(Resolved::without_image(
            Material::from_ron(preset_io::DEFAULT_PRESET).context("built-in default preset")?,
        )),
        Some(p) => Ok(preset_io::load_resolved(p)?),
    }
}

/// Where `render` or `report` would write, checked before rendering (a `.txt` output or an
/// existing file in the way would otherwise fail only after minutes of work): a single image
/// needs a `.png` or `.exr` name in an existing folder; a folder output must not be an existing
/// file.
pub fn check_output(out: &Path, folder: bool) -> Result<(), UsageError> {
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

/// The process's exit code for an error: 2 for bad presets, arguments, and sizes or materials
/// beyond the adapter's limits, 3 for a missing adapter, else 1.
pub fn exit_code(e: &anyhow::Error) -> u8 {
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
