//! `lodestone object`: the command's arguments, read into the sweep's [`Options`].

use crate::cli::{Context, args};
use crate::object::{self, Options};
use anyhow::Result;
use std::path::PathBuf;

/// The arguments of `lodestone object`.
#[derive(Debug, Clone, clap::Args)]
pub struct ObjectArgs {
    /// The base shape.
    #[arg(long, value_enum, default_value_t = args::ObjectShapeArg::Sphere)]
    pub shape: args::ObjectShapeArg,
    /// The closed, consistently oriented OBJ mesh of `--shape mesh`.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// The sphere's radius, or the torus's major radius (world units).
    #[arg(long, default_value_t = 1.0, value_parser = args::radius)]
    pub radius: f64,
    /// The torus's minor radius (world units, below the major; the relief may reach a quarter
    /// of the smaller of it and the hole's radius, major − minor).
    #[arg(long, default_value_t = 0.45, value_parser = args::radius)]
    pub minor: f64,
    /// Octree depth (finest voxels: the object's bounding cube over 2^depth; 2 to 10).
    #[arg(long, default_value_t = 7, value_parser = clap::value_parser!(u32).range(2..=10))]
    pub depth: u32,
    /// Image size of each panel, WxH.
    #[arg(long, default_value = "160x120", value_parser = args::parse_size)]
    pub size: (u32, u32),
    /// Camera distances from the object's centre, comma-separated (world units).
    #[arg(long, default_value = "8,4,2", value_delimiter = ',', value_parser = args::distance)]
    pub distances: Vec<f64>,
    /// Camera angle from +z, degrees (0 to 89.5).
    #[arg(long, default_value_t = 60.0, value_parser = args::view_angle)]
    pub view_deg: f64,
    /// Camera azimuth, degrees.
    #[arg(long, default_value_t = 30.0, value_parser = args::azimuth)]
    pub view_azimuth_deg: f64,
    /// Sun angle from +z, degrees (0 to 180).
    #[arg(long, default_value_t = 37.0, value_parser = args::light_angle)]
    pub light_deg: f64,
    /// Sun azimuth, degrees.
    #[arg(long, default_value_t = -37.0, value_parser = args::azimuth)]
    pub light_azimuth_deg: f64,
    /// Ground-truth rays per pixel (1 to 4096), before the truth is refined (--truth-se).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub rays: u32,
    /// Refine the truth until the covered mean's relative standard error is at most this many
    /// percent (0: no refinement; rays go where the variance is, at most --max-rays a pixel).
    #[arg(long, default_value_t = 0.5, value_parser = args::truth_se)]
    pub truth_se: f64,
    /// The most truth rays any pixel may get when refining (64 to 10⁶).
    #[arg(long, default_value_t = 16384, value_parser = clap::value_parser!(u32).range(64..=1_000_000))]
    pub max_rays: u32,
    /// Folder for the PNG strips (created if needed; none: only the table).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Leave out shadows (shadow rays in the truth, shadow cones in the voxel views) in both,
    /// to see what they carry of the error.
    #[arg(long)]
    pub no_shadows: bool,
    /// Also cone trace with masks in WGSL on the GPU adapter (a fifth panel and a column of
    /// its errors and time per pixel, measured after one warm-up frame).
    #[arg(long)]
    pub gpu: bool,
    /// Depth of field: the thin lens's radius (world units, 0 to 10; 0 is a pinhole), in the
    /// truth and as wider cones [HN12 Sec. 4.1].
    #[arg(long, default_value_t = 0.0, value_parser = args::lens_radius)]
    pub lens: f64,
    /// The distance in focus (world units; default: each distance, the object's centre).
    #[arg(long, value_parser = args::distance)]
    pub focus: Option<f64>,
}

impl ObjectArgs {
    /// The sweep these arguments ask for (the mesh read and checked).
    pub fn options(self) -> Result<Options> {
        Ok(Options {
            shadows: !self.no_shadows,
            gpu: self.gpu,
            lens: self.lens,
            focus: self.focus,
            truth_se: self.truth_se / 100.0,
            max_rays: self.max_rays as usize,
            shape: object::shape(
                self.shape.name(),
                self.mesh.as_deref(),
                self.radius,
                self.minor,
            )?,
            depth: self.depth,
            size: self.size,
            distances: self.distances,
            view: (self.view_deg, self.view_azimuth_deg),
            light: (self.light_deg, self.light_azimuth_deg),
            rays: self.rays as usize,
            out: self.out,
        })
    }
}

/// `lodestone object`'s defaults (the unit sphere, depth 7, 160 × 120, distances 8, 4, 2,
/// camera 60°/30°, sun 37°/−37°, 64 rays refined to 0.5%, shadows, CPU only, no strips):
/// what the command parses with no options.
pub fn sphere_defaults() -> Result<Options> {
    use clap::Parser;
    match crate::cli::Cli::try_parse_from(["lodestone", "object"])?.command {
        Some(crate::cli::Command::Object(a)) => a.options(),
        _ => anyhow::bail!("`lodestone object` did not parse as the object command"),
    }
}

/// Run the sweep and print its table.
pub fn run(args: ObjectArgs, ctx: &Context) -> Result<()> {
    let opts = args.options()?;
    out!("{}", object::run(&ctx.preset.material, &opts)?);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{Cli, Command};
    use clap::Parser;
    use lodestone_core::object::base_shape::BaseShape;

    /// [`sphere_defaults`] is what `lodestone object` parses with no options (the report's object
    /// section relies on it), so the two cannot drift apart.
    #[test]
    fn the_sphere_defaults_are_the_commands() {
        let Some(Command::Object(a)) = Cli::parse_from(["lodestone", "object"]).command else {
            panic!("not the object command");
        };
        let d = sphere_defaults().unwrap();
        assert_eq!(d.shape, BaseShape::Sphere { radius: a.radius });
        assert_eq!(
            (d.depth, d.size, d.distances),
            (a.depth, a.size, a.distances)
        );
        assert_eq!(d.view, (a.view_deg, a.view_azimuth_deg));
        assert_eq!(d.light, (a.light_deg, a.light_azimuth_deg));
        assert_eq!((d.rays, d.max_rays), (a.rays as usize, a.max_rays as usize));
        assert_eq!(
            (d.shadows, d.gpu, d.lens, d.focus),
            (!a.no_shadows, a.gpu, a.lens, a.focus)
        );
        assert_eq!(d.truth_se, a.truth_se / 100.0);
    }
}
