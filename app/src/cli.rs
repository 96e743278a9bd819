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
        #[arg(long, default_value_t = 0.0, value_parser = view_angle)]
        view_deg: f64,
        /// View azimuth, degrees.
        #[arg(long, default_value_t = 0.0, value_parser = azimuth)]
        view_azimuth_deg: f64,
        /// Light angle from the normal, degrees (0 to 180; past 90 the sun is below the horizon).
        #[arg(long, default_value_t = 0.0, value_parser = light_angle)]
        light_deg: f64,
        /// Light azimuth, degrees.
        #[arg(long, default_value_t = 0.0, value_parser = azimuth)]
        light_azimuth_deg: f64,
        /// Ground-truth samples (eye rays) for the patch (2 to 10⁸: its standard error needs two).
        #[arg(long, default_value_t = 40_000, value_parser = eval_samples)]
        spp: usize,
        /// The filtered model's masking of the visible slopes, overriding the preset's: Smith's
        /// (height alone), or conditioned on the facet's height and slope along the ray jointly
        /// (#17; the default; noise drivers).
        #[arg(long, value_enum)]
        slope_masking: Option<SlopeMaskingArg>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Which term carries the filtered model's error: the far patch of `eval` for the material and
    /// for variants with one term switched off in the model and the ground truth alike (diffuse
    /// only, specular only, diffuse in constant grey, sun or environment alone), at every
    /// combination of the listed view and light angles.
    Diagnose {
        /// View angles from the normal, degrees (0 to 89.5), comma-separated.
        #[arg(long, default_value = "0,45,75", value_delimiter = ',', value_parser = view_angle)]
        view_deg: Vec<f64>,
        /// Light angles from the normal, degrees (0 to 180), comma-separated.
        #[arg(long, default_value = "0,30", value_delimiter = ',', value_parser = light_angle)]
        light_deg: Vec<f64>,
        /// Light azimuths, degrees (the view's is 0: 0 puts the light on the viewer's side, 180
        /// opposite), comma-separated.
        #[arg(long, default_value = "0,180", value_delimiter = ',', value_parser = azimuth)]
        light_azimuth_deg: Vec<f64>,
        /// Sample the truth until its relative standard error is below this (0.0001 to 0.5).
        #[arg(long, default_value_t = 0.005, value_parser = precision)]
        precision: f64,
        /// At most this many ground-truth rays per variant and configuration (2 to 10⁸).
        #[arg(long, default_value_t = 2_000_000, value_parser = eval_samples)]
        max_spp: usize,
        /// Only the material itself, no variants (an accuracy grid over many configurations).
        #[arg(long)]
        full_only: bool,
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
        #[arg(long, default_value_t = 60.0, value_parser = view_angle)]
        view_deg: f64,
        /// Camera azimuth, degrees.
        #[arg(long, default_value_t = 0.0, value_parser = azimuth)]
        view_azimuth_deg: f64,
        /// Light angle from the normal, degrees (0 to 180; past 90 the sun is below the horizon).
        #[arg(long, default_value_t = 30.0, value_parser = light_angle)]
        light_deg: f64,
        /// Light azimuth, degrees.
        #[arg(long, default_value_t = 90.0, value_parser = azimuth)]
        light_azimuth_deg: f64,
        /// Camera distance to its target (world units, 0.02 to 5000, as in the editor); features
        /// are about 1 unit across.
        #[arg(long, default_value_t = 6.0, value_parser = distance)]
        distance: f64,
        /// Image size, WxH.
        #[arg(long, default_value = "512x384", value_parser = parse_size)]
        size: (u32, u32),
        /// The object: the plane, or a cylinder whose top line passes through the camera target.
        #[arg(long, value_enum, default_value_t = ShapeArg::Plane)]
        shape: ShapeArg,
        /// Radius of the cylinder (world units, 0.01 to 10⁴).
        #[arg(long, default_value_t = 2.0, value_parser = radius)]
        radius: f64,
        /// Ground-truth rays per pixel (1 to 65536).
        #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=65536))]
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
        /// Side of the pixel blocks on whose means errors are also measured against the truth
        /// with its own Monte Carlo noise taken out (`error` and `all`; 1 = per pixel).
        #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=256))]
        error_block: u32,
        /// Trace again, alone, the ground-truth rays whose loops a software adapter (llvmpipe)
        /// cut short, so they get the march's own answer instead of being counted as unreliable
        /// (slow near the horizon: those rays skim the relief for thousands of steps).
        #[arg(long)]
        retry_cut_rays: bool,
    },
    /// Time each mode's frame on the GPU adapter (medians of repeated frames) over presets × view
    /// angles × distances, against a "flat" reference (the same camera and colour with σ_h = 0: the
    /// cost of a textured plane), with the filtered/naive cost ratio.
    Bench {
        /// Image size, WxH.
        #[arg(long, default_value = "512x512", value_parser = parse_size)]
        size: (u32, u32),
        /// Camera angles from the normal to sweep, degrees (comma-separated, each 0 to 89.5).
        #[arg(long, default_value = "60", value_delimiter = ',', value_parser = view_angle)]
        view_deg: Vec<f64>,
        /// Camera distances to sweep, world units (comma-separated, each 0.02 to 5000).
        #[arg(long, default_value = "6", value_delimiter = ',', value_parser = distance)]
        distance: Vec<f64>,
        /// Presets to sweep (comma-separated RON files); the global --preset (or the built-in
        /// default) when omitted.
        #[arg(long, value_delimiter = ',')]
        presets: Vec<PathBuf>,
        /// Timed frames per mode (after one warm-up frame; 1 to 1000).
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
        frames: u32,
        /// Modes to time (comma-separated; the flat reference is always timed). Columns of modes
        /// left out print NaN.
        #[arg(long, value_enum, value_delimiter = ',', default_values_t = BenchMode::all())]
        modes: Vec<BenchMode>,
        /// Skip the reference march (its /ref columns print NaN): a quicker A/B of the fast march.
        #[arg(long)]
        no_reference: bool,
        /// Whether the analytic views' camera rays can stop on a crest's unresolved relief
        /// (`off` is the reference: rays meet h̄).
        #[arg(long, value_enum, default_value_t = InterceptionArg::Crests)]
        interception: InterceptionArg,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// The popping figure: a slow dolly (the editor's zoom sweep, geometric in distance) with the
    /// fast and the reference march; per pixel, the jump between consecutive frames of each
    /// analytic view, and how much more any pixel jumps under the fast march.
    Dolly {
        /// Camera angle from the normal, degrees (0 to 89.5).
        #[arg(long, default_value_t = 77.0, value_parser = view_angle)]
        view_deg: f64,
        /// Closest camera distance (world units).
        #[arg(long, default_value_t = 0.15, value_parser = distance)]
        from: f64,
        /// Farthest camera distance (world units).
        #[arg(long, default_value_t = 400.0, value_parser = distance)]
        to: f64,
        /// Frames along the dolly (2 to 10000).
        #[arg(long, default_value_t = 120, value_parser = clap::value_parser!(u32).range(2..=10000))]
        frames: u32,
        /// Image size, WxH.
        #[arg(long, default_value = "160x120", value_parser = parse_size)]
        size: (u32, u32),
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
        /// Light angle from the normal, degrees (0 puts it at the normal: no shadow rays; 0 to 180).
        #[arg(long, default_value_t = 30.0, value_parser = light_angle)]
        light_deg: f64,
        /// Light azimuth, degrees.
        #[arg(long, default_value_t = 90.0, value_parser = azimuth)]
        light_azimuth_deg: f64,
        /// The object: the plane, or a cylinder of radius 2.
        #[arg(long, value_enum, default_value_t = ShapeArg::Plane)]
        shape: ShapeArg,
        /// Also compile and time both pipelines on the GPU adapter (view 60°, distance 6). On a software
        /// adapter (llvmpipe) the all-features pipeline takes many minutes to compile.
        #[arg(long)]
        time: bool,
        /// Image size for --time, WxH.
        #[arg(long, default_value = "256x192", value_parser = parse_size)]
        size: (u32, u32),
        /// Timed batches of 8 frames per mode for --time (1 to 1000).
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
        frames: u32,
    },
    /// Write a MERL-format isotropic BRDF table (`.binary`, 90×90×180 half/difference angles, 35
    /// MB) of an analytic plastic: Lambert diffuse plus a GGX lobe with Schlick's Fresnel. For a
    /// preset that references a measured BRDF without the MERL database at hand (the library's
    /// `presets/measured/red-plastic.ron` is written with the defaults).
    Merl {
        /// The file to write (atomically).
        #[arg(long)]
        out: PathBuf,
        /// Diffuse albedo per channel (linear RGB), 0 to 1 each, comma-separated.
        #[arg(long, default_value = "0.5,0.06,0.05", value_delimiter = ',', value_parser = unit_fraction)]
        diffuse: Vec<f64>,
        /// Fresnel reflectance at normal incidence (Schlick's F0), 0 to 1.
        #[arg(long, default_value_t = 0.04, value_parser = unit_fraction)]
        f0: f64,
        /// GGX roughness α, 0.01 to 1.
        #[arg(long, default_value_t = 0.15, value_parser = ggx_alpha)]
        alpha: f64,
    },
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
    Object {
        /// The base shape.
        #[arg(long, value_enum, default_value_t = ObjectShapeArg::Sphere)]
        shape: ObjectShapeArg,
        /// The closed, consistently oriented OBJ mesh of `--shape mesh`.
        #[arg(long)]
        mesh: Option<PathBuf>,
        /// The sphere's radius, or the torus's major radius (world units).
        #[arg(long, default_value_t = 1.0, value_parser = radius)]
        radius: f64,
        /// The torus's minor radius (world units, below the major; the relief may reach a quarter
        /// of the smaller of it and the hole's radius, major − minor).
        #[arg(long, default_value_t = 0.45, value_parser = radius)]
        minor: f64,
        /// Octree depth (finest voxels: the object's bounding cube over 2^depth; 2 to 10).
        #[arg(long, default_value_t = 7, value_parser = clap::value_parser!(u32).range(2..=10))]
        depth: u32,
        /// Image size of each panel, WxH.
        #[arg(long, default_value = "160x120", value_parser = parse_size)]
        size: (u32, u32),
        /// Camera distances from the object's centre, comma-separated (world units).
        #[arg(long, default_value = "8,4,2", value_delimiter = ',', value_parser = distance)]
        distances: Vec<f64>,
        /// Camera angle from +z, degrees (0 to 89.5).
        #[arg(long, default_value_t = 60.0, value_parser = view_angle)]
        view_deg: f64,
        /// Camera azimuth, degrees.
        #[arg(long, default_value_t = 30.0, value_parser = azimuth)]
        view_azimuth_deg: f64,
        /// Sun angle from +z, degrees (0 to 180).
        #[arg(long, default_value_t = 37.0, value_parser = light_angle)]
        light_deg: f64,
        /// Sun azimuth, degrees.
        #[arg(long, default_value_t = -37.0, value_parser = azimuth)]
        light_azimuth_deg: f64,
        /// Ground-truth rays per pixel (1 to 4096), before the truth is refined (--truth-se).
        #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=4096))]
        rays: u32,
        /// Refine the truth until the covered mean's relative standard error is at most this many
        /// percent (0: no refinement; rays go where the variance is, at most --max-rays a pixel).
        #[arg(long, default_value_t = 0.5, value_parser = truth_se)]
        truth_se: f64,
        /// The most truth rays any pixel may get when refining (64 to 10⁶).
        #[arg(long, default_value_t = 16384, value_parser = clap::value_parser!(u32).range(64..=1_000_000))]
        max_rays: u32,
        /// Folder for the PNG strips (created if needed; none: only the table).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Leave out shadows (shadow rays in the truth, shadow cones in the voxel views) in both,
        /// to see what they carry of the error.
        #[arg(long)]
        no_shadows: bool,
        /// Also cone trace with masks in WGSL on the GPU adapter (a fifth panel and a column of
        /// its errors and time per pixel, measured after one warm-up frame).
        #[arg(long)]
        gpu: bool,
        /// Depth of field: the thin lens's radius (world units, 0 to 10; 0 is a pinhole), in the
        /// truth and as wider cones [HN12 Sec. 4.1].
        #[arg(long, default_value_t = 0.0, value_parser = lens_radius)]
        lens: f64,
        /// The distance in focus (world units; default: each distance, the object's centre).
        #[arg(long, value_parser = distance)]
        focus: Option<f64>,
    },
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
        /// Rays per pixel of the reference (1 to 65536).
        #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=65536))]
        reference_spp: u32,
        /// View angles from the normal, degrees (comma-separated, each 0 to 89.5).
        #[arg(long, default_value = "0,30,60,75,85,89", value_delimiter = ',', value_parser = view_angle)]
        views: Vec<f64>,
        /// Camera distances, one per zoom level (comma-separated, each 0.02 to 5000).
        #[arg(long, default_value = "1.5,6,40", value_delimiter = ',', value_parser = distance)]
        zooms: Vec<f64>,
        /// Timing repeats (the median is reported; 1 to 1000).
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
        repeats: u32,
        /// How the ray marches step and refine a crossing (the reference stays selectable).
        #[arg(long, value_enum, default_value_t = MarchArg::Fast)]
        march: MarchArg,
        /// Ray budgets of the adaptive ground truth, rays per pixel on average (comma-separated,
        /// each 1 to 4096; "0" leaves it out).
        #[arg(long, default_value = "4,16,64", value_delimiter = ',', value_parser = ray_budget)]
        adaptive_rpp: Vec<f64>,
        /// Trace again, alone, the ground-truth rays whose loops a software adapter (llvmpipe)
        /// cut short, so they get the march's own answer instead of being counted as unreliable
        /// (slow near the horizon: those rays skim the relief for thousands of steps).
        #[arg(long)]
        retry_cut_rays: bool,
        /// The object every configuration views: the plane, or a cylinder whose top line passes
        /// through the camera target.
        #[arg(long, value_enum, default_value_t = ShapeArg::Plane)]
        shape: ShapeArg,
        /// Radius of the cylinder (world units, 0.01 to 10⁴).
        #[arg(long, default_value_t = 2.0, value_parser = radius)]
        radius: f64,
        /// Also compare the whole-object views (#19: nearest voxels, alpha blended, masks, ground
        /// truth) on the unit sphere at these camera distances (comma-separated, each 0.02 to
        /// 5000), at the report's size and with `lodestone object`'s defaults otherwise: a section
        /// of report.md and its strips in OUT/objects. Empty (the default) leaves it out.
        #[arg(long, value_delimiter = ',', value_parser = distance)]
        object_distances: Vec<f64>,
        /// The sphere's octree depth for `--object-distances` (2 to 10).
        #[arg(long, default_value_t = 7, value_parser = clap::value_parser!(u32).range(2..=10))]
        object_depth: u32,
    },
    /// Run stiff and extreme cases (grazing angles, σ → 0 and 1e6, anisotropy 1e±6, L to 1e12, step
    /// maps, vertical transfer segments, constant images) through core f64, its f32 mirror and the
    /// WGSL; exit code 1 if any output is non-finite or exceeds its documented bound, 3 if the WGSL
    /// rows could not run.
    Stability {
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Only core's f64 and f32 rows (without it, no GPU adapter is exit code 3: the WGSL rows
        /// did not run).
        #[arg(long)]
        cpu_only: bool,
    },
}

/// `eval --slope-masking`: [`lodestone_core::microfacet::slope_masking::SlopeMasking`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SlopeMaskingArg {
    /// Smith's: visibility depends on the height alone.
    Smith,
    /// Conditioned on the facet's height and slope along the ray jointly (the default).
    Conditioned,
}

impl From<SlopeMaskingArg> for lodestone_core::microfacet::slope_masking::SlopeMasking {
    fn from(a: SlopeMaskingArg) -> Self {
        match a {
            SlopeMaskingArg::Smith => Self::Smith,
            SlopeMaskingArg::Conditioned => Self::Conditioned,
        }
    }
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

/// A view mode `bench` can time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BenchMode {
    /// The naive view.
    Naive,
    /// The view-independent filtered view.
    ViewIndependent,
    /// The filtered view.
    Filtered,
    /// Ground truth (one sample per pixel per frame).
    Truth,
}

impl BenchMode {
    /// Every mode, in the table's order.
    pub fn all() -> Vec<Self> {
        vec![
            Self::Naive,
            Self::ViewIndependent,
            Self::Filtered,
            Self::Truth,
        ]
    }

    /// The mode's name in the bench's JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Naive => "naive",
            Self::ViewIndependent => "view_independent",
            Self::Filtered => "filtered",
            Self::Truth => "truth",
        }
    }
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

/// Whether the analytic views' camera rays can stop on the unresolved relief of a crest they pass
/// (`lodestone_core::eval::interception::Interception`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum InterceptionArg {
    /// Rays meet h̄ only (the reference, before #17's middle-zoom work).
    Off,
    /// Rays can stop on crests (the views' default).
    Crests,
}

impl InterceptionArg {
    /// The core value.
    pub fn interception(self) -> lodestone_core::eval::interception::Interception {
        match self {
            Self::Off => lodestone_core::eval::interception::Interception::Off,
            Self::Crests => lodestone_core::eval::interception::Interception::Crests,
        }
    }
}

/// The base shape `object` displaces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ObjectShapeArg {
    /// A sphere of `--radius`.
    Sphere,
    /// A ring torus of `--radius` and `--minor` around z.
    Torus,
    /// The closed OBJ mesh of `--mesh`.
    Mesh,
}

impl ObjectShapeArg {
    /// Its name for [`crate::object_cmd::shape`].
    pub fn name(self) -> &'static str {
        match self {
            Self::Sphere => "sphere",
            Self::Torus => "torus",
            Self::Mesh => "mesh",
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

/// A finite number in `[lo, hi]` named `what`, or a message that gives the range and what was
/// typed (NaN and infinities are refused: they used to become black images or "0.00%" errors).
fn number_in(s: &str, lo: f64, hi: f64, what: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{what} must be a number, got {s:?}"))?;
    if !(lo..=hi).contains(&v) {
        return Err(format!("{what} must be between {lo} and {hi}, got {s}"));
    }
    Ok(v)
}

/// A reflectance or albedo: 0 to 1.
fn unit_fraction(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 1.0, "a reflectance")
}

/// A GGX roughness α: 0.01 to 1.
fn ggx_alpha(s: &str) -> Result<f64, String> {
    number_in(s, 0.01, 1.0, "the GGX roughness α")
}

/// A relative standard error to reach, 0.0001 to 0.5.
fn precision(s: &str) -> Result<f64, String> {
    number_in(s, 1e-4, 0.5, "relative standard error")
}

/// A camera angle from the normal: 0 to [`Camera::MAX_ELEVATION_DEG`] (89.5) degrees.
///
/// [`Camera::MAX_ELEVATION_DEG`]: lodestone_core::scene::camera::Camera::MAX_ELEVATION_DEG
pub fn view_angle(s: &str) -> Result<f64, String> {
    let max = lodestone_core::scene::camera::Camera::MAX_ELEVATION_DEG;
    number_in(s, 0.0, max, "the view angle (degrees from the normal)")
}

/// A light angle from the normal: 0 to 180 degrees (past 90 the sun is below the horizon).
pub fn light_angle(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 180.0, "the light angle (degrees from the normal)")
}

/// An azimuth: any finite angle up to ±3600 degrees.
pub fn azimuth(s: &str) -> Result<f64, String> {
    number_in(s, -3600.0, 3600.0, "the azimuth (degrees)")
}

/// A camera distance in the editor's range ([`DISTANCE_RANGE`]).
///
/// [`DISTANCE_RANGE`]: crate::editor::view_state::DISTANCE_RANGE
pub fn distance(s: &str) -> Result<f64, String> {
    let (lo, hi) = crate::editor::view_state::DISTANCE_RANGE;
    number_in(s, lo, hi, "the camera distance (world units)")
}

/// A target relative standard error in percent: 0 (none) to 100.
pub fn truth_se(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 100.0, "the truth's standard error target (percent)")
}

/// A thin lens's radius: 0 (a pinhole) to 10 world units.
pub fn lens_radius(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 10.0, "the lens radius (world units)")
}

/// An adaptive ground truth's budget: 0 (none) to 4096 rays per pixel on average.
pub fn ray_budget(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 4096.0, "the ray budget (rays per pixel)")
}

/// A cylinder radius: 0.01 to 10⁴ world units.
pub fn radius(s: &str) -> Result<f64, String> {
    number_in(s, 0.01, 1e4, "the cylinder radius (world units)")
}

/// `eval`'s ground-truth sample count: 2 (a standard error needs two) to 10⁸.
pub fn eval_samples(s: &str) -> Result<usize, String> {
    let v: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("the sample count must be a whole number, got {s:?}"))?;
    if !(2..=100_000_000).contains(&v) {
        return Err(format!(
            "the sample count must be between 2 and 100000000, got {s}"
        ));
    }
    Ok(v)
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
