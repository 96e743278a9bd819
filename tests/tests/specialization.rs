//! Build only what a scene needs: for presets in a plane scene under an oblique light, a plane
//! scene lit from the normal (no shadows) and on the cylinder, every view rendered by the
//! pipeline specialised to the material and scene equals the one rendered by the all-features
//! pipeline (with every table uploaded), within a tolerance that allows the flat-surface shortcut
//! (an exact plane hit where the all-features shader marches to a bisection tolerance): an ignored
//! test (measured on llvmpipe: 98 of 108 images identical, the worst 8.5e-5 of the peak on
//! average). CI runs a cover of the library that keeps and strips every feature ([`covering`])
//! against core's pixels instead.

use lodestone_core::eval::Method;
use lodestone_core::material::Material;
use lodestone_core::material::features::{Feature, FeatureSet};
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::shape::Shape;
use lodestone_render::material_data::material_data_for;
use lodestone_render::specialize::{ShaderSize, view_source_for};
use lodestone_render::{GpuMaterial, LinearImage, Scene, ViewMode};
use lodestone_tests::{prepare, presets};

const SIZE: (u32, u32) = (40, 26);

/// (mean absolute difference, fraction of pixels off by more than 2% of the brightest channel).
fn difference(a: &LinearImage, b: &LinearImage) -> (f64, f64) {
    let peak = b
        .pixels
        .iter()
        .flat_map(|p| p[..3].iter().copied())
        .fold(1e-6f32, f32::max);
    let (mut sum, mut far) = (0.0f64, 0usize);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let d = (0..3)
            .map(|k| (p[k] / p[3].max(1.0) - q[k] / q[3].max(1.0)).abs())
            .fold(0.0f32, f32::max);
        sum += f64::from(d / peak);
        far += usize::from(d > 0.02 * peak);
    }
    let n = a.pixels.len() as f64;
    (sum / n, far as f64 / n)
}

/// One preset in one scene, with the features its specialised pipeline has.
struct Case {
    path: String,
    material: Material,
    scene_name: &'static str,
    scene: Scene,
    set: FeatureSet,
}

/// Every preset in a plane scene under an oblique light, lit from the normal, and on the cylinder.
fn cases() -> Vec<Case> {
    let camera = Camera {
        elevation_deg: 62.0,
        azimuth_deg: 25.0,
        distance: 3.0,
        target: [0.4, -0.3],
        fov_deg: 35.0,
    };
    let oblique = direction(45f64.to_radians(), 2.0);
    let scenes = [
        ("oblique light", Shape::Plane, oblique),
        ("light at the normal", Shape::Plane, glam::DVec3::Z),
        ("cylinder", Shape::Cylinder { radius: 1.2 }, oblique),
    ];
    let mut out = Vec::new();
    for (path, text) in presets() {
        let material = Material::from_ron(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
        for (scene_name, shape, light) in scenes {
            let set = FeatureSet::derive(&material, shape, light).normalized();
            out.push(Case {
                path: path.clone(),
                material: material.clone(),
                scene_name,
                scene: Scene {
                    camera,
                    light,
                    shape,
                },
                set,
            });
        }
    }
    out
}

/// Indices of a few cases that together have every feature the library uses both present and
/// absent (greedy set cover of the (feature, present) pairs): each `//#if` block is then both
/// kept and stripped at least once. Compiling a pipeline on llvmpipe is what costs (tens of
/// seconds per feature set with a cold shader cache), so CI checks this cover and
/// [`every_preset_and_scene_specialises_correctly`] the whole library.
fn covering(cases: &[Case]) -> Vec<usize> {
    let pairs = |s: FeatureSet| Feature::ALL.map(|f| (f, s.contains(f)));
    let mut uncovered: std::collections::BTreeSet<(u16, bool)> = cases
        .iter()
        .flat_map(|c| pairs(c.set))
        .map(|(f, on)| (f as u16, on))
        .collect();
    let mut picked = Vec::new();
    while !uncovered.is_empty() {
        let gain = |c: &Case| {
            pairs(c.set)
                .iter()
                .filter(|(f, on)| uncovered.contains(&(*f as u16, *on)))
                .count()
        };
        let best = (0..cases.len())
            .max_by_key(|&i| (gain(&cases[i]), std::cmp::Reverse(i)))
            .expect("cases");
        for (f, on) in pairs(cases[best].set) {
            uncovered.remove(&(f as u16, on));
        }
        picked.push(best);
    }
    picked
}

/// Render `cases` with their specialised pipeline and the all-features one; the failures.
fn check(r: &lodestone_render::Renderer, cases: &[&Case]) -> Vec<String> {
    let mut failures = Vec::new();
    let (mut worst, mut exact, mut total) = ((0.0f64, 0.0f64), 0, 0);
    let mut materials: Vec<(String, GpuMaterial, GpuMaterial)> = Vec::new();
    for case in cases {
        if !materials.iter().any(|(p, _, _)| *p == case.path) {
            let prepared = prepare(&case.path, &case.material);
            let target = case.scene.camera.target;
            let special = GpuMaterial::new(r.context(), &prepared, target)
                .expect("the material fits the adapter");
            let all = GpuMaterial::all_features(r.context(), &prepared, target)
                .expect("the material fits the adapter");
            materials.push((case.path.clone(), special, all));
        }
        let (_, special, all) = materials
            .iter()
            .find(|(p, _, _)| *p == case.path)
            .expect("prepared above");
        let scene = case.scene;
        let set = special.pipeline_features(&scene);
        assert_eq!(all.pipeline_features(&scene), FeatureSet::all());
        assert_eq!(set, case.set);
        let took = r.prepare(set);
        eprintln!(
            "{} / {}: [{set}] compiled in {took:.1?}",
            case.path, case.scene_name
        );
        for mode in [
            ViewMode::Naive,
            ViewMode::ViewIndependent,
            ViewMode::Filtered,
            ViewMode::Truth,
        ] {
            let a = r.render(special, &scene, mode, SIZE, 4).expect("readback");
            let b = r.render(all, &scene, mode, SIZE, 4).expect("readback");
            assert!(
                a.pixels.iter().flatten().all(|v| v.is_finite()),
                "{} {} {mode:?}: non-finite",
                case.path,
                case.scene_name
            );
            let (mean, far) = difference(&a, &b);
            worst = (worst.0.max(mean), worst.1.max(far));
            exact += usize::from(mean == 0.0);
            total += 1;
            if mean > 5e-4 || far > 0.005 {
                failures.push(format!(
                    "{}, {}, {mode:?} [{set}]: mean difference {mean:.2e} of the peak, {:.1}% pixels off by > 2%",
                    case.path,
                    case.scene_name,
                    far * 100.0
                ));
            }
        }
    }
    eprintln!(
        "{exact} of {total} images identical; worst mean difference {:.2e} of the peak, worst {:.2}% pixels off by > 2%",
        worst.0,
        worst.1 * 100.0
    );
    failures
}

/// CI's check of what a specialised pipeline strips: a cover of the library's plane scenes that
/// keeps and strips every feature it uses ([`covering`]), the analytic views rendered by the
/// specialised pipeline equal core's pixels (the definition; the tolerance of the GPU view tests),
/// and the ground truth is finite. The comparison with the all-features pipeline is the ignored
/// [`every_preset_and_scene_specialises_correctly`]: llvmpipe compiles a compute shader as an LLVM
/// coroutine, whose frame construction is superlinear in the function's size, and the
/// all-features shader (every driver, curve, mixture and lobe in one function) took over 15
/// minutes to compile here. The cylinder's specialised pipeline is checked against core in
/// `render/tests/views.rs`.
#[test]
fn specialised_pipelines_render_what_core_renders() {
    let Some(r) = lodestone_tests::renderer("the specialisation test") else {
        return;
    };
    let all: Vec<Case> = cases()
        .into_iter()
        .filter(|c| c.scene.shape == Shape::Plane)
        .collect();
    let picked = covering(&all);
    let chosen: Vec<&Case> = picked.iter().map(|&i| &all[i]).collect();
    // The cover keeps and strips every feature the library's plane scenes use.
    for f in Feature::ALL {
        let used = all.iter().any(|c| c.set.contains(f));
        let unused = all.iter().any(|c| !c.set.contains(f));
        assert_eq!(used, chosen.iter().any(|c| c.set.contains(f)), "{f:?}");
        assert_eq!(unused, chosen.iter().any(|c| !c.set.contains(f)), "{f:?}");
    }
    let sets: std::collections::BTreeSet<String> =
        chosen.iter().map(|c| c.set.to_string()).collect();
    eprintln!("feature sets exercised: {sets:?}");
    assert!(sets.len() >= 3, "too few distinct feature sets: {sets:?}");
    let mut failures = Vec::new();
    for case in &chosen {
        let prepared = prepare(&case.path, &case.material);
        let special = GpuMaterial::new(r.context(), &prepared, case.scene.camera.target)
            .expect("the material fits the adapter");
        assert_eq!(special.pipeline_features(&case.scene), case.set);
        let took = r.prepare(case.set);
        eprintln!(
            "{} / {}: [{}] pipeline created in {took:.1?}",
            case.path, case.scene_name, case.set
        );
        let (w, h) = SIZE;
        for (mode, method) in [
            (ViewMode::Naive, Method::Naive),
            (ViewMode::ViewIndependent, Method::ViewIndependent),
            (ViewMode::Filtered, Method::Filtered),
        ] {
            let img = r
                .render(&special, &case.scene, mode, SIZE, 1)
                .expect("readback");
            let mut off = 0;
            for y in 0..h {
                for x in 0..w {
                    let c = glam::DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                    let want =
                        prepared.plane_pixel(method, &case.scene.camera, c, SIZE, case.scene.light);
                    let got = img.rgb(x, y);
                    off += usize::from((0..3).any(|k| {
                        !((f64::from(got[k]) - want[k]).abs() <= 5e-3 * want[k].abs() + 2e-4)
                    }));
                }
            }
            if off > (w * h) as usize / 100 {
                failures.push(format!(
                    "{}, {}, {mode:?} [{}]: {off} of {} pixels differ from core",
                    case.path,
                    case.scene_name,
                    case.set,
                    w * h
                ));
            }
        }
        let truth = r
            .render(&special, &case.scene, ViewMode::Truth, SIZE, 2)
            .expect("readback");
        assert!(
            truth.pixels.iter().flatten().all(|v| v.is_finite()),
            "{} {}: non-finite ground truth",
            case.path,
            case.scene_name
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The whole library against the all-features pipeline: every preset in every scene, every view
/// (a pipeline per distinct feature set, and the all-features one: tens of minutes on llvmpipe
/// with a cold shader cache, see [`specialised_pipelines_render_what_core_renders`]). Run with
/// `cargo test -p lodestone-tests --test specialization -- --ignored` after changing a shader.
#[test]
#[ignore = "compiles the all-features shader (over 15 minutes on llvmpipe): run by hand after changing a shader"]
fn every_preset_and_scene_specialises_correctly() {
    let Some(r) = lodestone_tests::renderer("the full specialisation sweep") else {
        return;
    };
    let all = cases();
    let sets: std::collections::BTreeSet<String> = all.iter().map(|c| c.set.to_string()).collect();
    eprintln!("feature sets exercised: {sets:?}");
    let chosen: Vec<&Case> = all.iter().collect();
    let failures = check(&r, &chosen);
    assert!(sets.len() >= 6, "too few distinct feature sets: {sets:?}");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn flat_colour_mapped_noise_compiles_a_fraction_of_the_shader_and_uploads_no_visibility_tables() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../presets/colormapped-noise.ron"),
    )
    .expect("preset");
    let m = Material::from_ron(&text).expect("valid");
    let set = FeatureSet::derive(&m, Shape::Plane, direction(0.7, 1.0));
    assert!(!set.contains(Feature::Relief) && !set.contains(Feature::Shadows));
    let full = ShaderSize::measure(&view_source_for(FeatureSet::all()).unwrap(), "view_main")
        .expect("valid");
    let small = ShaderSize::measure(&view_source_for(set).unwrap(), "view_main").expect("valid");
    assert!(
        small.statements * 3 < full.statements,
        "{small:?} against {full:?}"
    );
    let prepared = prepare("presets/colormapped-noise.ron", &m);
    let special = material_data_for(&prepared, [0.0; 2], set);
    let all = material_data_for(&prepared, [0.0; 2], FeatureSet::all());
    let names = |d: &lodestone_render::material_data::MaterialData| -> Vec<&str> {
        d.segments.iter().map(|(n, _)| *n).collect()
    };
    assert!(!names(&special).contains(&"visible-height table D_h"));
    assert!(names(&all).contains(&"visible-height table D_h"));
    // What is uploaded is exactly the sum of the parts.
    for d in [&special, &all] {
        let total: usize = d.segments.iter().map(|(_, b)| b).sum();
        assert_eq!(total, d.data.len() * 4);
    }
    assert!(special.data.len() < all.data.len());
}
