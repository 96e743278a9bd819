//! `lodestone bench`: the median frame time of every view over presets × views × distances,
//! against a flat reference and the reference march, in one run.

use crate::cli::Context;
use crate::cli::args;
use crate::cli::load;
use crate::cli::render::{View, frame_ms_interleaved, renderer};
use crate::preset_io::Resolved;
use anyhow::Result;
use lodestone_core::scene::march::March;
use lodestone_render::material_data::MarchTables;
use lodestone_render::{GpuMaterial, ViewMode, ViewTarget};
use std::path::Path;
use std::path::PathBuf;

/// The arguments of `lodestone bench`.
#[derive(Debug, Clone, clap::Args)]
pub struct BenchArgs {
    /// Image size, WxH.
    #[arg(long, default_value = "512x512", value_parser = args::parse_size)]
    pub size: (u32, u32),
    /// Camera angles from the normal to sweep, degrees (comma-separated, each 0 to 89.5).
    #[arg(long, default_value = "60", value_delimiter = ',', value_parser = args::view_angle)]
    pub view_deg: Vec<f64>,
    /// Camera distances to sweep, world units (comma-separated, each 0.02 to 5000).
    #[arg(long, default_value = "6", value_delimiter = ',', value_parser = args::distance)]
    pub distance: Vec<f64>,
    /// Presets to sweep (comma-separated RON files); the global --preset (or the built-in
    /// default) when omitted.
    #[arg(long, value_delimiter = ',')]
    pub presets: Vec<PathBuf>,
    /// Timed frames per mode (after one warm-up frame; 1 to 1000).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub frames: u32,
    /// Modes to time (comma-separated; the flat reference is always timed). Columns of modes
    /// left out print NaN.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = args::BenchMode::all())]
    pub modes: Vec<args::BenchMode>,
    /// Skip the reference march (its /ref columns print NaN): a quicker A/B of the fast march.
    #[arg(long)]
    pub no_reference: bool,
    /// Whether the analytic views' camera rays can stop on a crest's unresolved relief
    /// (`off` is the reference: rays meet h̄).
    #[arg(long, value_enum, default_value_t = args::InterceptionArg::Crests)]
    pub interception: args::InterceptionArg,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Leave the bound grid out of the GPU march (its skips of clear space), to time the march
    /// without it on the same build.
    #[arg(long, hide_short_help = true)]
    pub no_bound_grid: bool,
    /// Leave the bicubic field table out of the GPU march (it then sums the waves near the
    /// surface), to time the march without it on the same build.
    #[arg(long, hide_short_help = true)]
    pub no_field_table: bool,
}

/// Time the sweep over the listed presets (or the command's preset).
pub fn run(args: BenchArgs, ctx: &Context) -> Result<()> {
    let mut sweep = vec![];
    if args.presets.is_empty() {
        let name = ctx
            .path
            .as_ref()
            .map_or("default".to_owned(), |p| p.display().to_string());
        sweep.push((name, ctx.preset.clone()));
    } else {
        for p in &args.presets {
            sweep.push((p.display().to_string(), load(Some(p))?));
        }
    }
    let cfg = BenchSweep {
        view_deg: args.view_deg,
        distance: args.distance,
        size: args.size,
        frames: args.frames,
        modes: args.modes.iter().map(|m| m.name()).collect(),
        reference: !args.no_reference,
        interception: args.interception.interception(),
        tables: MarchTables {
            bound_grid: !args.no_bound_grid,
            field_table: !args.no_field_table,
        },
    };
    bench(&sweep, &cfg, args.json)
}

/// What `lodestone bench` sweeps.
#[derive(Clone, Debug)]
pub struct BenchSweep {
    /// Camera angles from the normal (degrees).
    pub view_deg: Vec<f64>,
    /// Camera distances (world units).
    pub distance: Vec<f64>,
    /// Image size.
    pub size: (u32, u32),
    /// Timed batches per mode.
    pub frames: u32,
    /// The modes to time (names of [`BENCH_MODES`]); the others print NaN.
    pub modes: Vec<&'static str>,
    /// Whether to time the reference march too (else its columns print NaN).
    pub reference: bool,
    /// Whether the analytic views' rays can stop on crests.
    pub interception: lodestone_core::eval::interception::Interception,
    /// Which march tables the GPU gets (both unless a timing leaves one out).
    pub tables: MarchTables,
}

/// The modes a bench row times, with their JSON names.
const BENCH_MODES: [(&str, ViewMode); 4] = [
    ("naive", ViewMode::Naive),
    ("view_independent", ViewMode::ViewIndependent),
    ("filtered", ViewMode::Filtered),
    ("truth", ViewMode::Truth),
];

/// One configuration's timings (ms per frame).
#[derive(Clone, Debug)]
pub struct BenchRow {
    /// The preset.
    pub preset: String,
    /// Camera angle from the normal (degrees).
    pub view_deg: f64,
    /// Camera distance.
    pub distance: f64,
    /// The same camera and colour with σ_h = 0 (no relief: a textured plane), naive mode.
    pub flat_ms: f64,
    /// Each mode's frame (truth: one ray per pixel), fast march.
    pub frame_ms: std::collections::BTreeMap<String, f64>,
    /// The same with the reference march.
    pub reference_ms: std::collections::BTreeMap<String, f64>,
}

impl BenchRow {
    fn ms(&self, mode: &str) -> f64 {
        self.frame_ms.get(mode).copied().unwrap_or(f64::NAN)
    }

    fn reference(&self, mode: &str) -> f64 {
        self.reference_ms.get(mode).copied().unwrap_or(f64::NAN)
    }
}

/// `lodestone bench`: every preset × view angle × distance, each mode's frame time with the fast
/// and the reference march, and the flat reference's, light 30° at azimuth 90°.
pub fn bench(presets: &[(String, Resolved)], cfg: &BenchSweep, json: bool) -> Result<()> {
    let r = renderer()?;
    let (w, h) = cfg.size;
    let mut target = ViewTarget::new(&r, w, h)?;
    let mut rows = vec![];
    for (name, preset) in presets {
        let mut prepared = preset.prepare()?;
        prepared.interception = cfg.interception;
        let mut reference = prepared.clone();
        reference.surface.march = March::Reference;
        let mut flat_material = preset.clone();
        flat_material.material.heights.sigma_h = 0.0;
        let flat = flat_material.prepare()?;
        for &distance in &cfg.distance {
            for &view_deg in &cfg.view_deg {
                let scene = View::measurement(view_deg, distance).scene();
                let gm = GpuMaterial::with_march_tables(
                    r.context(),
                    &prepared,
                    scene.camera.target,
                    cfg.tables,
                )?;
                let gref = GpuMaterial::with_march_tables(
                    r.context(),
                    &reference,
                    scene.camera.target,
                    cfg.tables,
                )?;
                let gflat = GpuMaterial::with_march_tables(
                    r.context(),
                    &flat,
                    scene.camera.target,
                    cfg.tables,
                )?;
                // Every case's batches interleaved: flat, then each mode with the fast and the
                // reference march.
                let chosen: Vec<_> = BENCH_MODES
                    .iter()
                    .filter(|(n, _)| cfg.modes.contains(n))
                    .collect();
                let marches: &[&GpuMaterial] = if cfg.reference { &[&gm, &gref] } else { &[&gm] };
                let mut cases = vec![(&gflat, ViewMode::Naive)];
                for g in marches {
                    cases.extend(chosen.iter().map(|(_, mode)| (*g, *mode)));
                }
                let ms = frame_ms_interleaved(&r, &mut target, &cases, &scene, cfg.frames);
                let flat_ms = ms[0];
                let named = |part: &[f64]| {
                    chosen
                        .iter()
                        .zip(part)
                        .map(|((n, _), t)| ((*n).to_owned(), *t))
                        .collect()
                };
                let frame_ms = named(&ms[1..=chosen.len()]);
                let reference_ms = named(ms.get(1 + chosen.len()..).unwrap_or_default());
                rows.push(BenchRow {
                    preset: name.clone(),
                    view_deg,
                    distance,
                    flat_ms,
                    frame_ms,
                    reference_ms,
                });
            }
        }
    }
    let adapter = r.context().describe();
    let pixels = f64::from(w) * f64::from(h);
    if json {
        let v = serde_json::json!({
            "adapter": adapter,
            "size": [w, h],
            "frames": cfg.frames,
            "timing": "synchronised wall time per frame: median over batches of 8 back-to-back frames, the cases of a row interleaved batch by batch",
            "flat": "the same camera and colour table with sigma_h = 0 (a textured plane), naive mode",
            "rows": rows.iter().map(|row| serde_json::json!({
                "preset": row.preset,
                "view_deg": row.view_deg,
                "distance": row.distance,
                "flat_ms": row.flat_ms,
                "frame_ms": row.frame_ms,
                "over_flat": BENCH_MODES.iter().map(|(n, _)| ((*n).to_owned(), serde_json::json!(row.ms(n) / row.flat_ms))).collect::<serde_json::Map<_, _>>(),
                "reference_march_ms": row.reference_ms,
                "over_reference_march": BENCH_MODES.iter().map(|(n, _)| ((*n).to_owned(), serde_json::json!(row.ms(n) / row.reference(n)))).collect::<serde_json::Map<_, _>>(),
                "filtered_over_naive": row.ms("filtered") / row.ms("naive"),
                "truth_ns_per_ray": row.ms("truth") * 1e6 / pixels,
            })).collect::<Vec<_>>(),
        });
        outln!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        outln!(
            "{adapter}, {w}×{h}, median over {} batches of 8 frames (synchronised wall time, all cases of a row interleaved batch by batch); \
             ×flat = frame time over the same view with σ_h = 0; /ref = fast march over the reference march",
            cfg.frames
        );
        outln!(
            "{:<28} {:>5} {:>6} {:>9} {:>9} {:>6} {:>9} {:>9} {:>6} {:>6} {:>9} {:>6} {:>6} {:>9} {:>6}",
            "preset",
            "view",
            "dist",
            "flat ms",
            "naive ms",
            "×flat",
            "v-ind ms",
            "filt ms",
            "×flat",
            "/ref",
            "truth ms",
            "×flat",
            "/ref",
            "ns/ray",
            "f/n"
        );
        for row in &rows {
            let (f, n, v, fi, t) = (
                row.flat_ms,
                row.ms("naive"),
                row.ms("view_independent"),
                row.ms("filtered"),
                row.ms("truth"),
            );
            outln!(
                "{:<28} {:>5.1} {:>6.2} {f:>9.2} {n:>9.2} {:>6.2} {v:>9.2} {fi:>9.2} {:>6.2} {:>6.2} {t:>9.2} {:>6.2} {:>6.2} {:>9.1} {:>6.2}",
                short_name(&row.preset),
                row.view_deg,
                row.distance,
                n / f,
                fi / f,
                fi / row.reference("filtered"),
                t / f,
                t / row.reference("truth"),
                t * 1e6 / pixels,
                fi / n
            );
        }
    }
    Ok(())
}

/// The file name of a preset path (the whole string when it has none), at most 28 characters.
fn short_name(p: &str) -> String {
    let name = Path::new(p)
        .file_name()
        .map_or_else(|| p.to_owned(), |n| n.to_string_lossy().into_owned());
    name.chars().take(28).collect()
}
