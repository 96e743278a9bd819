//! `lodestone report`: error against run time for every method, as tables and charts, with the
//! adaptive ground truth's gains and, on request, the whole object's voxel views.

use crate::cli::{Context, args, check_output};
use crate::{preset_io, report};
use anyhow::Result;
use std::path::PathBuf;

/// The arguments of `lodestone report`.
#[derive(Debug, Clone, clap::Args)]
pub struct ReportArgs {
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Image size WIDTHxHEIGHT of every rendering.
    #[arg(long, default_value = "64x40", value_parser = args::parse_size)]
    pub size: (u32, u32),
    /// Rays per pixel of the reference (1 to 65536).
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub reference_spp: u32,
    /// View angles from the normal, degrees (comma-separated, each 0 to 89.5).
    #[arg(long, default_value = "0,30,60,75,85,89", value_delimiter = ',', value_parser = args::view_angle)]
    pub views: Vec<f64>,
    /// Camera distances, one per zoom level (comma-separated, each 0.02 to 5000).
    #[arg(long, default_value = "1.5,6,40", value_delimiter = ',', value_parser = args::distance)]
    pub zooms: Vec<f64>,
    /// Timing repeats (the median is reported; 1 to 1000).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeats: u32,
    /// How the ray marches step and refine a crossing (the reference stays selectable).
    #[arg(long, value_enum, default_value_t = args::MarchArg::Fast)]
    pub march: args::MarchArg,
    /// Ray budgets of the adaptive ground truth, rays per pixel on average (comma-separated,
    /// each 1 to 4096; "0" leaves it out).
    #[arg(long, default_value = "4,16,64", value_delimiter = ',', value_parser = args::ray_budget)]
    pub adaptive_rpp: Vec<f64>,
    /// Trace again, alone, the ground-truth rays whose loops a software adapter (llvmpipe)
    /// cut short, so they get the march's own answer instead of being counted as unreliable
    /// (slow near the horizon: those rays skim the relief for thousands of steps).
    #[arg(long)]
    pub retry_cut_rays: bool,
    /// The object every configuration views: the plane, or a cylinder whose top line passes
    /// through the camera target.
    #[arg(long, value_enum, default_value_t = args::ShapeArg::Plane)]
    pub shape: args::ShapeArg,
    /// Radius of the cylinder (world units, 0.01 to 10⁴).
    #[arg(long, default_value_t = 2.0, value_parser = args::radius)]
    pub radius: f64,
    /// Also compare the whole-object views (nearest voxels, alpha blended, masks, ground
    /// truth) on the unit sphere at these camera distances (comma-separated, each 0.02 to
    /// 5000), at the report's size and with `lodestone object`'s defaults otherwise: a section
    /// of report.md and its strips in OUT/objects. Empty (the default) leaves it out.
    #[arg(long, value_delimiter = ',', value_parser = args::distance)]
    pub object_distances: Vec<f64>,
    /// The sphere's octree depth for `--object-distances` (2 to 10).
    #[arg(long, default_value_t = 7, value_parser = clap::value_parser!(u32).range(2..=10))]
    pub object_depth: u32,
}

/// Render the report, write it into `--out`, and print its markdown.
pub fn run(args: ReportArgs, ctx: &Context) -> Result<()> {
    let out = &args.out;
    check_output(out, true)?;
    let shape = args.shape.shape(args.radius).map_err(anyhow::Error::msg)?;
    let opts = report::Options {
        size: args.size,
        reference_spp: args.reference_spp,
        views: args.views,
        zooms: args.zooms,
        repeats: args.repeats,
        march: args.march.march(),
        adaptive: args.adaptive_rpp.into_iter().filter(|b| *b > 0.0).collect(),
        retry_cut_rays: args.retry_cut_rays,
        shape,
    };
    let rep = report::run(&ctx.preset, &opts)?;
    report::write(&rep, out)?;
    out!("{}", report::markdown(&rep));
    if !args.object_distances.is_empty() {
        // The whole object: `lodestone object`'s sweep on the unit sphere, its table appended
        // to report.md.
        let depth = args.object_depth;
        let sweep = crate::object::Options {
            depth,
            size: args.size,
            distances: args.object_distances,
            out: Some(out.join("objects")),
            ..crate::cli::object::sphere_defaults()?
        };
        let table = crate::object::run(&ctx.preset.material, &sweep)?;
        let section = format!(
            "\n## Whole object: voxel views against ground truth\n\n\
             `lodestone object` on the unit sphere, octree depth {depth}, at the \
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
    Ok(())
}
