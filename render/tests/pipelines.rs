//! The pipeline cache: one pipeline per feature set, compiled on first use or ahead of use (on a
//! background thread, or queued for the rendering thread on OpenGL), never twice.

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
    // Ahead of use; a set already cached is skipped.
    r.prewarm(vec![flat, bumpy]);
    if r.single_threaded() {
        // OpenGL: nothing compiles beside the thread that renders; the set waits for it.
        assert_eq!(r.compiling_threads(), 0);
        assert_eq!(r.deferred_count(), 1);
        assert!(!r.is_ready(bumpy));
        assert!(r.compile_deferred());
        assert!(r.is_ready(bumpy));
        assert!(!r.compile_deferred());
    } else {
        // On another thread.
        let t0 = Instant::now();
        while !r.is_ready(bumpy) {
            assert!(t0.elapsed() < Duration::from_secs(120), "never compiled");
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    assert_eq!(r.prepare(bumpy), Duration::ZERO);
    // Dropping the renderer joins the compile thread (nothing left running at exit).
    drop(r);
}
