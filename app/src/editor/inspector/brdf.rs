//! The inspector's measured base BRDF: a MERL table by dialog or drop, and its fit.

use super::*;

impl Inspector {
    /// The base BRDF's kind (analytic or a measured MERL file), the file, and the fit the
    /// filtered views use with its error.
    pub(super) fn measured_brdf(&mut self, ui: &mut Ui, b: &mut BaseBrdf) -> bool {
        let mut changed = false;
        let measured = b.measured.is_some();
        let mut want = measured;
        egui::ComboBox::from_label("BRDF kind")
                .selected_text(if measured { "Measured (MERL)" } else { "Analytic" })
                .show_ui(ui, |ui| {
                    ui.selectable_value(&mut want, false, "Analytic");
                    ui.selectable_value(&mut want, true, "Measured (MERL)");
                })
                .response
                .on_hover_text(
                    "Analytic: Lambert plus a slope-space Beckmann lobe. Measured: a MERL isotropic \
                     BRDF table (.binary, 90×90×180 half/difference angles) that ground truth and naive \
                     look up per facet; the filtered views use its fit, Lambert plus Beckmann lobes \
                     with a Schlick Fresnel term each (merl_fit.rs). The colour \
                     map tints the whole measured BRDF (white shows it as measured). Drop a .binary file \
                     on the window to use it",
                );
        if want != measured {
            b.measured = want.then(String::new);
            changed = true;
        }
        if let Some(path) = &mut b.measured {
            ui.horizontal(|ui| {
                let l = ui.label("Measured file");
                changed |= ui
                    .text_edit_singleline(path)
                    .labelled_by(l.id)
                    .on_hover_text("MERL .binary file, relative to the preset's folder")
                    .lost_focus();
                if ui.button("Browse…").clicked()
                    && let Some(p) = rfd::FileDialog::new()
                        .add_filter("MERL BRDF", &["binary"])
                        .pick_file()
                {
                    *path = p.display().to_string();
                    changed = true;
                }
            });
            match &self.measured_fit {
                Some(f) => {
                    let lobes: Vec<String> =
                        f.lobes.iter().map(|l| format!("{:.3}", l.sigma)).collect();
                    ui.label(format!(
                        "Fit for the filtered views: kd ({:.3}, {:.3}, {:.3}), lobes of σ {}",
                        f.kd[0],
                        f.kd[1],
                        f.kd[2],
                        if lobes.is_empty() {
                            "(none)".to_owned()
                        } else {
                            lobes.join(", ")
                        }
                    ));
                    let worst = f.relative_error.iter().copied().fold(0.0, f64::max);
                    let text = format!(
                        "Fit error: {:.1}% RMS of ρ·cos (worst channel)",
                        100.0 * worst
                    );
                    if worst > 0.1 {
                        ui.colored_label(ui.visuals().warn_fg_color, text);
                    } else {
                        ui.label(text);
                    }
                }
                None => {
                    ui.weak("Not loaded (see the status bar)");
                }
            }
        }
        changed
    }
}
