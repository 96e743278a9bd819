//! Small line/point charts for `lodestone report`, drawn once through a [`Canvas`] so the SVG and
//! the PNG show the same thing: SVG (exact, opens in a browser) and PNG rasterised with tiny-skia,
//! text by ab_glyph in egui's own Ubuntu font (both crates were already in the dependency tree
//! through eframe, so no new code is compiled for them).

use std::fmt::Write as _;

/// One series: label, colour (`#rrggbb`), points in data units, whether to join them.
pub type Series = (String, &'static str, Vec<(f64, f64)>, bool);

/// Horizontal text anchoring.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// Text starts at x.
    Start,
    /// Text is centred on x.
    Middle,
    /// Text ends at x.
    End,
}

/// What a chart is drawn with.
pub trait Canvas {
    /// A straight line.
    fn line(&mut self, a: (f64, f64), b: (f64, f64), color: &str, width: f64);
    /// A polyline.
    fn polyline(&mut self, points: &[(f64, f64)], color: &str, width: f64);
    /// A filled disc.
    fn disc(&mut self, centre: (f64, f64), radius: f64, color: &str);
    /// Text with its baseline at `y`.
    fn text(&mut self, x: f64, y: f64, text: &str, size: f64, anchor: Anchor);
}

/// The chart's labels and axes.
#[derive(Clone, Debug)]
pub struct Chart {
    /// Title (top left).
    pub title: String,
    /// x-axis label (below).
    pub x_label: String,
    /// y-axis label (above the axis, under the title).
    pub y_label: String,
    /// Log x axis.
    pub log_x: bool,
    /// Log y axis.
    pub log_y: bool,
}

/// Width and height of every chart, pixels.
pub const SIZE: (f64, f64) = (760.0, 460.0);
const MARGIN: (f64, f64, f64, f64) = (70.0, 240.0, 58.0, 50.0); // left, right, top, bottom

impl Chart {
    /// The chart as an SVG document.
    pub fn svg(&self, series: &[Series]) -> String {
        let mut c = SvgCanvas::default();
        self.draw(&mut c, series);
        c.finish()
    }

    /// The chart as an image.
    pub fn png(&self, series: &[Series]) -> image::RgbaImage {
        let mut c = PngCanvas::new();
        self.draw(&mut c, series);
        c.finish()
    }

    /// Draw `series` onto `c`.
    pub fn draw(&self, c: &mut dyn Canvas, series: &[Series]) {
        let (w, h) = SIZE;
        let (ml, mr, mt, mb) = MARGIN;
        let tx = |v: f64| if self.log_x { v.max(1e-12).log10() } else { v };
        let ty = |v: f64| if self.log_y { v.max(1e-12).log10() } else { v };
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (x, y) in series.iter().flat_map(|s| s.2.iter()) {
            let (x, y) = (tx(*x), ty(*y));
            if x.is_finite() && y.is_finite() {
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
        }
        if !(x1 > x0) {
            x0 = if x0 <= x1 { x0 } else { 0.0 };
            x1 = x0 + 1.0;
        }
        if !(y1 > y0) {
            y0 = if y0 <= y1 { y0 } else { 0.0 };
            y1 = y0 + 1.0;
        }
        let px = |x: f64| ml + (tx(x) - x0) / (x1 - x0) * (w - ml - mr);
        let py = |y: f64| h - mb - (ty(y) - y0) / (y1 - y0) * (h - mt - mb);
        c.text(ml, 22.0, &self.title, 15.0, Anchor::Start);
        c.text(ml, mt - 12.0, &self.y_label, 12.0, Anchor::Start);
        let fmt = |v: f64, log: bool| {
            let x = if log { 10f64.powf(v) } else { v };
            if x != 0.0 && (x.abs() < 0.01 || x.abs() >= 1e4) {
                format!("{x:.2e}")
            } else {
                format!("{x:.3}")
            }
        };
        for i in 0..=4 {
            let f = f64::from(i) / 4.0;
            let (gx, gy) = (ml + (w - ml - mr) * f, h - mb - (h - mt - mb) * f);
            c.line((ml, gy), (w - mr, gy), "#dddddd", 1.0);
            c.text(
                gx,
                h - mb + 16.0,
                &fmt(x0 + (x1 - x0) * f, self.log_x),
                12.0,
                Anchor::Middle,
            );
            c.text(
                ml - 6.0,
                gy + 4.0,
                &fmt(y0 + (y1 - y0) * f, self.log_y),
                12.0,
                Anchor::End,
            );
        }
        c.line((ml, h - mb), (w - mr, h - mb), "#000000", 1.0);
        c.line((ml, mt), (ml, h - mb), "#000000", 1.0);
        c.text(
            (ml + w - mr) / 2.0,
            h - 12.0,
            &self.x_label,
            12.0,
            Anchor::Middle,
        );
        for (i, (label, color, points, joined)) in series.iter().enumerate() {
            let screen: Vec<(f64, f64)> = points.iter().map(|(x, y)| (px(*x), py(*y))).collect();
            if *joined && screen.len() > 1 {
                c.polyline(&screen, color, 2.0);
            }
            for p in &screen {
                c.disc(*p, 4.0, color);
            }
            let ly = mt + 18.0 * i as f64;
            c.disc((w - mr + 16.0, ly), 5.0, color);
            c.text(w - mr + 26.0, ly + 4.0, label, 12.0, Anchor::Start);
        }
    }
}

/// SVG output.
#[derive(Debug, Default)]
pub struct SvgCanvas {
    body: String,
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

impl SvgCanvas {
    /// The document.
    pub fn finish(self) -> String {
        let (w, h) = SIZE;
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\">\n\
             <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n{}</svg>\n",
            self.body
        )
    }
}

impl Canvas for SvgCanvas {
    fn line(&mut self, a: (f64, f64), b: (f64, f64), color: &str, width: f64) {
        let _ = writeln!(
            self.body,
            "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"{color}\" stroke-width=\"{width}\"/>",
            a.0, a.1, b.0, b.1
        );
    }
    fn polyline(&mut self, points: &[(f64, f64)], color: &str, width: f64) {
        let p: Vec<String> = points
            .iter()
            .map(|(x, y)| format!("{x:.1},{y:.1}"))
            .collect();
        let _ = writeln!(
            self.body,
            "<polyline fill=\"none\" stroke=\"{color}\" stroke-width=\"{width}\" points=\"{}\"/>",
            p.join(" ")
        );
    }
    fn disc(&mut self, c: (f64, f64), r: f64, color: &str) {
        let _ = writeln!(
            self.body,
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"{r}\" fill=\"{color}\"/>",
            c.0, c.1
        );
    }
    fn text(&mut self, x: f64, y: f64, text: &str, size: f64, anchor: Anchor) {
        let a = match anchor {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        };
        let _ = writeln!(
            self.body,
            "<text x=\"{x:.1}\" y=\"{y:.1}\" font-size=\"{size}\" text-anchor=\"{a}\">{}</text>",
            escape(text)
        );
    }
}

/// PNG output: tiny-skia for shapes, ab_glyph for text.
pub struct PngCanvas {
    pixmap: tiny_skia::Pixmap,
    font: ab_glyph::FontRef<'static>,
}

/// An anti-aliased solid paint of `#rrggbb`.
fn paint(hex: &str) -> tiny_skia::Paint<'static> {
    let v = u32::from_str_radix(hex.trim_start_matches('#'), 16).unwrap_or(0);
    let mut paint = tiny_skia::Paint::default();
    paint.set_color(tiny_skia::Color::from_rgba8(
        (v >> 16) as u8,
        (v >> 8) as u8,
        v as u8,
        255,
    ));
    paint.anti_alias = true;
    paint
}

impl PngCanvas {
    /// A white canvas of [`SIZE`].
    pub fn new() -> Self {
        let (w, h) = SIZE;
        let mut pixmap =
            tiny_skia::Pixmap::new(w as u32, h as u32).expect("chart size is positive");
        pixmap.fill(tiny_skia::Color::WHITE);
        let font = ab_glyph::FontRef::try_from_slice(epaint_default_fonts::UBUNTU_LIGHT)
            .expect("egui's bundled font parses");
        Self { pixmap, font }
    }

    /// The image (opaque, so premultiplied equals straight RGBA).
    pub fn finish(self) -> image::RgbaImage {
        let (w, h) = (self.pixmap.width(), self.pixmap.height());
        image::RgbaImage::from_raw(w, h, self.pixmap.take()).expect("pixmap size matches")
    }

    fn stroke(&mut self, path: Option<tiny_skia::Path>, color: &str, width: f64) {
        let Some(path) = path else { return };
        let paint = paint(color);
        let stroke = tiny_skia::Stroke {
            width: width as f32,
            ..tiny_skia::Stroke::default()
        };
        self.pixmap.stroke_path(
            &path,
            &paint,
            &stroke,
            tiny_skia::Transform::identity(),
            None,
        );
    }
}

impl Canvas for PngCanvas {
    fn line(&mut self, a: (f64, f64), b: (f64, f64), color: &str, width: f64) {
        let mut pb = tiny_skia::PathBuilder::new();
        pb.move_to(a.0 as f32, a.1 as f32);
        pb.line_to(b.0 as f32, b.1 as f32);
        self.stroke(pb.finish(), color, width);
    }
    fn polyline(&mut self, points: &[(f64, f64)], color: &str, width: f64) {
        let mut pb = tiny_skia::PathBuilder::new();
        for (i, (x, y)) in points.iter().enumerate() {
            if i == 0 {
                pb.move_to(*x as f32, *y as f32);
            } else {
                pb.line_to(*x as f32, *y as f32);
            }
        }
        self.stroke(pb.finish(), color, width);
    }
    fn disc(&mut self, c: (f64, f64), r: f64, color: &str) {
        let Some(path) = tiny_skia::PathBuilder::from_circle(c.0 as f32, c.1 as f32, r as f32)
        else {
            return;
        };
        let paint = paint(color);
        self.pixmap.fill_path(
            &path,
            &paint,
            tiny_skia::FillRule::Winding,
            tiny_skia::Transform::identity(),
            None,
        );
    }
    fn text(&mut self, x: f64, y: f64, text: &str, size: f64, anchor: Anchor) {
        use ab_glyph::{Font, ScaleFont};
        let scaled = self.font.as_scaled(size as f32);
        let ids: Vec<_> = text.chars().map(|ch| scaled.glyph_id(ch)).collect();
        let mut width = 0.0f32;
        for (i, id) in ids.iter().enumerate() {
            if i > 0 {
                width += scaled.kern(ids[i - 1], *id);
            }
            width += scaled.h_advance(*id);
        }
        let mut pen = x as f32
            - match anchor {
                Anchor::Start => 0.0,
                Anchor::Middle => width / 2.0,
                Anchor::End => width,
            };
        let (w, h) = (self.pixmap.width() as i64, self.pixmap.height() as i64);
        for (i, id) in ids.iter().enumerate() {
            if i > 0 {
                pen += scaled.kern(ids[i - 1], *id);
            }
            let glyph = id.with_scale_and_position(size as f32, ab_glyph::point(pen, y as f32));
            pen += scaled.h_advance(*id);
            let Some(outline) = self.font.outline_glyph(glyph) else {
                continue;
            };
            let b = outline.px_bounds();
            let pixels = self.pixmap.pixels_mut();
            outline.draw(|gx, gy, coverage| {
                let (px, py) = (
                    b.min.x as i64 + i64::from(gx),
                    b.min.y as i64 + i64::from(gy),
                );
                if px < 0 || py < 0 || px >= w || py >= h {
                    return;
                }
                let p = &mut pixels[(py * w + px) as usize];
                let k = 1.0 - coverage.clamp(0.0, 1.0);
                let mix = |c: u8| (f32::from(c) * k).round() as u8; // black text over the pixel
                if let Some(q) = tiny_skia::PremultipliedColorU8::from_rgba(
                    mix(p.red()),
                    mix(p.green()),
                    mix(p.blue()),
                    255,
                ) {
                    *p = q;
                }
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series() -> Vec<Series> {
        vec![
            (
                "red points".into(),
                "#d62728",
                vec![(1.0, 2.0), (10.0, 20.0)],
                false,
            ),
            (
                "blue line".into(),
                "#1f77b4",
                vec![(2.0, 1.0), (5.0, 3.0), (50.0, 9.0)],
                true,
            ),
        ]
    }

    fn chart() -> Chart {
        Chart {
            title: "Test: ΔE against time".into(),
            x_label: "ms per frame (log)".into(),
            y_label: "mean ΔE*ab (log)".into(),
            log_x: true,
            log_y: true,
        }
    }

    #[test]
    fn png_has_the_series_colours_and_text() {
        let mut c = PngCanvas::new();
        chart().draw(&mut c, &series());
        let img = c.finish();
        if let Ok(dir) = std::env::var("LODESTONE_CHART_TEST_OUT") {
            let _ = img.save(std::path::Path::new(&dir).join("chart-test.png"));
        }
        assert_eq!(img.dimensions(), (SIZE.0 as u32, SIZE.1 as u32));
        let count = |f: &dyn Fn(&image::Rgba<u8>) -> bool| img.pixels().filter(|p| f(p)).count();
        // Discs and the line in their colours, and dark text pixels.
        assert!(count(&|p| p[0] > 200 && p[1] < 60 && p[2] < 60) > 50);
        assert!(count(&|p| p[2] > 150 && p[0] < 60) > 100);
        let dark = count(&|p| p[0] < 128 && p[1] < 128 && p[2] < 128);
        assert!(dark > 400, "{dark} dark pixels");
        // Text lands where it is anchored: the title's first glyphs start at the left margin.
        let title_row = (8..24).any(|y| (70..90).any(|x| img.get_pixel(x, y)[0] < 100));
        assert!(title_row);
    }

    #[test]
    fn svg_has_every_label_escaped_and_every_point() {
        let mut c = SvgCanvas::default();
        let mut s = series();
        s[0].0 = "a < b & c".into();
        chart().draw(&mut c, &s);
        let svg = c.finish();
        assert!(svg.contains("a &lt; b &amp; c"));
        assert_eq!(svg.matches("<circle").count(), 2 + 3 + 2); // points + legend discs
        assert_eq!(svg.matches("<polyline").count(), 1);
    }

    #[test]
    fn degenerate_data_draws_without_nan() {
        let mut c = SvgCanvas::default();
        chart().draw(&mut c, &[("one".into(), "#000000", vec![(3.0, 3.0)], true)]);
        assert!(!c.finish().contains("NaN"));
        let mut c = SvgCanvas::default();
        chart().draw(&mut c, &[]);
        assert!(!c.finish().contains("NaN"));
    }
}
