//! The editor: three linked views of one material (naive MIP, ground truth, filtered), the material
//! inspector, plots that follow the material, files, undo/redo and a persistent session.
//!
//! The views are drawn by a render worker on its own thread and device ([`worker`]); the window
//! only uploads finished images ([`frames`]), so it stays responsive on a software adapter.
//!
//! The parts: the [`document::Document`] (material, history, file, saved state, referenced
//! files), the [`commands::Command`] set with its shortcuts, the [`menu`], the [`status_bar`],
//! file operations ([`files`]), the inspector, views and plots.

mod commands;
pub mod curve_editor;
mod document;
mod files;
mod frames;
pub mod gradient_editor;
pub mod history;
pub mod inspector;
mod menu;
pub mod object_panel;
pub mod plots;
pub mod priority;
pub mod report_panel;
mod status_bar;
mod truth_maps;
pub mod view_state;
mod views;
pub mod worker;

#[cfg(test)]
mod tests;

use crate::preset_io;
use document::Document;
use files::recover;
use inspector::Inspector;
use lodestone_core::material::{Driver, Material};
use lodestone_render::ViewMode;
use plots::AnglePlots;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, VecDeque};
use std::path::{Path, PathBuf};
use view_state::{Sweep, ViewState};
use worker::{DeviceSource, Frame, Request, Worker};

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
    summary: frames::ErrorSummary,
    /// Generations of the two frames it was made from, the truth's rays, the block size and the
    /// heat scale's bits.
    from: (u64, u64, u32, u32, u32),
}

/// The ground truth's noise map as the truth viewport shows it, uploaded.
struct TruthHeatShown {
    texture: egui::TextureHandle,
    /// The value at the top of its scale.
    max: f64,
    /// The truth frame's generation and rays, and the display it shows.
    from: (u64, u32, view_state::TruthDisplay),
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

/// The editor application.
pub struct EditorApp {
    /// The material, its history and file.
    doc: Document,
    /// Recently opened or saved presets.
    recent: Vec<PathBuf>,
    view: ViewState,
    inspector: Inspector,
    sweep: Option<Sweep>,
    worker: Worker,
    /// Where the worker's device comes from (for a restart).
    device_source: DeviceSource,
    /// Render threads started again after one stopped on a panic.
    restarts: u32,
    device: DeviceStatus,
    material_error: Option<String>,
    shown: HashMap<ViewMode, Shown>,
    errors: HashMap<ViewMode, ErrorShown>,
    truth_heat: Option<TruthHeatShown>,
    generation: u64,
    last_request: Option<(Material, Request)>,
    /// Size of one viewport's image in physical pixels (the largest, when they differ).
    view_px: [u32; 2],
    plots: AnglePlots,
    report: report_panel::ReportPanel,
    object: object_panel::ObjectPanel,
    notice: Option<Notice>,
    pending: Option<Pending>,
    frame_times: VecDeque<f64>,
    last_frame: Option<f64>,
    persist: bool,
    title: String,
    /// Hide timings (pass times, fps) and the adapter's name so snapshots are reproducible.
    deterministic: bool,
    /// Files of the material still loading (status bar).
    loading: Vec<PathBuf>,
    /// `LODESTONE_FPS_LOG=1`: repaint continuously and log the window's frame rate (measurements).
    fps_log: Option<f64>,
}

impl std::fmt::Debug for EditorApp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EditorApp")
            .field("material", &self.doc.material.name)
            .field("path", &self.doc.path)
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
        let device_source = device;
        let worker = Worker::spawn(device, move || ctx.request_repaint());
        let mut app = Self {
            inspector: Inspector::new(&material),
            doc: Document::new(material, saved, path),
            recent: stored.recent.clone(),
            view: stored.view.clone(),
            sweep: None,
            worker,
            device_source,
            restarts: 0,
            device: DeviceStatus::Starting,
            material_error: None,
            shown: HashMap::new(),
            errors: HashMap::new(),
            truth_heat: None,
            generation: 0,
            last_request: None,
            view_px: [0, 0],
            plots: AnglePlots::default(),
            report: report_panel::ReportPanel::default(),
            object: object_panel::ObjectPanel::on(device_source),
            notice,
            pending: None,
            frame_times: VecDeque::new(),
            last_frame: None,
            persist: options.persist,
            title: String::new(),
            deterministic: false,
            loading: Vec::new(),
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

    /// The material being edited.
    #[cfg(test)]
    pub fn material(&self) -> &Material {
        &self.doc.material
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

    /// The material with its driver image, environment file and measured BRDF, loaded relative to the preset's
    /// folder (the current directory for an unsaved material). A load failure is reported once per
    /// path and leaves the file out (the views then show the material error, or no environment).
    /// `None` while a file is still loading (the status bar says which; the window repaints until
    /// it has loaded).
    fn resolved(&mut self, ctx: &egui::Context) -> Option<preset_io::Resolved> {
        let files = self.load_files(ctx);
        if !files.pending.is_empty() {
            ctx.request_repaint_after(std::time::Duration::from_millis(30));
            return None;
        }
        Some(preset_io::Resolved {
            material: self.doc.material.clone(),
            image: files.image,
            environment: files.environment,
            measured: files.measured,
        })
    }

    /// [`Self::resolved`] for a command the user asked for: while a file loads, a notice says so.
    fn resolved_now(&mut self, ctx: &egui::Context) -> Option<preset_io::Resolved> {
        let r = self.resolved(ctx);
        if r.is_none() {
            let files = self.loading.iter().map(|p| p.display().to_string());
            let text = format!(
                "Still loading {}: try again when it has loaded",
                files.collect::<Vec<_>>().join(", ")
            );
            self.notify(ctx, text, true);
        }
        r
    }

    /// The document's files ([`Document::load_files`]), each new failure reported once.
    fn load_files(&mut self, ctx: &egui::Context) -> document::LoadedFiles {
        let mut files = self.doc.load_files();
        for e in std::mem::take(&mut files.new_errors) {
            self.notify(ctx, e, true);
        }
        self.loading.clone_from(&files.pending);
        files
    }

    fn update_title(&mut self, ctx: &egui::Context) {
        let file = self
            .doc
            .path
            .as_ref()
            .and_then(|p| p.file_name())
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "untitled".into());
        let title = format!(
            "{}{} — {} — Lodestone",
            if self.doc.dirty() { "* " } else { "" },
            self.doc.material.name,
            file
        );
        if title != self.title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
    }

    fn session(&self) -> Session {
        Session {
            material: Some(self.doc.material.clone()),
            path: self.doc.path.clone(),
            saved: Some(self.doc.saved.clone()),
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
                    self.fps().unwrap_or(0.0),
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

        if self.report.ui(&ctx) == report_panel::Action::Start
            && let Some(preset) = self.resolved_now(&ctx)
        {
            self.report.start(preset, ctx.clone());
        }
        if self.object.ui(&ctx, &self.view) == object_panel::Action::Build
            && let Some(preset) = self.resolved_now(&ctx)
        {
            self.object.build(&ctx, preset.material);
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
                    if matches!(self.doc.material.driver, Driver::Image { .. })
                        || self.doc.material.brdf.measured.is_some()
                    {
                        // Loads the image or the measured BRDF when its path changed (cached
                        // otherwise).
                        let _ = self.load_files(&ctx);
                    }
                    self.inspector.measured_fit = self.doc.measured().map(|m| m.fit.clone());
                    self.inspector.driver_image = self.doc.driver_image();
                    self.inspector.driver_shape = self
                        .inspector
                        .driver_image
                        .as_ref()
                        .map(|img| (img.skewness, img.excess_kurtosis));
                    if self.inspector.ui(ui, &mut self.doc.material) {
                        ctx.request_repaint();
                    }
                    if let Err(problems) = self.doc.material.validate() {
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
            if !interacting
                && self.doc.material.validate().is_ok()
                && let Some(preset) = self.resolved(&ctx)
            {
                let c = ctx.clone();
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
        self.update_truth_heat(&ctx);
        if self.doc.material.validate().is_ok() {
            self.request_views(&ctx);
        }
        self.doc
            .history
            .settle(&self.doc.material, ctx.egui_is_using_pointer());
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
