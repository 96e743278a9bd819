//! Snapshot tests of the renderer through whatever adapter wgpu finds (llvmpipe on CI): every mode,
//! two presets, a near, a grazing and a far view, compared with a tolerance against small baselines
//! in `tests/snapshots/`. Regenerate with `UPDATE_SNAPSHOTS=1 cargo test -p lodestone-tests --test snapshots`.

use glam::DVec3;
use lodestone_core::eval::Evaluator;
use lodestone_core::material::Material;
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::shape::Shape;
use lodestone_render::{GpuMaterial, Renderer, Scene, ViewMode};
use std::path::PathBuf;

const SIZE: (u32, u32) = (64, 40);
const TRUTH_SAMPLES: u32 = 16;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Compare with a tolerance that a different adapter (or a real GPU) passes: mean absolute difference
/// ≤ 2/255 and at most 2% of pixels off by more than 12/255 in any channel.
fn compare(name: &str, got: &image::RgbaImage) -> Result<(), String> {
    let path = root().join("snapshots").join(format!("{name}.png"));
    let update = std::env::var("UPDATE_SNAPSHOTS").is_ok_and(|v| !v.is_empty() && v != "0");
    if update {
        got.save(&path)
            .map_err(|e| format!("{name}: cannot write baseline: {e}"))?;
        return Ok(());
    }
    let want = image::open(&path)
        .map_err(|e| {
            format!(
                "{name}: missing baseline {} ({e}); run with UPDATE_SNAPSHOTS=1",
                path.display()
            )
        })?
        .to_rgba8();
    if want.dimensions() != got.dimensions() {
        return Err(format!(
            "{name}: size {:?} vs baseline {:?}",
            got.dimensions(),
            want.dimensions()
        ));
    }
    let (mut sum, mut far) = (0.0f64, 0usize);
    for (a, b) in got.pixels().zip(want.pixels()) {
        let d = (0..3)
            .map(|k| (i32::from(a[k]) - i32::from(b[k])).unsigned_abs())
            .max()
            .unwrap_or(0);
        sum += f64::from(d);
        far += usize::from(d > 12);
    }
    let n = (got.width() * got.height()) as usize;
    let mean = sum / n as f64;
    if mean > 2.0 || far * 50 > n {
        let diff = root().join("snapshots").join(format!("{name}.new.png"));
        let _ = got.save(&diff);
        return Err(format!(
            "{name}: mean difference {mean:.2}/255, {far} of {n} pixels off by > 12/255 (new image: {})",
            diff.display()
        ));
    }
    Ok(())
}

#[test]
fn views_match_their_snapshots() {
    let Some(ctx) = lodestone_tests::gpu("the snapshot test") else {
        return;
    };
    let r = Renderer::new(ctx);
    let plane = Shape::Plane;
    let cylinder = Shape::Cylinder { radius: 1.2 };
    let views = [
        (
            "cylinder",
            cylinder,
            Camera {
                elevation_deg: 65.0,
                azimuth_deg: 80.0,
                distance: 5.0,
                target: [0.0, 0.0],
                fov_deg: 40.0,
            },
        ),
        (
            "near",
            plane,
            Camera {
                elevation_deg: 45.0,
                azimuth_deg: 15.0,
                distance: 2.0,
                target: [0.7, 0.2],
                fov_deg: 35.0,
            },
        ),
        (
            "grazing",
            plane,
            Camera {
                elevation_deg: 84.0,
                azimuth_deg: -30.0,
                distance: 4.0,
                target: [3.0, -1.0],
                fov_deg: 30.0,
            },
        ),
        (
            "far",
            plane,
            Camera {
                elevation_deg: 60.0,
                azimuth_deg: 120.0,
                distance: 150.0,
                target: [-40.0, 25.0],
                fov_deg: 30.0,
            },
        ),
    ];
    let light = direction(40f64.to_radians(), 2.0);
    let mut failures = vec![];
    for preset in ["default", "moss"] {
        let text = std::fs::read_to_string(root().join("../presets").join(format!("{preset}.ron")))
            .unwrap();
        let prepared = Evaluator::new(&Material::from_ron(&text).unwrap()).unwrap();
        for (view, shape, camera) in views {
            if shape != plane && preset != "default" {
                continue;
            }
            let scene = Scene {
                camera,
                light,
                shape,
            };
            let gm = GpuMaterial::new(r.context(), &prepared, camera.target)
                .expect("the material fits the adapter");
            for (mode_name, mode) in [
                ("naive", ViewMode::Naive),
                ("view_independent", ViewMode::ViewIndependent),
                ("filtered", ViewMode::Filtered),
                ("truth", ViewMode::Truth),
            ] {
                let img = r
                    .render(&gm, &scene, mode, SIZE, TRUTH_SAMPLES)
                    .expect("readback")
                    .to_srgb8();
                if let Err(e) = compare(&format!("{preset}-{view}-{mode_name}"), &img) {
                    failures.push(e);
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let _ = DVec3::Z;
}
