//! The editor: three linked views of one material (naive MIP, ground truth, filtered), the material
//! inspector, plots that follow the material, files, undo/redo and a persistent session.
//!
//! The views are drawn by a render worker on its own thread and device ([`worker`]); the window
//! only uploads finished images, so it stays responsive on a software adapter.

pub mod curve_editor;
pub mod gradient_editor;
pub mod history;
pub mod inspector;
pub mod plots;
pub mod priority;
pub mod report_panel;
pub mod view_state;
mod views;
pub mod worker;

#[cfg(test)]
mod tests;

use crate::preset_io;
use egui::{Key, KeyboardShortcut, Modifiers};
use history::History;
use inspector::Inspector;
use lodestone_core::environment::{Environment, EnvironmentSource};
use lodestone_core::image_driver::ImageDriver;
use lodestone_core::material::{Driver, Material};
use lodestone_core::sh::Sh9;
use lodestone_render::ViewMode;
use lodestone_render::error_map::ErrorStats;
use plots::AnglePlots;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use view_state::{Sweep, ViewState};
use worker::{DeviceSource, Event, Frame, Request, Worker};

/// Key of the session in eframe's storage.
const SESSION_KEY: &str = "lodestone-session";
/// Recent files kept.
const MAX_RECENT: usize = 8;

/// How the editor starts.
#[derive(Clone, Debug)]
pub struct Options {
    /// A preset given on the command line (already loaded), overriding the stored session.
    pub preset: Option<(PathBuf, Material)>,
    /// Where the render worker gets its device.
    pub device: DeviceSource,
    /// Restore and store the session (off in tests).
    pub persist: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            preset: None,
            device: DeviceSource::Headless,
            persist: true,
        }
    }
}

/// What is stored between runs.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(default)]
struct Session {
    /// The material being edited (saved or not).
    material: Option<Material>,
    /// The file it came from.
    path: Option<PathBuf>,
    /// The material as last saved or opened (unsaved changes are the difference).
    saved: Option<Material>,
    /// Camera, light and layout.
    view: ViewState,
    /// Recently opened or saved presets.
    recent: Vec<PathBuf>,
}

/// The render device's state as the window knows it.
#[derive(Clone, Debug, PartialEq)]
enum DeviceStatus {
    Starting,
    Ready(String),
    Failed(String),
}

/// The latest image of one mode, uploaded.
struct Shown {
    frame: Frame,
    texture: egui::TextureHandle,
}

/// The error heat map of one mode against ground truth, uploaded.
struct ErrorShown {
    texture: egui::TextureHandle,
    stats: ErrorStats,
    /// Generations of the two frames it was made from.
    from: (u64, u64, u32),
}

/// A message in the status bar.
#[derive(Clone, Debug)]
struct Notice {
    text: String,
    error: bool,
    time: f64,
}

/// What a confirmation dialog is about.
#[derive(Clone, Debug)]
enum Pending {
    /// Open this file, discarding unsaved changes.
    Open(PathBuf),
    /// Start a new material from the default.
    New,
}

/// A file loaded once per resolved path: the cache's result when `full` is the cached path, else
/// `load()` (stored). Returns the result and whether it was loaded just now.
fn cached_load<T: Clone>(
    cache: &mut Option<(PathBuf, Result<T, String>)>,
    full: PathBuf,
    load: impl FnOnce() -> Result<T, String>,
) -> (Result<T, String>, bool) {
    let fresh = cache.as_ref().is_none_or(|(p, _)| *p != full);
    if fresh {
        *cache = Some((full, load()));
    }
    let r = cache
        .as_ref()
        .map_or_else(|| Err("not loaded".to_owned()), |(_, r)| r.clone());
    (r, fresh)
}

/// The editor application.
pub struct EditorApp {
    material: Material,
    history: History,
    path: Option<PathBuf>,
    /// The driver image: resolved path and what loading it gave (cached; reloaded when the path
    /// or the preset's folder changes).
    image: Option<(PathBuf, Result<Arc<ImageDriver>, String>)>,
    /// The lighting's environment file: resolved path and its SH9 radiance (cached likewise).
    environment: Option<(PathBuf, Result<Sh9, String>)>,
    saved: Material,
    recent: Vec<PathBuf>,
    view: ViewState,
    inspector: Inspector,
    sweep: Option<Sweep>,
    worker: Worker,
    device: DeviceStatus,
    material_error: Option<String>,
    shown: HashMap<ViewMode, Shown>,
    errors: HashMap<ViewMode, ErrorShown>,
    generation: u64,
    last_request: Option<(Material, Request)>,
    /// Size of one viewport's image in physical pixels (the largest, when they differ).
    view_px: [u32; 2],
    plots: AnglePlots,
    report: report_panel::ReportPanel,
    notice: Option<Notice>,
    pending: Option<Pending>,
    frame_times: VecDeque<f64>,
    last_frame: Option<f64>,
    persist: bool,
    title: String,
    /// Hide timings (frame times, fps) so snapshots are reproducible.
    deterministic: bool,
    /// `LODESTONE_FPS_LOG=1`: repaint continuously and log the window's frame rate (measurements).
    fps_log: Option<f64>,
}

impl std::fmt::Debug for EditorApp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EditorApp")
            .field("material", &self.material.name)
            .field("path", &self.path)
            .finish_non_exhaustive()
    }
}

impl EditorApp {
    /// Create the editor (restores the stored session unless a preset is given).
    pub fn new(cc: &eframe::CreationContext<'_>, options: Options) -> Self {
        let stored: Session = if options.persist {
            cc.storage
                .and_then(|s| eframe::get_value(s, SESSION_KEY))
                .unwrap_or_default()
        } else {
            Session::default()
        };
        let mut notice = None;
        let (material, saved, path) = match options.preset {
            Some((p, m)) => {
                // Never lose unsaved work from the last session: keep a copy beside the session.
                if let (Some(cur), Some(sv)) = (&stored.material, &stored.saved)
                    && cur != sv
                {
                    notice = recover(cur).map(|p| Notice {
                        text: format!(
                            "The last session had unsaved changes; they were kept in {}",
                            p.display()
                        ),
                        error: false,
                        time: 0.0,
                    });
                }
                (m.clone(), m, Some(p))
            }
            None => {
                let m = stored
                    .material
                    .clone()
                    .filter(|m| m.validate().is_ok())
                    .unwrap_or_else(preset_io::default_material);
                let saved = stored.saved.clone().unwrap_or_else(|| m.clone());
                (m, saved, stored.path.clone())
            }
        };
        let ctx = cc.egui_ctx.clone();
        let device = if std::env::var_os("LODESTONE_NO_GPU").is_some() {
            DeviceSource::Unavailable
        } else {
            options.device
        };
        let worker = Worker::spawn(device, move || ctx.request_repaint());
        let mut app = Self {
            history: History::new(&material),
            inspector: Inspector::new(&material),
            material,
            path,
            image: None,
            environment: None,
            saved,
            recent: stored.recent.clone(),
            view: stored.view.clone(),
            sweep: None,
            worker,
            device: DeviceStatus::Starting,
            material_error: None,
            shown: HashMap::new(),
            errors: HashMap::new(),
            generation: 0,
            last_request: None,
            view_px: [0, 0],
            plots: AnglePlots::default(),
            report: report_panel::ReportPanel::default(),
            notice,
            pending: None,
            frame_times: VecDeque::new(),
            last_frame: None,
            persist: options.persist,
            title: String::new(),
            deterministic: false,
            fps_log: std::env::var_os("LODESTONE_FPS_LOG").map(|_| 0.0),
        };
        app.recent.retain(|p| p.exists());
        app
    }

    #[cfg(test)]
    /// Whether every view shows the latest request at its final resolution, ground truth has all
    /// its samples, error maps are up to date, and the plots are computed.
    pub fn idle(&self) -> bool {
        if !matches!(self.device, DeviceStatus::Ready(_)) || self.last_request.is_none() {
            return false;
        }
        let scale = self.view.max_scale.clamp(1.0 / 16.0, 1.0);
        let views_done = self.view.needed().iter().all(|m| {
            self.shown.get(m).is_some_and(|s| {
                s.frame.generation == self.generation
                    && s.frame.scale >= scale
                    && (*m != ViewMode::Truth || s.frame.samples >= self.view.truth_spp.max(1))
            })
        });
        let errors_done = !self.view.show_error
            || self.view.needed().iter().all(|m| {
                *m == ViewMode::Truth
                    || self
                        .errors
                        .get(m)
                        .is_some_and(|e| e.from.0 == self.generation && e.from.1 == self.generation)
            });
        let plots_done =
            !self.view.show_plots || (!self.plots.busy() && !self.plots.points().is_empty());
        views_done && errors_done && plots_done
    }

    /// Whether the material differs from the file.
    pub fn dirty(&self) -> bool {
        self.material != self.saved
    }

    /// The material being edited.
    #[cfg(test)]
    pub fn material(&self) -> &Material {
        &self.material
    }

    fn notify(&mut self, ctx: &egui::Context, text: impl Into<String>, error: bool) {
        let text = text.into();
        if error {
            log::warn!("{text}");
        }
        self.notice = Some(Notice {
            text,
            error,
            time: ctx.input(|i| i.time),
        });
    }

    fn remember(&mut self, p: &Path) {
        self.recent.retain(|q| q != p);
        self.recent.insert(0, p.to_owned());
        self.recent.truncate(MAX_RECENT);
    }

    /// The material with its driver image and environment file, loaded relative to the preset's
    /// folder (the current directory for an unsaved material). A load failure is reported once per
    /// path and leaves the file out (the views then show the material error, or no environment).
    fn resolved(&mut self, ctx: &egui::Context) -> preset_io::Resolved {
        let (image, environment) = self.load_files(ctx);
        preset_io::Resolved {
            material: self.material.clone(),
            image,
            environment,
        }
    }

    /// The driver image and environment radiance of [`EditorApp::resolved`], from the cache unless
    /// a path changed (cheap enough for every frame: nothing is cloned but the `Arc`).
    fn load_files(&mut self, ctx: &egui::Context) -> (Option<Arc<ImageDriver>>, Option<Sh9>) {
        let dir = self
            .path
            .as_ref()
            .and_then(|p| p.parent())
            .unwrap_or(Path::new("."))
            .to_owned();
        let (material, preset) = (&self.material, self.path.as_deref());
        let image = match &material.driver {
            Driver::Noise(_) => None,
            Driver::Image { path, .. } => {
                Some(cached_load(&mut self.image, dir.join(path), || {
                    preset_io::driver_image(material, preset)
                        .map_err(|e| e.to_string())
                        .and_then(|i| i.ok_or_else(|| "no image".to_owned()))
                }))
            }
        };
        let environment = match &material.lighting.environment {
            Some(Environment {
                source: EnvironmentSource::File { path },
                ..
            }) => Some(cached_load(&mut self.environment, dir.join(path), || {
                preset_io::environment_file(material, preset)
                    .map_err(|e| e.to_string())
                    .and_then(|i| i.ok_or_else(|| "no environment".to_owned()))
            })),
            _ => None,
        };
        (
            image.and_then(|r| self.report_load(ctx, r)),
            environment.and_then(|r| self.report_load(ctx, r)),
        )
    }

    /// The value of a [`cached_load`]; a fresh failure is reported (once: later calls hit the cache).
    fn report_load<T: Clone>(
        &mut self,
        ctx: &egui::Context,
        r: (Result<T, String>, bool),
    ) -> Option<T> {
        match r {
            (Ok(v), _) => Some(v),
            (Err(e), fresh) => {
                if fresh {
                    self.notify(ctx, e, true);
                }
                None
            }
        }
    }

    /// Open a preset now (no confirmation). Bad files leave everything as it was.
    pub fn open_path(&mut self, ctx: &egui::Context, p: &Path) {
        match preset_io::load(p) {
            Ok(m) => {
                self.history.reset(&m);
                self.inspector = Inspector::new(&m);
                self.saved = m.clone();
                self.material = m;
                self.path = Some(p.to_owned());
                self.remember(p);
                self.notify(ctx, format!("Opened {}", p.display()), false);
            }
            Err(e) => self.notify(ctx, e.to_string(), true),
        }
    }

    /// Open, asking first when there are unsaved changes.
    fn request_open(&mut self, ctx: &egui::Context, p: PathBuf) {
        if self.dirty() {
            self.pending = Some(Pending::Open(p));
        } else {
            self.open_path(ctx, &p);
        }
    }

    fn open_dialog(&mut self, ctx: &egui::Context) {
        let mut dlg = rfd::FileDialog::new().add_filter("Lodestone preset", &["ron"]);
        if let Some(dir) = self.path.as_ref().and_then(|p| p.parent()) {
            dlg = dlg.set_directory(dir);
        }
        if let Some(p) = dlg.pick_file() {
            self.request_open(ctx, p);
        }
    }

    /// Save to `p` (atomically).
    pub fn save_to(&mut self, ctx: &egui::Context, p: &Path) -> bool {
        match preset_io::save(p, &self.material) {
            Ok(()) => {
                self.saved = self.material.clone();
                self.path = Some(p.to_owned());
                self.remember(p);
                self.notify(ctx, format!("Saved {}", p.display()), false);
                true
            }
            Err(e) => {
                self.notify(ctx, e.to_string(), true);
                false
            }
        }
    }

    fn save(&mut self, ctx: &egui::Context) -> bool {
        match self.path.clone() {
            Some(p) => self.save_to(ctx, &p),
            None => self.save_as(ctx),
        }
    }

    fn save_as(&mut self, ctx: &egui::Context) -> bool {
        let name = format!("{}.ron", slug(&self.material.name));
        let mut dlg = rfd::FileDialog::new()
            .add_filter("Lodestone preset", &["ron"])
            .set_file_name(name);
        if let Some(dir) = self.path.as_ref().and_then(|p| p.parent()) {
            dlg = dlg.set_directory(dir);
        }
        match dlg.save_file() {
            Some(p) => self.save_to(ctx, &p),
            None => false,
        }
    }

    fn new_material(&mut self) {
        let m = preset_io::default_material();
        self.history.reset(&m);
        self.inspector = Inspector::new(&m);
        self.saved = m.clone();
        self.material = m;
        self.path = None;
    }

    /// Undo one step.
    pub fn undo(&mut self) -> bool {
        self.history.undo(&mut self.material)
    }

    /// Redo one step.
    pub fn redo(&mut self) -> bool {
        self.history.redo(&mut self.material)
    }

    /// Export the latest image of every rendered view (PNG, sRGB 8-bit, and EXR, linear) into `dir`,
    /// and for each analytic view its error against the ground truth (heat map PNG at the current
    /// error scale, per-channel |mode − truth| EXR).
    pub fn export_views(&self, dir: &Path) -> Result<Vec<PathBuf>, String> {
        let mut written = Vec::new();
        for (mode, s) in &self.shown {
            let name = match mode {
                ViewMode::Naive => "naive",
                ViewMode::ViewIndependent => "view-independent",
                ViewMode::Filtered => "filtered",
                ViewMode::Truth => "truth",
            };
            let png = dir.join(format!("{name}.png"));
            s.frame
                .image
                .to_srgb8()
                .save(&png)
                .map_err(|e| format!("{}: {e}", png.display()))?;
            let exr = dir.join(format!("{name}.exr"));
            image::DynamicImage::ImageRgba32F(s.frame.image.to_linear_f32())
                .save(&exr)
                .map_err(|e| format!("{}: {e}", exr.display()))?;
            written.extend([png, exr]);
            // The error map against the ground truth, when one of the same size is there.
            if let Some(t) = self.shown.get(&ViewMode::Truth).filter(|t| {
                *mode != ViewMode::Truth
                    && (t.frame.image.width, t.frame.image.height)
                        == (s.frame.image.width, s.frame.image.height)
            }) {
                use lodestone_render::error_map::{abs_difference, error_heat};
                let heat = error_heat(
                    &s.frame.image,
                    &t.frame.image,
                    f64::from(self.view.error_scale),
                );
                let png = dir.join(format!("error_{name}.png"));
                heat.to_srgb8()
                    .save(&png)
                    .map_err(|e| format!("{}: {e}", png.display()))?;
                let exr = dir.join(format!("error_{name}.exr"));
                image::DynamicImage::ImageRgba32F(
                    abs_difference(&s.frame.image, &t.frame.image).to_linear_f32(),
                )
                .save(&exr)
                .map_err(|e| format!("{}: {e}", exr.display()))?;
                written.extend([png, exr]);
            }
        }
        written.sort();
        Ok(written)
    }

    fn shortcuts(&mut self, ctx: &egui::Context) {
        let cmd_shift = Modifiers::COMMAND | Modifiers::SHIFT;
        let sc = |m, k| KeyboardShortcut::new(m, k);
        let (open, save_as, save, redo, redo_y, undo, new) = ctx.input_mut(|i| {
            (
                i.consume_shortcut(&sc(Modifiers::COMMAND, Key::O)),
                i.consume_shortcut(&sc(cmd_shift, Key::S)),
                i.consume_shortcut(&sc(Modifiers::COMMAND, Key::S)),
                i.consume_shortcut(&sc(cmd_shift, Key::Z)),
                i.consume_shortcut(&sc(Modifiers::COMMAND, Key::Y)),
                i.consume_shortcut(&sc(Modifiers::COMMAND, Key::Z)),
                i.consume_shortcut(&sc(Modifiers::COMMAND, Key::N)),
            )
        });
        if open {
            self.open_dialog(ctx);
        }
        if save_as {
            self.save_as(ctx);
        } else if save {
            self.save(ctx);
        }
        if redo || redo_y {
            self.redo();
        } else if undo {
            self.undo();
        }
        if new {
            if self.dirty() {
                self.pending = Some(Pending::New);
            } else {
                self.new_material();
            }
        }
        if !ctx.egui_wants_keyboard_input() {
            let (e, b, w, a) = ctx.input(|i| {
                (
                    i.key_pressed(Key::E),
                    i.key_pressed(Key::B),
                    i.key_pressed(Key::W),
                    i.key_pressed(Key::A),
                )
            });
            if e {
                self.view.show_error = !self.view.show_error;
            }
            if b {
                self.toggle_baseline();
            }
            if w {
                self.toggle_sweep(ctx);
            }
            if a {
                self.toggle_ab();
            }
        }
    }

    fn toggle_baseline(&mut self) {
        use view_state::Mode;
        self.view.baseline = match self.view.baseline {
            Mode::Naive => Mode::ViewIndependent,
            _ => Mode::Naive,
        };
    }

    fn toggle_ab(&mut self) {
        use view_state::{AbSwipe, Mode};
        self.view.ab = match self.view.ab {
            Some(_) => None,
            None => Some(AbSwipe {
                left: self.view.baseline,
                right: Mode::Filtered,
                split: 0.5,
            }),
        };
    }

    fn toggle_sweep(&mut self, ctx: &egui::Context) {
        self.sweep = match self.sweep {
            Some(s) => {
                self.view.camera.distance = s.start_distance;
                None
            }
            None => Some(Sweep {
                start_distance: self.view.camera.distance,
                start_time: ctx.input(|i| i.time),
                period: 12.0,
            }),
        };
    }

    /// Take the worker's news and upload new images.
    fn poll_worker(&mut self, ctx: &egui::Context) {
        for ev in self.worker.poll() {
            match ev {
                Event::Ready { adapter, software } => {
                    // A software rasterizer takes seconds per full-resolution frame: start at half
                    // resolution (the Resolution menu raises it).
                    if software && self.view.max_scale > 0.5 && !self.deterministic {
                        self.view.max_scale = 0.5;
                        self.notify(
                            ctx,
                            "Software GPU adapter: views render at 50% resolution (raise it under Resolution)",
                            false,
                        );
                    }
                    self.device = DeviceStatus::Ready(adapter);
                }
                Event::NoAdapter(e) => self.device = DeviceStatus::Failed(e),
                Event::MaterialError(e) => self.material_error = Some(e),
                Event::RenderError(e) => self.notify(ctx, e, true),
                Event::Frame(f) => {
                    self.material_error = None;
                    let img = f.image.to_srgb8();
                    let color = egui::ColorImage::from_rgba_unmultiplied(
                        [img.width() as usize, img.height() as usize],
                        img.as_raw(),
                    );
                    let opts = egui::TextureOptions::LINEAR;
                    match self.shown.get_mut(&f.mode) {
                        Some(s) => {
                            s.texture.set(color, opts);
                            s.frame = f;
                        }
                        None => {
                            let texture =
                                ctx.load_texture(format!("view-{:?}", f.mode), color, opts);
                            self.shown.insert(f.mode, Shown { frame: f, texture });
                        }
                    }
                }
            }
        }
    }

    /// Heat maps of each shown mode against the latest ground truth of the same size.
    fn update_errors(&mut self, ctx: &egui::Context) {
        if !self.view.show_error {
            return;
        }
        let Some(truth) = self.shown.get(&ViewMode::Truth) else {
            return;
        };
        let tf = &truth.frame;
        for (mode, s) in &self.shown {
            if *mode == ViewMode::Truth {
                continue;
            }
            let f = &s.frame;
            if (f.image.width, f.image.height) != (tf.image.width, tf.image.height) {
                continue;
            }
            let from = (f.generation, tf.generation, tf.samples);
            if self.errors.get(mode).is_some_and(|e| e.from == from) {
                continue;
            }
            let heat = lodestone_render::error_map::error_heat(
                &f.image,
                &tf.image,
                f64::from(self.view.error_scale),
            );
            let stats = lodestone_render::error_map::error_stats(&f.image, &tf.image);
            let img = heat.to_srgb8();
            let color = egui::ColorImage::from_rgba_unmultiplied(
                [img.width() as usize, img.height() as usize],
                img.as_raw(),
            );
            match self.errors.get_mut(mode) {
                Some(e) => {
                    e.texture.set(color, egui::TextureOptions::LINEAR);
                    e.stats = stats;
                    e.from = from;
                }
                None => {
                    let texture = ctx.load_texture(
                        format!("error-{mode:?}"),
                        color,
                        egui::TextureOptions::LINEAR,
                    );
                    self.errors.insert(
                        *mode,
                        ErrorShown {
                            texture,
                            stats,
                            from,
                        },
                    );
                }
            }
        }
    }

    /// Send the worker what the views need now, if it changed.
    fn request_views(&mut self, ctx: &egui::Context) {
        if self.view_px[0] == 0 || self.view_px[1] == 0 {
            return;
        }
        let scene = self.view.scene();
        let modes = self.view.needed();
        let truth_spp = self.view.truth_spp.max(1);
        let same = self.last_request.as_ref().is_some_and(|(m, r)| {
            *m == self.material
                && r.scene == scene
                && r.size == self.view_px
                && r.modes == modes
                && r.truth_spp == truth_spp
                && r.max_scale == self.view.max_scale
        });
        if same {
            return;
        }
        self.generation += 1;
        let resolved = self.resolved(ctx);
        let req = Request {
            generation: self.generation,
            material: Arc::new(self.material.clone()),
            image: resolved.image,
            environment: resolved.environment,
            scene,
            size: self.view_px,
            modes,
            truth_spp,
            max_scale: self.view.max_scale,
        };
        self.worker.request(req.clone());
        self.last_request = Some((self.material.clone(), req));
    }

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui
                    .add(egui::Button::new("New").shortcut_text("Ctrl+N"))
                    .clicked()
                {
                    if self.dirty() {
                        self.pending = Some(Pending::New);
                    } else {
                        self.new_material();
                    }
                }
                if ui
                    .add(egui::Button::new("Open…").shortcut_text("Ctrl+O"))
                    .clicked()
                {
                    self.open_dialog(&ctx);
                }
                ui.menu_button("Open recent", |ui| {
                    if self.recent.is_empty() {
                        ui.weak("No recent presets");
                    }
                    for p in self.recent.clone() {
                        if ui.button(p.display().to_string()).clicked() {
                            self.request_open(&ctx, p);
                        }
                    }
                });
                ui.menu_button("Built-in presets", |ui| {
                    for p in builtin_presets() {
                        let name = p
                            .file_stem()
                            .map(|s| s.to_string_lossy().into_owned())
                            .unwrap_or_default();
                        if ui.button(name).clicked() {
                            self.request_open(&ctx, p);
                        }
                    }
                });
                ui.separator();
                if ui
                    .add(egui::Button::new("Save").shortcut_text("Ctrl+S"))
                    .clicked()
                {
                    self.save(&ctx);
                }
                if ui
                    .add(egui::Button::new("Save as…").shortcut_text("Ctrl+Shift+S"))
                    .clicked()
                {
                    self.save_as(&ctx);
                }
                if ui
                    .button("Export engine bundle…")
                    .on_hover_text("Tables (EXR), manifest (JSON) and WGSL/GLSL snippets that evaluate the filtered material in another engine")
                    .clicked()
                    && let Some(dir) = rfd::FileDialog::new().pick_folder()
                {
                    let preset = self.resolved(&ctx);
                    match preset_io::export_bundle(&preset, &dir) {
                        Ok(w) => self.notify(
                            &ctx,
                            format!("Engine bundle: {} files in {}", w.len(), dir.display()),
                            false,
                        ),
                        Err(e) => self.notify(&ctx, format!("{e:#}"), true),
                    }
                }
                ui.separator();
                if ui
                    .button("Export views (PNG + EXR)…")
                    .on_hover_text(
                        "Write the current image of every view: 8-bit sRGB PNG and linear EXR",
                    )
                    .clicked()
                    && let Some(dir) = rfd::FileDialog::new().pick_folder()
                {
                    match self.export_views(&dir) {
                        Ok(w) => self.notify(
                            &ctx,
                            format!("Exported {} files to {}", w.len(), dir.display()),
                            false,
                        ),
                        Err(e) => self.notify(&ctx, e, true),
                    }
                }
            });
            ui.menu_button("Edit", |ui| {
                if ui
                    .add_enabled(
                        self.history.can_undo(&self.material),
                        egui::Button::new("Undo").shortcut_text("Ctrl+Z"),
                    )
                    .clicked()
                {
                    self.undo();
                }
                if ui
                    .add_enabled(
                        self.history.can_redo(),
                        egui::Button::new("Redo").shortcut_text("Ctrl+Shift+Z"),
                    )
                    .clicked()
                {
                    self.redo();
                }
            });
            ui.menu_button("View", |ui| {
                ui.checkbox(&mut self.view.show_error, "Error heat maps (E)");
                let mut vi = self.view.baseline == view_state::Mode::ViewIndependent;
                if ui
                    .checkbox(&mut vi, "View-independent baseline (B)")
                    .changed()
                {
                    self.toggle_baseline();
                }
                let mut ab = self.view.ab.is_some();
                if ui.checkbox(&mut ab, "A/B swipe (A)").changed() {
                    self.toggle_ab();
                }
                ui.checkbox(&mut self.view.show_plots, "Plots");
                ui.checkbox(&mut self.report.open, "Error against run time report");
                if ui.button("Sweep zoom (W)").clicked() {
                    self.toggle_sweep(&ctx);
                }
                if ui.button("Reset camera").clicked() {
                    self.view.camera = ViewState::default().camera;
                }
            });
            ui.menu_button("Help", |ui| {
                ui.label(
                    "Drag a view: orbit. Right-drag: move the light. Scroll: zoom.\n\
                     Double-click: reset the camera. E: error maps, B: baseline, A: A/B swipe,\n\
                     W: zoom sweep. Drop a .ron preset on the window to open it.",
                );
            });
        });
    }

    fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            if self.report.running() {
                ui.weak("Report running");
                ui.separator();
            }
            match &self.device {
                DeviceStatus::Starting => ui.weak("Starting the GPU device…"),
                DeviceStatus::Ready(a) => ui.weak(format!("Adapter: {a}")),
                DeviceStatus::Failed(_) => {
                    ui.colored_label(ui.visuals().error_fg_color, "No GPU adapter")
                }
            };
            ui.separator();
            for m in self.view.needed() {
                if let Some(s) = self.shown.get(&m) {
                    let f = &s.frame;
                    let mut t = if self.deterministic {
                        short(m).to_string()
                    } else {
                        format!("{}: {:.0} ms", short(m), f.pass_time.as_secs_f64() * 1e3)
                    };
                    if f.scale < 1.0 {
                        t += &format!(" @{:.0}%", f.scale * 100.0);
                    }
                    if m == ViewMode::Truth {
                        t += &format!(" ({}/{} spp)", f.samples, self.view.truth_spp);
                    }
                    ui.weak(t);
                }
            }
            if let Some(truth) = self.shown.get(&ViewMode::Truth) {
                let p = truth.frame.samples as f32 / self.view.truth_spp.max(1) as f32;
                ui.add(
                    egui::ProgressBar::new(p.min(1.0))
                        .desired_width(90.0)
                        .text("ground truth"),
                );
            }
            ui.separator();
            if !self.deterministic {
                let fps = self.fps();
                ui.weak(format!("UI {fps:.0} fps"));
            }
            let now = ui.input(|i| i.time);
            if let Some(n) = self
                .notice
                .as_ref()
                .filter(|n| n.error || now - n.time < 10.0)
            {
                ui.separator();
                if n.error {
                    ui.colored_label(ui.visuals().error_fg_color, &n.text);
                } else {
                    ui.label(&n.text);
                }
            }
        });
    }

    fn fps(&self) -> f64 {
        if self.frame_times.len() < 2 {
            return 0.0;
        }
        let span =
            self.frame_times.back().unwrap_or(&0.0) - self.frame_times.front().unwrap_or(&0.0);
        if span > 0.0 {
            (self.frame_times.len() - 1) as f64 / span
        } else {
            0.0
        }
    }

    fn confirm_dialog(&mut self, ctx: &egui::Context) {
        let Some(pending) = self.pending.clone() else {
            return;
        };
        let mut choice = None;
        egui::Modal::new(egui::Id::unique("unsaved")).show(ctx, |ui| {
            ui.heading("Unsaved changes");
            ui.label(format!(
                "'{}' has changes that are not saved. Save them first?",
                self.material.name
            ));
            ui.horizontal(|ui| {
                if ui.button("Save").clicked() {
                    choice = Some(0);
                }
                if ui.button("Discard").clicked() {
                    choice = Some(1);
                }
                if ui.button("Cancel").clicked() {
                    choice = Some(2);
                }
            });
        });
        let proceed = match choice {
            Some(0) => self.save(ctx),
            Some(1) => true,
            Some(_) => {
                self.pending = None;
                false
            }
            None => false,
        };
        if proceed {
            self.pending = None;
            match pending {
                Pending::Open(p) => self.open_path(ctx, &p),
                Pending::New => self.new_material(),
            }
        }
    }

    fn handle_drops(&mut self, ctx: &egui::Context) {
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        });
        if let Some(p) = dropped.into_iter().next() {
            let ext = p
                .extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase());
            if matches!(ext.as_deref(), Some("exr" | "hdr")) {
                // An environment map: the lighting's environment becomes that file (an undoable
                // edit); relative to the preset's folder when it lies inside it.
                let dir = self.path.as_ref().and_then(|p| p.parent());
                let path = dir
                    .and_then(|d| p.strip_prefix(d).ok())
                    .unwrap_or(&p)
                    .display()
                    .to_string();
                let intensity = self
                    .material
                    .lighting
                    .environment
                    .as_ref()
                    .map_or(1.0, |e| e.intensity);
                self.material.lighting.environment = Some(Environment {
                    source: EnvironmentSource::File { path: path.clone() },
                    intensity,
                });
                self.notify(ctx, format!("Environment: {path}"), false);
            } else {
                self.request_open(ctx, p);
            }
        }
    }

    fn update_title(&mut self, ctx: &egui::Context) {
        let file = self
            .path
            .as_ref()
            .and_then(|p| p.file_name())
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "untitled".into());
        let title = format!(
            "{}{} — {} — Lodestone",
            if self.dirty() { "* " } else { "" },
            self.material.name,
            file
        );
        if title != self.title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
    }

    fn session(&self) -> Session {
        Session {
            material: Some(self.material.clone()),
            path: self.path.clone(),
            saved: Some(self.saved.clone()),
            view: self.view.clone(),
            recent: self.recent.clone(),
        }
    }
}

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        let now = ctx.input(|i| i.time);
        self.frame_times.push_back(now);
        while self.frame_times.len() > 60 {
            self.frame_times.pop_front();
        }
        self.last_frame = Some(now);
        if let Some(last) = self.fps_log {
            ctx.request_repaint();
            if now - last > 2.0 {
                let truth = self
                    .shown
                    .get(&ViewMode::Truth)
                    .map_or(0, |s| s.frame.samples);
                let scale = self
                    .shown
                    .get(&ViewMode::Filtered)
                    .map_or(0.0, |s| s.frame.scale);
                log::warn!(
                    "fps {:.1} (truth {truth}/{} spp, analytic scale {scale})",
                    self.fps(),
                    self.view.truth_spp
                );
                self.fps_log = Some(now);
            }
        }
        self.poll_worker(&ctx);
        self.plots.poll();
        self.handle_drops(&ctx);
        self.shortcuts(&ctx);
        if let Some(s) = self.sweep {
            match s.distance(now) {
                Some(d) => {
                    self.view.camera.distance = d;
                    ctx.request_repaint();
                }
                None => {
                    self.view.camera.distance = s.start_distance;
                    self.sweep = None;
                }
            }
        }

        if self.report.ui(&ctx) == report_panel::Action::Start {
            let preset = self.resolved(&ctx);
            self.report.start(preset, ctx.clone());
        }
        egui::Panel::top("menu").show(ui, |ui| self.menu_bar(ui));
        egui::Panel::bottom("status").show(ui, |ui| self.status_bar(ui));
        egui::Panel::left("inspector")
            .resizable(true)
            .default_size(340.0)
            .min_size(260.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    ui.heading("Material");
                    if matches!(self.material.driver, Driver::Image { .. }) {
                        // Loads the image when its path changed (cached otherwise).
                        let _ = self.load_files(&ctx);
                    }
                    self.inspector.driver_image = match (&self.material.driver, &self.image) {
                        (Driver::Image { .. }, Some((_, Ok(img)))) => Some(img.clone()),
                        _ => None,
                    };
                    self.inspector.driver_shape = self
                        .inspector
                        .driver_image
                        .as_ref()
                        .map(|img| (img.skewness, img.excess_kurtosis));
                    if self.inspector.ui(ui, &mut self.material) {
                        ctx.request_repaint();
                    }
                    if let Err(problems) = self.material.validate() {
                        for p in problems {
                            ui.colored_label(ui.visuals().error_fg_color, p.to_string());
                        }
                    }
                });
            });
        if self.view.show_plots {
            let light = self.view.light();
            let az = self.view.camera.azimuth_deg;
            let interacting = ctx.egui_is_using_pointer();
            if !interacting && self.material.validate().is_ok() {
                let c = ctx.clone();
                let preset = self.resolved(&ctx);
                self.plots
                    .follow(&preset, light, az, move || c.request_repaint());
            }
            egui::Panel::bottom("plots")
                .resizable(true)
                .default_size(210.0)
                .min_size(120.0)
                .show(ui, |ui| self.plots.ui(ui));
        }
        egui::CentralPanel::default().show(ui, |ui| self.views_ui(ui));

        self.update_errors(&ctx);
        if self.material.validate().is_ok() {
            self.request_views(&ctx);
        }
        self.history
            .settle(&self.material, ctx.egui_is_using_pointer());
        self.confirm_dialog(&ctx);
        self.update_title(&ctx);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        if self.persist {
            eframe::set_value(storage, SESSION_KEY, &self.session());
        }
    }

    fn auto_save_interval(&self) -> std::time::Duration {
        std::time::Duration::from_secs(5)
    }
}

/// Short name of a mode for the status bar.
fn short(m: ViewMode) -> &'static str {
    match m {
        ViewMode::Naive => "naive",
        ViewMode::ViewIndependent => "view-indep.",
        ViewMode::Filtered => "filtered",
        ViewMode::Truth => "truth",
    }
}

/// A file-name-safe version of a material name.
fn slug(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect();
    let s = s.trim_matches('-').to_string();
    if s.is_empty() { "material".into() } else { s }
}

/// The presets shipped in `presets/` (when run from the source tree).
fn builtin_presets() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../presets");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|r| {
            r.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "ron"))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// Write an unsaved material to the recovery folder; returns its path.
fn recover(m: &Material) -> Option<PathBuf> {
    let dir = eframe::storage_dir("Lodestone")?.join("recovered");
    std::fs::create_dir_all(&dir).ok()?;
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let p = dir.join(format!("{}-{stamp}.ron", slug(&m.name)));
    preset_io::save(&p, m).ok().map(|()| p)
}
