//! Fixtures shared by Lodestone's integration tests (`tests/tests/`, `render/tests/`): the preset
//! library with its driver images, and the GPU adapter that tests skip without.
//!
//! Never require a GPU: without any adapter (not even Mesa's llvmpipe) a GPU test has nothing to
//! run on, so [`gpu`] and [`renderer`] say so on stderr and return `None` ([`skip`]); CI installs
//! llvmpipe so they run there, and sets [`REQUIRE_GPU`] so that a missing adapter fails every GPU
//! test instead of passing it green, and [`GPU_LOG`] to count the GPU tests that ran.

use lodestone_core::driver::image::ImageDriver;
use lodestone_core::eval::Evaluator;
use lodestone_core::material::{Driver, Material};
use lodestone_render::{GpuContext, Renderer};
use std::path::PathBuf;
use std::sync::Arc;

/// Environment variable: when set (to anything but `0` or nothing), a GPU test without an adapter
/// fails instead of skipping. `.ci/run` sets it.
pub const REQUIRE_GPU: &str = "LODESTONE_REQUIRE_GPU";

/// Environment variable: a file to which every GPU test that found an adapter appends a line
/// (`.ci/run` counts them).
pub const GPU_LOG: &str = "LODESTONE_GPU_LOG";

/// Whether [`REQUIRE_GPU`] is set.
pub fn gpu_required() -> bool {
    std::env::var_os(REQUIRE_GPU).is_some_and(|v| !v.is_empty() && v != "0")
}

/// A GPU test that has no adapter: "skipping {test}: {why}" on stderr, or a panic when
/// [`REQUIRE_GPU`] is set.
pub fn skip(test: &str, why: impl std::fmt::Display) {
    assert!(
        !gpu_required(),
        "{test}: no GPU adapter ({why}), and {REQUIRE_GPU} says this run must have one"
    );
    eprintln!("skipping {test}: {why}");
}

/// A GPU test that found its adapter: "{test} on {adapter}" on stderr and a line in [`GPU_LOG`].
pub fn ran(test: &str, adapter: &str) {
    eprintln!("{test} on {adapter}");
    if let Some(path) = std::env::var_os(GPU_LOG) {
        use std::io::Write;
        if let Ok(mut f) = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
        {
            // One write: `writeln!` writes piece by piece, and tests running in parallel
            // interleaved their pieces (CI counted lines with no adapter).
            let _ = f.write_all(format!("{test}\t{adapter}\n").as_bytes());
        }
    }
}

/// The headless GPU context, or `None` ([`skip`]) when there is no adapter.
pub fn gpu(test: &str) -> Option<GpuContext> {
    match GpuContext::new_headless() {
        Ok(ctx) => {
            ran(test, &ctx.describe());
            Some(ctx)
        }
        Err(e) => {
            skip(test, e);
            None
        }
    }
}

/// A renderer on [`gpu`], or `None` without an adapter.
pub fn renderer(test: &str) -> Option<Renderer> {
    gpu(test).map(Renderer::new)
}

/// The preset library folder, `presets/`.
pub fn presets_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../presets")
}

/// A preset of the library by file name (`"default.ron"`), parsed.
pub fn preset(name: &str) -> Material {
    let path = presets_dir().join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Material::from_ron(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Every preset of the library: (path, RON text), sorted by path.
pub fn presets() -> Vec<(String, String)> {
    let mut out = vec![];
    for entry in std::fs::read_dir(presets_dir()).expect("presets/ exists") {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "ron") {
            out.push((
                path.display().to_string(),
                std::fs::read_to_string(&path).unwrap(),
            ));
        }
    }
    out.sort();
    out
}

/// An evaluator for the preset at `path`, decoding its driver image (relative to the preset) when
/// it has one.
pub fn prepare(path: &str, m: &Material) -> Evaluator {
    let image = match &m.driver {
        Driver::Image { path: img, .. } => {
            let file = std::path::Path::new(path).parent().unwrap().join(img);
            let luma = image::open(&file)
                .unwrap_or_else(|e| panic!("{path}: driver image {}: {e}", file.display()))
                .to_luma32f();
            let (w, h) = luma.dimensions();
            Some(Arc::new(
                ImageDriver::new(w as usize, h as usize, luma.as_raw()).unwrap(),
            ))
        }
        Driver::Noise(_) => None,
    };
    Evaluator::with_image(m, image, None).unwrap_or_else(|e| panic!("{path}: {e}"))
}
