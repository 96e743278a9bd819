//! Plots that follow the material: the mean colour of a far, fully filtered patch against view angle
//! under every mode (like [HN12 Fig. 9]) and the relative error of naive and filtered against ground
//! truth. Computed by the CPU reference (lodestone-core) on a background thread, so a change of
//! material never blocks the window; a newer request cancels an older one between angles.

use crate::preset_io::Resolved;
use egui::Color32;
use egui_plot::{Corner, Legend, Line, Plot, PlotPoints};
use lodestone_core::eval::FootprintQuery;
use lodestone_core::material::Material;
use lodestone_core::scene::direction::direction;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, Sender};
use std::sync::{Arc, Mutex};

/// View angles of the curves (degrees).
pub const ANGLES: [f64; 14] = [
    0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 65.0, 70.0, 75.0, 80.0, 83.0, 86.0, 88.0,
];
/// Ground-truth eye rays per angle.
pub const TRUTH_SAMPLES: usize = 3000;

/// Mean linear luminance of every mode at one view angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnglePoint {
    /// View angle (degrees).
    pub angle: f64,
    /// Naive MIP.
    pub naive: f64,
    /// View-independent filtering.
    pub view_independent: f64,
    /// Filtered.
    pub filtered: f64,
    /// Ground truth.
    pub truth: f64,
    /// Its standard error.
    pub truth_se: f64,
}

/// Rec. 709 luminance of linear RGB.
pub fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// The curves for one material and light, by the CPU reference. `cancel` returns true to stop.
pub fn compute(
    m: &Resolved,
    light: glam::DVec3,
    azimuth_deg: f64,
    cancel: &(dyn Fn() -> bool + Sync),
) -> Result<Vec<AnglePoint>, String> {
    let p = m.prepare().map_err(|e| e.to_string())?;
    let points: Vec<Option<AnglePoint>> = ANGLES
        .par_iter()
        .map(|&a| {
            if cancel() {
                return None;
            }
            let wo = direction(a.to_radians(), azimuth_deg.to_radians());
            let cfg = FootprintQuery::far(&p, wo, light);
            let gt = p.ground_truth(&cfg, TRUTH_SAMPLES, 7);
            Some(AnglePoint {
                angle: a,
                naive: luminance(p.naive(&cfg)),
                view_independent: luminance(p.view_independent(&cfg)),
                filtered: luminance(p.filtered(&cfg)),
                truth: luminance(gt.mean),
                truth_se: luminance(gt.std_error),
            })
        })
        .collect();
    points
        .into_iter()
        .collect::<Option<Vec<_>>>()
        .ok_or_else(|| "cancelled".into())
}

/// Inputs of the curves.
#[derive(Clone, Debug, PartialEq)]
struct Key {
    material: Material,
    light: [f64; 3],
    azimuth: f64,
}

/// The plots panel: requests, background results and drawing.
#[derive(Debug)]
pub struct AnglePlots {
    key: Option<Key>,
    generation: Arc<AtomicU64>,
    tx: Sender<(u64, Result<Vec<AnglePoint>, String>)>,
    rx: Receiver<(u64, Result<Vec<AnglePoint>, String>)>,
    points: Vec<AnglePoint>,
    error: Option<String>,
    busy: Arc<Mutex<bool>>,
    /// Computation threads not yet joined (superseded ones finish at their next cancel check).
    threads: Vec<std::thread::JoinHandle<()>>,
}

impl Drop for AnglePlots {
    /// Cancels and joins every computation, so no thread outlives the editor.
    fn drop(&mut self) {
        self.generation.fetch_add(1, Ordering::SeqCst);
        for t in self.threads.drain(..) {
            if t.join().is_err() {
                log::error!("a plot computation panicked");
            }
        }
    }
}

impl Default for AnglePlots {
    fn default() -> Self {
        let (tx, rx) = std::sync::mpsc::channel();
        Self {
            key: None,
            generation: Arc::new(AtomicU64::new(0)),
            tx,
            rx,
            points: Vec::new(),
            error: None,
            busy: Arc::new(Mutex::new(false)),
            threads: Vec::new(),
        }
    }
}

impl AnglePlots {
    /// Follow `m` under `light` (seen from `azimuth_deg`); recomputes in the background when they
    /// changed. `repaint` wakes the UI when results arrive.
    pub fn follow(
        &mut self,
        m: &Resolved,
        light: glam::DVec3,
        azimuth_deg: f64,
        repaint: impl Fn() + Send + 'static,
    ) {
        let key = Key {
            material: m.material.clone(),
            light: light.to_array(),
            azimuth: azimuth_deg,
        };
        if self.key.as_ref() == Some(&key) {
            return;
        }
        self.key = Some(key);
        let generation = self.generation.fetch_add(1, Ordering::SeqCst) + 1;
        let counter = self.generation.clone();
        let tx = self.tx.clone();
        let m = m.clone();
        let busy = self.busy.clone();
        if let Ok(mut b) = busy.lock() {
            *b = true;
        }
        self.threads.retain(|t| !t.is_finished());
        self.threads.push(std::thread::spawn(move || {
            super::priority::lower_current_thread();
            let cancel = || counter.load(Ordering::SeqCst) != generation;
            let r = compute(&m, light, azimuth_deg, &cancel);
            if !cancel() {
                if let Ok(mut b) = busy.lock() {
                    *b = false;
                }
                let _ = tx.send((generation, r));
                repaint();
            }
        }));
    }

    /// Take finished results.
    pub fn poll(&mut self) {
        let current = self.generation.load(Ordering::SeqCst);
        for (g, r) in self.rx.try_iter() {
            if g != current {
                continue;
            }
            match r {
                Ok(p) => {
                    self.points = p;
                    self.error = None;
                }
                Err(e) => self.error = Some(e),
            }
        }
    }

    /// Whether a computation is running.
    pub fn busy(&self) -> bool {
        self.busy.lock().map(|b| *b).unwrap_or(false)
    }

    /// The latest curves.
    #[cfg(test)]
    pub fn points(&self) -> &[AnglePoint] {
        &self.points
    }

    /// Draw both plots side by side.
    pub fn ui(&self, ui: &mut egui::Ui) {
        if let Some(e) = &self.error {
            ui.colored_label(ui.visuals().error_fg_color, e);
            return;
        }
        let height = (ui.available_height() - 20.0).max(80.0);
        let width = ((ui.available_width() - 16.0) * 0.5).max(120.0);
        let curve = |f: &dyn Fn(&AnglePoint) -> f64| -> PlotPoints<'static> {
            self.points.iter().map(|p| [p.angle, f(p)]).collect()
        };
        let legend = || {
            Legend::default()
                .position(Corner::LeftTop)
                .text_style(egui::TextStyle::Small)
                .background_alpha(0.6)
                .follow_insertion_order(true)
        };
        const NAIVE: Color32 = Color32::from_rgb(230, 90, 80);
        const VI: Color32 = Color32::from_rgb(90, 150, 240);
        const FILTERED: Color32 = Color32::from_rgb(110, 210, 110);
        const TRUTH: Color32 = Color32::from_rgb(240, 240, 240);
        ui.horizontal(|ui| {
            ui.vertical(|ui| {
                ui.label(if self.busy() {
                    "Mean luminance of a far patch vs view angle (updating…)"
                } else {
                    "Mean luminance of a far patch vs view angle"
                });
                Plot::new("mean_vs_angle")
                    .legend(legend())
                    .width(width)
                    .height(height)
                    .x_axis_label("view angle (°)")
                    .include_y(0.0)
                    .include_x(0.0)
                    .include_x(90.0)
                    .allow_scroll(false)
                    .show(ui, |plot| {
                        plot.line(
                            Line::new("Ground truth", curve(&|p| p.truth))
                                .color(TRUTH)
                                .width(2.5),
                        );
                        plot.line(Line::new("Naive MIP", curve(&|p| p.naive)).color(NAIVE));
                        plot.line(
                            Line::new("View-independent", curve(&|p| p.view_independent)).color(VI),
                        );
                        plot.line(Line::new("Filtered", curve(&|p| p.filtered)).color(FILTERED));
                    });
            });
            ui.vertical(|ui| {
                ui.label("Relative error against ground truth (%)");
                let rel = |v: f64, t: f64| 100.0 * (v - t).abs() / t.abs().max(1e-9);
                Plot::new("error_vs_angle")
                    .legend(legend())
                    .width(width)
                    .height(height)
                    .x_axis_label("view angle (°)")
                    .include_y(0.0)
                    .include_x(0.0)
                    .include_x(90.0)
                    .allow_scroll(false)
                    .show(ui, |plot| {
                        plot.line(
                            Line::new("Naive MIP", curve(&|p| rel(p.naive, p.truth))).color(NAIVE),
                        );
                        plot.line(
                            Line::new(
                                "View-independent",
                                curve(&|p| rel(p.view_independent, p.truth)),
                            )
                            .color(VI),
                        );
                        plot.line(
                            Line::new("Filtered", curve(&|p| rel(p.filtered, p.truth)))
                                .color(FILTERED),
                        );
                    });
            });
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The curves agree with `lodestone eval`'s numbers: filtered within a few percent of truth at
    /// moderate angles, naive off at grazing angles (the default material).
    #[test]
    fn curves_show_filtered_tracking_truth() {
        let m = Resolved::without_image(crate::preset_io::default_material());
        let light = direction(0.0, 0.0);
        let pts = compute(&m, light, 0.0, &|| false).expect("curves");
        assert_eq!(pts.len(), ANGLES.len());
        for p in &pts {
            assert!(p.naive.is_finite() && p.filtered.is_finite() && p.truth.is_finite());
            if p.angle <= 60.0 {
                let rel = (p.filtered - p.truth).abs() / p.truth;
                assert!(rel < 0.02 + 3.0 * p.truth_se / p.truth, "{p:?}");
            }
        }
        let last = pts.last().expect("points");
        assert!((last.naive - last.truth).abs() > (last.filtered - last.truth).abs());
    }

    #[test]
    fn a_cancelled_computation_says_so() {
        let m = Resolved::without_image(crate::preset_io::default_material());
        assert!(compute(&m, direction(0.0, 0.0), 0.0, &|| true).is_err());
    }
}
