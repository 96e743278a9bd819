//! The Object window (#19, [HN12]): a whole object (sphere, torus or an OBJ mesh) displaced by the
//! material's relief, voxelised into the sparse octree on a background thread, and its voxel view
//! (HN12's masks, cone traced in WGSL) redrawn as the editor's camera and light move and as the
//! dolly slider brings it from a few pixels to filling the view. On request the comparison, on the
//! CPU: nearest voxels, alpha blending [CNLE09], ours and the ray-traced ground truth, with the
//! covered pixels' colour error and the silhouette's coverage error (what `lodestone object`
//! prints).

mod job;
use super::view_state::ViewState;
use super::worker::DeviceSource;
use crate::object as object_cmd;
use crate::object::scene::{GpuObject, ObjectScene, masks_shot};
use glam::DVec3;
use job::{color_image, run};
use lodestone_core::material::Material;
use lodestone_core::material::colormap::linear_to_srgb;
use lodestone_core::object::base_shape::BaseShape;
use lodestone_core::object::cone_trace::{Compositing, ConePixel, ConeTracer};
use lodestone_core::object::coverage_mask::MaskTable;
use lodestone_core::object::object_truth::{Lens, ObjectTruth, pixel_cone};
use lodestone_core::object::shading::ObjectLighting;
use lodestone_core::object::view_error::{ObjectImages, ViewErrors};
use lodestone_core::scene::camera::Camera;
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};

/// The base shapes the window offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeKind {
    /// A unit sphere.
    Sphere,
    /// A ring torus (major 1, minor 0.45).
    Torus,
    /// A closed OBJ mesh chosen by file dialog.
    Mesh,
}

impl ShapeKind {
    const ALL: [ShapeKind; 3] = [ShapeKind::Sphere, ShapeKind::Torus, ShapeKind::Mesh];

    fn name(self) -> &'static str {
        match self {
            ShapeKind::Sphere => "sphere",
            ShapeKind::Torus => "torus",
            ShapeKind::Mesh => "mesh",
        }
    }
}

/// What the window asks the editor to do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Nothing.
    None,
    /// Build the object from the current material.
    Build,
}

/// Camera, sun and image of one voxel image.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Shot {
    camera: Camera,
    light: DVec3,
    shadows: bool,
    size: (u32, u32),
    lens: Lens,
}

enum Job {
    Build(Box<(Material, BaseShape, u32)>),
    Render(Shot),
    Compare(Shot, u32),
}

/// A comparison's image size, its panels (name, pixels) and errors.
type Comparison = (u32, u32, Vec<(&'static str, Vec<ConePixel>)>, ViewErrors);

/// What the background thread hands the window.
#[derive(Default)]
struct Shared {
    status: String,
    busy: bool,
    version: u64,
    voxel: Option<(u32, u32, Vec<ConePixel>, f64)>,
    compare: Option<Comparison>,
}

/// The Object window's state.
pub struct ObjectPanel {
    /// Whether the window is shown.
    pub open: bool,
    shape: ShapeKind,
    mesh: Option<PathBuf>,
    depth: u32,
    distance: f64,
    shadows: bool,
    rays: u32,
    lens: f64,
    focus: f64,
    built: bool,
    last: Option<Shot>,
    jobs: Option<Sender<Job>>,
    shared: Arc<Mutex<Shared>>,
    seen: u64,
    textures: Vec<(String, egui::TextureHandle)>,
    thread: Option<std::thread::JoinHandle<()>>,
    /// Whether the voxel view may take a GPU device (the editor's choice; none: the CPU tracer).
    device: DeviceSource,
}

impl Default for ObjectPanel {
    fn default() -> Self {
        Self {
            open: false,
            shape: ShapeKind::Sphere,
            mesh: None,
            depth: 6,
            distance: 5.0,
            shadows: true,
            rays: 32,
            lens: 0.0,
            focus: 4.0,
            built: false,
            last: None,
            jobs: None,
            shared: Arc::default(),
            seen: 0,
            textures: vec![],
            thread: None,
            device: DeviceSource::Headless,
        }
    }
}

impl Drop for ObjectPanel {
    /// Closes the job channel and waits for the thread, so its GPU device is gone first.
    fn drop(&mut self) {
        self.jobs = None;
        if let Some(t) = self.thread.take()
            && t.join().is_err()
        {
            log::error!("the object thread panicked");
        }
    }
}

/// The image size of the views.
const SIZE: (u32, u32) = (192, 144);

fn set(shared: &Mutex<Shared>, f: impl FnOnce(&mut Shared)) {
    if let Ok(mut s) = shared.lock() {
        f(&mut s);
        s.version += 1;
    }
}

/// A voxel frame slower than this is preceded by a smaller preview (progressive refinement).
const PREVIEW_ABOVE_S: f64 = 0.2;

/// The time a preview aims at.
const PREVIEW_TARGET_S: f64 = 0.08;

/// The factor a preview's sides are divided by, from the seconds the last full frame took: 1 (no
/// preview) up to [`PREVIEW_ABOVE_S`], then the smallest factor k ≥ 2 whose k² fewer cones take
/// about [`PREVIEW_TARGET_S`], at most 8. A frame's cost is its cone count times a cost per cone
/// that changes slowly with the view (the object's distance), so the last frame predicts the next.
fn preview_divisor(last_full_s: f64) -> u32 {
    if !(last_full_s > PREVIEW_ABOVE_S) {
        return 1;
    }
    ((last_full_s / PREVIEW_TARGET_S).sqrt().ceil() as u32).clamp(2, 8)
}

impl ObjectPanel {
    /// The window with the editor's device choice: without one the voxel view is the CPU tracer's.
    pub fn on(device: DeviceSource) -> Self {
        let mut panel = Self::default();
        panel.device = device;
        panel
    }

    /// Sets the octree depth, truth rays and distance (tests and screenshots).
    #[cfg(test)]
    pub fn set_budget(&mut self, depth: u32, rays: u32, distance: f64) {
        self.depth = depth;
        self.rays = rays;
        self.distance = distance;
    }

    /// The voxel image's covered share and the comparison's errors, when there are ones (tests).
    #[cfg(test)]
    pub fn results(&self) -> (Option<f64>, Option<ViewErrors>) {
        let Ok(s) = self.shared.lock() else {
            return (None, None);
        };
        let cover = s
            .voxel
            .as_ref()
            .map(|(_, _, px, _)| px.iter().map(|p| p.coverage).sum::<f64>() / px.len() as f64);
        (cover, s.compare.as_ref().map(|c| c.3.clone()))
    }

    /// Whether the background thread is working.
    #[cfg(test)]
    pub fn busy(&self) -> bool {
        self.shared.lock().is_ok_and(|s| s.busy)
    }

    fn send(&mut self, ctx: &egui::Context, job: Job) {
        if self.jobs.is_none() {
            let (tx, rx) = channel();
            let shared = self.shared.clone();
            let c = ctx.clone();
            let device = self.device;
            self.thread = std::thread::Builder::new()
                .name("lodestone-object".into())
                .spawn(move || run(rx, shared, device, move || c.request_repaint()))
                .inspect_err(|e| log::error!("the object thread: {e}"))
                .ok();
            self.jobs = Some(tx);
        }
        if let Some(tx) = &self.jobs {
            let _ = tx.send(job);
        }
        if let Ok(mut s) = self.shared.lock() {
            s.busy = true;
        }
    }

    /// Builds the object from `material` (the editor answers [`Action::Build`] with it).
    pub fn build(&mut self, ctx: &egui::Context, material: Material) {
        let shape = match object_cmd::shape(self.shape.name(), self.mesh.as_deref(), 1.0, 0.45) {
            Ok(s) => s,
            Err(e) => {
                set(&self.shared, |s| s.status = format!("{e:#}"));
                return;
            }
        };
        self.built = true;
        self.last = None;
        self.send(ctx, Job::Build(Box::new((material, shape, self.depth))));
    }

    /// Opens the window on the OBJ mesh at `path` (a dropped file) and builds it from `material`;
    /// a bad mesh is reported in the window's status (the shape stays a mesh to choose again).
    pub fn open_mesh(&mut self, ctx: &egui::Context, path: PathBuf, material: Material) {
        self.open = true;
        self.shape = ShapeKind::Mesh;
        self.mesh = Some(path);
        self.build(ctx, material);
    }

    /// The window's status line (tests).
    #[cfg(test)]
    pub fn status(&self) -> String {
        self.shared
            .lock()
            .map(|s| s.status.clone())
            .unwrap_or_default()
    }

    fn shot(&self, view: &ViewState) -> Shot {
        Shot {
            camera: Camera {
                elevation_deg: view.camera.elevation_deg,
                azimuth_deg: view.camera.azimuth_deg,
                distance: self.distance,
                target: [0.0, 0.0],
                fov_deg: 30.0,
            },
            light: view.light(),
            shadows: self.shadows,
            size: SIZE,
            lens: Lens {
                radius: self.lens,
                focus: self.focus,
            },
        }
    }

    /// The window; `view` gives the camera's angles and the light (linked with the other views).
    pub fn ui(&mut self, ctx: &egui::Context, view: &ViewState) -> Action {
        let mut action = Action::None;
        if !self.open {
            return action;
        }
        let shot = self.shot(view);
        if self.built && self.last != Some(shot) {
            self.last = Some(shot);
            self.send(ctx, Job::Render(shot));
        }
        let mut open = self.open;
        egui::Window::new("Object (voxel octree, HN12)")
            .open(&mut open)
            .default_size([820.0, 560.0])
            .show(ctx, |ui| action = self.contents(ui, shot));
        self.open = open;
        action
    }

    fn contents(&mut self, ui: &mut egui::Ui, shot: Shot) -> Action {
        let mut action = Action::None;
        ui.horizontal(|ui| {
            egui::ComboBox::from_label("shape")
                .selected_text(self.shape.name())
                .show_ui(ui, |ui| {
                    for k in ShapeKind::ALL {
                        ui.selectable_value(&mut self.shape, k, k.name());
                    }
                })
                .response
                .on_hover_text("The base shape displaced by the material's relief: F = d_B − σ_h g(f) (docs/design/objects.md, Whole objects)");
            if self.shape == ShapeKind::Mesh {
                let name = self.mesh.as_ref().and_then(|p| p.file_name()).map_or("choose…".into(), |n| n.to_string_lossy().into_owned());
                if ui.button(format!("OBJ: {name}")).on_hover_text("A closed, consistently oriented triangle mesh (.obj)").clicked()
                    && let Some(p) = rfd::FileDialog::new().add_filter("OBJ mesh", &["obj"]).pick_file()
                {
                    self.mesh = Some(p);
                }
            }
            ui.add(egui::DragValue::new(&mut self.depth).range(3..=8).prefix("octree depth "))
                .on_hover_text("Finest level: the object's bounding cube cut into 2^depth voxels a side [HN12 Sec. 5.2]");
            if ui.button("Build").on_hover_text("Voxelise the object with the current material").clicked() {
                action = Action::Build;
            }
        });
        ui.horizontal(|ui| {
            ui.add(
                egui::Slider::new(&mut self.distance, 1.3..=40.0)
                    .logarithmic(true)
                    .text("distance"),
            )
            .on_hover_text("Dolly: the camera's distance from the object's centre (the cone's level follows its radius, HN12 Alg. 1)");
            ui.add(egui::Slider::new(&mut self.lens, 0.0..=0.5).text("lens radius"))
                .on_hover_text("Depth of field: the thin lens's radius; the cones widen by its circle of confusion, lens·|1 − t/focus| [HN12 Sec. 4.1, Fig. 1d]");
            ui.add(egui::Slider::new(&mut self.focus, 0.5..=40.0).logarithmic(true).text("focus"))
                .on_hover_text("The distance in focus along each pixel's axis (world units)");
            ui.checkbox(&mut self.shadows, "shadows")
                .on_hover_text("Shadow cones toward the sun (and shadow rays in the ground truth)");
            ui.add(egui::DragValue::new(&mut self.rays).range(4..=512).prefix("truth rays "))
                .on_hover_text("Ground-truth rays per pixel of the comparison (explicit displaced surface, supersampled)");
            if ui
                .add_enabled(self.built, egui::Button::new("Compare with ground truth"))
                .on_hover_text("Nearest voxels, alpha blending, ours and the ray-traced truth on the CPU, with their errors")
                .clicked()
            {
                self.send(ui.ctx(), Job::Compare(shot, self.rays));
            }
        });
        let (status, busy, version) = match self.shared.lock() {
            Ok(s) => (s.status.clone(), s.busy, s.version),
            Err(_) => (String::new(), false, 0),
        };
        ui.horizontal(|ui| {
            if busy {
                ui.spinner();
            }
            ui.label(if status.is_empty() {
                "Choose a shape and Build."
            } else {
                &status
            });
        });
        if version != self.seen {
            self.seen = version;
            self.refresh_textures(ui.ctx());
        }
        ui.horizontal_wrapped(|ui| {
            for (name, tex) in &self.textures {
                ui.vertical(|ui| {
                    ui.label(name.as_str());
                    ui.image((tex.id(), egui::vec2(SIZE.0 as f32, SIZE.1 as f32)));
                });
            }
        });
        if let Ok(s) = self.shared.lock()
            && let Some((_, _, _, e)) = &s.compare
        {
            egui::Grid::new("object_errors")
                .striped(true)
                .show(ui, |ui| {
                    ui.label("");
                    ui.label("mean colour error (covered; +: brighter)");
                    ui.label("silhouette coverage error");
                    ui.end_row();
                    for (name, m) in ["nearest voxels", "alpha blended", "ours (masks)"]
                        .iter()
                        .zip(&e.modes)
                    {
                        ui.label(*name);
                        ui.label(format!("{:+.2}%", 100.0 * m.mean_color_bias));
                        ui.label(if e.silhouette == 0 {
                            "—".into()
                        } else {
                            format!("{:.3}", m.coverage_error)
                        });
                        ui.end_row();
                    }
                    ui.label(format!(
                        "{} covered, {} silhouette pixels; truth's standard error {:.2}%",
                        e.covered,
                        e.silhouette,
                        100.0 * e.truth_error
                    ));
                    ui.end_row();
                });
        }
        action
    }

    fn refresh_textures(&mut self, ctx: &egui::Context) {
        let Ok(s) = self.shared.lock() else {
            return;
        };
        let mut images = vec![];
        if let Some((w, h, px, secs)) = &s.voxel {
            let label = if *w < SIZE.0 {
                format!("voxels, ours (preview {w} × {h}, {:.0} ms)", 1e3 * secs)
            } else {
                format!("voxels, ours (live, {:.0} ms)", 1e3 * secs)
            };
            images.push((label, color_image(*w, *h, px)));
        }
        if let Some((w, h, panels, _)) = &s.compare {
            for (name, px) in panels {
                images.push((name.to_string(), color_image(*w, *h, px)));
            }
        }
        drop(s);
        self.textures = images
            .into_iter()
            .enumerate()
            .map(|(i, (name, img))| {
                let tex =
                    ctx.load_texture(format!("object-{i}"), img, egui::TextureOptions::NEAREST);
                (name, tex)
            })
            .collect();
    }
}

#[cfg(test)]
mod tests;
