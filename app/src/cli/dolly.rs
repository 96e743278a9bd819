//! `lodestone dolly`: the popping figure of #15. A slow dolly (the editor's zoom sweep, from
//! closest to farthest, geometric in distance) rendered with the fast march and with the reference
//! march; per pixel, the jump between consecutive frames. The fast march has no level-of-detail
//! switch (its far field is the level-of-detail surface's slab, thin by construction), so it must
//! not make any pixel jump more than the reference march does: the figure is the largest excess
//! of a pixel's jump under the fast march over the same pixel's jump under the reference march.
//!
//! Ground truth is left out: its one-ray frames jump by their Monte Carlo noise, which would hide
//! any popping (and it has no level of detail to pop).

use crate::cli::Context;
use crate::cli::args;
use crate::cli::render::{View, renderer};
use crate::preset_io::Resolved;
use anyhow::Result;
use glam::DVec2;
use lodestone_core::eval::Method;
use lodestone_core::scene::march::March;
use lodestone_render::{GpuMaterial, LinearImage, ViewMode, ViewTarget};

/// The arguments of `lodestone dolly`.
#[derive(Debug, Clone, clap::Args)]
pub struct DollyArgs {
    /// Camera angle from the normal, degrees (0 to 89.5).
    #[arg(long, default_value_t = 77.0, value_parser = args::view_angle)]
    pub view_deg: f64,
    /// Closest camera distance (world units).
    #[arg(long, default_value_t = 0.15, value_parser = args::distance)]
    pub from: f64,
    /// Farthest camera distance (world units).
    #[arg(long, default_value_t = 400.0, value_parser = args::distance)]
    pub to: f64,
    /// Frames along the dolly (2 to 10000).
    #[arg(long, default_value_t = 120, value_parser = clap::value_parser!(u32).range(2..=10000))]
    pub frames: u32,
    /// Image size, WxH.
    #[arg(long, default_value = "160x120", value_parser = args::parse_size)]
    pub size: (u32, u32),
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Measure popping over the dolly and print the table (or JSON).
pub fn run_command(args: DollyArgs, ctx: &Context) -> Result<()> {
    let opts = Options {
        view_deg: args.view_deg,
        range: (args.from, args.to),
        frames: args.frames,
        size: args.size,
    };
    let (adapter, rows) = run(&ctx.preset, &opts)?;
    if args.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&to_json(&rows, &opts, &adapter))?
        );
    } else {
        out!("{}", table(&rows, &opts, &adapter));
    }
    Ok(())
}

/// What `lodestone dolly` sweeps.
#[derive(Clone, Debug)]
pub struct Options {
    /// Camera angle from the normal (degrees).
    pub view_deg: f64,
    /// Closest and farthest distance.
    pub range: (f64, f64),
    /// Frames along the dolly (distances geometric between the ends).
    pub frames: u32,
    /// Image size.
    pub size: (u32, u32),
}

/// A jump (or excess) larger than this counts in [`Jumps::over`] and [`Excess::count`]: half an
/// 8-bit step at mid grey, in linear RGB.
pub const VISIBLE: f32 = 2e-3;

/// Per-pixel jumps between consecutive frames of one mode and march: the largest channel's
/// absolute change in linear RGB.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Jumps {
    /// Largest jump.
    pub max: f32,
    /// 99.9th percentile.
    pub p999: f32,
    /// Mean jump.
    pub mean: f32,
    /// Fraction of pixel-frames whose jump exceeds [`VISIBLE`].
    pub over: f64,
}

/// How much more the fast march makes pixels jump than the reference march.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Excess {
    /// Largest (jump under fast − jump under reference) over all pixels and frame pairs
    /// (negative: the fast march never jumps more).
    pub max: f32,
    /// Pixel-frames where the excess is over [`VISIBLE`].
    pub count: usize,
    /// Largest per-pixel difference between the two marches' images on any frame.
    pub max_image_difference: f32,
    /// Per frame: the pixels where the two marches' images differ by more than [`VISIBLE`].
    pub differing_pixels: Vec<usize>,
}

/// Where the two marches' images differ by more than [`VISIBLE`]: which one core's f64 pixel
/// ([`lodestone_core::eval::Evaluator::plane_pixel`], the definition of the view) agrees with.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Arbiter {
    /// Pixels where the fast march is the nearer to core.
    pub fast_nearer: usize,
    /// Pixels where the reference march is the nearer.
    pub reference_nearer: usize,
    /// Largest difference between the fast march's pixel and core's among them.
    pub fast_off: f32,
    /// The same for the reference march.
    pub reference_off: f32,
}

/// One mode's figure.
#[derive(Clone, Debug)]
pub struct Row {
    /// The mode.
    pub mode: &'static str,
    /// Jumps under the fast march.
    pub fast: Jumps,
    /// Jumps under the reference march.
    pub reference: Jumps,
    /// Fast against reference.
    pub excess: Excess,
    /// Who is right where they differ.
    pub arbiter: Arbiter,
}

/// The modes a dolly renders (the analytic views: the ones with a level of detail).
const MODES: [(&str, ViewMode, Method); 3] = [
    ("naive", ViewMode::Naive, Method::Naive),
    (
        "view_independent",
        ViewMode::ViewIndependent,
        Method::ViewIndependent,
    ),
    ("filtered", ViewMode::Filtered, Method::Filtered),
];

/// The distance of frame `i` of `n`, geometric from `range.0` to `range.1`.
pub fn distance(range: (f64, f64), i: u32, n: u32) -> f64 {
    let t = if n <= 1 {
        0.0
    } else {
        f64::from(i) / f64::from(n - 1)
    };
    (range.0.ln() + t * (range.1.ln() - range.0.ln())).exp()
}

/// Largest channel's absolute difference between pixel `i` of `a` and `b` (both divided by their
/// weights).
fn pixel_difference(a: &LinearImage, b: &LinearImage, i: usize) -> f32 {
    let (p, q) = (a.pixels[i], b.pixels[i]);
    let (wp, wq) = (
        if p[3] > 0.0 { p[3] } else { 1.0 },
        if q[3] > 0.0 { q[3] } else { 1.0 },
    );
    (0..3)
        .map(|c| (p[c] / wp - q[c] / wq).abs())
        .fold(0.0, f32::max)
}

/// Per pixel and consecutive pair of `frames`, the jump; row-major within a pair.
pub fn jumps(frames: &[LinearImage]) -> Vec<f32> {
    frames
        .windows(2)
        .flat_map(|w| (0..w[0].pixels.len()).map(move |i| pixel_difference(&w[0], &w[1], i)))
        .collect()
}

/// Statistics of a list of jumps.
pub fn summarise(j: &[f32]) -> Jumps {
    if j.is_empty() {
        return Jumps::default();
    }
    let mut sorted = j.to_vec();
    sorted.sort_by(f32::total_cmp);
    let at =
        |q: f64| sorted[((q * (sorted.len() - 1) as f64).round() as usize).min(sorted.len() - 1)];
    Jumps {
        max: sorted[sorted.len() - 1],
        p999: at(0.999),
        mean: (j.iter().map(|&x| f64::from(x)).sum::<f64>() / j.len() as f64) as f32,
        over: j.iter().filter(|&&x| x > VISIBLE).count() as f64 / j.len() as f64,
    }
}

/// Fast against reference: `fast` and `reference` are the jumps of the same pixel-frames.
pub fn excess(fast: &[f32], reference: &[f32], images: (&[LinearImage], &[LinearImage])) -> Excess {
    let d: Vec<f32> = fast.iter().zip(reference).map(|(f, r)| f - r).collect();
    let max_image_difference = images
        .0
        .iter()
        .zip(images.1)
        .flat_map(|(a, b)| (0..a.pixels.len()).map(move |i| pixel_difference(a, b, i)))
        .fold(0.0, f32::max);
    let differing_pixels = images
        .0
        .iter()
        .zip(images.1)
        .map(|(a, b)| {
            (0..a.pixels.len())
                .filter(|&i| pixel_difference(a, b, i) > VISIBLE)
                .count()
        })
        .collect();
    Excess {
        max: d.iter().copied().fold(f32::NEG_INFINITY, f32::max),
        count: d.iter().filter(|&&x| x > VISIBLE).count(),
        max_image_difference,
        differing_pixels,
    }
}

/// Render the dolly with both marches and measure it; also returns the adapter's description.
pub fn run(preset: &Resolved, opts: &Options) -> Result<(String, Vec<Row>)> {
    let r = renderer()?;
    let (w, h) = opts.size;
    let mut target = ViewTarget::new(&r, w, h)?;
    let fast = preset.prepare()?;
    let mut reference = fast.clone();
    reference.surface.march = March::Reference;
    let view = |distance| View::measurement(opts.view_deg, distance);
    let target_point = view(1.0).scene().camera.target;
    let gpu_fast = GpuMaterial::new(r.context(), &fast, target_point)?;
    let gpu_reference = GpuMaterial::new(r.context(), &reference, target_point)?;
    let mut rows = vec![];
    for (name, mode, method) in MODES {
        let mut frames = |g: &GpuMaterial| -> Result<Vec<LinearImage>> {
            (0..opts.frames)
                .map(|i| {
                    let scene = view(distance(opts.range, i, opts.frames)).scene();
                    target.reset();
                    r.draw(&mut target, g, &scene, mode, 1);
                    Ok(target.read(&r)?)
                })
                .collect()
        };
        let (images_fast, images_reference) = (frames(&gpu_fast)?, frames(&gpu_reference)?);
        let (jf, jr) = (jumps(&images_fast), jumps(&images_reference));
        let mut arbiter = Arbiter::default();
        for (i, (a, b)) in images_fast.iter().zip(&images_reference).enumerate() {
            let scene = view(distance(opts.range, i as u32, opts.frames)).scene();
            for k in 0..a.pixels.len() {
                if pixel_difference(a, b, k) <= VISIBLE {
                    continue;
                }
                let (x, y) = (k as u32 % w, k as u32 / w);
                let p = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                let core = fast.plane_pixel(method, &scene.camera, p, (w, h), scene.light);
                let off = |img: &LinearImage| {
                    let got = img.rgb(x, y);
                    (0..3)
                        .map(|c| (f64::from(got[c]) - core[c]).abs() as f32)
                        .fold(0.0, f32::max)
                };
                let (of, or) = (off(a), off(b));
                if of <= or {
                    arbiter.fast_nearer += 1;
                } else {
                    arbiter.reference_nearer += 1;
                }
                arbiter.fast_off = arbiter.fast_off.max(of);
                arbiter.reference_off = arbiter.reference_off.max(or);
            }
        }
        rows.push(Row {
            mode: name,
            fast: summarise(&jf),
            reference: summarise(&jr),
            excess: excess(&jf, &jr, (&images_fast, &images_reference)),
            arbiter,
        });
    }
    Ok((r.context().describe(), rows))
}

/// The rows as JSON.
pub fn to_json(rows: &[Row], opts: &Options, adapter: &str) -> serde_json::Value {
    let jumps = |j: &Jumps| serde_json::json!({"max": j.max, "p999": j.p999, "mean": j.mean, "fraction_over_visible": j.over});
    serde_json::json!({
        "adapter": adapter,
        "view_deg": opts.view_deg,
        "distance_range": [opts.range.0, opts.range.1],
        "frames": opts.frames,
        "size": [opts.size.0, opts.size.1],
        "visible": VISIBLE,
        "jump": "per pixel and consecutive frames, the largest channel's |change| in linear RGB",
        "rows": rows.iter().map(|r| serde_json::json!({
            "mode": r.mode,
            "fast": jumps(&r.fast),
            "reference": jumps(&r.reference),
            "excess_max": r.excess.max,
            "excess_over_visible": r.excess.count,
            "max_image_difference": r.excess.max_image_difference,
            "differing_pixels_per_frame": r.excess.differing_pixels,
            "where_they_differ": {
                "fast_nearer_core": r.arbiter.fast_nearer,
                "reference_nearer_core": r.arbiter.reference_nearer,
                "fast_max_off_core": r.arbiter.fast_off,
                "reference_max_off_core": r.arbiter.reference_off,
            },
        })).collect::<Vec<_>>(),
    })
}

/// The rows as a table.
pub fn table(rows: &[Row], opts: &Options, adapter: &str) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{adapter}, {}×{}, view {}°, {} frames from distance {} to {} (×{:.4} per frame); jump = the \
         largest channel's |change| between consecutive frames (linear RGB); excess = a pixel's jump \
         under the fast march minus its jump under the reference march; visible > {VISIBLE}; where \
         the marches' images differ visibly, how many pixels core's f64 pixel is nearer the fast / the \
         reference march",
        opts.size.0,
        opts.size.1,
        opts.view_deg,
        opts.frames,
        opts.range.0,
        opts.range.1,
        (opts.range.1 / opts.range.0).powf(1.0 / f64::from(opts.frames.max(2) - 1)),
    );
    let _ = writeln!(
        s,
        "{:<17} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>10} {:>8} {:>10} {:>13}",
        "mode",
        "fast max",
        "fast p999",
        "fast >vis",
        "ref max",
        "ref p999",
        "ref >vis",
        "excess max",
        "#excess",
        "max |f−r|",
        "core: f / r"
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{:<17} {:>9.5} {:>9.5} {:>9.5} {:>9.5} {:>9.5} {:>9.5} {:>10.5} {:>8} {:>10.5} {:>13}",
            r.mode,
            r.fast.max,
            r.fast.p999,
            r.fast.over,
            r.reference.max,
            r.reference.p999,
            r.reference.over,
            r.excess.max,
            r.excess.count,
            r.excess.max_image_difference,
            format!("{} / {}", r.arbiter.fast_nearer, r.arbiter.reference_nearer)
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(values: &[f32]) -> LinearImage {
        LinearImage {
            width: values.len() as u32,
            height: 1,
            pixels: values.iter().map(|&v| [v, v * 0.5, 0.0, 1.0]).collect(),
        }
    }

    /// Distances are geometric and hit both ends.
    #[test]
    fn distances_are_geometric() {
        let r = (0.15, 400.0);
        assert!((distance(r, 0, 9) - 0.15).abs() < 1e-12);
        assert!((distance(r, 8, 9) - 400.0).abs() < 1e-9);
        let q = distance(r, 1, 9) / distance(r, 0, 9);
        for i in 1..8 {
            assert!((distance(r, i + 1, 9) / distance(r, i, 9) - q).abs() < 1e-9);
        }
        assert_eq!(distance(r, 0, 1), 0.15);
    }

    /// Jumps, their statistics and the excess on hand-made frames: a pixel that pops in one march
    /// only is found, with its size.
    #[test]
    fn a_pop_in_one_march_is_found() {
        let smooth = [image(&[0.1, 0.2]), image(&[0.11, 0.2]), image(&[0.12, 0.2])];
        let popping = [image(&[0.1, 0.2]), image(&[0.11, 0.2]), image(&[0.12, 0.5])];
        let (js, jp) = (jumps(&smooth), jumps(&popping));
        assert_eq!(js.len(), 4);
        let s = summarise(&jp);
        assert!((s.max - 0.3).abs() < 1e-6, "{s:?}");
        assert!((s.over - 0.75).abs() < 1e-12, "{s:?}");
        let e = excess(&jp, &js, (&popping, &smooth));
        assert!((e.max - 0.3).abs() < 1e-6, "{e:?}");
        assert_eq!(e.count, 1);
        assert!((e.max_image_difference - 0.3).abs() < 1e-6);
        let none = excess(&js, &js, (&smooth, &smooth));
        assert_eq!(
            (none.max, none.count, none.max_image_difference),
            (0.0, 0, 0.0)
        );
        assert_eq!(e.differing_pixels, vec![0, 0, 1]);
        assert_eq!(none.differing_pixels, vec![0, 0, 0]);
    }
}
