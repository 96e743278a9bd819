//! A material uploaded for the GPU: its data texture, parameters and wave table.

use crate::error::RenderError;
use crate::gpu::GpuContext;
use crate::gpu_codes::DATA_ROW;
use crate::gpu_types::MaterialParams;
use crate::material_data::{MarchTables, MaterialData, material_data_for, push_march_tables};
use crate::view::Scene;
use lodestone_core::eval::Evaluator;
use lodestone_core::material::features::FeatureSet;
use lodestone_core::scene::surface::Surface;

/// A material uploaded for the GPU: its data texture, parameters and wave table (all constant).
#[derive(Debug)]
pub struct GpuMaterial {
    /// The data's f32 words as the bits of an R32Uint texture, [`DATA_ROW`] a row (binding 1;
    /// `shaders/data_texture.wgsl`).
    pub(crate) data: wgpu::TextureView,
    pub(crate) params: wgpu::Buffer,
    /// The noise's waves as a uniform array of [`WAVE_TABLE_LEN`] `vec4`s (binding 9, zero-padded;
    /// `driver/noise.wgsl`'s `wave_table`), bound where the pipeline has the noise driver.
    pub(crate) waves: wgpu::Buffer,
    pub(crate) target: [f64; 2],
    /// The material's own features ([`FeatureSet::of_material`]).
    pub(crate) features: FeatureSet,
    /// Uploaded for the all-features pipeline (every table, drawn by the unspecialised shader).
    pub(crate) all_features: bool,
    /// Bytes per part of the data buffer.
    pub(crate) segments: Vec<(&'static str, usize)>,
    /// The explicit surface without its bound grid, to keep the eye above it
    /// ([`Surface::clear_camera`]).
    pub(crate) surface: Surface,
}

/// Bytes of material data `ctx`'s device can bind: [`DATA_ROW`] words a row, as many rows as
/// its largest 2-D texture has.
pub fn data_limit(ctx: &GpuContext) -> u64 {
    u64::from(DATA_ROW) * 4 * u64::from(ctx.device.limits().max_texture_dimension_2d)
}

/// The material's data as an R32Uint texture of [`DATA_ROW`] words a row, the last row
/// zero-padded (in place). The caller has checked the size against [`data_limit`].
pub(crate) fn data_texture(ctx: &GpuContext, mut words: Vec<f32>) -> wgpu::TextureView {
    let row = DATA_ROW as usize;
    let rows = words.len().div_ceil(row).max(1);
    words.resize(rows * row, 0.0);
    let size = wgpu::Extent3d {
        width: DATA_ROW,
        height: rows as u32,
        depth_or_array_layers: 1,
    };
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("material data"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R32Uint,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    ctx.queue.write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(&words),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(DATA_ROW * 4),
            rows_per_image: Some(rows as u32),
        },
        size,
    );
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}

/// Entries of the uniform wave table (`driver/noise.wgsl`'s `wave_table`):
/// [`lodestone_core::driver::noise::NoiseParams::MAX_COMPONENTS`] waves at most.
pub const WAVE_TABLE_LEN: usize = 256;

const _: () = assert!(
    WAVE_TABLE_LEN >= lodestone_core::driver::noise::NoiseParams::MAX_COMPONENTS as usize,
    "every wave fits the uniform table"
);

/// The uniform wave table: the waves as uploaded in the data buffer (k.x, k.y, amplitude, phase at
/// the camera target), zero-padded to [`WAVE_TABLE_LEN`] (all zero without a noise driver).
fn wave_table(data: &[f32], params: &MaterialParams) -> Vec<[f32; 4]> {
    let mut table = vec![[0.0f32; 4]; WAVE_TABLE_LEN];
    let first = params.waves_offset as usize;
    let n = (params.wave_count as usize).min(WAVE_TABLE_LEN);
    for (i, w) in table.iter_mut().enumerate().take(n) {
        if let Some(src) = data.get(first + 4 * i..first + 4 * i + 4) {
            w.copy_from_slice(src);
        }
    }
    table
}

impl GpuMaterial {
    /// Upload a prepared material with coordinates relative to `target` (the camera target), with
    /// only the data its features use ([`material_data_for`]); drawn by pipelines specialised to
    /// the material and scene. [`RenderError::TooLarge`] (and nothing created) when the data
    /// exceeds what the adapter can bind in one texture ([`data_limit`]).
    pub fn new(
        ctx: &GpuContext,
        prepared: &Evaluator,
        target: [f64; 2],
    ) -> Result<Self, RenderError> {
        Self::with_march_tables(ctx, prepared, target, MarchTables::default())
    }

    /// [`GpuMaterial::new`] with only the march tables `tables` asks for (to time the march
    /// without one).
    pub fn with_march_tables(
        ctx: &GpuContext,
        prepared: &Evaluator,
        target: [f64; 2],
        tables: MarchTables,
    ) -> Result<Self, RenderError> {
        let features = FeatureSet::of_material(&prepared.material);
        Self::upload(ctx, prepared, target, features, false, tables)
    }

    /// Upload every table the material has, to be drawn by the all-features pipeline (the
    /// reference the specialised pipelines are compared against, and the engine bundle's shader).
    pub fn all_features(
        ctx: &GpuContext,
        prepared: &Evaluator,
        target: [f64; 2],
    ) -> Result<Self, RenderError> {
        let features = FeatureSet::of_material(&prepared.material);
        Self::upload(
            ctx,
            prepared,
            target,
            features,
            true,
            MarchTables::default(),
        )
    }

    pub(crate) fn upload(
        ctx: &GpuContext,
        prepared: &Evaluator,
        target: [f64; 2],
        features: FeatureSet,
        all_features: bool,
        tables: MarchTables,
    ) -> Result<Self, RenderError> {
        let uses = if all_features {
            FeatureSet::all()
        } else {
            features
        };
        let mut d = material_data_for(prepared, target, uses);
        push_march_tables(prepared, target, uses, tables, &mut d);
        let MaterialData {
            mut data,
            params,
            segments,
        } = d;
        if data.is_empty() {
            data.push(0.0);
        }
        let limit = data_limit(ctx);
        let bytes = (data.len() * 4) as u64;
        if bytes > limit {
            let parts = segments
                .iter()
                .map(|(name, b)| format!("{name} {} MiB", b.div_ceil(1 << 20)))
                .collect::<Vec<_>>()
                .join(", ");
            return Err(RenderError::TooLarge {
                what: "the material's data".into(),
                bytes,
                limit,
                hint: format!(" ({parts}); use smaller tables or a smaller image"),
            });
        }
        let wave_words = wave_table(&data, &params);
        let data_view = data_texture(ctx, data);
        let params_buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("material params"),
            size: std::mem::size_of::<MaterialParams>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        ctx.queue
            .write_buffer(&params_buffer, 0, bytemuck::bytes_of(&params));
        let waves = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("material waves"),
            size: (WAVE_TABLE_LEN * 16) as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        ctx.queue
            .write_buffer(&waves, 0, bytemuck::cast_slice(&wave_words));
        Ok(Self {
            data: data_view,
            params: params_buffer,
            waves,
            target,
            features,
            all_features,
            segments,
            surface: Surface {
                grid: None,
                ..prepared.surface.clone()
            },
        })
    }

    /// The camera target the data was uploaded for.
    pub fn target(&self) -> [f64; 2] {
        self.target
    }

    /// The material's own features.
    pub fn features(&self) -> FeatureSet {
        self.features
    }

    /// Bytes of each part of the uploaded data.
    pub fn segments(&self) -> &[(&'static str, usize)] {
        &self.segments
    }

    /// The feature set of the pipeline that draws this material in `scene`: the material's
    /// features completed by the scene's, or every feature for [`GpuMaterial::all_features`].
    pub fn pipeline_features(&self, scene: &Scene) -> FeatureSet {
        if self.all_features {
            FeatureSet::all()
        } else {
            self.features
                .in_scene(scene.shape, scene.light.normalize())
                .normalized()
        }
    }
}
