//! `lodestone inspect`: what a preset needs in a scene, and what building only that saves.
//!
//! The feature set (and why each absent feature is unused), the view shader specialised to it
//! against the all-features shader (naga statements, expressions and functions reachable from the
//! entry point), the GPU data by part against what the all-features pipeline needs, and with
//! `--time` the pipeline compile times and frame times of both on the adapter.

use crate::cli::Context;
use crate::cli::args;
use crate::cli::render::{View, frame_ms_interleaved, renderer};
use crate::preset_io::Resolved;
use anyhow::Result;
use lodestone_core::material::features::FeatureSet;
use lodestone_render::material_data::material_data_for;
use lodestone_render::specialize::{ShaderSize, view_source_for};
use lodestone_render::{GpuMaterial, ViewMode, ViewTarget};
use serde_json::{Value, json};
use std::time::{Duration, Instant};

/// The arguments of `lodestone inspect`.
#[derive(Debug, Clone, clap::Args)]
pub struct InspectArgs {
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Light angle from the normal, degrees (0 puts it at the normal: no shadow rays; 0 to 180).
    #[arg(long, default_value_t = 30.0, value_parser = args::light_angle)]
    pub light_deg: f64,
    /// Light azimuth, degrees.
    #[arg(long, default_value_t = 90.0, value_parser = args::azimuth)]
    pub light_azimuth_deg: f64,
    /// The object: the plane, or a cylinder of radius 2.
    #[arg(long, value_enum, default_value_t = args::ShapeArg::Plane)]
    pub shape: args::ShapeArg,
    /// Also compile and time both pipelines on the GPU adapter (view 60°, distance 6). On a software
    /// adapter (llvmpipe) the all-features pipeline takes many minutes to compile.
    #[arg(long)]
    pub time: bool,
    /// Image size for --time, WxH.
    #[arg(long, default_value = "256x192", value_parser = args::parse_size)]
    pub size: (u32, u32),
    /// Timed batches of 8 frames per mode for --time (1 to 1000).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub frames: u32,
}

/// Inspect the preset and print what it needs (or JSON).
pub fn run(args: InspectArgs, ctx: &Context) -> Result<()> {
    let view = View {
        view_deg: 60.0,
        view_azimuth_deg: 0.0,
        light_deg: args.light_deg,
        light_azimuth_deg: args.light_azimuth_deg,
        distance: 6.0,
        shape: args.shape.shape(2.0).map_err(anyhow::Error::msg)?,
        march: lodestone_core::scene::march::March::default(),
        error_block: 8,
        retry_cut_rays: false,
    };
    let opts = Options {
        view,
        time: args.time,
        size: args.size,
        frames: args.frames,
    };
    let i = inspect(&ctx.preset, opts)?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&i.to_json())?);
    } else {
        out!("{}", i.to_text());
    }
    Ok(())
}

/// Options of `lodestone inspect`.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// The scene (camera, light, object).
    pub view: View,
    /// Time both pipelines on the adapter.
    pub time: bool,
    /// Image size for the timings.
    pub size: (u32, u32),
    /// Timed batches per mode.
    pub frames: u32,
}

/// Timings of the specialised and the all-features pipeline.
#[derive(Clone, Debug)]
struct Timings {
    adapter: String,
    compile: (Duration, Duration),
    frames: Vec<(&'static str, f64, f64)>,
}

/// The inspection of one preset in one scene.
#[derive(Clone, Debug)]
pub struct Inspection {
    name: String,
    features: FeatureSet,
    absent: Vec<(&'static str, &'static str)>,
    shader: ShaderSize,
    shader_all: ShaderSize,
    data: Vec<(&'static str, usize)>,
    data_all: Vec<(&'static str, usize)>,
    timings: Option<Timings>,
    opts: Options,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// Inspect `preset` (timings need a GPU adapter; the rest does not).
pub fn inspect(preset: &Resolved, opts: Options) -> Result<Inspection> {
    let prepared = preset.prepare()?;
    let m = &prepared.material;
    let scene = opts.view.scene();
    let features = FeatureSet::derive(m, scene.shape, scene.light).normalized();
    let measure = |set: FeatureSet| -> Result<ShaderSize> {
        let src = view_source_for(set)?;
        ShaderSize::measure(&src, "view_main").map_err(anyhow::Error::msg)
    };
    let target = scene.camera.target;
    let timings = if opts.time {
        let r = renderer()?;
        let special = GpuMaterial::new(r.context(), &prepared, target)?;
        let all = GpuMaterial::all_features(r.context(), &prepared, target)?;
        let mut t = ViewTarget::new(&r, opts.size.0, opts.size.1)?;
        // Pipeline creation and the first frame: drivers may compile lazily (Mesa JIT-compiles
        // at the first dispatch), so creation alone would not show the cost. The specialised
        // pipeline goes first and so also carries any one-time warm-up of the device.
        let mut first = |gm: &GpuMaterial| {
            let t0 = Instant::now();
            r.prepare(gm.pipeline_features(&scene));
            r.draw(&mut t, gm, &scene, ViewMode::Naive, 1);
            r.wait();
            t0.elapsed()
        };
        let compile = (first(&special), first(&all));
        let mut frames = Vec::new();
        for (name, mode) in [
            ("naive", ViewMode::Naive),
            ("view-independent", ViewMode::ViewIndependent),
            ("filtered", ViewMode::Filtered),
            ("truth (1 ray/pixel)", ViewMode::Truth),
        ] {
            let ms = frame_ms_interleaved(
                &r,
                &mut t,
                &[(&special, mode), (&all, mode)],
                &scene,
                opts.frames,
            );
            t.reset();
            frames.push((name, ms[0], ms[1]));
        }
        Some(Timings {
            adapter: r.context().describe(),
            compile,
            frames,
        })
    } else {
        None
    };
    Ok(Inspection {
        name: m.name.clone(),
        features,
        absent: features
            .absent(m)
            .into_iter()
            .map(|(f, why)| (f.name(), why))
            .collect(),
        shader: measure(features)?,
        shader_all: measure(FeatureSet::all())?,
        data: material_data_for(&prepared, target, features).segments,
        data_all: material_data_for(&prepared, target, FeatureSet::all()).segments,
        timings,
        opts,
    })
}

fn total(parts: &[(&'static str, usize)]) -> usize {
    parts.iter().map(|(_, b)| b).sum()
}

fn size_json(s: &ShaderSize) -> Value {
    json!({
        "functions": s.functions,
        "statements": s.statements,
        "expressions": s.expressions,
        "source_bytes": s.source_bytes,
    })
}

impl Inspection {
    /// The feature set.
    #[cfg(test)]
    pub fn features(&self) -> FeatureSet {
        self.features
    }

    /// As JSON.
    pub fn to_json(&self) -> Value {
        let parts = |p: &[(&str, usize)]| -> Value {
            p.iter()
                .map(|(n, b)| json!({"part": n, "bytes": b}))
                .collect()
        };
        let v = &self.opts.view;
        json!({
            "preset": self.name,
            "scene": {
                "shape": format!("{:?}", v.shape),
                "light_deg": v.light_deg,
                "light_azimuth_deg": v.light_azimuth_deg,
            },
            "features": self.features.iter().map(|f| f.name()).collect::<Vec<_>>(),
            "left_out": self.absent.iter().map(|(f, why)| json!({"feature": f, "why": why})).collect::<Vec<_>>(),
            "shader": {
                "specialised": size_json(&self.shader),
                "all_features": size_json(&self.shader_all),
                "counted": "naga IR of the functions reachable from view_main (statements include nested blocks; Emit excluded)",
            },
            "data": {
                "specialised": parts(&self.data),
                "specialised_bytes": total(&self.data),
                "all_features": parts(&self.data_all),
                "all_features_bytes": total(&self.data_all),
            },
            "timings": self.timings.as_ref().map(|t| json!({
                "adapter": t.adapter,
                "size": [self.opts.size.0, self.opts.size.1],
                "timing": "synchronised wall time per frame: median over batches of 8 back-to-back frames",
                "first_frame_ms": {"specialised": ms(t.compile.0), "all_features": ms(t.compile.1), "note": "pipeline creation and the first naive frame (drivers compile lazily)"},
                "frame_ms": t.frames.iter().map(|(n, a, b)| json!({"mode": n, "specialised": a, "all_features": b})).collect::<Vec<_>>(),
            })),
        })
    }

    /// As a human-readable report.
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let v = &self.opts.view;
        let _ = writeln!(
            s,
            "{}: {:?}, light {}° from the normal at azimuth {}°",
            self.name, v.shape, v.light_deg, v.light_azimuth_deg
        );
        let _ = writeln!(s, "features: {}", self.features);
        for (f, why) in &self.absent {
            let _ = writeln!(s, "  left out {f:<16} {why}");
        }
        let (a, b) = (&self.shader, &self.shader_all);
        let pct = |x: usize, y: usize| 100.0 * x as f64 / y.max(1) as f64;
        let _ = writeln!(
            s,
            "shader (naga, reachable from view_main): {} statements, {} expressions, {} functions \
             against {} / {} / {} for all features ({:.0}% of the statements)",
            a.statements,
            a.expressions,
            a.functions,
            b.statements,
            b.expressions,
            b.functions,
            pct(a.statements, b.statements)
        );
        let _ = writeln!(
            s,
            "GPU data: {} bytes against {} for all features",
            total(&self.data),
            total(&self.data_all)
        );
        for (name, bytes) in &self.data_all {
            let kept = self.data.iter().any(|(n, _)| n == name);
            let _ = writeln!(
                s,
                "  {name:<28} {bytes:>9} bytes{}",
                if kept { "" } else { "  (left out)" }
            );
        }
        if let Some(t) = &self.timings {
            let _ = writeln!(
                s,
                "{}, {}x{} (synchronised wall time, median of batches of 8 frames)",
                t.adapter, self.opts.size.0, self.opts.size.1
            );
            let _ = writeln!(
                s,
                "  pipeline creation + first frame (drivers compile lazily): {:.0} ms specialised, {:.0} ms all features",
                ms(t.compile.0),
                ms(t.compile.1)
            );
            for (n, a, b) in &t.frames {
                let _ = writeln!(
                    s,
                    "  {n:<20} {a:8.2} ms specialised, {b:8.2} ms all features ({:.2}x)",
                    b / a.max(1e-9)
                );
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lodestone_core::material::Material;
    use lodestone_core::material::features::Feature;
    use lodestone_core::scene::shape::Shape;

    fn view(light_deg: f64) -> View {
        View {
            view_deg: 60.0,
            view_azimuth_deg: 0.0,
            light_deg,
            light_azimuth_deg: 90.0,
            distance: 6.0,
            shape: Shape::Plane,
            march: Default::default(),
            error_block: 8,
            retry_cut_rays: false,
        }
    }

    #[test]
    fn the_default_preset_without_timings() {
        let preset = Resolved::without_image(Material::default());
        let opts = Options {
            view: view(30.0),
            time: false,
            size: (8, 8),
            frames: 1,
        };
        let i = inspect(&preset, opts).expect("inspect");
        assert!(i.features().contains(Feature::Shadows));
        assert!(i.shader.statements < i.shader_all.statements);
        // The default material uses relief, so its data equals the all-features data.
        assert_eq!(total(&i.data), total(&i.data_all));
        let j = i.to_json();
        assert_eq!(j["data"]["specialised_bytes"], total(&i.data));
        assert!(j["timings"].is_null());
        assert!(i.to_text().contains("left out curved"));
        // The light at the normal drops the shadow rays and shrinks the shader further.
        let z = inspect(
            &preset,
            Options {
                view: view(0.0),
                ..opts
            },
        )
        .expect("inspect");
        assert!(!z.features().contains(Feature::Shadows));
        assert!(z.shader.statements < i.shader.statements);
    }
}
