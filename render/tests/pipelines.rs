//! The pipeline cache: one pipeline per feature set, compiled on first use or ahead of use on a
//! background thread, never twice.

use lodestone_core::material::features::{Feature, FeatureSet};
use std::time::{Duration, Instant};

#[test]
fn prewarmed_pipelines_are_ready_without_compiling_at_draw_time() {
    let Some(r) = lodestone_tests::renderer("the pipeline test") else {
        return;
    };
    let flat: FeatureSet = [Feature::NoiseDriver, Feature::DriverColor]
        .into_iter()
        .collect();
    let bumpy = flat.with(Feature::Relief, true);
    assert!(!r.is_ready(flat) && !r.is_ready(bumpy));
    // Compiled on first use, then cached.
    r.prepare(flat);
    assert!(r.is_ready(flat));
    assert_eq!(r.prepare(flat), Duration::ZERO);
    // Ahead of use, on another thread; a set already cached is skipped.
    r.prewarm(vec![flat, bumpy]);
    let t0 = Instant::now();
    while !r.is_ready(bumpy) {
        assert!(t0.elapsed() < Duration::from_secs(120), "never compiled");
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(r.prepare(bumpy), Duration::ZERO);
    // Dropping the renderer joins the compile thread (nothing left running at exit).
    drop(r);
}
