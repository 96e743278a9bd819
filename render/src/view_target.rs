//! One view's render target: the accumulation buffers the view shader writes, and their readback.

use crate::error::RenderError;
use crate::gpu::GpuContext;
use crate::gpu_types::ViewParams;
use crate::image::LinearImage;
use crate::truth_noise::SampleMoments;
use crate::view::ViewMode;

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

/// One view's render target: an accumulation buffer (linear RGB + sample count per pixel), ground
/// truth's sums of squared samples beside it, and its own view parameters, so several views can be
/// drawn in one submission without sharing state.
#[derive(Debug)]
pub struct ViewTarget {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) accum: wgpu::Buffer,
    pub(crate) moments: wgpu::Buffer,
    pub(crate) view: wgpu::Buffer,
    /// The ray entries and pixel runs of [`Renderer::draw_planned`] (binding 5; 8 bytes each,
    /// grown on first use).
    pub(crate) order: wgpu::Buffer,
    /// Their rays' colours (binding 6; 16 bytes an entry).
    pub(crate) scratch: wgpu::Buffer,
    /// The pixels or rays whose march had a loop cut by the adapter (binding 7, one u32).
    pub(crate) cut: wgpu::Buffer,
    /// Ground truth's work per pixel (binding 8, one u32 each: the view shader's `work_sum`).
    pub(crate) work: wgpu::Buffer,
    /// Ground-truth rays per pixel accumulated so far (the most any pixel has, after
    /// [`Renderer::draw_planned`]).
    pub samples: u32,
    /// Rays per pixel after [`Renderer::draw_planned`]; `None` after [`Renderer::draw`].
    pub(crate) planned: Option<Vec<u32>>,
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
    pub fn new(
        renderer: &impl AsRef<GpuContext>,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        let device = &renderer.as_ref().device;
        let (width, height) = (width.max(1), height.max(1));
        let bytes = u64::from(width) * u64::from(height) * BYTES_PER_PIXEL;
        let limit = storage_limit(renderer.as_ref());
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
    pub fn cut_count(&self, renderer: &impl AsRef<GpuContext>) -> Result<u32, RenderError> {
        let words = read_words(renderer.as_ref(), &self.cut, 16)?;
        Ok(words.first().copied().unwrap_or(0))
    }

    /// Ground truth's work per pixel since the target last started (waits for the GPU): the sum
    /// over the pixel's rays of each ray's march steps plus its waves summed in eights (the view
    /// shader's `work`). Divided by the pixel's rays it is what one more ray there costs, in
    /// units comparable across pixels of one material ([`crate::adaptive_truth`]'s cost-aware
    /// counts). Row-major; rays traced again after a loop cut are not counted.
    pub fn read_work(&self, renderer: &impl AsRef<GpuContext>) -> Result<Vec<u32>, RenderError> {
        let n = (self.width as usize) * (self.height as usize);
        let mut words = read_words(renderer.as_ref(), &self.work, (n as u64 * 4).max(16))?;
        words.truncate(n);
        Ok(words)
    }

    /// Log a warning when [`cut_count`](Self::cut_count) is above 0 (what `mode` drew here).
    pub fn warn_if_cut(&self, renderer: &impl AsRef<GpuContext>, mode: ViewMode) {
        match self.cut_count(renderer) {
            Ok(n) => warn_cut(n, mode, (self.width, self.height)),
            Err(e) => log::warn!("could not read the cut-loop count: {e}"),
        }
    }

    /// Grow the plan buffers to hold `entries` entries (rays plus runs).
    pub(crate) fn ensure_plan_buffers(
        &mut self,
        renderer: &impl AsRef<GpuContext>,
        entries: usize,
    ) {
        if self.order.size() < entries as u64 * 8 {
            (self.order, self.scratch) = plan_buffers(&renderer.as_ref().device, entries);
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
    pub fn read(&self, renderer: &impl AsRef<GpuContext>) -> Result<LinearImage, RenderError> {
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
    pub fn read_moments(
        &self,
        renderer: &impl AsRef<GpuContext>,
    ) -> Result<SampleMoments, RenderError> {
        Ok(SampleMoments {
            width: self.width,
            height: self.height,
            sum_sq: self.read_buffer(renderer, &self.moments)?,
        })
    }

    /// Copy one of the target's per-pixel `vec4<f32>` buffers back.
    fn read_buffer(
        &self,
        renderer: &impl AsRef<GpuContext>,
        buffer: &wgpu::Buffer,
    ) -> Result<Vec<[f32; 4]>, RenderError> {
        let size = u64::from(self.width) * u64::from(self.height) * BYTES_PER_PIXEL;
        let words = read_words(renderer.as_ref(), buffer, size)?;
        let floats: &[f32] = bytemuck::cast_slice(&words);
        Ok(floats
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect())
    }
}

/// Log a warning when `n` pixels (analytic modes) or rays (ground truth) of a `size` view of
/// `mode` had loops the adapter cut ([`ViewTarget::cut_count`]).
pub(crate) fn warn_cut(n: u32, mode: ViewMode, (width, height): (u32, u32)) {
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
