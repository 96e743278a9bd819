//! Whole objects (`lodestone object` and the editor's Object window): a whole object (sphere, torus or an OBJ mesh) displaced by the
//! preset's relief, voxelised into the sparse octree and cone traced on the CPU (core's reference),
//! and with `--gpu` in WGSL on the adapter, beside its ray-traced ground truth, over a zoom sweep.
//! For each distance: a PNG strip (nearest voxels | alpha blended | masks, HN12 | ground truth |
//! GPU masks) and a table row of the colour error of covered pixels, the silhouette's coverage
//! error and the time per pixel; with `--out`, the strips and the report as `object.md` (the table)
//! and `object.json` (every number, unrounded, with the octree's memory per level). Bad shapes,
//! meshes and materials are usage errors (exit code 2).

pub mod scene;

use crate::UsageError;
use crate::object::scene::{GpuObject, ObjectScene, masks_shot};
use anyhow::{Context, Result};
use lodestone_core::material::Material;
use lodestone_core::material::colormap::linear_to_srgb;
use lodestone_core::object::base_shape::BaseShape;
use lodestone_core::object::cone_trace::{Compositing, ConePixel, ConeTracer};
use lodestone_core::object::coverage_mask::MaskTable;
use lodestone_core::object::mesh::TriMesh;
use lodestone_core::object::object_truth::{Lens, ObjectTruth};
use lodestone_core::object::shading::ObjectLighting;
use lodestone_core::object::view_error::ObjectImages;
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The modes, in the strip's order (the truth last).
const MODES: [Compositing; 3] = [
    Compositing::Nearest,
    Compositing::AlphaBlend,
    Compositing::Masks,
];

/// What `lodestone object` was asked.
#[derive(Clone, Debug)]
pub struct Options {
    /// The base shape (a mesh already loaded).
    pub shape: BaseShape,
    /// Octree depth.
    pub depth: u32,
    /// Image size.
    pub size: (u32, u32),
    /// Camera distances from the object's centre.
    pub distances: Vec<f64>,
    /// Camera angle from +z and azimuth, degrees.
    pub view: (f64, f64),
    /// Sun angle from +z and azimuth, degrees.
    pub light: (f64, f64),
    /// Ground-truth rays per pixel.
    pub rays: usize,
    /// Output folder for the strips (none: only the table).
    pub out: Option<PathBuf>,
    /// Shadows in both the truth and the voxel views.
    pub shadows: bool,
    /// Also the masks traced in WGSL on the GPU adapter.
    pub gpu: bool,
    /// The thin lens's radius (0: a pinhole).
    pub lens: f64,
    /// The distance in focus (none: each distance's, the object's centre).
    pub focus: Option<f64>,
    /// The truth is refined until its covered mean's relative standard error is at most this
    /// (0: not refined).
    pub truth_se: f64,
    /// The most truth rays a pixel may get when refining.
    pub max_rays: usize,
}

/// The base shape named on the command line; a mesh is read and checked here.
pub fn shape(kind: &str, mesh: Option<&Path>, radius: f64, minor: f64) -> Result<BaseShape> {
    let shape = match kind {
        "sphere" => BaseShape::Sphere { radius },
        "torus" => BaseShape::Torus {
            major: radius,
            minor,
        },
        _ => {
            let path =
                mesh.ok_or_else(|| UsageError("--shape mesh needs --mesh FILE.obj".into()))?;
            let text = std::fs::read_to_string(path)
                .map_err(|e| UsageError(format!("cannot read the mesh {}: {e}", path.display())))?;
            let m = TriMesh::from_obj(&text)
                .map_err(|e| UsageError(format!("{}: {e}", path.display())))?;
            BaseShape::Mesh(Arc::new(m))
        }
    };
    shape
        .validate()
        .map_err(|e| UsageError(format!("--shape {kind}: {e}")))?;
    Ok(shape)
}

/// Builds the object and its octree, renders every distance, writes the strips; the table's text.
pub fn run(material: &Material, opts: &Options) -> Result<String> {
    let scene = ObjectScene::build(material, opts.shape.clone(), opts.depth)?;
    if let Some(out) = &opts.out {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    }
    let color = |f: f64| scene.color(f);
    let (object, field, build) = (&scene.object, &scene.field, scene.build_seconds);
    let table = MaskTable::new();
    let lighting = ObjectLighting::of_material(
        material,
        direction(opts.light.0.to_radians(), opts.light.1.to_radians()),
    );
    let tracer = ConeTracer {
        field,
        table: &table,
        lighting: &lighting,
        shadows: opts.shadows,
    };
    let truth = ObjectTruth {
        object,
        lighting: &lighting,
        color: &color,
        shadows: opts.shadows,
    };
    let gpu = if opts.gpu {
        Some(GpuObject::new(field).context("the GPU object view")?)
    } else {
        None
    };
    let mut text = String::new();
    if let Some(g) = &gpu {
        writeln!(
            text,
            "GPU: {} (octree uploaded: {:.2} MiB with its hash table)",
            g.ctx.describe(),
            g.octree.bytes as f64 / (1 << 20) as f64
        )?;
    }
    let bytes: usize = scene.memory.iter().map(|l| l.gpu_bytes).sum();
    let finest = scene.memory.last().map_or(0, |l| l.voxels);
    writeln!(
        text,
        "{}: {}, octree depth {} ({} voxels at the finest level, {:.2} MiB at {} bytes a voxel over all levels; built in {:.1} s)",
        material.name,
        kind_name(&opts.shape),
        opts.depth,
        finest,
        bytes as f64 / (1 << 20) as f64,
        lodestone_core::object::octree::GPU_BYTES_PER_VOXEL,
        build
    )?;
    let gpu_col = if gpu.is_some() { " / masks (GPU)" } else { "" };
    writeln!(
        text,
        "| distance | across | covered / silhouette px | truth's s.e. (rays a covered pixel) | mean colour error (+: brighter than the truth): nearest / alpha / masks{gpu_col} | silhouette coverage error: nearest / alpha / masks{gpu_col} | µs a pixel: nearest / alpha / masks (CPU, one core){gpu_col} |"
    )?;
    writeln!(text, "|---|---|---|---|---|---|---|")?;
    let mut rows = vec![];
    for &distance in &opts.distances {
        let camera = Camera {
            elevation_deg: opts.view.0,
            azimuth_deg: opts.view.1,
            distance,
            target: [0.0, 0.0],
            fov_deg: 30.0,
        };
        let lens = Lens {
            radius: opts.lens,
            focus: opts.focus.unwrap_or(distance),
        };
        let mut images =
            ObjectImages::render(&truth, &tracer, &camera, opts.size, opts.rays, &MODES, lens);
        if let Some(g) = &gpu {
            let shot = masks_shot(&camera, &lighting, opts.shadows, opts.size, lens);
            let (px, seconds) = g.render(&shot, true)?;
            images.views.push((Compositing::Masks, px, seconds));
        }
        if opts.truth_se > 0.0 {
            images.converge_truth(&truth, &camera, lens, opts.truth_se, opts.max_rays);
        }
        let e = images.errors();
        let covered_rays: Vec<usize> = (0..images.truth.len())
            .filter(|&i| images.truth[i].coverage >= 0.99)
            .map(|i| images.truth_rays[i])
            .collect();
        let mean_rays =
            covered_rays.iter().sum::<usize>() as f64 / covered_rays.len().max(1) as f64;
        let pixel = 2.0 * camera.tan_half_fov() / f64::from(opts.size.1);
        let across = 2.0 * object.bounding_radius() / distance / pixel;
        let touched = (e.covered + e.silhouette).max(1) as f64;
        let col = |f: &dyn Fn(&lodestone_core::object::view_error::ModeErrors) -> String| {
            e.modes.iter().map(f).collect::<Vec<_>>().join(" / ")
        };
        writeln!(
            text,
            "| {distance} | {across:.0} px | {} / {} | {:.2}% ({mean_rays:.0}) | {} | {} | {} |",
            e.covered,
            e.silhouette,
            100.0 * e.truth_error,
            col(&|m| format!("{:+.2}%", 100.0 * m.mean_color_bias)),
            if e.silhouette == 0 {
                "— (no silhouette in view)".to_string()
            } else {
                col(&|m| format!("{:.3}", m.coverage_error))
            },
            col(&|m| format!("{:.1}", 1e6 * m.seconds / touched)),
        )?;
        if let Some(out) = &opts.out {
            let path = out.join(format!("object-d{distance}.png"));
            strip(&images)
                .save(&path)
                .with_context(|| format!("writing {}", path.display()))?;
        }
        rows.push(Row {
            distance,
            across_px: across,
            lens,
            truth_rays_per_covered_pixel: mean_rays,
            errors: e,
        });
    }
    if let Some(out) = &opts.out {
        let report = Report {
            material: material.name.clone(),
            shape: kind_name(&opts.shape),
            depth: opts.depth,
            build_seconds: build,
            gpu_bytes_per_voxel: lodestone_core::object::octree::GPU_BYTES_PER_VOXEL,
            levels: scene.memory.clone(),
            gpu: gpu.as_ref().map(|g| g.ctx.describe()),
            modes: MODES
                .iter()
                .map(|m| format!("{m:?} (CPU)"))
                .chain(gpu.iter().map(|_| "Masks (GPU)".to_string()))
                .collect(),
            rows,
        };
        let json = serde_json::to_string_pretty(&report)?;
        for (name, body) in [("object.json", json.as_str()), ("object.md", text.as_str())] {
            let path = out.join(name);
            crate::preset_io::write_atomic(&path, body)
                .with_context(|| format!("writing {}", path.display()))?;
        }
    }
    Ok(text)
}

/// One distance of the sweep, as `object.json` holds it.
#[derive(serde::Serialize)]
struct Row {
    distance: f64,
    across_px: f64,
    lens: Lens,
    truth_rays_per_covered_pixel: f64,
    errors: lodestone_core::object::view_error::ViewErrors,
}

/// `object.json`: the sweep's settings and rows (the table's numbers, unrounded).
#[derive(serde::Serialize)]
struct Report {
    material: String,
    shape: &'static str,
    depth: u32,
    build_seconds: f64,
    gpu_bytes_per_voxel: usize,
    levels: Vec<lodestone_core::object::octree::LevelMemory>,
    gpu: Option<String>,
    modes: Vec<String>,
    rows: Vec<Row>,
}

fn kind_name(s: &BaseShape) -> &'static str {
    match s {
        BaseShape::Sphere { .. } => "sphere",
        BaseShape::Torus { .. } => "torus",
        BaseShape::Mesh(_) => "mesh",
    }
}

/// nearest | alpha | masks | truth (| GPU masks), side by side with 4-pixel gaps, in sRGB.
fn strip(images: &ObjectImages) -> image::RgbImage {
    let (w, h) = (images.width, images.height);
    let gap = 4;
    let cpu = MODES.len().min(images.views.len());
    let panels: Vec<&[ConePixel]> = images.views[..cpu]
        .iter()
        .map(|v| v.1.as_slice())
        .chain(std::iter::once(images.truth.as_slice()))
        .chain(images.views[cpu..].iter().map(|v| v.1.as_slice()))
        .collect();
    let mut img = image::RgbImage::from_pixel(
        panels.len() as u32 * (w + gap) - gap,
        h,
        image::Rgb([40, 40, 48]),
    );
    for (k, panel) in panels.iter().enumerate() {
        for y in 0..h {
            for x in 0..w {
                let p = panel[(y * w + x) as usize];
                let c = p
                    .color
                    .map(|v| (linear_to_srgb(v.clamp(0.0, 1.0)) * 255.0).round() as u8);
                img.put_pixel(k as u32 * (w + gap) + x, y, image::Rgb(c));
            }
        }
    }
    img
}
