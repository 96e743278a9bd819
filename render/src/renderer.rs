//! The plane scene rendered under every view mode by one compute pass per frame, with readback to
//! linear f32 and 8-bit sRGB images. One accumulation target per view.

use crate::gpu::GpuContext;
use crate::gpu_codes::{
    ColorCode, CombineCode, CorrelationCode, DriverCode, HeightFilterCode, MarchCode, ModeCode,
    ShapeCode, TransferCode,
};
use crate::gpu_types::{MaterialParams, ViewParams};
use crate::specialize::{SpecializeError, view_source_for};
use crate::truth_noise::SampleMoments;
use glam::{DVec2, DVec3};
use lodestone_core::driver::field::{DriverField, TiledImage};
use lodestone_core::driver::noise::SumOfSines;
use lodestone_core::eval::Evaluator;
use lodestone_core::eval::compiled::CompiledTransfer;
use lodestone_core::eval::interception::Interception;
use lodestone_core::eval::mixture_bins::conditioned_slope_rule;
use lodestone_core::material::color_terms::CombineMode;
use lodestone_core::material::colormap::linear_to_srgb;
use lodestone_core::material::features::{Feature, FeatureSet};
use lodestone_core::material::preconvolved::PreconvolvedTable;
use lodestone_core::material::transfer::TransferFunction;
use lodestone_core::material::{ColorModel, ColorSource};
use lodestone_core::math::piecewise::PiecewisePoly;
use lodestone_core::microfacet::effective_height::{EffectiveHeightTable, HeightFilter};
use lodestone_core::microfacet::height_mixture::bin_slope_points;
use lodestone_core::microfacet::masking_shadowing::Correlation;
use lodestone_core::microfacet::slope_density::NoiseSlopes;
use lodestone_core::microfacet::slope_rule::SlopeRule;
use lodestone_core::scene::bound_grid::BoundGrid;
use lodestone_core::scene::camera::{Camera, PIXEL_SIGMA};
use lodestone_core::scene::field_grid::{FIELD_MARGIN_F32, FieldGrid};
use lodestone_core::scene::march::March;
use lodestone_core::scene::shape::Shape;
use lodestone_core::scene::surface::Surface;
use std::collections::HashMap;
use std::f64::consts::TAU;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

/// Errors while rendering.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The GPU could not hand the image back (device lost, out of memory, …).
    #[error("reading the image back from the GPU failed: {0}")]
    Readback(String),
    /// A buffer would exceed what the adapter can bind (checked before anything is created).
    #[error(
        "{what} needs {} MiB, more than this adapter can bind ({} MiB){hint}",
        bytes.div_ceil(1 << 20),
        limit >> 20
    )]
    TooLarge {
        /// What the buffer is for.
        what: String,
        /// Bytes it needs.
        bytes: u64,
        /// The adapter's limit in bytes.
        limit: u64,
        /// What to do about it ("; at most … pixels" for an image), or empty.
        hint: String,
    },
}

/// The most ground-truth rays one chunk of [`Renderer::draw_planned`] traces (its scratch buffer
/// holds 16 bytes a ray: 4 MiB), and the most rays one call adds to a pixel.
pub const PLANNED_CHUNK: u32 = 1 << 18;

/// Bytes per pixel of a view target's accumulation buffer (linear RGB + sample count, f32).
pub const BYTES_PER_PIXEL: u64 = 16;

/// The most bytes one storage buffer may hold on `ctx`'s device: the smaller of its binding and
/// buffer size limits.
pub fn storage_limit(ctx: &GpuContext) -> u64 {
    let l = ctx.device.limits();
    l.max_storage_buffer_binding_size.min(l.max_buffer_size)
}

/// The most pixels a [`ViewTarget`] may have on `ctx`'s device.
pub fn max_pixels(ctx: &GpuContext) -> u64 {
    storage_limit(ctx) / BYTES_PER_PIXEL
}

/// What a view shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ViewMode {
    /// Colour map of the filtered driver, filtered normal, no masking [HNPN14 Sec. 9].
    Naive,
    /// Exact footprint average of the colour, no masking.
    ViewIndependent,
    /// The papers' filtering.
    Filtered,
    /// Ray-traced explicit micro-geometry.
    Truth,
}

impl ViewMode {
    fn code(self) -> u32 {
        match self {
            Self::Naive => ModeCode::Naive,
            Self::ViewIndependent => ModeCode::ViewIndependent,
            Self::Filtered => ModeCode::Filtered,
            Self::Truth => ModeCode::Truth,
        }
        .code()
    }
}

/// Camera, light and object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// Unit direction toward the light.
    pub light: DVec3,
    /// The object: the plane, or a cylinder.
    pub shape: Shape,
}

/// A linear-RGB image; `pixels[i][3]` is the sample count (1 for the analytic views).
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Row-major RGB + weight.
    pub pixels: Vec<[f32; 4]>,
}

impl LinearImage {
    /// Linear RGB of pixel (x, y), divided by its weight.
    pub fn rgb(&self, x: u32, y: u32) -> [f32; 3] {
        let p = self.pixels[(y * self.width + x) as usize];
        let w = if p[3] > 0.0 { p[3] } else { 1.0 };
        [p[0] / w, p[1] / w, p[2] / w]
    }

    /// 8-bit sRGB, opaque.
    pub fn to_srgb8(&self) -> image::RgbaImage {
        image::RgbaImage::from_fn(self.width, self.height, |x, y| {
            let c = self
                .rgb(x, y)
                .map(|v| (linear_to_srgb(f64::from(v)) * 255.0).round() as u8);
            image::Rgba([c[0], c[1], c[2], 255])
        })
    }

    /// Linear RGBA f32 (alpha 1), for EXR.
    pub fn to_linear_f32(&self) -> image::Rgba32FImage {
        image::Rgba32FImage::from_fn(self.width, self.height, |x, y| {
            let c = self.rgb(x, y);
            image::Rgba([c[0], c[1], c[2], 1.0])
        })
    }
}

/// Offsets (in f32 units) of each table in the material's data buffer.
#[derive(Clone, Copy, Debug, Default)]
struct Layout {
    waves: u32,
    color_table: u32,
    transfer_table: u32,
    dh: u32,
    slope_rule: u32,
    color_poly: u32,
    transfer_poly: u32,
}

/// A material uploaded for the GPU: its data texture, parameters and wave table (all constant).
#[derive(Debug)]
pub struct GpuMaterial {
    /// The data's f32 words as the bits of an R32Uint texture, [`DATA_ROW`] a row (binding 1;
    /// `shaders/data_texture.wgsl`).
    data: wgpu::TextureView,
    params: wgpu::Buffer,
    /// The noise's waves as a uniform array of [`WAVE_TABLE_LEN`] `vec4`s (binding 9, zero-padded;
    /// `driver/noise.wgsl`'s `wave_table`), bound where the pipeline has the noise driver.
    waves: wgpu::Buffer,
    target: [f64; 2],
    /// The material's own features ([`FeatureSet::of_material`]).
    features: FeatureSet,
    /// Uploaded for the all-features pipeline (every table, drawn by the unspecialised shader).
    all_features: bool,
    /// Bytes per part of the data buffer.
    segments: Vec<(&'static str, usize)>,
    /// The explicit surface without its bound grid, to keep the eye above it
    /// ([`Surface::clear_camera`]).
    surface: Surface,
}

/// Words of the material's data per row of its texture (a power of two; `DATA_ROW` in WGSL).
pub const DATA_ROW: u32 = 4096;

const _: () = assert!(DATA_ROW.is_power_of_two());

/// Bytes of material data `ctx`'s device can bind: [`DATA_ROW`] words a row, as many rows as
/// its largest 2-D texture has.
pub fn data_limit(ctx: &GpuContext) -> u64 {
    u64::from(DATA_ROW) * 4 * u64::from(ctx.device.limits().max_texture_dimension_2d)
}

/// The material's data as an R32Uint texture of [`DATA_ROW`] words a row, the last row
/// zero-padded (in place). The caller has checked the size against [`data_limit`].
fn data_texture(ctx: &GpuContext, mut words: Vec<f32>) -> wgpu::TextureView {
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

/// One view's render target: an accumulation buffer (linear RGB + sample count per pixel), ground
/// truth's sums of squared samples beside it, and its own view parameters, so several views can be
/// drawn in one submission without sharing state.
#[derive(Debug)]
pub struct ViewTarget {
    width: u32,
    height: u32,
    accum: wgpu::Buffer,
    moments: wgpu::Buffer,
    view: wgpu::Buffer,
    /// The ray entries and pixel runs of [`Renderer::draw_planned`] (binding 5; 8 bytes each,
    /// grown on first use).
    order: wgpu::Buffer,
    /// Their rays' colours (binding 6; 16 bytes an entry).
    scratch: wgpu::Buffer,
    /// The pixels or rays whose march had a loop cut by the adapter (binding 7, one u32).
    cut: wgpu::Buffer,
    /// Ground truth's work per pixel (binding 8, one u32 each: the view shader's `work_sum`).
    work: wgpu::Buffer,
    /// Ground-truth rays per pixel accumulated so far (the most any pixel has, after
    /// [`Renderer::draw_planned`]).
    pub samples: u32,
    /// Rays per pixel after [`Renderer::draw_planned`]; `None` after [`Renderer::draw`].
    planned: Option<Vec<u32>>,
}

/// Map a finished `MAP_READ` buffer and copy it out as 32-bit words (waits for the GPU).
/// A storage buffer the view shader writes and the CPU can clear and read back.
fn readable_storage(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The first `bytes` of `src` as u32 words (waits for the GPU).
pub(crate) fn read_words(
    ctx: &GpuContext,
    src: &wgpu::Buffer,
    bytes: u64,
) -> Result<Vec<u32>, RenderError> {
    let device = &ctx.device;
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("readback"),
    });
    enc.copy_buffer_to_buffer(src, 0, &readback, 0, bytes);
    ctx.queue.submit([enc.finish()]);
    map_words(ctx, &readback)
}

fn map_words(ctx: &GpuContext, readback: &wgpu::Buffer) -> Result<Vec<u32>, RenderError> {
    let slice = readback.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    match rx.recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(RenderError::Readback(e.to_string())),
        Err(e) => return Err(RenderError::Readback(e.to_string())),
    }
    let view = slice
        .get_mapped_range()
        .map_err(|e| RenderError::Readback(format!("{e:?}")))?;
    Ok(bytemuck::cast_slice(&view).to_vec())
}

/// The `order` (8 bytes an entry) and `scratch` (16 bytes an entry) buffers of a planned ground
/// truth for `entries` entries.
fn plan_buffers(device: &wgpu::Device, entries: usize) -> (wgpu::Buffer, wgpu::Buffer) {
    let make = |label, bytes: u64, usage| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | usage,
            mapped_at_creation: false,
        })
    };
    let n = entries.max(1) as u64;
    (
        make("plan entries", n * 8, wgpu::BufferUsages::COPY_DST),
        make("plan rays", n * 16, wgpu::BufferUsages::empty()),
    )
}

impl ViewTarget {
    /// A target of `width × height` pixels, or [`RenderError::TooLarge`] when its accumulation
    /// buffer would exceed what the adapter can bind ([`max_pixels`]): nothing is created then.
    pub fn new(renderer: &Renderer, width: u32, height: u32) -> Result<Self, RenderError> {
        let device = &renderer.ctx.device;
        let (width, height) = (width.max(1), height.max(1));
        let bytes = u64::from(width) * u64::from(height) * BYTES_PER_PIXEL;
        let limit = storage_limit(&renderer.ctx);
        if bytes > limit {
            let side = ((limit / BYTES_PER_PIXEL) as f64).sqrt().floor();
            return Err(RenderError::TooLarge {
                what: format!("an image of {width}×{height} pixels"),
                bytes,
                limit,
                hint: format!(
                    "; at most {} pixels here, e.g. {side}×{side}",
                    limit / BYTES_PER_PIXEL
                ),
            });
        }
        let accum = readable_storage(device, "accumulation", bytes);
        let moments = readable_storage(device, "truth moments", bytes);
        let view = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("view params"),
            size: std::mem::size_of::<ViewParams>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (order, scratch) = plan_buffers(device, 1);
        let cut = readable_storage(device, "cut loops", 16);
        let work = readable_storage(
            device,
            "work per pixel",
            (u64::from(width) * u64::from(height) * 4).max(16),
        );
        Ok(Self {
            width,
            height,
            accum,
            moments,
            view,
            order,
            scratch,
            cut,
            work,
            samples: 0,
            planned: None,
        })
    }

    /// Start accumulating afresh (the next ground-truth frame overwrites instead of adding).
    pub fn reset(&mut self) {
        self.samples = 0;
        self.planned = None;
    }

    /// The pixels (analytic modes) or ground-truth rays whose march had a loop cut short since
    /// the target last started (waits for the GPU). Mesa's software adapters (llvmpipe,
    /// lavapipe) leave any loop of a shader after 65535 iterations over one SIMD batch of
    /// invocations, silently; a long march near the horizon can reach that, and its answer is
    /// then not the march's. Counted rays are still in the image: a count above 0 says how many
    /// of its values are unreliable. Real GPUs have no such cap: 0 there, bar a march that ran out
    /// of its 20000 steps.
    pub fn cut_count(&self, renderer: &Renderer) -> Result<u32, RenderError> {
        let words = read_words(&renderer.ctx, &self.cut, 16)?;
        Ok(words.first().copied().unwrap_or(0))
    }

    /// Ground truth's work per pixel since the target last started (waits for the GPU): the sum
    /// over the pixel's rays of each ray's march steps plus its waves summed in eights (the view
    /// shader's `work`). Divided by the pixel's rays it is what one more ray there costs, in
    /// units comparable across pixels of one material ([`crate::adaptive_truth`]'s cost-aware
    /// counts). Row-major; rays traced again after a loop cut are not counted.
    pub fn read_work(&self, renderer: &Renderer) -> Result<Vec<u32>, RenderError> {
        let n = (self.width as usize) * (self.height as usize);
        let mut words = read_words(&renderer.ctx, &self.work, (n as u64 * 4).max(16))?;
        words.truncate(n);
        Ok(words)
    }

    /// Log a warning when [`cut_count`](Self::cut_count) is above 0 (what `mode` drew here).
    pub fn warn_if_cut(&self, renderer: &Renderer, mode: ViewMode) {
        match self.cut_count(renderer) {
            Ok(n) => warn_cut(n, mode, (self.width, self.height)),
            Err(e) => log::warn!("could not read the cut-loop count: {e}"),
        }
    }

    /// Grow the plan buffers to hold `entries` entries (rays plus runs).
    fn ensure_plan_buffers(&mut self, renderer: &Renderer, entries: usize) {
        if self.order.size() < entries as u64 * 8 {
            (self.order, self.scratch) = plan_buffers(&renderer.ctx.device, entries);
        }
    }

    /// Ground-truth rays of each pixel (row-major) after [`Renderer::draw_planned`]; `None` when
    /// every pixel has [`samples`](Self::samples).
    pub fn planned_rays(&self) -> Option<&[u32]> {
        self.planned.as_deref()
    }

    /// Size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Read the target back (waits for the GPU).
    pub fn read(&self, renderer: &Renderer) -> Result<LinearImage, RenderError> {
        Ok(LinearImage {
            width: self.width,
            height: self.height,
            pixels: self.read_buffer(renderer, &self.accum)?,
        })
    }

    /// Read ground truth's per-pixel sums of squared samples back (waits for the GPU): the
    /// truth's own noise, with [`read`](Self::read)'s sums ([`TruthEstimate`]). Meaningless for
    /// a target that holds an analytic mode.
    ///
    /// [`TruthEstimate`]: crate::truth_noise::TruthEstimate
    pub fn read_moments(&self, renderer: &Renderer) -> Result<SampleMoments, RenderError> {
        Ok(SampleMoments {
            width: self.width,
            height: self.height,
            sum_sq: self.read_buffer(renderer, &self.moments)?,
        })
    }

    /// Copy one of the target's per-pixel `vec4<f32>` buffers back.
    fn read_buffer(
        &self,
        renderer: &Renderer,
        buffer: &wgpu::Buffer,
    ) -> Result<Vec<[f32; 4]>, RenderError> {
        let size = u64::from(self.width) * u64::from(self.height) * BYTES_PER_PIXEL;
        let words = read_words(&renderer.ctx, buffer, size)?;
        let floats: &[f32] = bytemuck::cast_slice(&words);
        Ok(floats
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect())
    }
}

/// The renderer: one compute pipeline for every mode.
#[derive(Debug)]
pub struct Renderer {
    ctx: GpuContext,
    pipelines: Arc<PipelineCache>,
    /// Threads compiling pipelines ahead of use ([`Renderer::prewarm`]); joined on drop.
    prewarming: Mutex<Vec<std::thread::JoinHandle<()>>>,
    /// Ground-truth rays whose loops a software adapter cut are traced again alone
    /// ([`Renderer::set_retry_cut`]).
    retry_cut: bool,
}

/// One compiled view pipeline per feature set. An entry's `OnceLock` is created under the map's
/// lock and filled outside it, so different sets compile concurrently and a second request for
/// a set being compiled waits for that compilation instead of starting another.
#[derive(Debug, Default)]
struct PipelineCache {
    map: Mutex<HashMap<FeatureSet, Arc<OnceLock<Compiled>>>>,
}

/// A compiled pipeline and what it cost.
#[derive(Debug, Clone)]
struct Compiled {
    pipeline: Arc<wgpu::ComputePipeline>,
    took: Duration,
}

impl PipelineCache {
    fn entry(&self, set: FeatureSet) -> Arc<OnceLock<Compiled>> {
        let mut map = self.map.lock().unwrap_or_else(|e| e.into_inner());
        map.entry(set).or_default().clone()
    }

    fn get(&self, device: &wgpu::Device, set: FeatureSet) -> Compiled {
        self.entry(set).get_or_init(|| compile(device, set)).clone()
    }

    fn ready(&self, set: FeatureSet) -> bool {
        let map = self.map.lock().unwrap_or_else(|e| e.into_inner());
        map.get(&set).is_some_and(|e| e.get().is_some())
    }
}

fn compile(device: &wgpu::Device, set: FeatureSet) -> Compiled {
    let t0 = Instant::now();
    // The shipped sources are checked for every feature set by a test; failing here is a bug.
    let source = view_source_for(set).expect("the view shader specialises for every feature set");
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("view"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("view"),
        layout: None,
        module: &module,
        entry_point: Some("view_main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let took = t0.elapsed();
    log::info!("view pipeline [{set}] compiled in {took:.1?}");
    Compiled {
        pipeline: Arc::new(pipeline),
        took,
    }
}

/// The WGSL of the all-features view pass: special functions, material model, image driver,
/// cylinder, view entry point.
pub fn view_source() -> String {
    view_source_for(FeatureSet::all()).expect("the all-features shader specialises")
}

/// The WGSL of the view pass specialised to `features` (see [`crate::specialize`]).
pub fn view_source_specialized(features: FeatureSet) -> Result<String, SpecializeError> {
    view_source_for(features)
}

fn push_table(data: &mut Vec<f32>, t: &PreconvolvedTable) -> u32 {
    let off = data.len() as u32;
    data.extend(t.texels.iter().flatten());
    off
}

/// Knots, then per segment and channel 4 coefficients (degree ≤ 3), then left and right tails.
fn push_poly(data: &mut Vec<f32>, p: &PiecewisePoly, channels: &[usize]) -> u32 {
    let off = data.len() as u32;
    data.extend(p.knots.iter().map(|k| *k as f32));
    for seg in 0..p.segments() {
        for &ch in channels {
            let c = &p.coeffs[seg * p.channels + ch];
            data.extend(c[..4].iter().map(|v| *v as f32));
        }
    }
    data.extend(channels.iter().map(|&ch| p.left[ch] as f32));
    data.extend(channels.iter().map(|&ch| p.right[ch] as f32));
    off
}

/// The image pyramid: per level the value grid (f̄, f²‾) and the cell grid (f_x, f_y, f_x², f_y²,
/// f_x·f_y), then a level table of [`IMAGE_LEVEL_SLOTS`] slots per level (value offset, grad
/// offset, width, height as u32 bits; mean variance, Lipschitz constants along x and y per level-0
/// texel as f32). The target is folded into the texel origin in f64.
/// Slots per level in the image's level table (WGSL `IMAGE_LEVEL_SLOTS`).
pub const IMAGE_LEVEL_SLOTS: usize = 7;

fn push_image(
    data: &mut Vec<f32>,
    base: &mut MaterialParams,
    tiled: &TiledImage,
    target: [f64; 2],
) {
    let img = &tiled.image;
    let mut offsets = Vec::with_capacity(img.levels.len());
    for l in &img.levels {
        let v = data.len() as u32;
        data.extend(l.value.iter().flatten());
        let g = data.len() as u32;
        data.extend(l.grad.iter().flatten());
        offsets.push((v, g));
    }
    base.image_offset = data.len() as u32;
    for (l, (v, g)) in img.levels.iter().zip(offsets) {
        data.extend([
            f32::from_bits(v),
            f32::from_bits(g),
            f32::from_bits(l.width as u32),
            f32::from_bits(l.height as u32),
            l.mean_variance as f32,
            l.lipschitz.x as f32,
            l.lipschitz.y as f32,
        ]);
    }
    let scale = tiled.texels_per_unit();
    let (w, h) = img.size();
    base.driver_kind = DriverCode::Image.code();
    base.image_levels = img.levels.len() as u32;
    base.image_scale = scale as f32;
    base.image_u0 = (target[0] * scale).rem_euclid(w as f64) as f32;
    base.image_v0 = (target[1] * scale).rem_euclid(h as f64) as f32;
    base.image_lip_x = img.lipschitz.x as f32;
    base.image_lip_y = img.lipschitz.y as f32;
}

/// The material's data buffer and its parameters (WGSL `Params`), see [`material_data_for`]
/// (with every table the material has: what the all-features shader reads).
pub fn material_data(prepared: &Evaluator, target: [f64; 2]) -> (Vec<f32>, MaterialParams) {
    let d = material_data_for(prepared, target, FeatureSet::all());
    (d.data, d.params)
}

/// A material's GPU data, by part.
#[derive(Clone, Debug)]
pub struct MaterialData {
    /// The data buffer (f32 words).
    pub data: Vec<f32>,
    /// The material's parameters.
    pub params: MaterialParams,
    /// Bytes of each part present (waves, image pyramid, colour table, …).
    pub segments: Vec<(&'static str, usize)>,
}

/// The material's data buffer (waves, image pyramid, tables, D_h, quadrature rule, curve
/// polynomials, as f32) and its parameters (WGSL `Params`), with coordinates relative to
/// `target`: each wave's phase absorbs 2π k·target in f64, so f32 phases stay accurate anywhere
/// on the plane. Parts the material has but `features` does not use are left out: the D_h table
/// and the slope quadrature rule need [`Feature::Relief`] (the colour and transfer tables, the
/// image and the waves exist only for the materials that use them). Shared by the renderer and
/// the engine bundle ([`crate::export`]).
pub fn material_data_for(
    prepared: &Evaluator,
    target: [f64; 2],
    features: FeatureSet,
) -> MaterialData {
    let mut segments: Vec<(&'static str, usize)> = Vec::new();
    let mut mark = |data: &Vec<f32>, start: usize, name: &'static str| {
        if data.len() > start {
            segments.push((name, (data.len() - start) * 4));
        }
    };
    let m = &prepared.material;
    let s = &prepared.surface;
    let mut data: Vec<f32> = Vec::new();
    let mut lay = Layout {
        waves: 0,
        ..Layout::default()
    };
    let mut base = MaterialParams::default();
    let start = data.len();
    match &s.driver {
        DriverField::Noise(noise) => {
            for w in &noise.waves {
                let phase =
                    (w.phase + TAU * (w.k.x * target[0] + w.k.y * target[1])).rem_euclid(TAU);
                data.extend([w.k.x as f32, w.k.y as f32, w.amplitude as f32, phase as f32]);
            }
            base.wave_count = noise.waves.len() as u32;
            let ends = &s.levels;
            base.level_count = ends.len() as u32;
            base.level_ends = ends
                .iter()
                .take(ends.len().saturating_sub(1))
                .enumerate()
                .map(|(l, &e)| (e.min(255) as u32) << (8 * l))
                .sum();
        }
        DriverField::Image(tiled) => push_image(&mut data, &mut base, tiled, target),
    }
    mark(
        &data,
        start,
        match s.driver {
            DriverField::Noise(_) => "noise waves",
            DriverField::Image(_) => "image pyramid",
        },
    );
    if let Some(t) = prepared.color.table() {
        let start = data.len();
        lay.color_table = push_table(&mut data, t);
        mark(&data, start, "colour table");
        base.ct_size_m = t.size_m as u32;
        base.ct_size_s = t.size_sigma as u32;
        base.ct_m_min = t.m_min as f32;
        base.ct_m_max = t.m_max as f32;
        base.ct_sigma_max = t.sigma_max as f32;
    }
    if let Some(t) = prepared.color.gaussianize_table() {
        // The colour table is over the image histogram's Gaussian space: H maps (f̄, σ_f) there.
        let start = data.len();
        base.ht_offset = push_table(&mut data, t);
        mark(&data, start, "histogram table H");
        base.ht_size_m = t.size_m as u32;
        base.ht_size_s = t.size_sigma as u32;
        base.ht_m_min = t.m_min as f32;
        base.ht_m_max = t.m_max as f32;
        base.ht_sigma_max = t.sigma_max as f32;
    }
    if let Some(t) = prepared
        .image_slopes
        .as_ref()
        .filter(|_| features.contains(Feature::TransferMixture))
    {
        let start = data.len();
        base.is_offset = data.len() as u32;
        base.is_on = 1;
        data.extend(t.scale.iter().chain(&t.inverse).map(|v| *v as f32));
        mark(&data, start, "image's value-conditioned slopes and T⁻¹");
    }
    if let Some(t) = prepared.transfer.table() {
        let start = data.len();
        lay.transfer_table = push_table(&mut data, t);
        mark(&data, start, "transfer table");
        base.tt_size_m = t.size_m as u32;
        base.tt_size_s = t.size_sigma as u32;
        base.tt_m_min = t.m_min as f32;
        base.tt_m_max = t.m_max as f32;
        base.tt_sigma_max = t.sigma_max as f32;
    }
    if let CompiledTransfer::Curve { slopes, .. } = &prepared.transfer
        && features.contains(Feature::Relief)
    {
        let start = data.len();
        base.ts_offset = data.len() as u32;
        base.ts_p = slopes.p as u32;
        data.extend(&slopes.entries);
        mark(&data, start, "transfer table's slope pyramids");
    }
    let rule = m.slope_rule();
    if features.contains(Feature::Relief) {
        // Built on first use (process-wide): a session of flat materials never builds it.
        let dh = EffectiveHeightTable::shared();
        base.dh_size = dh.mean.len() as u32;
        base.dh_ln_min = dh.ln_l_min as f32;
        base.dh_ln_max = dh.ln_l_max as f32;
        let start = data.len();
        lay.dh = data.len() as u32;
        for (a, b) in dh.mean.iter().zip(&dh.std) {
            data.extend([*a as f32, *b as f32]);
        }
        mark(&data, start, "visible-height table D_h");
        let start = data.len();
        lay.slope_rule = push_rule(&mut data, rule);
        mark(&data, start, "slope quadrature rule");
        if let Some(t) = &prepared.slope_masking {
            let start = data.len();
            base.cm_offset = data.len() as u32;
            base.cm_on = 1;
            data.extend([t.r0 as f32, t.level_step as f32]);
            data.extend(&t.data);
            mark(&data, start, "slope-conditioned masking table");
        }
        if m.transfer_mixture() {
            let n = bin_slope_points(rule, m.terms.slope.is_some());
            base.mix_nodes = n.len() as u32;
            base.mix_rule_offset = shared_or_pushed(
                &mut data,
                n,
                (rule, lay.slope_rule),
                &mut mark,
                "slope rule of the transfer mixture's bins",
            );
            if let Some(t) = &prepared.transfer_masking {
                let start = data.len();
                base.tm_offset = data.len() as u32;
                base.tm_on = 1;
                data.push(t.sigma_f as f32);
                data.extend(t.gradient.map(|g| g as f32));
                data.extend(&t.moments);
                mark(
                    &data,
                    start,
                    "transfer curve's value- and slope-conditioned masking moments",
                );
                let tn = conditioned_slope_rule(n);
                base.tm_nodes = tn.len() as u32;
                base.tm_rule_offset = shared_or_pushed(
                    &mut data,
                    tn,
                    (n, base.mix_rule_offset),
                    &mut mark,
                    "slope rule of the conditioned bins",
                );
            }
        }
    }
    match &m.color {
        ColorModel::Gradient { map, source } => {
            let p = map.to_piecewise();
            let start = data.len();
            lay.color_poly = push_poly(&mut data, &p, &[0, 1, 2]);
            mark(&data, start, "colour map polynomial");
            base.cp_knots = p.knots.len() as u32;
            base.color_kind = match source {
                ColorSource::Driver => ColorCode::Driver,
                ColorSource::Height => ColorCode::Height,
            }
            .code();
        }
        ColorModel::Attribute { mean, correlation } => {
            base.color_kind = ColorCode::Attribute.code();
            base.attr_mean = mean.map(|v| v as f32);
            base.attr_corr = correlation.map(|v| v as f32);
        }
    }
    // Colour terms: an absent term has weight 0 (see material.wgsl's `affine`).
    let terms = &m.terms;
    base.combine_mode = match terms.mode {
        CombineMode::Linear => CombineCode::Linear,
        CombineMode::Multiplicative => CombineCode::Multiplicative,
    }
    .code();
    if let Some(c) = &terms.constant {
        base.c0 = c.color.map(|v| v as f32);
        base.kappa0 = c.weight as f32;
    }
    base.kappa1 = terms.height.unwrap_or(0.0) as f32;
    if let (Some(t), Some(sc)) = (&terms.slope, &prepared.slope_color) {
        base.kappa2 = t.weight as f32;
        base.sc_dir = sc.direction.to_array().map(|v| v as f32);
        if features.contains(Feature::SlopeColor) {
            let start = data.len();
            base.sp_offset = push_poly(&mut data, &sc.poly, &[0, 1, 2]);
            base.sp_knots = sc.poly.knots.len() as u32;
            mark(&data, start, "slope colour polynomial");
        }
    }
    base.sun = m.lighting.sun as f32;
    if let Some(env) = &prepared.environment
        && features.contains(Feature::Environment)
    {
        let start = data.len();
        base.env_offset = data.len() as u32;
        base.has_env = 1;
        for c in env.irradiance_coefficients() {
            data.extend(c.map(|v| v as f32));
        }
        mark(&data, start, "environment SH9");
    }
    if let Some(measured) = &prepared.measured
        && features.contains(Feature::Measured)
    {
        let start = data.len();
        base.merl_offset = data.len() as u32;
        base.measured = 1;
        data.extend(measured.table.values());
        mark(&data, start, "measured BRDF table");
        let start = data.len();
        base.lobe_offset = data.len() as u32;
        base.lobe_count = measured.fit.lobes.len() as u32;
        for l in &measured.fit.lobes {
            data.push(l.sigma as f32);
            data.extend(l.weight.map(|v| v as f32));
            data.extend(l.fresnel.map(|v| v as f32));
        }
        mark(&data, start, "measured BRDF's fitted lobes");
    }
    if let TransferFunction::Curve(c) = &m.heights.transfer {
        let p = c.moment_poly();
        let start = data.len();
        lay.transfer_poly = push_poly(&mut data, &p, &[0, 2]);
        mark(&data, start, "transfer polynomial");
        base.tp_knots = p.knots.len() as u32;
        base.transfer_kind = TransferCode::Curve.code();
    }
    if data.is_empty() {
        data.push(0.0);
    }
    base.waves_offset = lay.waves;
    base.ct_offset = lay.color_table;
    base.tt_offset = lay.transfer_table;
    base.dh_offset = lay.dh;
    base.slope_rule_offset = lay.slope_rule;
    base.slope_nodes = rule.len() as u32;
    base.noise_slopes = u32::from(m.filtering.noise_slopes == NoiseSlopes::Exact);
    base.interception = u32::from(prepared.interception == Interception::Crests);
    let g = prepared.surface.driver.gradient_cov();
    (base.grad_cov_xx, base.grad_cov_yy, base.grad_cov_xy) =
        (g.xx as f32, g.yy as f32, g.xy as f32);
    base.cp_offset = lay.color_poly;
    base.tp_offset = lay.transfer_poly;
    base.sigma_h = s.sigma_h as f32;
    let weights = prepared.channel_weights();
    base.kd_rgb = weights.kd.map(|v| v as f32);
    base.albedo = m.brdf.albedo as f32;
    base.specular = m.brdf.specular as f32;
    base.roughness = m.brdf.roughness as f32;
    base.h_max = s.h_max as f32;
    base.g_lip = s.g_lip as f32;
    base.min_step = s.min_step as f32;
    base.slope_bound = s.slope_bound() as f32;
    base.correlation = match m.filtering.correlation {
        Correlation::Uncorrelated => CorrelationCode::Uncorrelated,
        Correlation::HeightDirection => CorrelationCode::HeightDirection,
    }
    .code();
    base.height_filter = match m.filtering.height_filter {
        HeightFilter::Exact => HeightFilterCode::Exact,
        HeightFilter::PaperFit => HeightFilterCode::PaperFit,
    }
    .code();
    base.march = match s.march {
        March::Reference => MarchCode::Reference,
        March::Fast => MarchCode::Fast,
    }
    .code();
    base.transfer_monotone = match &m.heights.transfer {
        TransferFunction::Identity => 1,
        TransferFunction::Curve(c) => match c.monotone() {
            Some(true) => 1,
            Some(false) => 2,
            None => 0,
        },
    };
    base.g_mean = prepared.global_height.0 as f32;
    base.g_std = prepared.global_height.1 as f32;
    MaterialData {
        data,
        params: base,
        segments,
    }
}

/// The offset of `rule`: the already uploaded `shared` rule's when it is the same rule, else
/// `rule` appended ([`push_rule`]) and marked as `name`.
fn shared_or_pushed(
    data: &mut Vec<f32>,
    rule: SlopeRule,
    (shared, offset): (SlopeRule, u32),
    mark: &mut impl FnMut(&Vec<f32>, usize, &'static str),
    name: &'static str,
) -> u32 {
    if rule == shared {
        return offset;
    }
    let start = data.len();
    let at = push_rule(data, rule);
    mark(data, start, name);
    at
}

/// Append a slope rule's nodes ([`SlopeRule::nodes`]: x, y, weight per node) and return its
/// offset.
fn push_rule(data: &mut Vec<f32>, rule: SlopeRule) -> u32 {
    let offset = data.len() as u32;
    for (z, w) in rule.nodes() {
        data.extend([z.x as f32, z.y as f32, *w as f32]);
    }
    offset
}

/// The noise driver the octave march sums, when the march is fast, the scene has relief and σ_h > 0:
/// what the bound grid and the field table are built from (`None` otherwise).
fn marched_noise(prepared: &Evaluator, features: FeatureSet) -> Option<&SumOfSines> {
    let s = &prepared.surface;
    let DriverField::Noise(noise) = &s.driver else {
        return None;
    };
    (s.march == March::Fast && features.contains(Feature::Relief) && s.sigma_h > 0.0)
        .then_some(noise)
}

/// Cells per side of the bound grid the GPU march reads (core's [`BoundGrid::around`]): 512² cells,
/// a pyramid of 2.8 MB, built in tens of milliseconds.
pub const GPU_GRID_CELLS: usize = 512;

/// Append the octave march's tables of a noise driver's explicit surface around `target` to `d`
/// when the march is fast and the scene has relief ([`push_bound_grid`], [`push_field_grid`]);
/// nothing otherwise (`grid_n` and `field_n` stay 0: the march sums the waves everywhere).
pub fn push_march_tables(
    prepared: &Evaluator,
    target: [f64; 2],
    features: FeatureSet,
    d: &mut MaterialData,
) {
    let Some(noise) = marched_noise(prepared, features) else {
        return;
    };
    let centre = DVec2::from(target);
    push_bound_grid(noise, centre, d);
    push_field_grid(noise, centre, d);
}

/// Append the bound grid of `noise` around `centre` to `d` (the octave march's skips;
/// [`lodestone_core::scene::bound_grid`]): the pyramid's levels one after the other, `[lo, hi]` per
/// cell, in coordinates relative to `centre` like the waves. Nothing when the environment variable
/// `LODESTONE_NO_GRID` is set (`grid_n` stays 0: no skips), so `lodestone bench` can time both on
/// the same build.
fn push_bound_grid(noise: &SumOfSines, centre: DVec2, d: &mut MaterialData) {
    if std::env::var_os("LODESTONE_NO_GRID").is_some() {
        return;
    }
    let Some(grid) = BoundGrid::around(noise, centre, GPU_GRID_CELLS) else {
        return;
    };
    let start = d.data.len();
    d.params.grid_offset = start as u32;
    for level in &grid.levels {
        for r in level {
            d.data.extend(r);
        }
    }
    d.segments.push(("bound grid", (d.data.len() - start) * 4));
    d.params.grid_n = grid.n as u32;
    d.params.grid_levels = grid.levels.len() as u32;
    d.params.grid_cell = grid.cell as f32;
    d.params.grid_x0 = (grid.origin.x - centre.x) as f32;
    d.params.grid_y0 = (grid.origin.y - centre.y) as f32;
    d.params.grid_amp = noise.waves.iter().map(|w| w.amplitude.abs()).sum::<f64>() as f32;
}

/// Cells per side of the field table the GPU march reads (core's [`FieldGrid::around`]): 512²
/// cells, 4.2 MB.
pub const GPU_FIELD_CELLS: usize = 512;

/// Append the field table of `noise` around `centre` to `d` (the octave march's steps near the
/// surface; [`lodestone_core::scene::field_grid`]), its origin relative to `centre` like the waves
/// and its error bounds widened by [`FIELD_MARGIN_F32`] for the f32 arithmetic. Nothing when the
/// environment variable `LODESTONE_NO_FIELD` is set (`field_n` stays 0): the march then sums the
/// waves near the surface, so `lodestone bench` can time both on the same build.
fn push_field_grid(noise: &SumOfSines, centre: DVec2, d: &mut MaterialData) {
    if std::env::var_os("LODESTONE_NO_FIELD").is_some() {
        return;
    }
    let Some(field) = FieldGrid::around(noise, centre, GPU_FIELD_CELLS) else {
        return;
    };
    let start = d.data.len();
    d.params.field_offset = start as u32;
    for v in &field.vertices {
        d.data.extend(v);
    }
    d.segments.push(("field table", (d.data.len() - start) * 4));
    let amp = field.amplitude_sum;
    let fine = noise
        .waves
        .iter()
        .map(|w| std::f64::consts::TAU * w.k.abs())
        .fold(DVec2::ZERO, DVec2::max);
    let margin = FIELD_MARGIN_F32 * amp;
    d.params.field_n = field.n as u32;
    d.params.field_cell = field.cell as f32;
    d.params.field_x0 = (field.origin.x - centre.x) as f32;
    d.params.field_y0 = (field.origin.y - centre.y) as f32;
    d.params.field_error = (field.error + margin) as f32;
    d.params.field_slope_error_x = (field.slope_error.x + margin * fine.x) as f32;
    d.params.field_slope_error_y = (field.slope_error.y + margin * fine.y) as f32;
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
        let features = FeatureSet::of_material(&prepared.material);
        Self::upload(ctx, prepared, target, features, false)
    }

    /// Upload every table the material has, to be drawn by the all-features pipeline (the
    /// reference the specialised pipelines are compared against, and the engine bundle's shader).
    pub fn all_features(
        ctx: &GpuContext,
        prepared: &Evaluator,
        target: [f64; 2],
    ) -> Result<Self, RenderError> {
        let features = FeatureSet::of_material(&prepared.material);
        Self::upload(ctx, prepared, target, features, true)
    }

    fn upload(
        ctx: &GpuContext,
        prepared: &Evaluator,
        target: [f64; 2],
        features: FeatureSet,
        all_features: bool,
    ) -> Result<Self, RenderError> {
        let uses = if all_features {
            FeatureSet::all()
        } else {
            features
        };
        let mut d = material_data_for(prepared, target, uses);
        push_march_tables(prepared, target, uses, &mut d);
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

impl Drop for Renderer {
    /// Waits for pipelines still compiling ahead of use, so no thread holds the device after its
    /// renderer is gone (a thread tearing down an llvmpipe device during process exit corrupted
    /// the heap once).
    fn drop(&mut self) {
        let threads = std::mem::take(self.prewarming.get_mut().unwrap_or_else(|e| e.into_inner()));
        for t in threads {
            if t.join().is_err() {
                log::error!("a pipeline compilation thread panicked");
            }
        }
    }
}

impl Renderer {
    /// A renderer on `ctx`. Pipelines are compiled on first use, one per feature set, and cached
    /// ([`Renderer::prewarm`] compiles them ahead of use on another thread).
    pub fn new(ctx: GpuContext) -> Self {
        Self {
            ctx,
            pipelines: Arc::default(),
            prewarming: Mutex::new(Vec::new()),
            retry_cut: false,
        }
    }

    /// On a software adapter (Mesa's llvmpipe or lavapipe), trace every ground-truth ray whose
    /// loops the adapter cut ([`ViewTarget::cut_count`]) again, alone in its SIMD batch, so it
    /// gets the march's own answer (all but those that need more than 65535 iterations of one
    /// loop even alone, which stay counted). Off by default: the rays cut are the ones that skim
    /// the surface near the horizon for thousands of steps, and tracing them alone cost 50× the
    /// frame at 80° (docs/design.md). Ignored on other adapters, which cut nothing.
    pub fn set_retry_cut(&mut self, on: bool) {
        self.retry_cut = on;
    }

    /// The pipeline for `features`, compiling it now if needed; returns how long that
    /// compilation took (zero when it was cached).
    pub fn prepare(&self, features: FeatureSet) -> Duration {
        let cached = self.pipelines.ready(features);
        let c = self.pipelines.get(&self.ctx.device, features);
        if cached { Duration::ZERO } else { c.took }
    }

    /// Whether the pipeline for `features` is compiled.
    pub fn is_ready(&self, features: FeatureSet) -> bool {
        self.pipelines.ready(features)
    }

    /// Compile the pipelines for `sets` on a background thread (those not cached yet), so that a
    /// later [`Renderer::draw`] needing one does not wait. Finished threads are reaped here.
    pub fn prewarm(&self, sets: Vec<FeatureSet>) {
        let missing: Vec<_> = sets
            .into_iter()
            .filter(|s| !self.pipelines.ready(*s))
            .collect();
        let mut threads = self.prewarming.lock().unwrap_or_else(|e| e.into_inner());
        threads.retain(|t| !t.is_finished());
        if missing.is_empty() {
            return;
        }
        let (device, cache) = (self.ctx.device.clone(), self.pipelines.clone());
        let spawned = std::thread::Builder::new()
            .name("lodestone-pipelines".into())
            .spawn(move || {
                for s in missing {
                    cache.get(&device, s);
                }
            });
        match spawned {
            Ok(t) => threads.push(t),
            Err(e) => log::warn!("cannot compile pipelines ahead of use: {e}"),
        }
    }

    /// The GPU context.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// Render `mode` at `width × height` into a fresh target and read it back. Ground truth takes
    /// `samples` rays per pixel; the analytic modes ignore it.
    pub fn render(
        &self,
        material: &GpuMaterial,
        scene: &Scene,
        mode: ViewMode,
        (width, height): (u32, u32),
        samples: u32,
    ) -> Result<LinearImage, RenderError> {
        let (image, cut) = self.render_counted(material, scene, mode, (width, height), samples)?;
        warn_cut(cut, mode, (width, height));
        Ok(image)
    }

    /// [`Renderer::render`], with the count of pixels (analytic modes) or rays (ground truth)
    /// whose loops the adapter cut ([`ViewTarget::cut_count`]), for a caller that shows it.
    pub fn render_counted(
        &self,
        material: &GpuMaterial,
        scene: &Scene,
        mode: ViewMode,
        (width, height): (u32, u32),
        samples: u32,
    ) -> Result<(LinearImage, u32), RenderError> {
        let mut target = ViewTarget::new(self, width, height)?;
        self.draw(&mut target, material, scene, mode, samples);
        Ok((target.read(self)?, target.cut_count(self)?))
    }

    /// Draw into a persistent target. Analytic modes overwrite it; ground truth adds `samples` more
    /// rays per pixel to what the target holds (progressive; low-discrepancy, so any count is
    /// unbiased). Call [`ViewTarget::reset`] when the camera, light or material changes.
    pub fn draw(
        &self,
        target: &mut ViewTarget,
        material: &GpuMaterial,
        scene: &Scene,
        mode: ViewMode,
        samples: u32,
    ) {
        let retry = mode == ViewMode::Truth && self.retries_cut();
        if retry {
            target.ensure_plan_buffers(self, (target.width * target.height) as usize);
        }
        let (pipeline, mut params, bind) = self.view_pass(target, material, scene, mode);
        target.planned = None;
        params.retry_cut = u32::from(retry);
        let frames = if mode == ViewMode::Truth {
            samples.max(1)
        } else {
            1
        };
        if mode != ViewMode::Truth || target.samples == 0 {
            self.clear_cut(target);
        }
        for _ in 0..frames {
            params.frame = if mode == ViewMode::Truth {
                target.samples
            } else {
                0
            };
            self.dispatch_view(target, &pipeline, &bind, &params, target.height);
            if retry {
                let slots = target.width * target.height;
                self.retry_cut(target, &pipeline, &bind, &params, 3, slots);
            }
            target.samples += u32::from(mode == ViewMode::Truth);
            // Keep the queue short: long progressive runs otherwise pile up thousands of submissions.
            if target.samples % 8 == 7 {
                self.wait();
            }
        }
    }

    /// Ground truth with a ray count per pixel (an adaptive plan, [BSSBH13 Sec. 2.4];
    /// `lodestone_core::eval::sampling_plan`): bring every pixel `p` to `rays[p]` rays in all
    /// (row-major; a pixel that has more keeps them, one that is missing from `rays` gets none).
    /// Only the rays still needed are traced, each by its own invocation (a pixel planned hundreds
    /// of rays costs what hundreds of pixels of one ray cost, not hundreds of passes), in chunks
    /// of at most [`PLANNED_CHUNK`] rays: a pass traces the chunk's rays into a scratch buffer, a
    /// second adds each pixel's rays to its sums in sequence order. Each pixel's rays are its own
    /// low-discrepancy sequence's next ones, so a pixel brought to n rays holds exactly what
    /// [`draw`](Self::draw)'s first n give it. A target last drawn by `draw` (or reset) starts
    /// afresh. Pixels with no ray read 0 (weight 0).
    pub fn draw_planned(
        &self,
        target: &mut ViewTarget,
        material: &GpuMaterial,
        scene: &Scene,
        rays: &[u32],
    ) {
        let n = (target.width * target.height) as usize;
        let mut done = match target.planned.take() {
            Some(d) if target.samples > 0 => d,
            _ => {
                target.samples = 0;
                vec![0; n]
            }
        };
        let need: Vec<u32> = (0..n)
            .map(|p| {
                rays.get(p)
                    .copied()
                    .unwrap_or(0)
                    .saturating_sub(done[p])
                    .min(PLANNED_CHUNK)
            })
            .collect();
        target.ensure_plan_buffers(self, PLANNED_CHUNK as usize + n);
        let (pipeline, mut params, bind) = self.view_pass(target, material, scene, ViewMode::Truth);
        let mut p = 0;
        while p < n {
            // The next chunk: whole pixels, at most PLANNED_CHUNK rays.
            let mut entries: Vec<[u32; 2]> = Vec::new();
            let mut runs: Vec<[u32; 2]> = Vec::new();
            while p < n && entries.len() + need[p] as usize <= PLANNED_CHUNK as usize {
                if need[p] > 0 {
                    runs.push([entries.len() as u32, need[p]]);
                    entries.extend((0..need[p]).map(|j| [p as u32, done[p] + j]));
                }
                p += 1;
            }
            if runs.is_empty() {
                continue;
            }
            let runs_at = entries.len();
            entries.extend_from_slice(&runs);
            self.ctx
                .queue
                .write_buffer(&target.order, 0, bytemuck::cast_slice(&entries));
            // A fresh target's first pass overwrites (frame 0); later ones add (frame 1), so
            // pixels outside this chunk are cleared first.
            if target.samples == 0 {
                let mut enc =
                    self.ctx
                        .device
                        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                            label: Some("clear"),
                        });
                enc.clear_buffer(&target.accum, 0, None);
                enc.clear_buffer(&target.moments, 0, None);
                enc.clear_buffer(&target.cut, 0, None);
                enc.clear_buffer(&target.work, 0, None);
                self.ctx.queue.submit([enc.finish()]);
                target.samples = 1;
            }
            params.frame = 1;
            params.runs_at = runs_at as u32;
            params.retry_cut = u32::from(self.retries_cut());
            params.phase = 0;
            params.list_len = runs_at as u32;
            self.dispatch_view(
                target,
                &pipeline,
                &bind,
                &params,
                params.list_len.div_ceil(target.width),
            );
            if params.retry_cut == 1 {
                self.retry_cut(target, &pipeline, &bind, &params, 2, runs_at as u32);
            }
            params.phase = 1;
            params.list_len = runs.len() as u32;
            self.dispatch_view(
                target,
                &pipeline,
                &bind,
                &params,
                params.list_len.div_ceil(target.width),
            );
            self.wait();
        }
        for p in 0..n {
            done[p] += need[p];
        }
        target.samples = target.samples.max(done.iter().copied().max().unwrap_or(0));
        target.planned = Some(done);
    }

    /// The pipeline, parameters and bind group of one view pass (`frame` and `list_len` left at 0).
    fn view_pass(
        &self,
        target: &ViewTarget,
        material: &GpuMaterial,
        scene: &Scene,
        mode: ViewMode,
    ) -> (
        std::sync::Arc<wgpu::ComputePipeline>,
        ViewParams,
        wgpu::BindGroup,
    ) {
        let (width, height) = (target.width, target.height);
        let pipeline = self
            .pipelines
            .get(&self.ctx.device, material.pipeline_features(scene))
            .pipeline;
        let mut params = ViewParams::default();
        // The eye is kept clear of the relief, as core's `plane_pixel` and `cylinder_pixel` do.
        let lifted = match scene.shape {
            Shape::Plane => material.surface.clear_camera(&scene.camera),
            Shape::Cylinder { radius } => material
                .surface
                .clear_cylinder_camera(&scene.camera, radius),
        };
        let cam = Camera {
            target: [
                lifted.target[0] - scene.camera.target[0],
                lifted.target[1] - scene.camera.target[1],
            ],
            ..lifted
        };
        let (r, u, f) = cam.basis();
        let v3 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        params.eye = v3(cam.eye());
        params.right = v3(r);
        params.up = v3(u);
        params.forward = v3(f);
        params.light = v3(scene.light.normalize());
        params.tan_half_fov = scene.camera.tan_half_fov() as f32;
        params.aspect = (f64::from(width) / f64::from(height.max(1))) as f32;
        params.pixel_sigma = PIXEL_SIGMA as f32;
        params.width = width;
        params.height = height;
        params.mode = mode.code();
        match scene.shape {
            Shape::Plane => params.shape = ShapeCode::Plane.code(),
            Shape::Cylinder { radius } => {
                params.shape = ShapeCode::Cylinder.code();
                params.radius = radius as f32;
            }
        }
        let mut entries = vec![
            material.params.as_entire_binding(),
            wgpu::BindingResource::TextureView(&material.data),
            target.accum.as_entire_binding(),
            target.view.as_entire_binding(),
            target.moments.as_entire_binding(),
            target.order.as_entire_binding(),
            target.scratch.as_entire_binding(),
            target.cut.as_entire_binding(),
            target.work.as_entire_binding(),
        ];
        // The wave table exists in the shader only where the noise driver does (binding 9).
        if material
            .pipeline_features(scene)
            .contains(Feature::NoiseDriver)
        {
            entries.push(material.waves.as_entire_binding());
        }
        let entries: Vec<wgpu::BindGroupEntry> = entries
            .into_iter()
            .enumerate()
            .map(|(i, resource)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource,
            })
            .collect();
        let bind = self
            .ctx
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("view"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            });
        (pipeline, params, bind)
    }

    /// Whether cut rays are traced again ([`Renderer::set_retry_cut`] on a software adapter).
    fn retries_cut(&self) -> bool {
        self.retry_cut && self.ctx.is_software()
    }

    /// Trace again, alone in its SIMD batch, every ray of the last pass whose loops the adapter cut
    /// (`phase` 2: the `slots` entries of a planned chunk; 3: the `slots` pixels of a frame).
    fn retry_cut(
        &self,
        target: &ViewTarget,
        pipeline: &wgpu::ComputePipeline,
        bind: &wgpu::BindGroup,
        params: &ViewParams,
        phase: u32,
        slots: u32,
    ) {
        let mut p = *params;
        p.phase = phase;
        p.list_len = slots;
        let batches_per_row = target.width.div_ceil(8);
        self.dispatch_view(target, pipeline, bind, &p, slots.div_ceil(batches_per_row));
    }

    /// Zero the target's count of cut loops and its work per pixel.
    fn clear_cut(&self, target: &ViewTarget) {
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("clear"),
            });
        enc.clear_buffer(&target.cut, 0, None);
        enc.clear_buffer(&target.work, 0, None);
        self.ctx.queue.submit([enc.finish()]);
    }

    /// Write `params` and dispatch one view pass over `rows` rows of the target's width.
    fn dispatch_view(
        &self,
        target: &ViewTarget,
        pipeline: &wgpu::ComputePipeline,
        bind: &wgpu::BindGroup,
        params: &ViewParams,
        rows: u32,
    ) {
        self.ctx
            .queue
            .write_buffer(&target.view, 0, bytemuck::bytes_of(params));
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("view"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("view"),
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups(target.width.div_ceil(8), rows.div_ceil(8), 1);
        }
        self.ctx.queue.submit([enc.finish()]);
    }

    /// Block until the GPU has finished all submitted work (for timing).
    pub fn wait(&self) {
        let _ = self.ctx.device.poll(wgpu::PollType::wait_indefinitely());
    }
}

/// Log a warning when `n` pixels (analytic modes) or rays (ground truth) of a `size` view of
/// `mode` had loops the adapter cut ([`ViewTarget::cut_count`]).
fn warn_cut(n: u32, mode: ViewMode, (width, height): (u32, u32)) {
    if n == 0 {
        return;
    }
    let what = if mode == ViewMode::Truth {
        format!("{n} ground-truth rays")
    } else {
        format!("{n} pixels of {mode:?}")
    };
    log::warn!(
        "{what} ({width}×{height}) ran out of the adapter's loop budget and may be wrong \
         (Mesa's software rasterizer gives a shader invocation 65535 loop iterations in all; \
         `--retry-cut-rays` traces such rays again alone, slowly)"
    );
}
