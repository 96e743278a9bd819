//! File operations of the editor: open (with confirmation of unsaved changes), save, save as, new,
//! export of the views, drag-and-drop, and the recovery copy of an unsaved session.

use super::inspector::Inspector;
use super::{EditorApp, Pending};
use crate::preset_io;
use lodestone_core::material::Material;
use lodestone_core::material::environment::{Environment, EnvironmentSource};
use lodestone_render::ViewMode;
use std::path::{Path, PathBuf};

impl EditorApp {
    /// Open a preset now (no confirmation). Bad files leave everything as it was.
    pub fn open_path(&mut self, ctx: &egui::Context, p: &Path) {
        match preset_io::load(p) {
            Ok(m) => {
                self.inspector = Inspector::new(&m);
                self.doc.replace(m, Some(p.to_owned()));
                self.remember(p);
                self.notify(ctx, format!("Opened {}", p.display()), false);
            }
            Err(e) => self.notify(ctx, e.to_string(), true),
        }
    }

    /// Open, asking first when there are unsaved changes.
    pub(super) fn request_open(&mut self, ctx: &egui::Context, p: PathBuf) {
        if self.doc.dirty() {
            self.pending = Some(Pending::Open(p));
        } else {
            self.open_path(ctx, &p);
        }
    }

    /// Pick a preset by file dialog and open it (asking first about unsaved changes).
    pub(super) fn open_dialog(&mut self, ctx: &egui::Context) {
        let mut dlg = rfd::FileDialog::new().add_filter("Lodestone preset", &["ron"]);
        if let Some(dir) = self.doc.path.as_ref().and_then(|p| p.parent()) {
            dlg = dlg.set_directory(dir);
        }
        if let Some(p) = dlg.pick_file() {
            self.request_open(ctx, p);
        }
    }

    /// Save to `p` (atomically).
    pub fn save_to(&mut self, ctx: &egui::Context, p: &Path) -> bool {
        // Into another folder, the driver image and environment paths are rewritten to still name
        // their files (which restarts the undo history: older states hold the old paths).
        let relocated = preset_io::relocate(&self.doc.material, self.doc.path.as_deref(), p);
        match preset_io::save(p, &relocated) {
            Ok(()) => {
                if relocated != self.doc.material {
                    self.doc.replace(relocated, Some(p.to_owned()));
                }
                self.doc.mark_saved(p);
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

    /// Save to the current file, or ask where when there is none. Whether it saved.
    pub(super) fn save(&mut self, ctx: &egui::Context) -> bool {
        match self.doc.path.clone() {
            Some(p) => self.save_to(ctx, &p),
            None => self.save_as(ctx),
        }
    }

    /// Ask where, then save there. Whether it saved.
    pub(super) fn save_as(&mut self, ctx: &egui::Context) -> bool {
        let name = format!("{}.ron", slug(&self.doc.material.name));
        let mut dlg = rfd::FileDialog::new()
            .add_filter("Lodestone preset", &["ron"])
            .set_file_name(name);
        if let Some(dir) = self.doc.path.as_ref().and_then(|p| p.parent()) {
            dlg = dlg.set_directory(dir);
        }
        match dlg.save_file() {
            Some(p) => self.save_to(ctx, &p),
            None => false,
        }
    }

    /// Replace the material with the built-in default (no file, nothing unsaved).
    pub(super) fn new_material(&mut self) {
        let m = preset_io::default_material();
        self.inspector = Inspector::new(&m);
        self.doc.replace(m, None);
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
                use lodestone_render::error_map::abs_difference;
                let heat = super::frames::error_map(
                    &s.frame.image,
                    &t.frame,
                    self.view.error_block.max(1),
                    f64::from(self.view.error_scale),
                )
                .heat;
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

    /// The "unsaved changes" dialog of a pending open or new: save, discard or cancel.
    pub(super) fn confirm_dialog(&mut self, ctx: &egui::Context) {
        let Some(pending) = self.pending.clone() else {
            return;
        };
        let mut choice = None;
        egui::Modal::new(egui::Id::unique("unsaved")).show(ctx, |ui| {
            ui.heading("Unsaved changes");
            ui.label(format!(
                "'{}' has changes that are not saved. Save them first?",
                self.doc.material.name
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

    /// `p` relative to the preset's folder when it lies inside it, as written into the material.
    fn relative_to_preset(&self, p: &Path) -> String {
        let dir = self.doc.path.as_ref().and_then(|d| d.parent());
        dir.and_then(|d| p.strip_prefix(d).ok())
            .unwrap_or(p)
            .display()
            .to_string()
    }

    /// Files dropped on the window: a `.ron` opens (asking first), an `.hdr`/`.exr` becomes the
    /// environment and a `.binary` (MERL) the measured base BRDF (undoable edits); an `.obj` mesh
    /// opens in the Object window, voxelised with the current material.
    pub(super) fn handle_drops(&mut self, ctx: &egui::Context) {
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
            if ext.as_deref() == Some("obj") {
                self.object.open_mesh(ctx, p, self.doc.material.clone());
            } else if ext.as_deref() == Some("binary") {
                // A MERL measured BRDF: the base BRDF becomes that file (an undoable edit).
                let path = self.relative_to_preset(&p);
                self.doc.material.brdf.measured = Some(path.clone());
                self.notify(ctx, format!("Measured BRDF: {path}"), false);
            } else if matches!(ext.as_deref(), Some("exr" | "hdr")) {
                // An environment map: the lighting's environment becomes that file (an undoable
                // edit); relative to the preset's folder when it lies inside it.
                let path = self.relative_to_preset(&p);
                let intensity = self
                    .doc
                    .material
                    .lighting
                    .environment
                    .as_ref()
                    .map_or(1.0, |e| e.intensity);
                self.doc.material.lighting.environment = Some(Environment {
                    source: EnvironmentSource::File { path: path.clone() },
                    intensity,
                });
                self.notify(ctx, format!("Environment: {path}"), false);
            } else {
                self.request_open(ctx, p);
            }
        }
    }
}

/// A file-name-safe version of a material name.
pub(super) fn slug(name: &str) -> String {
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
pub(super) fn builtin_presets() -> Vec<PathBuf> {
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
pub(super) fn recover(m: &Material) -> Option<PathBuf> {
    let dir = eframe::storage_dir("Lodestone")?.join("recovered");
    std::fs::create_dir_all(&dir).ok()?;
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let p = dir.join(format!("{}-{stamp}.ron", slug(&m.name)));
    preset_io::save(&p, m).ok().map(|()| p)
}
