//! The menu bar: files, edit, view and help. Items that are commands show their shortcut from
//! [`Command`] (one definition, formatted by egui).

use super::EditorApp;
use super::commands::Command;
use super::files::builtin_presets;
use super::view_state::{self, TruthDisplay, ViewState};
use crate::preset_io;

impl EditorApp {
    pub(super) fn menu_bar(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                self.command_button(ui, "New", Command::New);
                self.command_button(ui, "Open…", Command::Open);
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
                self.command_button(ui, "Save", Command::Save);
                self.command_button(ui, "Save as…", Command::SaveAs);
                if ui
                    .button("Export engine bundle…")
                    .on_hover_text("Tables (EXR), manifest (JSON) and WGSL/GLSL snippets that evaluate the filtered material in another engine")
                    .clicked()
                    && let Some(dir) = rfd::FileDialog::new().pick_folder()
                    && let Some(preset) = self.resolved_now(&ctx)
                {
                    match preset_io::export_bundle(&preset, self.doc.path.as_deref(), &dir) {
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
                let (can_undo, can_redo) = (
                    self.doc.history.can_undo(&self.doc.material),
                    self.doc.history.can_redo(),
                );
                ui.add_enabled_ui(can_undo, |ui| {
                    self.command_button(ui, "Undo", Command::Undo)
                });
                ui.add_enabled_ui(can_redo, |ui| {
                    self.command_button(ui, "Redo", Command::Redo)
                });
            });
            ui.menu_button("View", |ui| {
                ui.checkbox(
                    &mut self.view.show_error,
                    format!(
                        "Error heat maps ({})",
                        Command::ToggleErrorMaps.shortcut_text(&ctx)
                    ),
                );
                let mut vi = self.view.baseline == view_state::Mode::ViewIndependent;
                if ui
                    .checkbox(
                        &mut vi,
                        format!(
                            "View-independent baseline ({})",
                            Command::ToggleBaseline.shortcut_text(&ctx)
                        ),
                    )
                    .changed()
                {
                    self.toggle_baseline();
                }
                let mut ab = self.view.ab.is_some();
                if ui
                    .checkbox(
                        &mut ab,
                        format!("A/B swipe ({})", Command::ToggleAbSwipe.shortcut_text(&ctx)),
                    )
                    .changed()
                {
                    self.toggle_ab();
                }
                ui.checkbox(&mut self.view.adaptive_truth, "Adaptive ground truth")
                    .on_hover_text(
                        "Give each ground-truth pixel its own ray count, in proportion to its predicted and measured noise (BSSBH13 Sec. 2.4), instead of the same count everywhere",
                    );
                ui.separator();
                ui.weak("Ground truth shows");
                for d in TruthDisplay::ALL {
                    ui.radio_value(&mut self.view.truth_display, d, d.label())
                        .on_hover_text(d.help());
                }
                ui.separator();
                ui.checkbox(&mut self.view.show_plots, "Plots");
                ui.separator();
                ui.menu_button("Debug", |ui| {
                    ui.checkbox(&mut self.view.reference_march, "Reference march")
                        .on_hover_text(
                            "Render every view with the reference march (over-relaxed sphere tracing with one global Lipschitz bound) instead of the fast octave march: the same surface, slower; to compare the two in the editor",
                        );
                });
                ui.checkbox(&mut self.report.open, "Error against run time report");
                ui.checkbox(&mut self.object.open, "Object (voxel octree)")
                    .on_hover_text("A sphere, torus or mesh displaced by the material, voxelised and cone traced [HN12]");
                self.command_button(ui, "Sweep zoom", Command::ToggleSweep);
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

    /// A menu button that runs `command`, with its shortcut.
    fn command_button(&mut self, ui: &mut egui::Ui, text: &str, command: Command) {
        let shortcut = command.shortcut_text(ui.ctx());
        if ui
            .add(egui::Button::new(text).shortcut_text(shortcut))
            .clicked()
        {
            self.run(&ui.ctx().clone(), command);
        }
    }
}
