//! A whole object ready to render (#19), shared by `lodestone object` and the editor's Object
//! window: the displaced surface, the material's colour of the driver, the voxel octree's field
//! and memory, and the sun with the base BRDF; plus the WGSL cone tracer with the octree uploaded.

use crate::UsageError;
use anyhow::{Context, Result};
use lodestone_core::eval::Evaluator;
use lodestone_core::material::Material;
use lodestone_core::object::base_shape::BaseShape;
use lodestone_core::object::cone_trace::{Compositing, ConePixel};
use lodestone_core::object::displaced::DisplacedObject;
use lodestone_core::object::object_truth::Lens;
use lodestone_core::object::octree::{LevelMemory, VoxelOctree};
use lodestone_core::object::shading::ObjectLighting;
use lodestone_core::object::voxel_field::VoxelField;
use lodestone_core::scene::camera::Camera;
use lodestone_render::GpuContext;
use lodestone_render::object::object_view::{ObjectBuffers, ObjectShot, ObjectView};
use lodestone_render::object::voxel_store::GpuVoxels;

/// The object, its colour and its octree.
pub struct ObjectScene {
    /// The displaced object (what the ground truth traces).
    pub object: DisplacedObject,
    /// The material prepared (its colour map of the driver).
    pub ev: Evaluator,
    /// The octree's field (what the cone tracers read).
    pub field: VoxelField,
    /// The octree's levels and their GPU bytes.
    pub memory: Vec<LevelMemory>,
    /// Seconds the octree took to build.
    pub build_seconds: f64,
}

impl std::fmt::Debug for ObjectScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ObjectScene")
            .field("shape", &self.object.shape)
            .field("levels", &self.memory.len())
            .finish_non_exhaustive()
    }
}

impl ObjectScene {
    /// Displaces `shape` by `material`'s relief and voxelises it down to `depth` (a usage error when
    /// the material or the shape cannot make an object).
    pub fn build(material: &Material, shape: BaseShape, depth: u32) -> Result<Self> {
        let object = DisplacedObject::new(material, shape)
            .map_err(|e| UsageError(format!("the object: {e}")))?;
        let ev = Evaluator::new(material).context("preparing the material")?;
        let started = std::time::Instant::now();
        let tree = VoxelOctree::of_object(&object, |f| ev.color_at(f), depth, 4.0, 1);
        let build_seconds = started.elapsed().as_secs_f64();
        Ok(Self {
            field: VoxelField::new(&tree),
            memory: tree.memory(),
            object,
            ev,
            build_seconds,
        })
    }

    /// The driver value's colour (the truth's facets).
    pub fn color(&self, f: f64) -> [f64; 3] {
        self.ev.color_at(f)
    }
}

/// The WGSL cone tracer with an octree uploaded.
#[derive(Debug)]
pub struct GpuObject {
    /// The device.
    pub ctx: GpuContext,
    view: ObjectView,
    /// The uploaded octree.
    pub octree: ObjectBuffers,
}

impl GpuObject {
    /// A device, the pipeline and `field` uploaded.
    pub fn new(field: &VoxelField) -> Result<Self> {
        let ctx = GpuContext::new_headless()?;
        let view = ObjectView::new(&ctx);
        let octree = view.upload(&ctx, &GpuVoxels::encode(field))?;
        Ok(Self { ctx, view, octree })
    }

    /// One image as cone pixels and its seconds; with `warm`, after one unmeasured frame.
    pub fn render(&self, shot: &ObjectShot, warm: bool) -> Result<(Vec<ConePixel>, f64)> {
        if warm {
            self.view.render(&self.ctx, &self.octree, shot)?;
        }
        let t = std::time::Instant::now();
        let img = self.view.render(&self.ctx, &self.octree, shot)?;
        let seconds = t.elapsed().as_secs_f64();
        if img.cut > 0 {
            log::warn!(
                "{} object pixels had their loops cut by the adapter",
                img.cut
            );
        }
        let px = img
            .pixels
            .iter()
            .map(|p| ConePixel {
                color: [0, 1, 2].map(|k| f64::from(p[k])),
                coverage: f64::from(p[3]),
                variance: [0.0; 3],
            })
            .collect();
        Ok((px, seconds))
    }
}

/// The shot of masks (ours) for `camera` and `lighting` through `lens`.
pub fn masks_shot<'a>(
    camera: &'a Camera,
    lighting: &'a ObjectLighting,
    shadows: bool,
    size: (u32, u32),
    lens: Lens,
) -> ObjectShot<'a> {
    ObjectShot {
        camera,
        lighting,
        mode: Compositing::Masks,
        shadows,
        size,
        lens,
    }
}
