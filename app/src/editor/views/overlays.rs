//! What the views draw over their images: heat-map legends, notes, and the error summary.

use super::*;

/// A heat bar from 0 to `max` in the bottom left corner of `img`, titled.
pub(super) fn heat_bar(ui: &Ui, img: Rect, max: &str, title: &str) {
    let g = lodestone_render::error_map::heat_gradient();
    let r = Rect::from_min_size(
        Pos2::new(img.left() + 8.0, img.bottom() - 22.0),
        Vec2::new((img.width() * 0.4).min(160.0), 10.0),
    );
    let n = 32;
    for i in 0..n {
        let t = i as f64 / f64::from(n - 1);
        let x0 = r.left() + r.width() * i as f32 / n as f32;
        ui.painter().rect_filled(
            Rect::from_min_size(
                Pos2::new(x0, r.top()),
                Vec2::new(r.width() / n as f32 + 0.5, r.height()),
            ),
            0.0,
            color32(g.sample(t)),
        );
    }
    let font = egui::FontId::proportional(11.0);
    ui.painter().text(
        r.left_bottom() + Vec2::new(0.0, 1.0),
        egui::Align2::LEFT_TOP,
        "0",
        font.clone(),
        Color32::WHITE,
    );
    ui.painter().text(
        r.right_bottom() + Vec2::new(0.0, 1.0),
        egui::Align2::RIGHT_TOP,
        max,
        font.clone(),
        Color32::WHITE,
    );
    ui.painter().text(
        r.right_center() + Vec2::new(8.0, 0.0),
        egui::Align2::LEFT_CENTER,
        title,
        font,
        Color32::from_gray(170),
    );
}

/// The legend of the truth viewport's noise map.
pub(super) fn truth_legend(ui: &Ui, img: Rect, display: TruthDisplay, max: f64) {
    let (top, unit) = match display {
        TruthDisplay::Rays => (format!("{max:.0}"), "rays per pixel"),
        TruthDisplay::Cost => (format!("{max:.0}"), "cost of a ray (march steps + waves/8)"),
        TruthDisplay::StandardError => (
            format!("{max:.3}"),
            "standard error of the mean luminance (grey: under 2 rays)",
        ),
        TruthDisplay::WindowRadius => (
            format!("{max:.0}"),
            "window radius, pixels (flat within the truth's noise)",
        ),
        TruthDisplay::PredictedBandwidth => {
            (format!("{max:.1}"), "cycles per pixel (0.5: Nyquist)")
        }
        TruthDisplay::Image | TruthDisplay::Reconstructed => return,
        _ => (format!("{max:.3}"), "σ̂ of one ray's luminance"),
    };
    heat_bar(ui, img, &top, unit);
}

/// One line of text over the top left of `img`, on a dark backing.
pub(super) fn note(ui: &Ui, img: Rect, text: &str) {
    let painter = ui.painter_at(img);
    let galley = painter.layout_no_wrap(
        text.to_string(),
        egui::FontId::proportional(12.0),
        Color32::WHITE,
    );
    let at = Pos2::new(img.left() + 4.0, img.top() + 4.0);
    painter.rect_filled(
        Rect::from_min_size(at, galley.size()).expand(2.0),
        2.0,
        Color32::from_black_alpha(160),
    );
    painter.galley(at, galley, Color32::WHITE);
}

pub(super) fn px(size: Vec2, ppp: f32) -> [u32; 2] {
    [
        (size.x * ppp).round().max(1.0) as u32,
        (size.y * ppp).round().max(1.0) as u32,
    ]
}

/// The error map's numbers, over the top left of its image: the RMSE beyond the truth's noise with
/// its range, the share of significant blocks, and the raw per-pixel RMSE and max.
pub(super) fn error_summary(ui: &Ui, img: Rect, e: &crate::editor::frames::ErrorSummary) {
    let mut lines = Vec::new();
    match (e.beyond_noise, e.significant) {
        (Some((rmse, (lo, hi))), Some(sig)) => {
            lines.push(format!(
                "RMSE beyond truth noise {rmse:.4} ({lo:.4}–{hi:.4})"
            ));
            lines.push(format!(
                "{:.0}% of {b}×{b} blocks significant",
                sig * 100.0,
                b = e.block
            ));
        }
        _ => lines.push("truth noise unknown until 2 rays per pixel".to_string()),
    }
    lines.push(format!(
        "per pixel: RMSE {:.4}, max {:.3}",
        e.rmse_raw, e.max
    ));
    let font = egui::FontId::proportional(12.0);
    let painter = ui.painter_at(img);
    let mut y = img.top() + 4.0;
    for line in lines {
        let galley = painter.layout_no_wrap(line, font.clone(), Color32::WHITE);
        let r = Rect::from_min_size(Pos2::new(img.left() + 4.0, y), galley.size()).expand(2.0);
        painter.rect_filled(r, 2.0, Color32::from_black_alpha(160));
        painter.galley(Pos2::new(img.left() + 4.0, y), galley, Color32::WHITE);
        y += r.height();
    }
}
