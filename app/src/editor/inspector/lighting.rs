//! The inspector's Lighting section: the sun's strength and the environment.

use super::*;

/// The directional light's strength and the environment [HNPN14 Sec. 5.3].
pub(super) fn lighting(ui: &mut Ui, l: &mut Lighting) -> bool {
    let mut changed = false;
    changed |= slider_f64(
        ui,
        &mut l.sun,
        0.0..=4.0,
        "Sun",
        "Radiance scale of the directional light (its direction is the scene's light); 0 leaves only the environment",
        false,
    );
    #[derive(PartialEq, Clone, Copy)]
    enum Kind {
        None,
        Sky,
        File,
    }
    let kind = match &l.environment {
        None => Kind::None,
        Some(Environment {
            source: EnvironmentSource::Sky(_),
            ..
        }) => Kind::Sky,
        Some(_) => Kind::File,
    };
    let mut want = kind;
    egui::ComboBox::from_label("Environment")
        .selected_text(match kind {
            Kind::None => "None",
            Kind::Sky => "Procedural sky",
            Kind::File => "File (EXR/HDR)",
        })
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut want, Kind::None, "None");
            ui.selectable_value(&mut want, Kind::Sky, "Procedural sky");
            ui.selectable_value(&mut want, Kind::File, "File (EXR/HDR)");
        })
        .response
        .on_hover_text("An irradiance environment map (SH9, Ramamoorthi–Hanrahan 2001) treated as a slope colour map and filtered over D_s [HNPN14 Sec. 5.3]");
    if want != kind {
        let intensity = l.environment.as_ref().map_or(1.0, |e| e.intensity);
        l.environment = match want {
            Kind::None => None,
            Kind::Sky => Some(Environment {
                source: EnvironmentSource::Sky(Sky::default()),
                intensity,
            }),
            Kind::File => Some(Environment {
                source: EnvironmentSource::File {
                    path: "environment.hdr".into(),
                },
                intensity,
            }),
        };
        changed = true;
    }
    if let Some(env) = &mut l.environment {
        changed |= slider_f64(
            ui,
            &mut env.intensity,
            0.0..=4.0,
            "Environment intensity",
            "Multiplies the environment's radiance",
            false,
        );
        match &mut env.source {
            EnvironmentSource::Sky(sky) => {
                changed |= slider_f64(
                    ui,
                    &mut sky.sun_elevation_deg,
                    -10.0..=90.0,
                    "Sky sun elevation",
                    "Elevation of the sky's sun glow, degrees (independent of the directional light)",
                    false,
                );
                changed |= slider_f64(
                    ui,
                    &mut sky.sun_azimuth_deg,
                    -180.0..=180.0,
                    "Sky sun azimuth",
                    "Azimuth of the sky's sun glow, degrees from +x toward +y",
                    false,
                );
            }
            EnvironmentSource::File { path } => {
                ui.horizontal(|ui| {
                    let l = ui.label("File");
                    changed |= ui
                        .text_edit_singleline(path)
                        .labelled_by(l.id)
                        .on_hover_text("Equirectangular .exr or .hdr, relative to the preset's folder (top row = zenith)")
                        .lost_focus();
                    if ui.button("Browse…").clicked()
                        && let Some(p) = rfd::FileDialog::new()
                            .add_filter("Environment maps", &["exr", "hdr"])
                            .pick_file()
                    {
                        *path = p.display().to_string();
                        changed = true;
                    }
                });
            }
        }
    }
    changed
}
