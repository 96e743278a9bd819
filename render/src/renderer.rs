//! The plane scene rendered under every view mode by one compute pass per frame, with readback to
//! linear f32 and 8-bit sRGB images. One accumulation target per view.

use crate::error::RenderError;
use crate::gpu::GpuContext;
use crate::gpu_codes::ShapeCode;
use crate::gpu_material::GpuMaterial;
use crate::gpu_types::ViewParams;
use crate::image::LinearImage;
use crate::pipelines::PipelineCache;
use crate::view::{Scene, ViewMode};
use crate::view_target::{ViewTarget, warn_cut};
use glam::DVec3;
use lodestone_core::material::features::{Feature, FeatureSet};
use lodestone_core::scene::camera::{Camera, PIXEL_SIGMA};
use lodestone_core::scene::shape::Shape;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// The most ground-truth rays one chunk of [`Renderer::draw_planned`] traces (its scratch buffer
/// holds 16 bytes a ray: 4 MiB), and the most rays one call adds to a pixel.
pub const PLANNED_CHUNK: u32 = 1 << 18;

/// The renderer: one compute pipeline for every mode.
#[derive(Debug)]
pub struct Renderer {
    ctx: GpuContext,
    pipelines: Arc<PipelineCache>,
    /// Threads compiling pipelines ahead of use ([`Renderer::prewarm`]); joined on drop.
    prewarming: Mutex<Vec<std::thread::JoinHandle<()>>>,
    /// Pipelines [`Renderer::prewarm`] asked for on a device one thread must own (OpenGL), for
    /// the render thread to compile when it is idle ([`Renderer::compile_deferred`]).
    deferred: Mutex<Vec<FeatureSet>>,
    /// Ground-truth rays whose loops a software adapter cut are traced again alone
    /// ([`Renderer::set_retry_cut`]).
    retry_cut: bool,
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
            deferred: Mutex::new(Vec::new()),
            retry_cut: false,
        }
    }

    /// On a software adapter (Mesa's llvmpipe or lavapipe), trace every ground-truth ray whose
    /// loops the adapter cut ([`ViewTarget::cut_count`]) again, alone in its SIMD batch, so it
    /// gets the march's own answer (all but those that need more than 65535 iterations of one
    /// loop even alone, which stay counted). Off by default: the rays cut are the ones that skim
    /// the surface near the horizon for thousands of steps, and tracing them alone cost 50× the
    /// frame at 80° (docs/design/software-adapter.md). Ignored on other adapters, which cut nothing.
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

    /// Whether the device must be used from one thread at a time: wgpu's OpenGL backend holds
    /// one context lock per device and gives up (panics) after about a second of waiting, and a
    /// pipeline of a large shader takes llvmpipe longer than that to compile, so on OpenGL no
    /// compile may run beside a frame. Vulkan, Metal and DX12 compile on any thread.
    pub fn single_threaded(&self) -> bool {
        self.ctx.info.backend == wgpu::Backend::Gl
    }

    /// Compile the pipelines for `sets` ahead of use (those not cached yet), so that a later
    /// [`Renderer::draw`] needing one does not wait: on a background thread where the backend
    /// allows it (finished threads are reaped here); on a [`single_threaded`](Self::single_threaded)
    /// device they are queued instead, for the thread that renders to compile between frames
    /// with [`Renderer::compile_deferred`] (a draw that needs one first compiles it itself).
    pub fn prewarm(&self, sets: Vec<FeatureSet>) {
        let missing: Vec<_> = sets
            .into_iter()
            .filter(|s| !self.pipelines.ready(*s))
            .collect();
        if self.single_threaded() {
            let mut deferred = self.deferred.lock().unwrap_or_else(|e| e.into_inner());
            for s in missing {
                if !deferred.contains(&s) {
                    deferred.push(s);
                }
            }
            return;
        }
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

    /// Compile one pipeline [`Renderer::prewarm`] queued, on the calling thread (the one that
    /// renders); `false` when none is left. Call it when idle: it takes as long as the compile.
    pub fn compile_deferred(&self) -> bool {
        loop {
            let next = {
                let mut deferred = self.deferred.lock().unwrap_or_else(|e| e.into_inner());
                if deferred.is_empty() {
                    return false;
                }
                deferred.remove(0)
            };
            if !self.pipelines.ready(next) {
                self.pipelines.get(&self.ctx.device, next);
                return true;
            }
        }
    }

    /// How many pipelines [`Renderer::prewarm`] queued for [`Renderer::compile_deferred`].
    pub fn deferred_count(&self) -> usize {
        self.deferred
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .len()
    }

    /// How many threads are compiling pipelines ahead of use now.
    pub fn compiling_threads(&self) -> usize {
        let threads = self.prewarming.lock().unwrap_or_else(|e| e.into_inner());
        threads.iter().filter(|t| !t.is_finished()).count()
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
    /// `lodestone_core::adaptive::sampling_plan`): bring every pixel `p` to `rays[p]` rays in all
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
    pub(crate) fn retry_cut(
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

impl AsRef<GpuContext> for Renderer {
    fn as_ref(&self) -> &GpuContext {
        &self.ctx
    }
}
