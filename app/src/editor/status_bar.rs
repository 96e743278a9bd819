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
                        ui.colored_label(
                            ui.visuals().warn_fg_color,
                            format!("{} truth rays cut", f.cut_rays),
                        )
                        .on_hover_text(
                            "These ground-truth rays skim the relief near the horizon for so many \
                             steps that the software adapter (Mesa's llvmpipe) stopped their loops \
                             after 65535 iterations: their pixels may be wrong. \
                             `lodestone render --retry-cut-rays` traces them again alone.",
                        );
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

    pub(super) fn fps(&self) -> f64 {
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
