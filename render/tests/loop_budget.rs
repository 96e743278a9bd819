//! No analytic pixel of any preset runs out of the software adapter's loop budget under the fast
//! march (bindings.wgsl `loop_cut`: an invocation gets 65535 loop iterations in all on Mesa's
//! llvmpipe, and once they are spent every later loop is left silently; `note_budget` flags it).
//! The views where the budget is tightest: grazing, close and at middle zoom, where the camera
//! ray is stopped on crests and the footprint is shaded twice, on the heaviest shading (the
//! transfer curves' binned mixture with its conditioned masking). With the per-knot and per-term
//! loops as they were before session 27 this fails: terraces runs out in 24 (78°, distance 3) and
//! 88 (80°, distance 10) of the 640 filtered pixels (checked). On adapters without a limiter
//! nothing is ever cut and the test passes trivially.

use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::march::March;
use lodestone_core::scene::shape::Shape;
use lodestone_render::{GpuMaterial, Scene, ViewMode, ViewTarget};

#[test]
fn no_analytic_pixel_runs_out_of_the_loop_budget() {
    let Some(r) = lodestone_tests::renderer("the loop-budget test") else {
        return;
    };
    let (w, h) = (32u32, 20u32);
    let mut cut = vec![];
    for (path, text) in lodestone_tests::presets() {
        let m = lodestone_core::material::Material::from_ron(&text).expect("a preset parses");
        let p = lodestone_tests::prepare(&path, &m);
        assert_eq!(p.surface.march, March::Fast, "the default march");
        for (elevation_deg, distance, fov_deg) in [(78.0, 3.0, 35.0), (80.0, 10.0, 10.0)] {
            let camera = Camera {
                elevation_deg,
                azimuth_deg: 20.0,
                distance,
                target: [0.3, -0.2],
                fov_deg,
            };
            let scene = Scene {
                camera,
                light: direction(0.9, 2.0),
                shape: Shape::Plane,
            };
            let gm = GpuMaterial::new(r.context(), &p, camera.target).expect("fits");
            for mode in [
                ViewMode::Naive,
                ViewMode::ViewIndependent,
                ViewMode::Filtered,
            ] {
                let mut target = ViewTarget::new(&r, w, h).expect("target");
                r.draw(&mut target, &gm, &scene, mode, 1);
                let n = target.cut_count(&r).expect("readback");
                if n > 0 {
                    cut.push(format!("{path} {elevation_deg}°/{distance} {mode:?}: {n}"));
                }
            }
        }
    }
    assert!(cut.is_empty(), "pixels out of the loop budget: {cut:#?}");
}
