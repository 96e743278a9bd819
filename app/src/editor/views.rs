//! The viewports: the camera and light toolbar, three linked views in resizable columns (or one A/B
//! swipe view), their labels, error heat maps and mouse interaction.

mod overlays;
use super::gradient_editor::color32;
use super::view_state::{DISTANCE_RANGE, Mode, TruthDisplay};
use super::{DeviceStatus, EditorApp};
use egui::{Color32, Pos2, Rect, Role, Sense, Stroke, Ui, Vec2, WidgetInfo};
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::shape::Shape;
use lodestone_render::ViewMode;
use overlays::{error_summary, heat_bar, note, px, truth_legend};

/// Width of the draggable gap between viewports.
const GAP: f32 = 6.0;
/// Height of a viewport's label row.
const LABEL_H: f32 = 20.0;

impl EditorApp {
    pub(super) fn views_ui(&mut self, ui: &mut Ui) {
        self.toolbar(ui);
        ui.add_space(4.0);
        let area = ui.available_rect_before_wrap();
        ui.allocate_rect(area, Sense::hover());
        if let DeviceStatus::Failed(e) = &self.device {
            ui.painter().text(
                area.center(),
                egui::Align2::CENTER_CENTER,
                format!(
                    "Nothing is drawn: {e}\nThe material can still be edited, saved and exported as a preset."
                ),
                egui::FontId::proportional(15.0),
                ui.visuals().error_fg_color,
            );
            return;
        }
        let ppp = ui.ctx().pixels_per_point();
        match self.view.ab {
            Some(ab) => {
                let img = Rect::from_min_max(area.min + Vec2::new(0.0, LABEL_H), area.max);
                self.view_px = px(img.size(), ppp);
                self.label_row(
                    ui,
                    Rect::from_min_size(area.min, Vec2::new(area.width(), LABEL_H)),
                    &format!("A/B: {} | {}", ab.left.label(), ab.right.label()),
                    None,
                );
                self.ab_view(ui, img);
            }
            None => {
                let w = (area.width() - 2.0 * GAP).max(30.0);
                let f = self.view.widths;
                let xs = [
                    area.left(),
                    area.left() + w * f[0] + GAP,
                    area.left() + w * (f[0] + f[1]) + 2.0 * GAP,
                ];
                let ws = [w * f[0], w * f[1], w * (1.0 - f[0] - f[1])];
                let max_w = ws.iter().cloned().fold(1.0, f32::max);
                self.view_px = px(Vec2::new(max_w, area.height() - LABEL_H), ppp);
                let modes = self.view.shown();
                for (k, mode) in modes.iter().enumerate() {
                    let col = Rect::from_min_size(
                        Pos2::new(xs[k], area.top()),
                        Vec2::new(ws[k], area.height()),
                    );
                    self.viewport(ui, col, *mode, max_w);
                }
                // Dividers: drag to resize the columns.
                for k in 0..2 {
                    let x = xs[k] + ws[k] + GAP * 0.5;
                    let r = Rect::from_center_size(
                        Pos2::new(x, area.center().y),
                        Vec2::new(GAP, area.height()),
                    );
                    let resp = ui
                        .interact(r, ui.scope_id().with(("divider", k)), Sense::drag())
                        .on_hover_cursor(egui::CursorIcon::ResizeHorizontal);
                    resp.widget_info(|| {
                        WidgetInfo::labeled(Role::Slider, true, format!("View divider {}", k + 1))
                    });
                    if resp.dragged() {
                        let d = resp.drag_delta().x / w;
                        let mut f = self.view.widths;
                        if k == 0 {
                            f[0] = (f[0] + d).clamp(0.1, 0.8);
                            f[1] = (f[1] - d).max(0.1);
                        } else {
                            f[1] = (f[1] + d).clamp(0.1, 0.9 - f[0]);
                        }
                        if f[0] + f[1] <= 0.9 {
                            self.view.widths = f;
                        }
                    }
                    let c = if resp.hovered() || resp.dragged() {
                        ui.visuals().widgets.hovered.fg_stroke.color
                    } else {
                        ui.visuals().widgets.noninteractive.bg_stroke.color
                    };
                    ui.painter().line_segment(
                        [Pos2::new(x, area.top()), Pos2::new(x, area.bottom())],
                        Stroke::new(1.0, c),
                    );
                }
            }
        }
    }

    /// Camera, light and rendering controls above the views.
    fn toolbar(&mut self, ui: &mut Ui) {
        ui.horizontal(|ui| {
            self.light_gizmo(ui);
            ui.vertical(|ui| {
                ui.horizontal(|ui| {
                    let c = &mut self.view.camera;
                    ui.add(
                        egui::Slider::new(&mut c.elevation_deg, 0.0..=Camera::MAX_ELEVATION_DEG)
                            .text("View °")
                            .max_decimals(1),
                    )
                    .on_hover_text("Camera angle from the surface normal (0° overhead, 89.5° grazing)");
                    ui.add(
                        egui::Slider::new(&mut c.azimuth_deg, 0.0..=360.0)
                            .text("Azimuth °")
                            .max_decimals(0),
                    )
                    .on_hover_text("Camera azimuth around the normal");
                    ui.add(
                        egui::Slider::new(&mut c.distance, DISTANCE_RANGE.0..=DISTANCE_RANGE.1)
                            .logarithmic(true)
                            .text("Distance")
                            .max_decimals(2),
                    )
                    .on_hover_text("Camera distance (log scale): from a few micro-features per view to thousands per pixel");
                });
                ui.horizontal(|ui| {
                    ui.add(
                        egui::Slider::new(&mut self.view.light_elevation_deg, 0.0..=90.0)
                            .text("Light °")
                            .max_decimals(1),
                    )
                    .on_hover_text("Light angle from the normal");
                    ui.add(
                        egui::Slider::new(&mut self.view.light_azimuth_deg, 0.0..=360.0)
                            .text("Light azimuth °")
                            .max_decimals(0),
                    )
                    .on_hover_text("Light azimuth around the normal");
                    ui.add(
                        egui::Slider::new(&mut self.view.truth_spp, 1..=1024)
                            .logarithmic(true)
                            .text("Truth spp"),
                    )
                    .on_hover_text("Ground-truth rays per pixel to accumulate (progressive, one per pixel per frame)");
                });
                ui.horizontal(|ui| {
                    let is_cyl = matches!(self.view.shape, Shape::Cylinder { .. });
                    let mut want_cyl = is_cyl;
                    egui::ComboBox::from_label("Object")
                        .selected_text(if is_cyl { "Cylinder" } else { "Plane" })
                        .show_ui(ui, |ui| {
                            ui.selectable_value(&mut want_cyl, false, "Plane");
                            ui.selectable_value(&mut want_cyl, true, "Cylinder");
                        })
                        .response
                        .on_hover_text("The unbounded plane, or a cylinder (silhouettes and grazing light) whose top line passes through the camera target");
                    if want_cyl != is_cyl {
                        self.view.shape = if want_cyl {
                            Shape::Cylinder { radius: 1.5 }
                        } else {
                            Shape::Plane
                        };
                    }
                    if let Shape::Cylinder { radius } = &mut self.view.shape {
                        ui.add(
                            egui::Slider::new(radius, 0.1..=50.0)
                                .logarithmic(true)
                                .text("Radius"),
                        )
                        .on_hover_text("Cylinder radius (world units)");
                    }
                    egui::ComboBox::from_label("Resolution")
                        .selected_text(format!("{:.0}%", self.view.max_scale * 100.0))
                        .show_ui(ui, |ui| {
                            for s in [1.0f32, 0.5, 0.25, 0.125] {
                                ui.selectable_value(
                                    &mut self.view.max_scale,
                                    s,
                                    format!("{:.0}%", s * 100.0),
                                );
                            }
                        })
                        .response
                        .on_hover_text("Largest resolution of the views; each change renders coarse first and refines");
                    let mut sweeping = self.sweep.is_some();
                    if ui
                        .toggle_value(&mut sweeping, "Sweep zoom")
                        .on_hover_text("Animate the distance close, far and back to show the level of detail (W)")
                        .clicked()
                    {
                        let ctx = ui.ctx().clone();
                        self.toggle_sweep(&ctx);
                    }
                    ui.checkbox(&mut self.view.show_error, "Error maps")
                        .on_hover_text("|mode − ground truth| on block means, max over RGB, as a heat map; blocks whose difference is within the truth's own Monte Carlo noise (under 2 standard errors) are grey (E)");
                    if self.view.show_error {
                        ui.add(
                            egui::Slider::new(&mut self.view.error_scale, 0.005..=1.0)
                                .logarithmic(true)
                                .text("Error scale"),
                        )
                        .on_hover_text("Error at the top of the heat scale (linear RGB)");
                        egui::ComboBox::from_label("Error block")
                            .selected_text(format!("{0}×{0}", self.view.error_block))
                            .show_ui(ui, |ui| {
                                for b in [1u32, 2, 4, 8, 16, 32] {
                                    ui.selectable_value(
                                        &mut self.view.error_block,
                                        b,
                                        format!("{b}×{b}"),
                                    );
                                }
                            })
                            .response
                            .on_hover_text("Pixels per block whose means are compared (1×1: per pixel). Over a block the micro-geometry's own realisation averages out while a bias stays, and the truth's noise shrinks; the RMSE shown is what remains once that noise is taken out");
                    }
                });
            });
        });
        if let Some(e) = &self.material_error {
            ui.colored_label(
                ui.visuals().error_fg_color,
                format!("Cannot render this material: {e}"),
            );
        }
    }

    /// A disc seen from above: the light's position over the hemisphere. Drag to move it.
    fn light_gizmo(&mut self, ui: &mut Ui) {
        let size = 66.0;
        let (rect, resp) = ui.allocate_exact_size(Vec2::splat(size), Sense::click_and_drag());
        resp.widget_info(|| WidgetInfo::labeled(Role::Slider, true, "Light direction"));
        let resp = resp.on_hover_text(
            "Light direction seen from above: centre = overhead, rim = grazing. Drag to move the light.",
        );
        let c = rect.center();
        let r = size * 0.5 - 3.0;
        if (resp.dragged() || resp.clicked())
            && let Some(p) = resp.interact_pointer_pos()
        {
            let d = (p - c) / r;
            self.view
                .set_light_from_disc(f64::from(d.x), f64::from(-d.y));
        }
        let painter = ui.painter_at(rect);
        let vis = ui.visuals();
        painter.circle(
            c,
            r,
            vis.extreme_bg_color,
            Stroke::new(1.0, vis.weak_text_color()),
        );
        painter.circle_stroke(c, r * 0.5, Stroke::new(0.5, vis.weak_text_color()));
        // The camera's azimuth, for orientation.
        let az = self.view.camera.azimuth_deg.to_radians();
        let cam = c + Vec2::new(az.cos() as f32, -az.sin() as f32) * r;
        painter.line_segment([c, cam], Stroke::new(1.0, vis.weak_text_color()));
        let (x, y) = self.view.light_disc();
        let lp = c + Vec2::new(x as f32, -y as f32) * r;
        painter.circle(
            lp,
            5.0,
            Color32::from_rgb(255, 210, 80),
            Stroke::new(1.0, Color32::BLACK),
        );
    }

    fn label_row(&self, ui: &Ui, rect: Rect, title: &str, extra: Option<String>) {
        let painter = ui.painter_at(rect);
        painter.text(
            rect.left_center() + Vec2::new(4.0, 0.0),
            egui::Align2::LEFT_CENTER,
            title,
            egui::FontId::proportional(14.0),
            ui.visuals().strong_text_color(),
        );
        if let Some(extra) = extra {
            painter.text(
                rect.right_center() - Vec2::new(4.0, 0.0),
                egui::Align2::RIGHT_CENTER,
                extra,
                egui::FontId::proportional(12.0),
                ui.visuals().weak_text_color(),
            );
        }
    }

    /// Camera interaction on an image rect: drag to orbit, right-drag for the light, scroll to
    /// zoom, double-click to reset.
    fn interact_camera(&mut self, ui: &Ui, rect: Rect, id: egui::Id, name: &str) -> egui::Response {
        let resp = ui.interact(rect, id, Sense::click_and_drag());
        resp.widget_info(|| WidgetInfo::labeled(Role::Image, true, name));
        if resp.dragged_by(egui::PointerButton::Primary) {
            let d = resp.drag_delta();
            self.view.orbit(d.x, d.y);
            self.sweep = None;
        }
        if resp.dragged_by(egui::PointerButton::Secondary) {
            let d = resp.drag_delta();
            self.view.light_azimuth_deg =
                (self.view.light_azimuth_deg - f64::from(d.x) * 0.5).rem_euclid(360.0);
            self.view.light_elevation_deg =
                (self.view.light_elevation_deg + f64::from(d.y) * 0.3).clamp(0.0, 90.0);
        }
        if resp.double_clicked() {
            self.view.camera = super::view_state::ViewState::default().camera;
        }
        if resp.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y + (i.zoom_delta() - 1.0) * 400.0);
            if scroll != 0.0 {
                self.view.zoom(f64::from(scroll) / 40.0);
                self.sweep = None;
            }
        }
        resp
    }

    /// One viewport: label row, image (or heat map), interaction.
    fn viewport(&mut self, ui: &mut Ui, col: Rect, mode: Mode, max_w: f32) {
        let rm = mode.render_mode();
        let label = Rect::from_min_size(col.min, Vec2::new(col.width(), LABEL_H));
        let img = Rect::from_min_max(col.min + Vec2::new(0.0, LABEL_H), col.max);
        let show_error = self.view.show_error && rm != ViewMode::Truth;
        let extra = if show_error {
            None
        } else if rm == ViewMode::Truth {
            self.shown
                .get(&rm)
                .map(|s| format!("{}/{} spp", s.frame.samples, self.view.truth_spp))
        } else {
            None
        };
        // The truth viewport may show one of its noise maps instead of its image.
        let truth_map = (rm == ViewMode::Truth && self.view.truth_display != TruthDisplay::Image)
            .then_some(self.view.truth_display);
        let title = if show_error {
            format!("{} − truth", mode.label())
        } else if let Some(d) = truth_map {
            format!("{}: {}", mode.label(), d.label())
        } else {
            mode.label().to_string()
        };
        self.label_row(ui, label, &title, extra);
        if matches!(mode, Mode::Naive | Mode::ViewIndependent) {
            // The baseline switches between naive MIP and view-independent filtering in place.
            let other = if mode == Mode::Naive {
                "show view-independent"
            } else {
                "show naive MIP"
            };
            let title_w = ui
                .painter()
                .layout_no_wrap(
                    title.clone(),
                    egui::FontId::proportional(14.0),
                    Color32::WHITE,
                )
                .size()
                .x;
            let r = Rect::from_min_size(
                Pos2::new(label.left() + title_w + 14.0, label.top() + 1.0),
                Vec2::new(170.0, LABEL_H - 2.0),
            )
            .intersect(label);
            if ui
                .put(
                    r,
                    egui::Button::new(other)
                        .small()
                        .wrap_mode(egui::TextWrapMode::Extend),
                )
                .on_hover_text(
                    "Switch this view between naive MIP (colour map of the filtered driver) and view-independent texture filtering (the exact footprint average, no masking) (B)",
                )
                .clicked()
            {
                self.toggle_baseline();
            }
        }
        let heat = truth_map.and(self.truth_heat.as_ref());
        let tex = if show_error {
            self.errors.get(&rm).map(|e| e.texture.id())
        } else if let Some(h) = heat {
            Some(h.texture.id())
        } else {
            self.shown.get(&rm).map(|s| s.texture.id())
        };
        // The image covers the whole rect: a backdrop under it would only cost fill (on a
        // software adapter the window's frame rate is bound by fill).
        if tex.is_none() {
            ui.painter().rect_filled(img, 0.0, Color32::from_gray(20));
        }
        // All views render at the widest view's size; narrower ones show the centre.
        let u = (img.width() / max_w).clamp(0.0, 1.0);
        let uv = Rect::from_min_max(Pos2::new(0.5 - u * 0.5, 0.0), Pos2::new(0.5 + u * 0.5, 1.0));
        match tex {
            Some(t) => {
                ui.painter().image(t, img, uv, Color32::WHITE);
            }
            None => {
                ui.painter().text(
                    img.center(),
                    egui::Align2::CENTER_CENTER,
                    if show_error {
                        "waiting for ground truth…"
                    } else {
                        "rendering…"
                    },
                    egui::FontId::proportional(14.0),
                    ui.visuals().weak_text_color(),
                );
            }
        }
        if let (Some(d), Some(h)) = (truth_map, heat) {
            truth_legend(ui, img, d, h.max);
        } else if let Some(d) = truth_map
            && tex.is_some()
        {
            let why = match d {
                TruthDisplay::PredictedDeviation
                | TruthDisplay::PredictedBandwidth
                | TruthDisplay::Cost => ": it needs adaptive ground truth (View menu)",
                _ => "",
            };
            note(
                ui,
                img,
                &format!("no {} for this truth yet{why}", d.label()),
            );
        }
        if show_error {
            self.legend(ui, img);
            if let Some(e) = self.errors.get(&rm) {
                error_summary(ui, img, &e.summary);
            }
        }
        self.interact_camera(ui, img, ui.scope_id().with(("view", mode)), mode.label());
    }

    /// Heat-scale legend in the corner of an error view.
    fn legend(&self, ui: &Ui, img: Rect) {
        heat_bar(
            ui,
            img,
            &format!("{:.3}", self.view.error_scale),
            "grey: within the truth's noise",
        );
    }

    /// The A/B swipe view: left mode left of the split, right mode right of it.
    fn ab_view(&mut self, ui: &mut Ui, img: Rect) {
        let Some(mut ab) = self.view.ab else { return };
        ui.painter().rect_filled(img, 0.0, Color32::from_gray(20));
        let split_x = img.left() + img.width() * ab.split.clamp(0.0, 1.0);
        let uv_split = ab.split.clamp(0.0, 1.0);
        for (mode, left) in [(ab.left, true), (ab.right, false)] {
            if let Some(s) = self.shown.get(&mode.render_mode()) {
                let (r, uv) = if left {
                    (
                        Rect::from_min_max(img.min, Pos2::new(split_x, img.bottom())),
                        Rect::from_min_max(Pos2::ZERO, Pos2::new(uv_split, 1.0)),
                    )
                } else {
                    (
                        Rect::from_min_max(Pos2::new(split_x, img.top()), img.max),
                        Rect::from_min_max(Pos2::new(uv_split, 0.0), Pos2::new(1.0, 1.0)),
                    )
                };
                ui.painter().image(s.texture.id(), r, uv, Color32::WHITE);
            }
        }
        self.interact_camera(ui, img, ui.scope_id().with("ab-view"), "A/B view");
        // Mode pickers in the corners.
        for (k, side) in [(0, egui::Align2::LEFT_TOP), (1, egui::Align2::RIGHT_TOP)] {
            let pos = if k == 0 {
                img.left_top() + Vec2::new(6.0, 6.0)
            } else {
                img.right_top() + Vec2::new(-186.0, 6.0)
            };
            let _ = side;
            let mut m = if k == 0 { ab.left } else { ab.right };
            let mut child = ui.new_child(
                egui::UiBuilder::new().max_rect(Rect::from_min_size(pos, Vec2::new(180.0, 24.0))),
            );
            egui::ComboBox::from_id_salt(("ab-mode", k))
                .selected_text(m.label())
                .show_ui(&mut child, |ui| {
                    for o in Mode::ALL {
                        ui.selectable_value(&mut m, o, o.label());
                    }
                });
            if k == 0 {
                ab.left = m;
            } else {
                ab.right = m;
            }
        }
        let handle = Rect::from_center_size(
            Pos2::new(split_x, img.center().y),
            Vec2::new(10.0, img.height()),
        );
        let resp = ui
            .interact(handle, ui.scope_id().with("ab-split"), Sense::drag())
            .on_hover_cursor(egui::CursorIcon::ResizeHorizontal);
        resp.widget_info(|| WidgetInfo::slider(true, f64::from(ab.split), "A/B split"));
        if resp.dragged() {
            ab.split = (ab.split + resp.drag_delta().x / img.width()).clamp(0.0, 1.0);
        }
        ui.painter().line_segment(
            [
                Pos2::new(split_x, img.top()),
                Pos2::new(split_x, img.bottom()),
            ],
            Stroke::new(2.0, Color32::WHITE),
        );
        self.view.ab = Some(ab);
    }
}
