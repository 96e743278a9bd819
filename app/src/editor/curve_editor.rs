//! The height transfer function editor: the curve g with draggable control points (click empty
//! space to add a point, right-click a point to remove it), named shapes, and a live histogram of
//! the resulting heights h = g(f), f ~ N(0, 1) [HNPN14 Sec. 7].

use egui::{Color32, Pos2, Rect, Role, Sense, Stroke, Ui, Vec2, WidgetInfo};
use lodestone_core::driver::image::ImageDriver;
use lodestone_core::microfacet::transfer::{Curve, CurveInterpolation, TransferFunction};
use std::sync::Arc;

/// Persistent UI state (the selected point).
#[derive(Clone, Debug, Default)]
pub struct CurveEditor {
    /// Selected control point.
    pub selected: usize,
    /// The height histogram, cached with the curve and image it was computed for.
    histogram: Option<(TransferFunction, Option<usize>, Histogram)>,
}

/// A histogram: the range of g it covers and the probability per bin.
type Histogram = (f64, f64, Vec<f64>);

/// Driver range shown on the f axis.
const F_RANGE: (f64, f64) = (-3.5, 3.5);
/// Bins of the height histogram.
const BINS: usize = 48;

/// Histogram of `g(f)`, f ~ N(0, 1): probability per bin over `[lo, hi]`, by quadrature of the
/// Gaussian over a fine grid of f (exact up to the grid, no sampling noise).
pub fn height_histogram(t: &TransferFunction, bins: usize) -> Histogram {
    const N: usize = 4000;
    let (a, b) = (-6.0f64, 6.0f64);
    let df = (b - a) / N as f64;
    let samples = (0..N).map(|i| {
        let f = a + (i as f64 + 0.5) * df;
        (
            f,
            (-0.5 * f * f).exp() / (2.0 * std::f64::consts::PI).sqrt() * df,
        )
    });
    weighted_histogram(t, samples, bins)
}

/// Histogram of `g(f)` over an image driver's standardized texels (what its explicit surface
/// shows, not the Gaussian the filtered views assume): every texel of level 0 up to 2¹⁶ of them,
/// evenly strided beyond, with equal weights.
pub fn image_height_histogram(t: &TransferFunction, image: &ImageDriver, bins: usize) -> Histogram {
    let Some(level) = image.levels.first() else {
        return height_histogram(t, bins);
    };
    let n = level.value.len().max(1);
    let stride = n.div_ceil(1 << 16).max(1);
    let count = n.div_ceil(stride);
    let samples = level
        .value
        .iter()
        .step_by(stride)
        .map(|v| (f64::from(v[0]), 1.0 / count as f64));
    weighted_histogram(t, samples, bins)
}

/// Probability per bin of g(f) for weighted samples of f, over the 0.1%–99.9% quantiles of g.
fn weighted_histogram(
    t: &TransferFunction,
    samples: impl Iterator<Item = (f64, f64)>,
    bins: usize,
) -> Histogram {
    // g through its polynomial once (TransferFunction::eval builds it per call).
    let vals: Vec<(f64, f64)> = match t {
        TransferFunction::Identity => samples.collect(),
        TransferFunction::Curve(c) => {
            let p = c.moment_poly();
            let mut o = [0.0; 4];
            samples
                .map(|(f, w)| {
                    p.eval(f, &mut o);
                    (o[0], w)
                })
                .collect()
        }
    };
    // Range: the 0.1% and 99.9% quantiles of g, so rare tails do not squash the histogram.
    let mut sorted = vals.clone();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = sorted.iter().map(|v| v.1).sum();
    let quantile = |q: f64| {
        let mut acc = 0.0;
        for (g, w) in &sorted {
            acc += w;
            if acc >= q * total {
                return *g;
            }
        }
        sorted.last().map_or(0.0, |v| v.0)
    };
    let (lo, hi) = (quantile(1e-3), quantile(1.0 - 1e-3));
    let (lo, hi) = if hi - lo > 1e-9 {
        (lo, hi)
    } else {
        (lo - 0.5, hi + 0.5)
    };
    let mut h = vec![0.0; bins.max(1)];
    for (g, w) in vals {
        let k = (((g - lo) / (hi - lo)) * bins as f64).floor() as isize;
        h[k.clamp(0, bins as isize - 1) as usize] += w;
    }
    (lo, hi, h)
}

impl CurveEditor {
    /// Show the editor for `t`; `image` is the material's image driver, whose texels the height
    /// histogram then shows. Returns true when it changed.
    pub fn ui(
        &mut self,
        ui: &mut Ui,
        t: &mut TransferFunction,
        image: Option<&Arc<ImageDriver>>,
    ) -> bool {
        let mut changed = false;
        ui.horizontal_wrapped(|ui| {
            let shapes: [(&str, &str, TransferFunction); 5] = [
                (
                    "Identity",
                    "g(f) = f: Gaussian heights",
                    TransferFunction::Identity,
                ),
                (
                    "Moss",
                    "A flat floor with rounded clumps where the driver is high",
                    TransferFunction::Curve(Curve::moss()),
                ),
                (
                    "Sponge",
                    "A flat top pierced by steep pits where the driver is low",
                    TransferFunction::Curve(Curve::sponge()),
                ),
                (
                    "Terraces",
                    "Flat shelves joined by steep risers",
                    TransferFunction::Curve(Curve::terraces(4)),
                ),
                (
                    "Linear curve",
                    "An editable straight line g(f) = f",
                    TransferFunction::Curve(Curve {
                        points: vec![[-3.0, -3.0], [0.0, 0.0], [3.0, 3.0]],
                        interpolation: CurveInterpolation::MonotoneCubic,
                    }),
                ),
            ];
            for (name, tip, shape) in shapes {
                if ui.button(name).on_hover_text(tip).clicked() {
                    *t = shape;
                    self.selected = 0;
                    changed = true;
                }
            }
        });
        let plot_h = 150.0;
        let width = ui.available_width().max(160.0);
        let (rect, bg) = ui.allocate_exact_size(Vec2::new(width, plot_h), Sense::click());
        bg.widget_info(|| {
            WidgetInfo::labeled(
                Role::Button,
                true,
                "Transfer curve plot (click to add a point)",
            )
        });
        let (glo, ghi) = {
            let (lo, hi) = sample_range(t);
            let pad = ((hi - lo) * 0.1).max(0.1);
            (lo - pad, hi + pad)
        };
        let to_screen = |f: f64, g: f64| {
            Pos2::new(
                rect.left() + ((f - F_RANGE.0) / (F_RANGE.1 - F_RANGE.0)) as f32 * rect.width(),
                rect.bottom() - ((g - glo) / (ghi - glo)) as f32 * rect.height(),
            )
        };
        let from_screen = |p: Pos2| {
            (
                F_RANGE.0 + f64::from((p.x - rect.left()) / rect.width()) * (F_RANGE.1 - F_RANGE.0),
                glo + f64::from((rect.bottom() - p.y) / rect.height()) * (ghi - glo),
            )
        };
        let painter = ui.painter_at(rect);
        let vis = ui.visuals();
        painter.rect_filled(rect, 2.0, vis.extreme_bg_color);
        let axis = Stroke::new(1.0, vis.weak_text_color().gamma_multiply(0.5));
        painter.line_segment([to_screen(0.0, glo), to_screen(0.0, ghi)], axis);
        painter.line_segment([to_screen(F_RANGE.0, 0.0), to_screen(F_RANGE.1, 0.0)], axis);
        // The Gaussian density of f, faintly, for where the driver actually lives.
        let density: Vec<Pos2> = (0..=100)
            .map(|i| {
                let f = F_RANGE.0 + (F_RANGE.1 - F_RANGE.0) * f64::from(i) / 100.0;
                let d = (-0.5 * f * f).exp();
                Pos2::new(
                    to_screen(f, 0.0).x,
                    rect.bottom() - d as f32 * rect.height() * 0.3,
                )
            })
            .collect();
        painter.add(egui::Shape::line(
            density,
            Stroke::new(1.0, vis.weak_text_color().gamma_multiply(0.4)),
        ));
        let curve: Vec<Pos2> = (0..=200)
            .map(|i| {
                let f = F_RANGE.0 + (F_RANGE.1 - F_RANGE.0) * f64::from(i) / 200.0;
                to_screen(f, t.eval(f))
            })
            .collect();
        painter.add(egui::Shape::line(
            curve,
            Stroke::new(2.0, Color32::from_rgb(230, 160, 60)),
        ));
        if let TransferFunction::Curve(c) = t {
            if bg.clicked()
                && let Some(p) = bg.interact_pointer_pos()
            {
                let (f, g) = from_screen(p);
                let at = c.points.partition_point(|q| q[0] <= f);
                c.points.insert(at, [f, g]);
                self.selected = at;
                changed = true;
            }
            let mut moved = None;
            let mut remove = None;
            for (i, q) in c.points.iter().enumerate() {
                let p = to_screen(q[0], q[1]);
                let r = ui.interact(
                    Rect::from_center_size(p, Vec2::splat(12.0)),
                    ui.scope_id().with(("point", i)),
                    Sense::click_and_drag(),
                );
                r.widget_info(|| {
                    WidgetInfo::labeled(
                        Role::Slider,
                        true,
                        format!("Control point {} (f = {:.2}, g = {:.2})", i + 1, q[0], q[1]),
                    )
                });
                let r = r.on_hover_text(format!(
                    "f = {:.3}, g = {:.3}: drag to move, right-click to remove",
                    q[0], q[1]
                ));
                if r.clicked() || r.drag_started() {
                    self.selected = i;
                }
                if r.secondary_clicked() {
                    remove = Some(i);
                }
                if r.dragged()
                    && let Some(pos) = r.interact_pointer_pos()
                {
                    moved = Some((i, from_screen(pos)));
                }
                let fill = if i == self.selected {
                    vis.selection.bg_fill
                } else {
                    vis.widgets.inactive.fg_stroke.color
                };
                painter.circle(p, 4.5, fill, Stroke::new(1.0, vis.strong_text_color()));
            }
            if let Some((i, (f, g))) = moved
                && f.is_finite()
                && g.is_finite()
            {
                // Keep the points sorted: a point moves between its neighbours.
                let lo = if i > 0 { c.points[i - 1][0] } else { -10.0 };
                let hi = c.points.get(i + 1).map_or(10.0, |q| q[0]);
                c.points[i] = [f.clamp(lo, hi), g];
                changed = true;
            }
            if let Some(i) = remove
                && c.points.len() > 2
            {
                c.points.remove(i);
                self.selected = self.selected.min(c.points.len() - 1);
                changed = true;
            }
            ui.horizontal(|ui| {
                let mut interp = c.interpolation;
                egui::ComboBox::from_label("Curve interpolation")
                    .selected_text(match interp {
                        CurveInterpolation::Linear => "Linear",
                        CurveInterpolation::MonotoneCubic => "Monotone cubic",
                    })
                    .show_ui(ui, |ui| {
                        ui.selectable_value(&mut interp, CurveInterpolation::Linear, "Linear");
                        ui.selectable_value(
                            &mut interp,
                            CurveInterpolation::MonotoneCubic,
                            "Monotone cubic",
                        );
                    })
                    .response
                    .on_hover_text("Fritsch–Carlson monotone cubic never overshoots monotone data");
                if interp != c.interpolation {
                    c.interpolation = interp;
                    changed = true;
                }
                if ui
                    .button("Normalise")
                    .on_hover_text(
                        "Shift and scale g so g(f), f ~ N(0,1), has mean 0 and std 1: σ_h is then the surface's height std",
                    )
                    .clicked()
                {
                    *c = c.clone().normalized();
                    changed = true;
                }
            });
        } else {
            ui.weak("Identity: pick a shape above to edit a curve.");
        }
        // Height histogram (cached per curve and image).
        let key = image.map(|i| Arc::as_ptr(i) as usize);
        if self
            .histogram
            .as_ref()
            .is_none_or(|(tc, k, _)| tc != &*t || *k != key)
        {
            let h = match image {
                Some(img) => image_height_histogram(t, img, BINS),
                None => height_histogram(t, BINS),
            };
            self.histogram = Some((t.clone(), key, h));
        }
        let Some((_, _, (lo, hi, hist))) = self.histogram.clone() else {
            return changed;
        };
        ui.label(if image.is_some() {
            "Height histogram of g(f), f = the image's standardized texels"
        } else {
            "Height histogram of g(f), f ~ N(0, 1)"
        });
        let (hrect, _) = ui.allocate_exact_size(Vec2::new(width, 60.0), Sense::hover());
        let painter = ui.painter_at(hrect);
        painter.rect_filled(hrect, 2.0, vis_bg(ui));
        let peak = hist.iter().cloned().fold(1e-12, f64::max);
        let bw = hrect.width() / hist.len() as f32;
        for (k, p) in hist.iter().enumerate() {
            let hgt = (p / peak) as f32 * (hrect.height() - 2.0);
            let x0 = hrect.left() + bw * k as f32;
            painter.rect_filled(
                Rect::from_min_max(
                    Pos2::new(x0 + 0.5, hrect.bottom() - hgt),
                    Pos2::new(x0 + bw - 0.5, hrect.bottom()),
                ),
                0.0,
                Color32::from_rgb(110, 150, 210),
            );
        }
        ui.horizontal(|ui| {
            ui.weak(format!("g from {lo:.2}"));
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                ui.weak(format!("to {hi:.2}"));
            });
        });
        changed
    }
}

fn vis_bg(ui: &Ui) -> Color32 {
    ui.visuals().extreme_bg_color
}

/// Range of g over the displayed f range and the control points.
fn sample_range(t: &TransferFunction) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for i in 0..=100 {
        let f = F_RANGE.0 + (F_RANGE.1 - F_RANGE.0) * f64::from(i) / 100.0;
        let g = t.eval(f);
        lo = lo.min(g);
        hi = hi.max(g);
    }
    if let TransferFunction::Curve(c) = t {
        for p in &c.points {
            lo = lo.min(p[1]);
            hi = hi.max(p[1]);
        }
    }
    if !(hi > lo) {
        (lo - 1.0, lo + 1.0)
    } else {
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For the identity the histogram is the Gaussian itself: its bins integrate the normal density.
    #[test]
    fn identity_histogram_is_the_normal_density() {
        let (lo, hi, h) = height_histogram(&TransferFunction::Identity, 12);
        // The 0.1% quantile of N(0, 1) is −3.0902.
        assert!(
            (lo + 3.0902).abs() < 0.01 && (hi - 3.0902).abs() < 0.01,
            "{lo} {hi}"
        );
        let total: f64 = h.iter().sum();
        assert!((total - 1.0).abs() < 1e-8, "{total}");
        // Bin [0, 3.09/6): Φ(0.515) − Φ(0) = 0.1967 (tails are clamped into the end bins).
        let edge = hi / 6.0;
        let expect = 0.5 * libm_erf(edge / std::f64::consts::SQRT_2);
        assert!((h[6] - expect).abs() < 2e-3, "{} vs {expect}", h[6]);
    }

    fn libm_erf(x: f64) -> f64 {
        lodestone_core::math::special::erf(x)
    }

    #[test]
    fn terraces_pile_heights_on_shelves() {
        let (_, _, h) = height_histogram(&TransferFunction::Curve(Curve::terraces(4)), 48);
        let mut sorted = h.clone();
        sorted.sort_by(|a, b| b.total_cmp(a));
        let top4: f64 = sorted[..8].iter().sum();
        assert!(top4 > 0.6, "shelves should hold most of the mass: {top4}");
    }

    /// An image driver's histogram is its texels': a two-valued image (a quarter high, three
    /// quarters low) puts exactly those masses in the two end bins, not a Gaussian's.
    #[test]
    fn image_histogram_counts_the_texels() {
        let values: Vec<f32> = (0..64)
            .map(|i| if i % 4 == 0 { 3.0 } else { 1.0 })
            .collect();
        let img = ImageDriver::new(8, 8, &values).unwrap();
        let (lo, hi, h) = image_height_histogram(&TransferFunction::Identity, &img, 10);
        assert!(lo < hi);
        let total: f64 = h.iter().sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
        assert!(
            (h[0] - 0.75).abs() < 1e-12 && (h[9] - 0.25).abs() < 1e-12,
            "{h:?}"
        );
        assert!(h[1..9].iter().all(|v| *v == 0.0), "{h:?}");
    }
}
