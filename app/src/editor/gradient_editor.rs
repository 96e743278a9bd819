//! The colour map editor: a gradient bar with draggable stops (click the bar to add a stop, drag a
//! handle to move it), the selected stop's colour and position, interpolation, flip, distribute and
//! the built-in maps.

use egui::{Color32, Pos2, Rect, Role, Sense, Stroke, Ui, Vec2, WidgetInfo};
use lodestone_core::material::colormap::{ColorStop, Gradient, Interpolation, linear_to_srgb};

/// Persistent UI state of the editor (which stop is selected).
#[derive(Clone, Copy, Debug, Default)]
pub struct GradientEditor {
    /// Index of the selected stop.
    pub selected: usize,
}

/// Linear RGB → display colour.
pub fn color32(c: [f64; 3]) -> Color32 {
    let s = c.map(|v| (linear_to_srgb(v.clamp(0.0, 1.0)) * 255.0).round() as u8);
    Color32::from_rgb(s[0], s[1], s[2])
}

/// The built-in maps, over a range.
pub fn builtin(name: &str, lo: f64, hi: f64) -> Option<Gradient> {
    match name {
        "viridis" => Some(Gradient::viridis(lo, hi)),
        "terrain" => Some(Gradient::terrain(lo, hi)),
        "rust" => Some(Gradient::rust(lo, hi)),
        _ => None,
    }
}

/// Names of the built-in maps.
pub const BUILTINS: [&str; 3] = ["viridis", "terrain", "rust"];

/// Move stop `i` to `pos`, keeping the stops sorted; returns its new index.
fn move_stop(g: &mut Gradient, i: usize, pos: f64) -> usize {
    let mut stop = g.stops.remove(i);
    stop.position = pos;
    let at = g.stops.partition_point(|s| s.position <= pos);
    g.stops.insert(at, stop);
    at
}

/// Height of the bar in points.
const BAR_HEIGHT: f32 = 26.0;
/// Size of a stop handle.
const HANDLE: f32 = 11.0;

impl GradientEditor {
    /// Show the editor for `g`. Returns true when `g` changed.
    pub fn ui(&mut self, ui: &mut Ui, g: &mut Gradient) -> bool {
        let mut changed = false;
        if g.stops.is_empty() {
            g.stops.push(ColorStop {
                position: 0.0,
                color: [0.5; 3],
            });
            changed = true;
        }
        self.selected = self.selected.min(g.stops.len() - 1);
        let (lo, hi) = g.range();
        let pad = ((hi - lo) * 0.08).max(0.25);
        let (vlo, vhi) = (lo - pad, hi + pad);
        let width = ui.available_width().max(120.0);
        let (rect, bar) =
            ui.allocate_exact_size(Vec2::new(width, BAR_HEIGHT + HANDLE + 4.0), Sense::click());
        bar.widget_info(|| {
            WidgetInfo::labeled(Role::Button, true, "Colour map bar (click to add a stop)")
        });
        let bar_rect = Rect::from_min_size(rect.min, Vec2::new(width, BAR_HEIGHT));
        let to_x = |v: f64| bar_rect.left() + ((v - vlo) / (vhi - vlo)) as f32 * bar_rect.width();
        let to_v = |x: f32| vlo + f64::from((x - bar_rect.left()) / bar_rect.width()) * (vhi - vlo);
        // The bar: one quad per column.
        let painter = ui.painter_at(rect.expand(2.0));
        let columns = (bar_rect.width() / 2.0).ceil() as usize;
        let mut mesh = egui::Mesh::default();
        for i in 0..=columns {
            let x = bar_rect.left() + bar_rect.width() * i as f32 / columns as f32;
            let c = color32(g.sample(to_v(x)));
            mesh.colored_vertex(Pos2::new(x, bar_rect.top()), c);
            mesh.colored_vertex(Pos2::new(x, bar_rect.bottom()), c);
            if i > 0 {
                let k = (2 * i) as u32;
                mesh.add_triangle(k - 2, k - 1, k);
                mesh.add_triangle(k - 1, k, k + 1);
            }
        }
        painter.add(mesh);
        painter.rect_stroke(
            bar_rect,
            2.0,
            Stroke::new(1.0, ui.visuals().widgets.noninteractive.bg_stroke.color),
            egui::StrokeKind::Inside,
        );
        if bar.clicked()
            && let Some(p) = bar.interact_pointer_pos()
            && bar_rect.contains(p)
        {
            let v = to_v(p.x);
            let stop = ColorStop {
                position: v,
                color: g.sample(v),
            };
            let at = g.stops.partition_point(|s| s.position <= v);
            g.stops.insert(at, stop);
            self.selected = at;
            changed = true;
        }
        // Handles.
        let mut moved: Option<(usize, f64)> = None;
        for (i, s) in g.stops.iter().enumerate() {
            let x = to_x(s.position);
            let top = bar_rect.bottom() + 2.0;
            let hr =
                Rect::from_center_size(Pos2::new(x, top + HANDLE * 0.5), Vec2::splat(HANDLE + 4.0));
            let r = ui.interact(hr, ui.scope_id().with(("stop", i)), Sense::click_and_drag());
            r.widget_info(|| {
                WidgetInfo::slider(true, s.position, format!("Colour stop {}", i + 1))
            });
            let r = r.on_hover_text(format!(
                "Stop {} at {:.3}: drag to move, click to select",
                i + 1,
                s.position
            ));
            if r.clicked() || r.drag_started() {
                self.selected = i;
            }
            if r.dragged() {
                let dv = f64::from(r.drag_delta().x / bar_rect.width()) * (vhi - vlo);
                moved = Some((i, s.position + dv));
            }
            let sel = i == self.selected;
            let pts = vec![
                Pos2::new(x, top),
                Pos2::new(x - HANDLE * 0.5, top + HANDLE),
                Pos2::new(x + HANDLE * 0.5, top + HANDLE),
            ];
            let outline = if sel {
                Stroke::new(2.0, ui.visuals().selection.stroke.color)
            } else {
                Stroke::new(1.0, ui.visuals().widgets.inactive.fg_stroke.color)
            };
            painter.add(egui::Shape::convex_polygon(pts, color32(s.color), outline));
        }
        if let Some((i, pos)) = moved
            && pos.is_finite()
        {
            self.selected = move_stop(g, i, pos);
            changed = true;
        }
        // The selected stop.
        ui.horizontal(|ui| {
            let i = self.selected;
            let n = g.stops.len();
            if let Some(s) = g.stops.get_mut(i) {
                ui.label(format!("Stop {}/{n}", i + 1));
                let mut c = s.color.map(|v| v as f32);
                let r = egui::color_picker::color_edit_button_rgb(ui, &mut c)
                    .on_hover_text("Colour of the selected stop (linear RGB)");
                if r.changed() {
                    s.color = c.map(f64::from);
                    changed = true;
                }
                let mut pos = s.position;
                let l = ui.label("at");
                let r = ui
                    .add(egui::DragValue::new(&mut pos).speed(0.01).max_decimals(3))
                    .labelled_by(l.id)
                    .on_hover_text("Position of the selected stop along the mapped value (f or standardized height)");
                if r.changed() && pos.is_finite() {
                    self.selected = move_stop(g, i, pos);
                    changed = true;
                }
            }
            if ui
                .add_enabled(n > 1, egui::Button::new("Remove stop"))
                .on_hover_text("Delete the selected stop (a map keeps at least one)")
                .clicked()
            {
                g.stops.remove(i);
                self.selected = i.saturating_sub(1);
                changed = true;
            }
        });
        ui.horizontal(|ui| {
            let mut interp = g.interpolation;
            egui::ComboBox::from_label("Interpolation")
                .selected_text(format!("{interp:?}"))
                .show_ui(ui, |ui| {
                    for v in [
                        Interpolation::Linear,
                        Interpolation::Smooth,
                        Interpolation::Constant,
                    ] {
                        ui.selectable_value(&mut interp, v, format!("{v:?}"));
                    }
                })
                .response
                .on_hover_text("Between stops: linear, smoothstep, or constant (a step map)");
            if interp != g.interpolation {
                g.interpolation = interp;
                changed = true;
            }
        });
        ui.horizontal(|ui| {
            if ui
                .button("Flip")
                .on_hover_text("Reverse the map within its range")
                .clicked()
            {
                *g = g.flipped();
                changed = true;
            }
            if ui
                .button("Distribute")
                .on_hover_text("Space the stops evenly over the range")
                .clicked()
            {
                *g = g.distributed();
                changed = true;
            }
            let mut pick: Option<&str> = None;
            egui::ComboBox::from_label("Built-in")
                .selected_text("choose…")
                .show_ui(ui, |ui| {
                    for name in BUILTINS {
                        if ui.selectable_label(false, name).clicked() {
                            pick = Some(name);
                        }
                    }
                })
                .response
                .on_hover_text("Replace the map by a built-in one over the same range");
            if let Some(name) = pick {
                let (lo, hi) = if hi > lo { (lo, hi) } else { (-2.0, 2.0) };
                if let Some(b) = builtin(name, lo, hi) {
                    *g = b;
                    self.selected = 0;
                    changed = true;
                }
            }
        });
        changed
    }
}
