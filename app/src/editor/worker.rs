//! The render worker: a thread that owns its own headless GPU device and renders the views the
//! editor asks for, so the window stays responsive however slow the adapter is (Mesa's llvmpipe
//! takes seconds for a full-resolution ray-marched frame).
//!
//! Every request carries the whole state (material, scene, view size, modes). The worker always
//! serves the newest request: older ones are dropped unread. For a request it
//! 1. prepares the material (tables are rebuilt only when the material changed),
//! 2. renders the analytic modes at a resolution chosen so a pass fits a time budget, then
//!    doubles the resolution pass by pass up to the full view size (progressive refinement),
//! 3. accumulates ground truth one ray per pixel per frame at the final resolution until the
//!    requested samples per pixel are reached,
//!
//! checking for a newer request between passes.

mod truth;
use lodestone_core::driver::image::ImageDriver;
use lodestone_core::eval::Evaluator;
use lodestone_core::material::Material;
use lodestone_core::material::measured::MeasuredBrdf;
use lodestone_core::math::sh::Sh9;
use lodestone_core::scene::march::March;
use lodestone_render::adaptive_truth::{Progressive, ray_costs, render_progressive};
use lodestone_render::truth_noise::SampleMoments;
use lodestone_render::{
    GpuContext, GpuMaterial, LinearImage, Renderer, Scene, ViewMode, ViewTarget,
};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::time::{Duration, Instant};

/// What the editor wants drawn.
#[derive(Clone, Debug)]
pub struct Request {
    /// Increases with every change the views must follow.
    pub generation: u64,
    /// The material.
    pub material: Arc<Material>,
    /// Its driver image (image drivers only).
    pub image: Option<Arc<ImageDriver>>,
    /// The SH9 radiance of its environment file (file environments only).
    pub environment: Option<Sh9>,
    /// Its measured base BRDF (materials that name one, once the file has loaded).
    pub measured: Option<Arc<MeasuredBrdf>>,
    /// Camera and light.
    pub scene: Scene,
    /// Full size of one view in physical pixels.
    pub size: [u32; 2],
    /// Modes to render (each at most once).
    pub modes: Vec<ViewMode>,
    /// Ground-truth rays per pixel to accumulate.
    pub truth_spp: u32,
    /// Largest fraction of the full size to render (1 = full resolution).
    pub max_scale: f32,
    /// Ground truth gives each pixel its own ray count from the predicted and measured noise.
    pub adaptive_truth: bool,
    /// How every view's rays march (the fast march, or the reference kept selectable).
    pub march: March,
}

/// A finished image of one mode.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The request it answers.
    pub generation: u64,
    /// Its mode.
    pub mode: ViewMode,
    /// Linear RGB (divided by the weight on read).
    pub image: Arc<LinearImage>,
    /// Ground-truth rays per pixel in it, on average over the pixels (0 for analytic modes).
    pub samples: u32,
    /// An adaptive ground truth's rays per pixel (row-major; `None` for uniform truth and
    /// analytic modes).
    pub rays: Option<Arc<Vec<u32>>>,
    /// The predicted deviation of one truth ray's luminance per pixel that planned them
    /// (`Evaluator::predict_truth`; `None` where nothing was predicted).
    pub predicted_sd: Option<Arc<Vec<f32>>>,
    /// The image's predicted local bandwidth per pixel, cycles per pixel, that came with that
    /// prediction (`Evaluator::predict_bandwidth` [BSSBH13 Sec. 2.2]; `None` where nothing was
    /// predicted).
    pub predicted_bandwidth: Option<Arc<Vec<f32>>>,
    /// What one more truth ray costs per pixel, in march steps plus eights of waves summed (the
    /// view shader's `work` over the pixel's rays, plus one; `None` for analytic modes).
    pub cost: Option<Arc<Vec<f32>>>,
    /// Ground truth's per-pixel sums of squared rays (its own noise; `None` for analytic modes).
    pub moments: Option<Arc<SampleMoments>>,
    /// GPU time of the pass that produced it (for truth: of the last ray per pixel).
    pub pass_time: Duration,
    /// Ground-truth rays, or an analytic mode's pixels, in it whose loops the adapter cut
    /// (`ViewTarget::cut_count`: Mesa's loop budget on llvmpipe).
    pub cut_rays: u32,
    /// Resolution as a fraction of the full view size.
    pub scale: f32,
}

/// Messages from the worker.
#[derive(Debug)]
pub enum Event {
    /// The device is up.
    Ready {
        /// "name (backend, type)".
        adapter: String,
        /// The adapter is a software rasterizer (llvmpipe, lavapipe, WARP).
        software: bool,
    },
    /// No device: nothing will be drawn.
    NoAdapter(String),
    /// The material cannot be prepared (e.g. an image driver file is missing).
    MaterialError(String),
    /// A new image.
    Frame(Frame),
    /// Rendering failed.
    RenderError(String),
    /// The render thread stopped on a panic (a driver's, e.g. wgpu's GL backend when it cannot
    /// take its context lock in time on a loaded machine): the message. Nothing more will come
    /// from this worker; the window starts a new one ([`MAX_RESTARTS`]).
    Stopped(String),
}

/// How many times the window starts a new render thread after one stopped on a panic, before it
/// says the renderer failed.
pub const MAX_RESTARTS: u32 = 3;

/// Tests: a request of this generation makes the worker panic, as a driver would (a value the
/// window never reaches, and no state shared between tests).
#[cfg(test)]
pub(crate) const PANIC_GENERATION: u64 = u64::MAX - 7;

/// The message of a caught panic.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".to_owned())
}

/// Handle on the worker thread.
#[derive(Debug)]
pub struct Worker {
    /// `None` only while dropping: taking it disconnects the channel, which stops the thread.
    requests: Option<Sender<Request>>,
    events: Receiver<Event>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Drop for Worker {
    /// Stops the thread and waits for it, so the GPU device is torn down before the process
    /// exits: a detached thread still dropping an llvmpipe device while the process runs its
    /// exit handlers corrupted the heap (`malloc_consolidate(): unaligned fastbin chunk`).
    fn drop(&mut self) {
        self.requests.take();
        if let Some(t) = self.thread.take()
            && t.join().is_err()
        {
            log::error!("the render thread panicked");
        }
    }
}

/// Where the worker's device comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceSource {
    /// The best headless adapter.
    Headless,
    /// None: the no-adapter path (tests, or `LODESTONE_NO_GPU=1`).
    Unavailable,
}

/// Target duration of one analytic pass when picking the first resolution.
const PASS_BUDGET: Duration = Duration::from_millis(60);
/// Smallest resolution scale.
const MIN_SCALE: f32 = 1.0 / 16.0;
/// How long the render thread waits for a request before it compiles a pipeline queued ahead of
/// use (OpenGL: [`Renderer::compile_deferred`]).
const IDLE_BEFORE_COMPILE: Duration = Duration::from_secs(2);

impl Worker {
    /// Start the worker. `repaint` is called after every event (wakes the UI).
    pub fn spawn(source: DeviceSource, repaint: impl Fn() + Send + 'static) -> Self {
        let (req_tx, req_rx) = std::sync::mpsc::channel::<Request>();
        let (ev_tx, ev_rx) = std::sync::mpsc::channel::<Event>();
        let spawned = std::thread::Builder::new()
            .name("lodestone-render".into())
            .spawn(move || {
                // Before the device exists, so its rasterizer threads inherit the priority.
                super::priority::lower_current_thread();
                let send = |e: Event| {
                    let _ = ev_tx.send(e);
                    repaint();
                };
                let ctx = match source {
                    DeviceSource::Headless => GpuContext::new_headless().map_err(|e| e.to_string()),
                    DeviceSource::Unavailable => {
                        Err("no GPU adapter (disabled for this session)".to_string())
                    }
                };
                match ctx {
                    Ok(ctx) => {
                        // A panic below (in the driver, most likely) must not leave the window
                        // waiting for frames that will never come: say so, and end the thread.
                        let served = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                            let t0 = Instant::now();
                            let renderer = Renderer::new(ctx);
                            log::info!("view pipeline compiled in {:.1?}", t0.elapsed());
                            let ctx = renderer.context();
                            send(Event::Ready {
                                adapter: ctx.describe(),
                                software: ctx.is_software(),
                            });
                            State::new(renderer).run(&req_rx, &send);
                        }));
                        if let Err(payload) = served {
                            let msg = panic_message(payload.as_ref());
                            log::error!("the render thread stopped: {msg}");
                            send(Event::Stopped(msg));
                        }
                    }
                    Err(e) => send(Event::NoAdapter(e)),
                }
            });
        let thread = spawned
            .inspect_err(|e| log::error!("cannot start the render thread: {e}"))
            .ok();
        Self {
            requests: Some(req_tx),
            events: ev_rx,
            thread,
        }
    }

    /// Ask for a new set of views (replaces any pending request).
    pub fn request(&self, r: Request) {
        if let Some(tx) = &self.requests {
            let _ = tx.send(r);
        }
    }

    /// Events that arrived since the last call.
    pub fn poll(&self) -> Vec<Event> {
        self.events.try_iter().collect()
    }

    /// Wait up to `timeout` for the next event (tests).
    #[cfg(test)]
    pub fn wait(&self, timeout: Duration) -> Option<Event> {
        self.events.recv_timeout(timeout).ok()
    }
}

/// The worker's state between requests.
struct State {
    renderer: Renderer,
    material: Option<(Arc<Material>, GpuMaterial)>,
    /// The last prepared material (its tables are reused when their inputs did not change).
    prepared: Option<Evaluator>,
    /// The environment radiance the prepared material was given.
    environment: Option<Sh9>,
    /// The measured BRDF the prepared material was given.
    measured: Option<Arc<MeasuredBrdf>>,
    /// Seconds per pixel of each analytic mode, measured.
    cost: Vec<(ViewMode, f64)>,
    truth: Option<ViewTarget>,
}

impl State {
    fn new(renderer: Renderer) -> Self {
        Self {
            renderer,
            material: None,
            prepared: None,
            environment: None,
            measured: None,
            cost: Vec::new(),
            truth: None,
        }
    }

    /// Newest request waiting, if any (drains the queue). `Err` when the editor is gone.
    fn newest(rx: &Receiver<Request>) -> Result<Option<Request>, ()> {
        let mut last = None;
        loop {
            match rx.try_recv() {
                Ok(r) => last = Some(r),
                Err(TryRecvError::Empty) => return Ok(last),
                Err(TryRecvError::Disconnected) => return Err(()),
            }
        }
    }

    fn run(mut self, rx: &Receiver<Request>, send: &dyn Fn(Event)) {
        let mut pending: Option<Request> = None;
        loop {
            let req = match pending.take() {
                Some(r) => r,
                // Idle with pipelines prewarm queued (OpenGL's device is this thread's alone):
                // once no request has come for a moment, compile one, then look again. The wait
                // keeps a quick switch of presets from queueing behind a compile it does not need.
                None if self.renderer.deferred_count() > 0 => {
                    match rx.recv_timeout(IDLE_BEFORE_COMPILE) {
                        Ok(r) => r,
                        Err(RecvTimeoutError::Timeout) => {
                            self.renderer.compile_deferred();
                            continue;
                        }
                        Err(RecvTimeoutError::Disconnected) => return,
                    }
                }
                None => match rx.recv_timeout(Duration::from_secs(3600)) {
                    Ok(r) => r,
                    Err(RecvTimeoutError::Timeout) => continue,
                    Err(RecvTimeoutError::Disconnected) => return,
                },
            };
            let req = match Self::newest(rx) {
                Ok(Some(newer)) => newer,
                Ok(None) => req,
                Err(()) => return,
            };
            match self.serve(&req, rx, send) {
                Ok(next) => pending = next,
                Err(()) => return,
            }
        }
    }

    fn upload(
        &mut self,
        material: &Arc<Material>,
        image: &Option<Arc<ImageDriver>>,
        environment: &Option<Sh9>,
        measured: &Option<Arc<MeasuredBrdf>>,
        march: March,
        send: &dyn Fn(Event),
    ) -> bool {
        let same_image = |p: &Evaluator| match (p.surface.driver.image(), image) {
            (None, None) => true,
            (Some(a), Some(b)) => Arc::ptr_eq(&a.image, b),
            _ => false,
        };
        if let Some((m, _)) = &self.material
            && (Arc::ptr_eq(m, material) || **m == **material)
            && self
                .prepared
                .as_ref()
                .is_some_and(|p| same_image(p) && p.surface.march == march)
            && self.environment == *environment
            && match (&self.measured, measured) {
                (None, None) => true,
                (Some(a), Some(b)) => Arc::ptr_eq(a, b),
                _ => false,
            }
        {
            return true;
        }
        match Evaluator::with_image(material, image.clone(), self.prepared.as_ref()) {
            Ok(mut p) => {
                p.surface.march = march;
                if let Some(sh) = environment {
                    p.set_environment_radiance(sh);
                }
                self.environment = *environment;
                if let Some(m) = measured {
                    p.set_measured(m.clone());
                }
                self.measured = measured.clone();
                match GpuMaterial::new(self.renderer.context(), &p, [0.0, 0.0]) {
                    Ok(gm) => {
                        self.material = Some((material.clone(), gm));
                        self.prepared = Some(p);
                        true
                    }
                    Err(e) => {
                        self.material = None;
                        send(Event::MaterialError(e.to_string()));
                        false
                    }
                }
            }
            Err(e) => {
                self.material = None;
                send(Event::MaterialError(e.to_string()));
                false
            }
        }
    }

    fn cost_of(&self, mode: ViewMode) -> Option<f64> {
        self.cost.iter().find(|(m, _)| *m == mode).map(|(_, c)| *c)
    }

    fn set_cost(&mut self, mode: ViewMode, per_pixel: f64) {
        match self.cost.iter_mut().find(|(m, _)| *m == mode) {
            Some(c) => c.1 = per_pixel,
            None => self.cost.push((mode, per_pixel)),
        }
    }

    /// First scale: the largest power-of-two fraction whose analytic passes fit the budget.
    fn first_scale(&self, req: &Request) -> f32 {
        let full = f64::from(req.size[0]) * f64::from(req.size[1]);
        let per_pixel: f64 = req
            .modes
            .iter()
            .filter(|m| **m != ViewMode::Truth)
            .map(|m| self.cost_of(*m).unwrap_or(2e-6))
            .sum::<f64>()
            .max(1e-12);
        let mut s = req.max_scale.clamp(MIN_SCALE, 1.0);
        while s > MIN_SCALE && full * f64::from(s * s) * per_pixel > PASS_BUDGET.as_secs_f64() {
            s *= 0.5;
        }
        s
    }

    fn size_at(req: &Request, scale: f32) -> (u32, u32) {
        let f = |v: u32| ((v as f32 * scale).round() as u32).max(1);
        (f(req.size[0]), f(req.size[1]))
    }

    /// Serve one request until done or superseded. Returns the superseding request, if any;
    /// `Err` when the editor has gone.
    fn serve(
        &mut self,
        req: &Request,
        rx: &Receiver<Request>,
        send: &dyn Fn(Event),
    ) -> Result<Option<Request>, ()> {
        #[cfg(test)]
        if req.generation == PANIC_GENERATION {
            panic!("injected for a test");
        }
        if !self.upload(
            &req.material,
            &req.image,
            &req.environment,
            &req.measured,
            req.march,
            send,
        ) {
            return Ok(None);
        }
        if let Some((_, gm)) = &self.material {
            // The pipeline this scene needs is compiled at its first draw; the variant for the
            // light on the other side of the normal (shadow rays or none) is compiled ahead (on
            // another thread, or on this one when it is idle on OpenGL, whose device one thread
            // must own), so dragging the light through the zenith does not wait for one.
            let f = gm.features();
            let shape = req.scene.shape;
            self.renderer.prewarm(vec![
                f.in_scene(shape, glam::DVec3::Z).normalized(),
                f.in_scene(shape, glam::DVec3::X).normalized(),
            ]);
        }
        let max_scale = req.max_scale.clamp(MIN_SCALE, 1.0);
        let mut scale = self.first_scale(req);
        loop {
            let size = Self::size_at(req, scale);
            for &mode in req.modes.iter().filter(|m| **m != ViewMode::Truth) {
                let Some((_, gm)) = &self.material else {
                    return Ok(None);
                };
                let t0 = Instant::now();
                let img = self.renderer.render_counted(gm, &req.scene, mode, size, 1);
                let dt = t0.elapsed();
                match img {
                    Ok((image, cut)) => {
                        self.set_cost(mode, dt.as_secs_f64() / f64::from(size.0 * size.1));
                        send(Event::Frame(Frame {
                            generation: req.generation,
                            mode,
                            image: Arc::new(image),
                            samples: 0,
                            rays: None,
                            predicted_sd: None,
                            predicted_bandwidth: None,
                            cost: None,
                            moments: None,
                            pass_time: dt,
                            cut_rays: cut,
                            scale,
                        }));
                    }
                    Err(e) => {
                        send(Event::RenderError(e.to_string()));
                        return Ok(None);
                    }
                }
                if let Some(newer) = Self::newest(rx)? {
                    return Ok(Some(newer));
                }
            }
            if scale >= max_scale {
                break;
            }
            scale = (scale * 2.0).min(max_scale);
        }
        if !req.modes.contains(&ViewMode::Truth) || req.truth_spp == 0 {
            return Ok(None);
        }
        if req.adaptive_truth {
            return self.accumulate_adaptive(req, scale, rx, send);
        }
        self.accumulate_truth(req, scale, rx, send)
    }

    /// The truth target at `size`, reused when it has that size.
    fn truth_target(&mut self, size: (u32, u32), send: &dyn Fn(Event)) -> Option<ViewTarget> {
        match self.truth.take() {
            Some(t) if t.size() == size => Some(t),
            _ => match ViewTarget::new(&self.renderer, size.0, size.1) {
                Ok(t) => Some(t),
                Err(e) => {
                    send(Event::RenderError(e.to_string()));
                    None
                }
            },
        }
    }
}

/// Longest side of the grid on which an adaptive truth's ray deviation is predicted (core, on the
/// CPU: about 25 µs a pixel here, so at most ~0.2 s on two cores).
const PREDICT_SIDE: u32 = 96;
/// An adaptive truth gives no pixel more than this many times the requested rays per pixel.
const MAX_RAYS_FACTOR: u32 = 8;

/// One truth ray's predicted luminance deviation per pixel of a `size` view of `scene`, predicted
/// on a grid of at most [`PREDICT_SIDE`] a side and upsampled to nearest.
fn predicted_deviation(prepared: &Evaluator, scene: &Scene, (w, h): (u32, u32)) -> Vec<f64> {
    let f = w.max(h).div_ceil(PREDICT_SIDE).max(1);
    let (sw, sh) = (w.div_ceil(f).max(1), h.div_ceil(f).max(1));
    let pred = prepared.predict_truth_of(scene.shape, &scene.camera, (sw, sh), scene.light);
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        let sy = (u64::from(y) * u64::from(sh) / u64::from(h.max(1))) as usize;
        for x in 0..w {
            let sx = (u64::from(x) * u64::from(sw) / u64::from(w.max(1))) as usize;
            out.push(pred.sd.get(sy * sw as usize + sx).copied().unwrap_or(0.0));
        }
    }
    out
}

/// The image's predicted bandwidth per pixel of a `size` view of `scene` (cycles per pixel of
/// that view), evaluated at the centres of blocks that leave at most [`PREDICT_SIDE`] a side
/// (about 22 µs a block here).
fn predicted_bandwidth(prepared: &Evaluator, scene: &Scene, (w, h): (u32, u32)) -> Vec<f32> {
    let step = w.max(h).div_ceil(PREDICT_SIDE).max(1);
    prepared
        .predict_bandwidth(scene.shape, &scene.camera, (w, h), scene.light, step)
        .cycles
        .into_iter()
        .map(|v| v as f32)
        .collect()
}

/// [`ray_costs`] as the frames carry it.
fn costs_f32(work: &[u32], rays: &[u32]) -> Vec<f32> {
    ray_costs(work, rays)
        .into_iter()
        .map(|c| c as f32)
        .collect()
}

#[cfg(test)]
mod tests;
