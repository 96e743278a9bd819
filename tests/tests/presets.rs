//! Every preset in presets/ loads, validates, round-trips (load → save → load gives an equal value),
//! evaluates finite on the CPU and renders under every mode on the GPU adapter.

use lodestone_core::eval::FootprintQuery;
use lodestone_core::material::Material;
use lodestone_core::scene::direction::direction;

use lodestone_tests::{prepare, presets};

#[test]
fn every_preset_loads_validates_and_round_trips() {
    let all = presets();
    assert!(
        all.len() >= 4,
        "expected the preset library, found {}",
        all.len()
    );
    for (path, text) in all {
        let m = Material::from_ron(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
        let again =
            Material::from_ron(&m.to_ron()).unwrap_or_else(|e| panic!("{path} after saving: {e}"));
        assert_eq!(m, again, "{path} does not round-trip");
    }
}

#[test]
fn every_preset_evaluates_finite() {
    for (path, text) in presets() {
        let m = Material::from_ron(&text).unwrap();
        let p = prepare(&path, &m);
        for deg in [0.0_f64, 60.0, 89.0] {
            let cfg =
                FootprintQuery::far(&p, direction(deg.to_radians(), 0.2), direction(0.6, 2.0));
            for v in [
                p.naive(&cfg),
                p.view_independent(&cfg),
                p.filtered(&cfg),
                p.ground_truth(&cfg, 200, 1).mean,
            ] {
                assert!(
                    v.iter().all(|c| c.is_finite() && *c >= 0.0),
                    "{path} at {deg}°: {v:?}"
                );
            }
        }
    }
}

#[test]
fn default_preset_is_the_core_default() {
    let text = include_str!("../../presets/default.ron");
    assert_eq!(Material::from_ron(text).unwrap(), Material::default());
}

/// Every preset renders on the GPU adapter (software or real) under every mode: finite, non-negative,
/// and not black (each preset is lit from 40° and seen from 60°).
#[test]
fn every_preset_renders() {
    use lodestone_core::scene::camera::Camera;
    use lodestone_core::scene::shape::Shape;
    use lodestone_render::{GpuMaterial, Scene, ViewMode};
    let Some(r) = lodestone_tests::renderer("the render test") else {
        return;
    };
    let scene = Scene {
        camera: Camera {
            elevation_deg: 60.0,
            distance: 4.0,
            ..Camera::default()
        },
        light: direction(40f64.to_radians(), 2.0),
        shape: Shape::Plane,
    };
    for (path, text) in presets() {
        let m = Material::from_ron(&text).unwrap();
        let p = prepare(&path, &m);
        let gm = GpuMaterial::new(r.context(), &p, scene.camera.target)
            .expect("the material fits the adapter");
        for mode in [
            ViewMode::Naive,
            ViewMode::ViewIndependent,
            ViewMode::Filtered,
            ViewMode::Truth,
        ] {
            let img = r.render(&gm, &scene, mode, (24, 16), 2).expect("readback");
            let mut sum = 0.0f64;
            for y in 0..16 {
                for x in 0..24 {
                    let c = img.rgb(x, y);
                    assert!(
                        c.iter().all(|v| v.is_finite() && *v >= 0.0),
                        "{path} {mode:?}: {c:?}"
                    );
                    sum += f64::from(c[0] + c[1] + c[2]);
                }
            }
            assert!(sum > 0.0, "{path} {mode:?} is black");
        }
    }
}
