//! `lodestone render` and `lodestone bench`: headless GPU work.

use crate::cli::{Formats, RenderMode};
use crate::preset_io::Resolved;
use anyhow::{Context, Result, bail};
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::shape::Shape;
use lodestone_render::error_map::{abs_difference, error_stats, heat_map};
use lodestone_render::{
    GpuContext, GpuMaterial, LinearImage, Renderer, Scene, ViewMode, ViewTarget,
};
use std::path::Path;
use std::time::Instant;

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
}

impl View {
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

fn save(img: &LinearImage, path: &Path) -> Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "png" => img.to_srgb8().save(path),
        "exr" => image::DynamicImage::ImageRgba32F(img.to_linear_f32()).save(path),
        _ => bail!("unsupported output {} (use .png or .exr)", path.display()),
    }
    .with_context(|| format!("writing {}", path.display()))
}

fn save_as(img: &LinearImage, dir: &Path, name: &str, formats: Formats) -> Result<()> {
    if formats != Formats::Exr {
        save(img, &dir.join(format!("{name}.png")))?;
    }
    if formats != Formats::Png {
        save(img, &dir.join(format!("{name}.exr")))?;
    }
    Ok(())
}

pub fn renderer() -> Result<Renderer> {
    let ctx = GpuContext::new_headless()?;
    log::info!("adapter: {}", ctx.describe());
    Ok(Renderer::new(ctx))
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
    let prepared = preset.prepare()?;
    let r = renderer()?;
    let scene = view.scene();
    let gm = GpuMaterial::new(r.context(), &prepared, scene.camera.target);
    let draw = |m: ViewMode| r.render(&gm, &scene, m, size, spp);
    let draw = |m: ViewMode| -> Result<LinearImage> { Ok(draw(m)?) };
    match mode {
        RenderMode::Naive => save(&draw(ViewMode::Naive)?, out)?,
        RenderMode::ViewIndependent => save(&draw(ViewMode::ViewIndependent)?, out)?,
        RenderMode::Filtered => save(&draw(ViewMode::Filtered)?, out)?,
        RenderMode::Truth => save(&draw(ViewMode::Truth)?, out)?,
        RenderMode::Error => {
            let (f, t) = (draw(ViewMode::Filtered)?, draw(ViewMode::Truth)?);
            let s = error_stats(&f, &t);
            outln!(
                "filtered vs truth: RMSE {:.5}, max {:.5} (legend 0 … {:.5})",
                s.rmse,
                s.max,
                s.max
            );
            save(&heat_map(&f, &t, s.max), out)?;
        }
        RenderMode::All => {
            std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
            let truth = draw(ViewMode::Truth)?;
            let modes = [
                ("naive", draw(ViewMode::Naive)?),
                ("view_independent", draw(ViewMode::ViewIndependent)?),
                ("filtered", draw(ViewMode::Filtered)?),
            ];
            // One legend for every error map: the largest error of any mode.
            let scale = modes
                .iter()
                .map(|(_, i)| error_stats(i, &truth).max)
                .fold(0.0, f64::max);
            for (name, img) in &modes {
                let s = error_stats(img, &truth);
                outln!("{name:>16} vs truth: RMSE {:.5}, max {:.5}", s.rmse, s.max);
                save_as(img, out, name, formats)?;
                save(
                    &heat_map(img, &truth, scale),
                    &out.join(format!("error_{name}.png")),
                )?;
                if formats != Formats::Png {
                    save(
                        &abs_difference(img, &truth),
                        &out.join(format!("error_{name}.exr")),
                    )?;
                }
            }
            outln!(
                "error maps share the legend 0 … {scale:.5} (linear RGB), truth {spp} rays/pixel"
            );
            save_as(&truth, out, "truth", formats)?;
        }
    }
    Ok(())
}

/// Median of a list of durations in milliseconds.
fn median(mut v: Vec<f64>) -> f64 {
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

/// Median frame time of `mode` in milliseconds, after one warm-up frame (which also compiles the
/// pipeline). Throughput: batches of 8 frames submitted back to back, one wait per batch; the
/// median over `frames` batches of the mean frame time (single-frame submit/wait latency would
/// dominate on a fast GPU otherwise).
pub fn frame_ms(
    r: &Renderer,
    target: &mut ViewTarget,
    gm: &GpuMaterial,
    scene: &Scene,
    mode: ViewMode,
    frames: u32,
) -> f64 {
    const BATCH: u32 = 8;
    r.draw(target, gm, scene, mode, 1);
    r.wait();
    let mut times = vec![];
    for _ in 0..frames.max(1) {
        let t = Instant::now();
        for _ in 0..BATCH {
            r.draw(target, gm, scene, mode, 1);
        }
        r.wait();
        times.push(t.elapsed().as_secs_f64() * 1e3 / f64::from(BATCH));
    }
    median(times)
}

/// `lodestone bench`.
pub fn bench(preset: &Resolved, size: (u32, u32), frames: u32, json: bool) -> Result<()> {
    let prepared = preset.prepare()?;
    let r = renderer()?;
    let scene = View {
        view_deg: 60.0,
        view_azimuth_deg: 0.0,
        light_deg: 30.0,
        light_azimuth_deg: 90.0,
        distance: 6.0,
        shape: Shape::Plane,
    }
    .scene();
    let gm = GpuMaterial::new(r.context(), &prepared, scene.camera.target);
    let mut target = ViewTarget::new(&r, size.0, size.1);
    let mut rows = vec![];
    for (name, mode) in [
        ("naive", ViewMode::Naive),
        ("view_independent", ViewMode::ViewIndependent),
        ("filtered", ViewMode::Filtered),
        ("truth (1 ray/pixel)", ViewMode::Truth),
    ] {
        rows.push((name, frame_ms(&r, &mut target, &gm, &scene, mode, frames)));
    }
    let ratio = rows[2].1 / rows[0].1;
    let adapter = r.context().describe();
    if json {
        let modes: serde_json::Map<String, serde_json::Value> = rows
            .iter()
            .map(|(n, ms)| ((*n).to_string(), serde_json::json!(ms)))
            .collect();
        let v = serde_json::json!({
            "adapter": adapter,
            "size": [size.0, size.1],
            "frames": frames,
            "timing": "synchronised wall time per frame: median over batches of 8 back-to-back frames",
            "frame_ms": modes,
            "filtered_over_naive": ratio,
        });
        outln!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        outln!(
            "{adapter}, {}×{}, median over {frames} batches of 8 frames (synchronised wall time)",
            size.0,
            size.1
        );
        for (n, ms) in &rows {
            outln!("{n:>22}: {ms:9.2} ms");
        }
        outln!("{:>22}: {ratio:9.2}×", "filtered / naive");
    }
    Ok(())
}
