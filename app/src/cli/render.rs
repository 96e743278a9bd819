//! `lodestone render` and `lodestone bench`: headless GPU work.

use crate::UsageError;
use crate::cli::Context;
use crate::cli::args;
use crate::cli::args::{Formats, RenderMode};
use crate::cli::check_output;
use crate::preset_io::Resolved;
use anyhow::{Context as _, Result, bail};
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::march::March;
use lodestone_core::scene::shape::Shape;
use lodestone_render::error_map::{
    abs_difference, error_stats, heat_gradient, heat_map, with_legend,
};
use lodestone_render::truth_noise::{BlockErrors, SampleMoments, TruthEstimate};
use lodestone_render::{
    GpuContext, GpuMaterial, LinearImage, Renderer, Scene, ViewMode, ViewTarget,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The arguments of `lodestone render`.
#[derive(Debug, Clone, clap::Args)]
pub struct RenderArgs {
    /// naive, view-independent, filtered, truth, error (filtered against truth) or all.
    #[arg(long, value_enum, default_value_t = args::RenderMode::All)]
    pub mode: args::RenderMode,
    /// Camera angle from the normal, degrees (0 to 89.5).
    #[arg(long, default_value_t = 60.0, value_parser = args::view_angle)]
    pub view_deg: f64,
    /// Camera azimuth, degrees.
    #[arg(long, default_value_t = 0.0, value_parser = args::azimuth)]
    pub view_azimuth_deg: f64,
    /// Light angle from the normal, degrees (0 to 180; past 90 the sun is below the horizon).
    #[arg(long, default_value_t = 30.0, value_parser = args::light_angle)]
    pub light_deg: f64,
    /// Light azimuth, degrees.
    #[arg(long, default_value_t = 90.0, value_parser = args::azimuth)]
    pub light_azimuth_deg: f64,
    /// Camera distance to its target (world units, 0.02 to 5000, as in the editor); features
    /// are about 1 unit across.
    #[arg(long, default_value_t = 6.0, value_parser = args::distance)]
    pub distance: f64,
    /// Image size, WxH.
    #[arg(long, default_value = "512x384", value_parser = args::parse_size)]
    pub size: (u32, u32),
    /// The object: the plane, or a cylinder whose top line passes through the camera target.
    #[arg(long, value_enum, default_value_t = args::ShapeArg::Plane)]
    pub shape: args::ShapeArg,
    /// Radius of the cylinder (world units, 0.01 to 10⁴).
    #[arg(long, default_value_t = 2.0, value_parser = args::radius)]
    pub radius: f64,
    /// Ground-truth rays per pixel (1 to 65536).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub spp: u32,
    /// Output: a .png or .exr file, or a directory for `--mode all`.
    #[arg(long)]
    pub out: PathBuf,
    /// args::Formats written by `--mode all`.
    #[arg(long, value_enum, default_value_t = args::Formats::Both)]
    pub formats: args::Formats,
    /// How the ray marches step and refine a crossing (the reference stays selectable).
    #[arg(long, value_enum, default_value_t = args::MarchArg::Fast)]
    pub march: args::MarchArg,
    /// Side of the pixel blocks on whose means errors are also measured against the truth
    /// with its own Monte Carlo noise taken out (`error` and `all`; 1 = per pixel).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub error_block: u32,
    /// Trace again, alone, the ground-truth rays whose loops a software adapter (llvmpipe)
    /// cut short, so they get the march's own answer instead of being counted as unreliable
    /// (slow near the horizon: those rays skim the relief for thousands of steps).
    #[arg(long)]
    pub retry_cut_rays: bool,
}

/// Render the views the arguments ask for, after checking where they go.
pub fn run(args: RenderArgs, ctx: &Context) -> Result<()> {
    let shape = args.shape.shape(args.radius).map_err(UsageError)?;
    check_output(&args.out, args.mode == args::RenderMode::All)?;
    let view = View {
        view_deg: args.view_deg,
        view_azimuth_deg: args.view_azimuth_deg,
        light_deg: args.light_deg,
        light_azimuth_deg: args.light_azimuth_deg,
        distance: args.distance,
        shape,
        march: args.march.march(),
        error_block: args.error_block,
        retry_cut_rays: args.retry_cut_rays,
    };
    render(
        &ctx.preset,
        view,
        args.mode,
        args.size,
        args.spp,
        &args.out,
        args.formats,
    )
}

/// Camera and light settings from the command line.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// Camera angle from the normal (degrees).
    pub view_deg: f64,
    /// Camera azimuth (degrees).
    pub view_azimuth_deg: f64,
    /// Light angle from the normal (degrees).
    pub light_deg: f64,
    /// Light azimuth (degrees).
    pub light_azimuth_deg: f64,
    /// Camera distance.
    pub distance: f64,
    /// The object.
    pub shape: Shape,
    /// How the marches refine a crossing.
    pub march: March,
    /// Side of the pixel blocks on whose means errors against the truth are also measured with
    /// its own noise taken out (`lodestone_render::truth_noise`).
    pub error_block: u32,
    /// Trace cut ground-truth rays again alone (`Renderer::set_retry_cut`).
    pub retry_cut_rays: bool,
}

impl View {
    /// The measurement view of `bench` and `dolly`: the plane seen from `view_deg` at azimuth 0 and
    /// `distance`, light 30° from the normal at azimuth 90°, the fast march.
    pub fn measurement(view_deg: f64, distance: f64) -> Self {
        Self {
            view_deg,
            view_azimuth_deg: 0.0,
            light_deg: 30.0,
            light_azimuth_deg: 90.0,
            distance,
            shape: Shape::Plane,
            march: March::Fast,
            error_block: 8,
            retry_cut_rays: false,
        }
    }

    /// The scene: camera on the plane's origin, light from the given angles.
    pub fn scene(&self) -> Scene {
        let camera = Camera {
            elevation_deg: self.view_deg.clamp(0.0, Camera::MAX_ELEVATION_DEG),
            azimuth_deg: self.view_azimuth_deg,
            distance: self.distance.max(1e-3),
            target: [0.0, 0.0],
            fov_deg: 35.0,
        };
        let light = direction(
            self.light_deg.clamp(0.0, 90.0).to_radians(),
            self.light_azimuth_deg.to_radians(),
        );
        Scene {
            camera,
            light,
            shape: self.shape,
        }
    }
}

/// The image encoded as `ext` ("png": sRGB 8-bit, "exr": linear f32), in memory.
fn encode(img: &LinearImage, ext: &str) -> Result<Vec<u8>> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    match ext {
        "png" => img.to_srgb8().write_to(&mut bytes, image::ImageFormat::Png),
        "exr" => image::DynamicImage::ImageRgba32F(img.to_linear_f32())
            .write_to(&mut bytes, image::ImageFormat::OpenExr),
        _ => bail!("unsupported output format .{ext} (use .png or .exr)"),
    }
    .with_context(|| format!("encoding {ext}"))?;
    Ok(bytes.into_inner())
}

/// Write one image atomically (an interrupted run leaves the old file or none, never half a file).
fn save(img: &LinearImage, path: &Path) -> Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let bytes = encode(img, &ext).with_context(|| format!("writing {}", path.display()))?;
    crate::preset_io::write_atomic_bytes(path, &bytes)?;
    Ok(())
}

/// `name.png` and/or `name.exr`, encoded, for a set written at once.
fn encoded_as(
    img: &LinearImage,
    name: &str,
    formats: Formats,
    set: &mut Vec<(String, Vec<u8>)>,
) -> Result<()> {
    if formats != Formats::Exr {
        set.push((format!("{name}.png"), encode(img, "png")?));
    }
    if formats != Formats::Png {
        set.push((format!("{name}.exr"), encode(img, "exr")?));
    }
    Ok(())
}

pub fn renderer() -> Result<Renderer> {
    let ctx = GpuContext::new_headless()?;
    log::info!("adapter: {}", ctx.describe());
    Ok(Renderer::new(ctx))
}

/// "beyond truth noise: RMSE …" of block errors against the truth, or why it is unknown.
fn noise_line(b: Option<&BlockErrors>) -> String {
    match b {
        Some(b) => {
            let (lo, hi) = b.rmse_range(2.0);
            format!(
                "beyond truth noise on {k}×{k} blocks: RMSE {:.5} ({lo:.5}–{hi:.5}), {:.0}% of blocks significant",
                b.rmse(),
                b.significant_fraction() * 100.0,
                k = b.block
            )
        }
        None => "truth noise unknown (fewer than 2 rays per pixel)".to_string(),
    }
}

/// `lodestone render`.
pub fn render(
    preset: &Resolved,
    view: View,
    mode: RenderMode,
    size: (u32, u32),
    spp: u32,
    out: &Path,
    formats: Formats,
) -> Result<()> {
    let mut prepared = preset.prepare()?;
    prepared.surface.march = view.march;
    let mut r = renderer()?;
    r.set_retry_cut(view.retry_cut_rays);
    let scene = view.scene();
    let gm = GpuMaterial::new(r.context(), &prepared, scene.camera.target)?;
    let draw = |m: ViewMode| r.render(&gm, &scene, m, size, spp);
    let draw = |m: ViewMode| -> Result<LinearImage> { Ok(draw(m)?) };
    // Ground truth with its per-pixel squared sums (its own noise).
    let draw_truth = || -> Result<(LinearImage, SampleMoments)> {
        let mut t = ViewTarget::new(&r, size.0, size.1)?;
        r.draw(&mut t, &gm, &scene, ViewMode::Truth, spp);
        t.warn_if_cut(&r, ViewMode::Truth);
        Ok((t.read(&r)?, t.read_moments(&r)?))
    };
    // The block errors of `img` against the truth (None while its noise is unknown).
    let blocks_of = |img: &LinearImage, truth: &LinearImage, moments: &SampleMoments| {
        TruthEstimate::new(truth, moments).and_then(|t| BlockErrors::new(img, &t, view.error_block))
    };
    match mode {
        RenderMode::Naive => save(&draw(ViewMode::Naive)?, out)?,
        RenderMode::ViewIndependent => save(&draw(ViewMode::ViewIndependent)?, out)?,
        RenderMode::Filtered => save(&draw(ViewMode::Filtered)?, out)?,
        RenderMode::Truth => save(&draw(ViewMode::Truth)?, out)?,
        RenderMode::Error => {
            let (f, (t, tm)) = (draw(ViewMode::Filtered)?, draw_truth()?);
            let s = error_stats(&f, &t);
            outln!(
                "filtered vs truth: RMSE {:.5}, max {:.5} (legend 0 … {:.5}); {}",
                s.rmse,
                s.max,
                s.max,
                noise_line(blocks_of(&f, &t, &tm).as_ref())
            );
            save(&heat_map(&f, &t, s.max), out)?;
        }
        RenderMode::All => {
            let (truth, moments) = draw_truth()?;
            let modes = [
                ("naive", draw(ViewMode::Naive)?),
                ("view_independent", draw(ViewMode::ViewIndependent)?),
                ("filtered", draw(ViewMode::Filtered)?),
            ];
            // The error maps compare block means against the truth with its noise taken out
            // (blocks within the noise grey), as the editor does; per pixel while the truth's
            // noise is unknown (one ray). One legend for every map: the largest error of any mode.
            let blocks: Vec<Option<BlockErrors>> = modes
                .iter()
                .map(|(_, i)| blocks_of(i, &truth, &moments))
                .collect();
            let scale = modes
                .iter()
                .zip(&blocks)
                .map(|((_, i), b)| match b {
                    Some(b) => b.blocks.iter().map(|k| k.max_abs()).fold(0.0, f64::max),
                    None => error_stats(i, &truth).max,
                })
                .fold(0.0, f64::max);
            // Every file is encoded first and the set written at once (staged, then renamed):
            // an interrupted run leaves the previous set, never a mix.
            let mut set = Vec::new();
            for ((name, img), block) in modes.iter().zip(&blocks) {
                let s = error_stats(img, &truth);
                outln!(
                    "{name:>16} vs truth: RMSE {:.5}, max {:.5}; {}",
                    s.rmse,
                    s.max,
                    noise_line(block.as_ref())
                );
                encoded_as(img, name, formats, &mut set)?;
                let heat = match block {
                    Some(b) => with_legend(b.heat(img.width, img.height, &heat_gradient(), scale)),
                    None => heat_map(img, &truth, scale),
                };
                set.push((format!("error_{name}.png"), encode(&heat, "png")?));
                if formats != Formats::Png {
                    set.push((
                        format!("error_{name}.exr"),
                        encode(&abs_difference(img, &truth), "exr")?,
                    ));
                }
            }
            outln!(
                "error maps ({}) share the legend 0 … {scale:.5} (linear RGB), truth {spp} rays/pixel",
                if blocks.iter().all(Option::is_some) {
                    format!(
                        "means of {k}×{k} blocks, grey within the truth's noise",
                        k = view.error_block
                    )
                } else {
                    "per pixel".to_string()
                }
            );
            encoded_as(&truth, "truth", formats, &mut set)?;
            crate::preset_io::write_set(out, &set)?;
        }
    }
    Ok(())
}

/// Median of a list of durations in milliseconds.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        0.0
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Median frame times in milliseconds of several (material, mode) cases, after one warm-up frame
/// each (which also compiles the pipeline). Throughput: batches of 8 frames submitted back to
/// back, one wait per batch; the median over `frames` batches of the mean frame time (single-frame
/// submit/wait latency would dominate on a fast GPU otherwise). The batches are interleaved round by round
/// (case 1, case 2, …, case 1, …): a machine that slows down or speeds up during the run shifts
/// every case alike, so the ratios between them hold (on the shared 2-core machine, timing the
/// cases one after the other moved a ratio by 40% between runs).
pub fn frame_ms_interleaved(
    r: &Renderer,
    target: &mut ViewTarget,
    cases: &[(&GpuMaterial, ViewMode)],
    scene: &Scene,
    frames: u32,
) -> Vec<f64> {
    const BATCH: u32 = 8;
    for (gm, mode) in cases {
        target.reset();
        r.draw(target, gm, scene, *mode, 1);
        r.wait();
    }
    let mut times = vec![vec![]; cases.len()];
    for _ in 0..frames.max(1) {
        for ((gm, mode), case_times) in cases.iter().zip(&mut times) {
            target.reset();
            let t = Instant::now();
            for _ in 0..BATCH {
                r.draw(target, gm, scene, *mode, 1);
            }
            r.wait();
            case_times.push(t.elapsed().as_secs_f64() * 1e3 / f64::from(BATCH));
        }
    }
    times.into_iter().map(median).collect()
}
