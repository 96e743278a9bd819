//! The object view's compute pipeline (`shaders/object_view.wgsl` and `shaders/object/`): one cone
//! per pixel through the uploaded voxel octree [HN12 Alg. 1], masks, alpha blending or nearest
//! voxels, shadow cones toward the sun. The material's BRDF reaches the shader through its
//! `MaterialParams` (albedo, F0, roughness, the masking correlation); the shader is specialised
//! once to the features the cone tracer's shading reads (relief's masking, the specular lobe and
//! HN12's height-correlated attribute).
//!
//! Pixels whose loops the adapter cut (Mesa's per-invocation loop budget, `bindings.wgsl`) are
//! counted in [`ObjectImage::cut`]: a nonzero count says the image is not the tracer's answer.

use crate::error::RenderError;
use crate::gpu::GpuContext;
use crate::gpu_codes::CorrelationCode;
use crate::gpu_types::{MaterialParams, ObjectParams};
use crate::object::voxel_store::GpuVoxels;
use crate::shaders;
use crate::specialize::specialize;
use crate::view_target::{read_words, storage_limit};
use glam::DVec3;
use lodestone_core::material::features::{Feature, FeatureSet};
use lodestone_core::microfacet::masking_shadowing::Correlation;
use lodestone_core::object::cone_trace::Compositing;
use lodestone_core::object::coverage_mask::MaskTable;
use lodestone_core::object::object_truth::{Lens, pixel_cone};
use lodestone_core::object::shading::ObjectLighting;
use lodestone_core::scene::camera::Camera;
use wgpu::util::DeviceExt;

/// The features the object shader is specialised to.
fn object_features() -> FeatureSet {
    FeatureSet::EMPTY
        .with(Feature::Relief, true)
        .with(Feature::Specular, true)
        .with(Feature::AttributeColor, true)
}

/// The object shader's full source (specialised; see the module docs).
pub fn object_source() -> String {
    let parts = [
        shaders::SPECIAL,
        shaders::material(),
        shaders::object_bindings(),
        shaders::object(),
    ];
    specialize(&parts.join("\n"), object_features()).expect("the object shader's directives match")
}

/// The compiled object view.
#[derive(Debug)]
pub struct ObjectView {
    pipeline: wgpu::ComputePipeline,
    masks: wgpu::Buffer,
}

/// An octree on the GPU.
#[derive(Debug)]
pub struct ObjectBuffers {
    slots: wgpu::Buffer,
    voxels: wgpu::Buffer,
    half: f64,
    depth: u32,
    slot_mask: u32,
    /// Bytes uploaded (voxels and hash slots).
    pub bytes: u64,
}

/// What one object image shows.
#[derive(Clone, Copy, Debug)]
pub struct ObjectShot<'a> {
    /// The camera (its target is the object's centre).
    pub camera: &'a Camera,
    /// The sun and the base BRDF.
    pub lighting: &'a ObjectLighting,
    /// Compositing of the elements.
    pub mode: Compositing,
    /// Shadow cones.
    pub shadows: bool,
    /// Image size, pixels.
    pub size: (u32, u32),
    /// The thin lens (depth of field; [`Lens::PINHOLE`] for none).
    pub lens: Lens,
}

/// A rendered object image: linear RGB and coverage per pixel, row-major.
#[derive(Clone, Debug)]
pub struct ObjectImage {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `[r, g, b, coverage]` per pixel.
    pub pixels: Vec<[f32; 4]>,
    /// Pixels whose loops the adapter cut (0 on a complete image).
    pub cut: u32,
}

fn storage(
    ctx: &GpuContext,
    label: &str,
    bytes: &[u8],
    what: &str,
) -> Result<wgpu::Buffer, RenderError> {
    let limit = storage_limit(ctx);
    if bytes.len() as u64 > limit {
        return Err(RenderError::TooLarge {
            what: what.into(),
            bytes: bytes.len() as u64,
            limit,
            hint: "; use a shallower octree".into(),
        });
    }
    Ok(ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage: wgpu::BufferUsages::STORAGE,
        }))
}

fn v3(v: DVec3) -> [f32; 3] {
    v.as_vec3().to_array()
}

impl ObjectView {
    /// Compiles the pipeline and uploads the mask table.
    pub fn new(ctx: &GpuContext) -> Self {
        let module = ctx
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("object view"),
                source: wgpu::ShaderSource::Wgsl(object_source().into()),
            });
        let pipeline = ctx
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("object view"),
                layout: None,
                module: &module,
                entry_point: Some("object_main"),
                compilation_options: Default::default(),
                cache: None,
            });
        let table = MaskTable::new();
        let words: Vec<u32> = table
            .masks
            .iter()
            .flat_map(|m| [*m as u32, (*m >> 32) as u32])
            .collect();
        let masks = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("object masks"),
                contents: bytemuck::cast_slice(&words),
                usage: wgpu::BufferUsages::STORAGE,
            });
        Self { pipeline, masks }
    }

    /// Uploads an octree.
    pub fn upload(
        &self,
        ctx: &GpuContext,
        voxels: &GpuVoxels,
    ) -> Result<ObjectBuffers, RenderError> {
        let slot_words: Vec<u32> = voxels.slots.iter().flatten().copied().collect();
        let mut voxel_words: Vec<u32> = voxels.voxels.iter().flatten().copied().collect();
        if voxel_words.is_empty() {
            voxel_words.resize(8, 0);
        }
        let slots = storage(
            ctx,
            "object slots",
            bytemuck::cast_slice(&slot_words),
            "the octree's hash table",
        )?;
        let vox = storage(
            ctx,
            "object voxels",
            bytemuck::cast_slice(&voxel_words),
            "the octree's voxels",
        )?;
        Ok(ObjectBuffers {
            slots,
            voxels: vox,
            half: voxels.half,
            depth: voxels.depth,
            slot_mask: voxels.slots.len() as u32 - 1,
            bytes: voxels.gpu_bytes() as u64,
        })
    }

    /// Renders one image of the uploaded octree and reads it back.
    pub fn render(
        &self,
        ctx: &GpuContext,
        octree: &ObjectBuffers,
        shot: &ObjectShot,
    ) -> Result<ObjectImage, RenderError> {
        let (w, h) = (shot.size.0.max(1), shot.size.1.max(1));
        let out_bytes = u64::from(w) * u64::from(h) * 16;
        let limit = storage_limit(ctx);
        if out_bytes > limit {
            return Err(RenderError::TooLarge {
                what: format!("a {w} × {h} object image"),
                bytes: out_bytes,
                limit,
                hint: String::new(),
            });
        }
        let cam = shot.camera;
        // The camera's own affine map from pixel coordinates to ray directions, and core's cone.
        let (step_x, step_y) = cam.pixel_steps(w, h);
        let l = shot.lighting;
        let params = ObjectParams {
            eye: v3(cam.eye()),
            half: octree.half as f32,
            dir00: v3(cam.raw_dir(glam::DVec2::ZERO, w, h)),
            spread: pixel_cone(cam, 0.5, 0.5, w, h).spread as f32,
            step_x: v3(step_x),
            width: w,
            step_y: v3(step_y),
            height: h,
            light: v3(l.light),
            sun: l.sun as f32,
            depth: octree.depth,
            slot_mask: octree.slot_mask,
            mode: match shot.mode {
                Compositing::Masks => 0,
                Compositing::AlphaBlend => 1,
                Compositing::Nearest => 2,
            },
            shadows: u32::from(shot.shadows),
            two: 2,
            lens: shot.lens.radius.max(0.0) as f32,
            focus: shot.lens.focus as f32,
            ..Default::default()
        };
        let material = MaterialParams {
            albedo: l.brdf.albedo as f32,
            specular: l.brdf.specular as f32,
            roughness: l.brdf.roughness as f32,
            correlation: match l.correlation {
                Correlation::Uncorrelated => CorrelationCode::Uncorrelated,
                Correlation::HeightDirection => CorrelationCode::HeightDirection,
            }
            .code(),
            ..Default::default()
        };
        let device = &ctx.device;
        let init = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let material_buf = init(
            "object material",
            bytemuck::bytes_of(&material),
            wgpu::BufferUsages::STORAGE,
        );
        let params_buf = init(
            "object params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::STORAGE,
        );
        let cut = init(
            "object cut",
            &[0u8; 16],
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let out = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("object image"),
            size: out_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            }
        }
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("object view"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[
                entry(0, &material_buf),
                entry(4, &params_buf),
                entry(5, &octree.slots),
                entry(6, &octree.voxels),
                entry(7, &self.masks),
                entry(8, &out),
                entry(9, &cut),
            ],
        });
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("object view"),
        });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("object view"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        ctx.queue.submit([enc.finish()]);
        let words = read_words(ctx, &out, out_bytes)?;
        let cut = read_words(ctx, &cut, 16)?[0];
        let floats: &[f32] = bytemuck::cast_slice(&words);
        Ok(ObjectImage {
            width: w,
            height: h,
            pixels: floats
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
            cut,
        })
    }
}
