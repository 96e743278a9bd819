//! The GPU's camera rays stop on crests as core's do (#17, `core/src/eval/interception.rs`): at
//! middle zoom and 80° the filtered and view-independent pixels with the interception equal
//! core's, and they are not the pixels without it (so a GPU that ignored it would fail).

use glam::DVec2;
use lodestone_core::eval::interception::Interception;
use lodestone_core::eval::{Evaluator, Method};
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::shape::Shape;
use lodestone_render::{GpuMaterial, Scene, ViewMode};
use lodestone_tests::preset;

/// Relative and absolute tolerance of a pixel, as `views.rs` (f32 against f64).
fn close(got: f32, want: f64) -> bool {
    (f64::from(got) - want).abs() <= 5e-3 * want.abs() + 2e-4
}

#[test]
fn crest_interception_on_the_gpu_matches_core() {
    let Some(r) = lodestone_tests::renderer("the GPU interception test") else {
        return;
    };
    let camera = Camera {
        elevation_deg: 80.0,
        azimuth_deg: 15.0,
        distance: 10.0,
        target: [3.0, -7.0],
        fov_deg: 10.0,
    };
    let scene = Scene {
        camera,
        light: direction(0.5, 0.4),
        shape: Shape::Plane,
    };
    let (w, h) = (32u32, 24u32);
    let on = Evaluator::new(&preset("default.ron")).unwrap();
    assert_eq!(on.interception, Interception::Crests, "the views' default");
    let mut off = on.clone();
    off.interception = Interception::Off;
    for (mode, method) in [
        (ViewMode::Filtered, Method::Filtered),
        (ViewMode::ViewIndependent, Method::ViewIndependent),
    ] {
        let (mut mismatched, mut moved) = (vec![], 0);
        for p in [&on, &off] {
            let gm = GpuMaterial::new(r.context(), p, camera.target).expect("fits");
            let img = r.render(&gm, &scene, mode, (w, h), 1).expect("readback");
            for y in 0..h {
                for x in 0..w {
                    let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                    let want = p.plane_pixel(method, &camera, c, (w, h), scene.light);
                    let got = img.rgb(x, y);
                    if !(0..3).all(|k| close(got[k], want[k])) {
                        mismatched.push((p.interception, x, y, got, want));
                    }
                    if p.interception == Interception::Crests {
                        let without = off.plane_pixel(method, &camera, c, (w, h), scene.light);
                        if !(0..3).all(|k| close(got[k], without[k])) {
                            moved += 1;
                        }
                    }
                }
            }
        }
        // As in views.rs: 1% of the pixels may sit on a silhouette or shadow edge that f32 and
        // f64 rays see on different sides.
        let allowed = 2 * (w * h) as usize / 100;
        assert!(
            mismatched.len() <= allowed,
            "{mode:?}: {} of {} pixels differ from core, e.g. {:?}",
            mismatched.len(),
            2 * w * h,
            &mismatched[..mismatched.len().min(3)]
        );
        assert!(
            moved * 20 >= (w * h) as usize,
            "{mode:?}: only {moved} of {} pixels move with the interception",
            w * h
        );
    }
}
