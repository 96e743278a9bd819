//! `lodestone object` (#19): a whole object (sphere, torus or an OBJ mesh) displaced by the
//! preset's relief, voxelised into the sparse octree and cone traced on the CPU (the reference the
//! GPU views will be tested against), beside its ray-traced ground truth, over a zoom sweep. For
//! each distance: a PNG strip (nearest voxels | alpha blended | masks, HN12 | ground truth) and a
//! table row of the colour error of covered pixels, the silhouette's coverage error and the CPU
//! time per pixel. Bad shapes, meshes and materials are usage errors (exit code 2).

use crate::UsageError;
use anyhow::{Context, Result};
use lodestone_core::eval::Evaluator;
use lodestone_core::material::Material;
use lodestone_core::material::colormap::linear_to_srgb;
use lodestone_core::object::base_shape::BaseShape;
use lodestone_core::object::cone_trace::{Compositing, ConePixel, ConeTracer};
use lodestone_core::object::coverage_mask::MaskTable;
use lodestone_core::object::displaced::DisplacedObject;
use lodestone_core::object::mesh::TriMesh;
use lodestone_core::object::object_truth::ObjectTruth;
use lodestone_core::object::octree::VoxelOctree;
use lodestone_core::object::shading::ObjectLighting;
use lodestone_core::object::view_error::ObjectImages;
use lodestone_core::object::voxel_field::VoxelField;
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
    let object = DisplacedObject::new(material, opts.shape.clone())
        .map_err(|e| UsageError(format!("the object: {e}")))?;
    if let Some(out) = &opts.out {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    }
    let ev = Evaluator::new(material).context("preparing the material")?;
    let color = |f: f64| ev.color_at(f);
    let started = std::time::Instant::now();
    let tree = VoxelOctree::of_object(&object, color, opts.depth, 4.0, 1);
    let build = started.elapsed().as_secs_f64();
    let field = VoxelField::new(&tree);
    let table = MaskTable::new();
    let lighting = ObjectLighting {
        light: direction(opts.light.0.to_radians(), opts.light.1.to_radians()),
        sun: material.lighting.sun,
        brdf: material.brdf.clone(),
        correlation: material.filtering.correlation,
    };
    let tracer = ConeTracer {
        field: &field,
        table: &table,
        lighting: &lighting,
        shadows: opts.shadows,
    };
    let truth = ObjectTruth {
        object: &object,
        lighting: &lighting,
        color: &color,
        shadows: opts.shadows,
    };
    let mut text = String::new();
    let bytes: usize = tree.memory().iter().map(|l| l.gpu_bytes).sum();
    let finest = tree.memory().last().map_or(0, |l| l.voxels);
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
    writeln!(
        text,
        "| distance | across | covered / silhouette px | truth's s.e. | mean colour error: nearest / alpha / masks | silhouette coverage error: nearest / alpha / masks | µs a pixel (CPU): nearest / alpha / masks |"
    )?;
    writeln!(text, "|---|---|---|---|---|---|---|")?;
    for &distance in &opts.distances {
        let camera = Camera {
            elevation_deg: opts.view.0,
            azimuth_deg: opts.view.1,
            distance,
            target: [0.0, 0.0],
            fov_deg: 30.0,
        };
        let images = ObjectImages::render(&truth, &tracer, &camera, opts.size, opts.rays, &MODES);
        let e = images.errors();
        let pixel = 2.0 * camera.tan_half_fov() / f64::from(opts.size.1);
        let across = 2.0 * object.bounding_radius() / distance / pixel;
        let touched = (e.covered + e.silhouette).max(1) as f64;
        let col = |f: &dyn Fn(&lodestone_core::object::view_error::ModeErrors) -> String| {
            e.modes.iter().map(f).collect::<Vec<_>>().join(" / ")
        };
        writeln!(
            text,
            "| {distance} | {across:.0} px | {} / {} | {:.2}% | {} | {} | {} |",
            e.covered,
            e.silhouette,
            100.0 * e.truth_error,
            col(&|m| format!("{:.2}%", 100.0 * m.mean_color_error)),
            col(&|m| format!("{:.3}", m.coverage_error)),
            col(&|m| format!("{:.1}", 1e6 * m.seconds / touched)),
        )?;
        if let Some(out) = &opts.out {
            let path = out.join(format!("object-d{distance}.png"));
            strip(&images)
                .save(&path)
                .with_context(|| format!("writing {}", path.display()))?;
        }
    }
    Ok(text)
}

fn kind_name(s: &BaseShape) -> &'static str {
    match s {
        BaseShape::Sphere { .. } => "sphere",
        BaseShape::Torus { .. } => "torus",
        BaseShape::Mesh(_) => "mesh",
    }
}

/// nearest | alpha | masks | truth, side by side with 4-pixel gaps, in sRGB.
fn strip(images: &ObjectImages) -> image::RgbImage {
    let (w, h) = (images.width, images.height);
    let gap = 4;
    let panels: Vec<&[ConePixel]> = images
        .views
        .iter()
        .map(|v| v.1.as_slice())
        .chain(std::iter::once(images.truth.as_slice()))
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
