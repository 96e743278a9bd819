//! The Report window: `lodestone report` from the editor, on a background thread with its own GPU
//! device. Progress and the two charts (error against view angle, error against time) fill in as
//! configurations finish; the result can be saved as report.json, report.md and SVG charts.

use crate::preset_io::Resolved;
use crate::report::{self, ConfigResult, Options, Report};
use egui_plot::{Legend, Line, Plot, PlotPoints, Points};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

#[derive(Default)]
struct Shared {
    done: usize,
    total: usize,
    configs: Vec<ConfigResult>,
    finished: Option<Result<Report, String>>,
}

/// What the window asks the editor to do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Nothing.
    None,
    /// Start a report on the current material.
    Start,
}

/// The Report window's state.
pub struct ReportPanel {
    /// Whether the window is shown.
    pub open: bool,
    width: u32,
    height: u32,
    reference_spp: u32,
    shared: Arc<Mutex<Shared>>,
    cancel: Arc<AtomicBool>,
    running: bool,
    message: Option<String>,
    /// The running (or last) report thread, joined before the next starts and on drop.
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Drop for ReportPanel {
    /// Cancels a running report and waits for its thread, so its GPU device is gone before the
    /// process exits (see `Worker`'s drop).
    fn drop(&mut self) {
        self.stop();
    }
}

impl Default for ReportPanel {
    fn default() -> Self {
        Self {
            open: false,
            width: 16,
            height: 10,
            reference_spp: 64,
            shared: Arc::default(),
            cancel: Arc::new(AtomicBool::new(false)),
            running: false,
            message: None,
            thread: None,
        }
    }
}

const COLORS: [egui::Color32; 4] = [
    egui::Color32::from_rgb(230, 90, 80),
    egui::Color32::from_rgb(90, 140, 230),
    egui::Color32::from_rgb(240, 170, 60),
    egui::Color32::from_rgb(90, 200, 110),
];

const NAMES: [&str; 4] = [
    "naive MIP",
    "view-independent",
    "filtered (paper fits, uncorrelated)",
    "filtered (exact, correlated)",
];

impl ReportPanel {
    /// Set the image size and reference rays of the next run (tests and screenshots).
    #[cfg(test)]
    pub fn set_budget(&mut self, width: u32, height: u32, reference_spp: u32) {
        self.width = width;
        self.height = height;
        self.reference_spp = reference_spp;
    }

    /// Whether a report is running.
    pub fn running(&self) -> bool {
        self.running
    }

    /// Cancel a running report and wait for its thread (at most one truth pass).
    fn stop(&mut self) {
        self.cancel.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take()
            && t.join().is_err()
        {
            log::error!("the report thread panicked");
        }
    }

    /// Start a report on `preset` (cancels a running one).
    pub fn start(&mut self, preset: Resolved, ctx: egui::Context) {
        self.stop();
        self.cancel = Arc::new(AtomicBool::new(false));
        self.shared = Arc::default();
        self.running = true;
        self.message = None;
        let opts = Options {
            size: (self.width.max(4), self.height.max(4)),
            reference_spp: self.reference_spp.max(4),
            repeats: 3,
            ..Options::default()
        };
        let (shared, cancel) = (self.shared.clone(), self.cancel.clone());
        self.thread = Some(std::thread::spawn(move || {
            super::priority::lower_current_thread();
            let progress = |done: usize, total: usize, c: &ConfigResult| {
                if let Ok(mut s) = shared.lock() {
                    s.done = done;
                    s.total = total;
                    s.configs.push(c.clone());
                }
                ctx.request_repaint();
            };
            let r = report::run_with(&preset, &opts, &progress, &|| cancel.load(Ordering::SeqCst));
            if let Ok(mut s) = shared.lock() {
                s.finished = Some(r.map_err(|e| format!("{e:#}")));
            }
            ctx.request_repaint();
        }));
    }

    /// The window; returns what the editor should do.
    pub fn ui(&mut self, ctx: &egui::Context) -> Action {
        let mut action = Action::None;
        if !self.open {
            return action;
        }
        let mut open = self.open;
        egui::Window::new("Error against run time")
            .open(&mut open)
            .default_size([760.0, 520.0])
            .show(ctx, |ui| action = self.contents(ui));
        self.open = open;
        action
    }

    fn contents(&mut self, ui: &mut egui::Ui) -> Action {
        let mut action = Action::None;
        let (done, total, configs, finished) = match self.shared.lock() {
            Ok(s) => (s.done, s.total, s.configs.clone(), s.finished.clone()),
            Err(_) => (0, 0, Vec::new(), None),
        };
        if let Some(f) = &finished {
            self.running = false;
            if let Err(e) = f {
                self.message = Some(e.clone());
            }
        }
        ui.label(
            "Every method against a ground-truth reference over view angles 0 to 89 degrees, light at \
             the normal, along the view and opposite, and three zoom levels (lodestone report).",
        );
        ui.horizontal(|ui| {
            ui.add(
                egui::DragValue::new(&mut self.width)
                    .range(4..=512)
                    .prefix("width "),
            )
            .on_hover_text("Image width of every rendering (pixels)");
            ui.add(
                egui::DragValue::new(&mut self.height)
                    .range(4..=512)
                    .prefix("height "),
            )
            .on_hover_text("Image height of every rendering (pixels)");
            ui.add(
                egui::DragValue::new(&mut self.reference_spp)
                    .range(4..=4096)
                    .prefix("reference rays "),
            )
            .on_hover_text(
                "Ground-truth rays per pixel of the reference (1024 in the command's default)",
            );
            if self.running {
                if ui.button("Cancel").clicked() {
                    self.cancel.store(true, Ordering::SeqCst);
                }
            } else if ui.button("Run").clicked() {
                action = Action::Start;
            }
            if let Some(Ok(rep)) = &finished
                && ui.button("Save...").clicked()
                && let Some(dir) = rfd::FileDialog::new().pick_folder()
            {
                self.message = Some(match report::write(rep, &dir) {
                    Ok(()) => format!(
                        "Saved report.json, report.md and charts in {}",
                        dir.display()
                    ),
                    Err(e) => format!("Saving failed: {e:#}"),
                });
            }
        });
        if total > 0 {
            ui.add(
                egui::ProgressBar::new(done as f32 / total as f32)
                    .text(format!("{done} of {total} configurations"))
                    .animate(self.running),
            );
        }
        if let Some(m) = &self.message {
            ui.label(m);
        }
        if configs.is_empty() {
            return action;
        }
        let h = (ui.available_height() - 30.0).max(120.0);
        let w = (ui.available_width() / 2.0 - 8.0).max(150.0);
        ui.horizontal(|ui| {
            let mut zooms: Vec<f64> = configs.iter().map(|c| c.distance).collect();
            zooms.dedup();
            let mid = zooms[zooms.len() / 2];
            Plot::new("report_error_vs_view")
                .legend(Legend::default())
                .width(w)
                .height(h)
                .x_axis_label(format!(
                    "view angle (degrees), light at the normal, distance {mid}"
                ))
                .y_axis_label("mean Delta E")
                .include_y(0.0)
                .show(ui, |plot| {
                    for (i, name) in NAMES.iter().enumerate() {
                        let pts: Vec<[f64; 2]> = configs
                            .iter()
                            .filter(|c| c.distance == mid && c.light == "normal")
                            .map(|c| [c.view_deg, c.methods[i].delta_e_mean])
                            .collect();
                        plot.line(
                            Line::new(*name, PlotPoints::from(pts))
                                .color(COLORS[i])
                                .width(2.0),
                        );
                    }
                });
            Plot::new("report_error_vs_time")
                .legend(Legend::default())
                .width(w)
                .height(h)
                .x_axis_label("log10 ms per frame (all configurations)")
                .y_axis_label("mean Delta E")
                .include_y(0.0)
                .show(ui, |plot| {
                    let n = configs.len() as f64;
                    let methods = configs[0].methods.len();
                    let avg = |i: usize| {
                        let t = configs.iter().map(|c| c.methods[i].ms).sum::<f64>() / n;
                        let e = configs
                            .iter()
                            .map(|c| c.methods[i].delta_e_mean)
                            .sum::<f64>()
                            / n;
                        [t.max(1e-6).log10(), e]
                    };
                    for (i, name) in NAMES.iter().enumerate() {
                        plot.points(
                            Points::new(*name, vec![avg(i)])
                                .radius(6.0)
                                .color(COLORS[i]),
                        );
                    }
                    let truth: Vec<[f64; 2]> = (NAMES.len()..methods).map(avg).collect();
                    plot.line(Line::new(
                        "ground truth, 1 to 256 rays",
                        PlotPoints::from(truth),
                    ));
                });
        });
        action
    }
}
