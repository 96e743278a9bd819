//! The status bar: device, each view's pass time and resolution, ground-truth progress, UI frame
//! rate and the latest notice.

use super::{DeviceStatus, EditorApp};
use lodestone_render::ViewMode;

impl EditorApp {
    pub(super) fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            if self.report.running() {
                ui.weak("Report running");
                ui.separator();
            }
            match &self.device {
                DeviceStatus::Starting => ui.weak("Starting the GPU device…"),
                // Snapshots leave the adapter's name out: it is not what they test.
                DeviceStatus::Ready(_) if self.deterministic => ui.weak("Adapter ready"),
                DeviceStatus::Ready(a) => ui.weak(format!("Adapter: {a}")),
                DeviceStatus::Failed(_) => {
                    ui.colored_label(ui.visuals().error_fg_color, "No GPU adapter")
                }
            };
            ui.separator();
            for p in &self.loading {
                let name = p.file_name().map_or_else(
                    || p.display().to_string(),
                    |n| n.to_string_lossy().into_owned(),
                );
                ui.add(egui::Spinner::new());
                ui.weak(format!("Loading {name}…"));
                ui.separator();
            }
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
                        let adaptive = if f.rays.is_some() { " adaptive" } else { "" };
                        t += &format!(" ({}/{} spp{adaptive})", f.samples, self.view.truth_spp);
                    }
                    ui.weak(t);
                    // Adapter-dependent (llvmpipe only): left out of snapshots like the times.
                    if f.cut_rays > 0 && !self.deterministic {
                        let (what, hint) = if m == ViewMode::Truth {
                            (
                                "truth rays",
                                "`lodestone render --retry-cut-rays` traces them again alone.",
                            )
                        } else {
                            ("pixels", "A real GPU has no such limit.")
                        };
                        ui.colored_label(
                            ui.visuals().warn_fg_color,
                            format!("{} {what} cut", f.cut_rays),
                        )
                        .on_hover_text(format!(
                            "The software adapter (Mesa's llvmpipe) gives each shader invocation \
                             65535 loop iterations in all (shared by the 8 pixels or rays of its \
                             SIMD batch) and then stops every loop silently; these {what} ran out \
                             (long marches skimming the relief near the horizon, mostly), so they \
                             may be wrong. {hint}"
                        ));
                    }
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
                let text = match self.fps() {
                    Some(fps) => format!("UI {fps:.0} fps"),
                    None => "UI idle".to_string(),
                };
                ui.weak(text).on_hover_text(
                    "The window's repaint rate while it repaints back to back (dragging, zoom \
                     sweep); idle between changes, when nothing asks for a frame",
                );
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

    /// The window's repaint rate ([`repaint_rate`] over the last frames' times).
    pub(super) fn fps(&self) -> Option<f64> {
        repaint_rate(&self.frame_times)
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

/// Most seconds between two frames of one run of back-to-back repaints.
const BUSY_GAP: f64 = 0.5;

/// Frames per second over the newest run of frames painted back to back (gaps up to
/// [`BUSY_GAP`]), or `None` when the window is idle: egui repaints only on input or a new image, so
/// a rate taken across idle gaps would read as a frozen window ("UI 0 fps") when nothing asked
/// for a frame. Needs three frames in the run.
fn repaint_rate(times: &std::collections::VecDeque<f64>) -> Option<f64> {
    let newest = *times.back()?;
    let mut oldest = newest;
    let mut frames = 1usize;
    for &t in times.iter().rev().skip(1) {
        if !(oldest - t <= BUSY_GAP) {
            break;
        }
        oldest = t;
        frames += 1;
    }
    let span = newest - oldest;
    (frames >= 3 && span > 0.0).then(|| (frames - 1) as f64 / span)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::VecDeque;

    #[test]
    fn the_repaint_rate_counts_only_the_newest_busy_run() {
        // 20 frames a second for a second, then idle for 3 s and one frame: idle.
        let mut t: VecDeque<f64> = (0..=20).map(|i| f64::from(i) * 0.05).collect();
        assert!((repaint_rate(&t).unwrap() - 20.0).abs() < 1e-9);
        t.push_back(4.0);
        assert_eq!(repaint_rate(&t), None);
        // Two more frames at 8 fps start a new run: its own rate, not the earlier one.
        t.extend([4.125, 4.25]);
        assert!((repaint_rate(&t).unwrap() - 8.0).abs() < 1e-9);
        assert_eq!(repaint_rate(&VecDeque::new()), None);
        assert_eq!(repaint_rate(&VecDeque::from([1.0, f64::NAN, 2.0])), None);
    }
}
