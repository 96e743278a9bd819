//! The GPU views against lodestone-core: every pixel of naive, view-independent and filtered images
//! equals core's CPU evaluation of that pixel's footprint (f32 against f64), over several materials
//! and cameras (near, grazing, far); the GPU ground truth agrees with core's CPU ray tracer.

use glam::{DVec2, DVec3};
use lodestone_core::eval::{Evaluator, FootprintQuery, Method};
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::shape::Shape;
use lodestone_render::{GpuMaterial, Renderer, Scene, ViewMode};
use lodestone_tests::preset;
use std::f64::consts::PI;

fn renderer() -> Option<Renderer> {
    lodestone_tests::renderer("the GPU view test")
}

fn cpu_pixel(
    p: &Evaluator,
    scene: &Scene,
    mode: ViewMode,
    x: u32,
    y: u32,
    w: u32,
    h: u32,
) -> [f64; 3] {
    let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
    let method = match mode {
        ViewMode::Naive => Method::Naive,
        ViewMode::ViewIndependent => Method::ViewIndependent,
        ViewMode::Filtered => Method::Filtered,
        ViewMode::Truth => unreachable!(),
    };
    p.plane_pixel(method, &scene.camera, c, (w, h), scene.light)
}

/// A distant, narrow camera: every pixel covers many features, so the GPU truth image's mean
/// estimates the same stationary expectation as the CPU's far patch; they agree within 2% per
/// channel at 0° and 60° from the normal, under `light`.
fn far_truth_matches_cpu(r: &Renderer, p: &Evaluator, label: &str, light: DVec3) {
    far_truth_matches_cpu_with(r, p, label, light, 16, 60_000);
}

/// [`far_truth_matches_cpu`] with a `side`² image of 64 rays a pixel and `cpu_rays` CPU rays (a
/// sharp lobe's glints need more of both for 2%).
fn far_truth_matches_cpu_with(
    r: &Renderer,
    p: &Evaluator,
    label: &str,
    light: DVec3,
    side: u32,
    cpu_rays: usize,
) {
    for elevation in [0.0_f64, 60.0] {
        let camera = Camera {
            elevation_deg: elevation,
            azimuth_deg: 0.0,
            distance: 2000.0,
            target: [5.0, 3.0],
            fov_deg: 2.0,
        };
        let scene = Scene {
            camera,
            light,
            shape: Shape::Plane,
        };
        let gm =
            GpuMaterial::new(r.context(), p, camera.target).expect("the material fits the adapter");
        let img = r
            .render(&gm, &scene, ViewMode::Truth, (side, side), 64)
            .expect("readback");
        let mut mean = [0.0f64; 3];
        for y in 0..side {
            for x in 0..side {
                let c = img.rgb(x, y);
                for k in 0..3 {
                    mean[k] += f64::from(c[k]) / f64::from(side * side);
                }
            }
        }
        let cpu = p.ground_truth(
            &FootprintQuery::far(p, direction(elevation.to_radians(), 0.0), light),
            cpu_rays,
            9,
        );
        for k in 0..3 {
            let rel = (mean[k] - cpu.mean[k]).abs() / cpu.mean[k];
            assert!(
                rel < 0.02,
                "{label}, elevation {elevation}°, channel {k}: GPU truth {} vs CPU truth {} ± {}",
                mean[k],
                cpu.mean[k],
                cpu.std_error[k]
            );
        }
        eprintln!(
            "{label}, elevation {elevation}°: GPU truth {mean:.4?}, CPU truth {:.4?} ± {:.4?}",
            cpu.mean, cpu.std_error
        );
    }
}

#[test]
fn analytic_views_match_core_pixel_by_pixel() {
    let Some(r) = renderer() else { return };
    let cameras = [
        (
            "near",
            Camera {
                elevation_deg: 35.0,
                azimuth_deg: 20.0,
                distance: 0.6,
                target: [1.3, -2.1],
                fov_deg: 40.0,
            },
        ),
        (
            "grazing",
            Camera {
                elevation_deg: 82.0,
                azimuth_deg: -40.0,
                distance: 3.0,
                target: [40.0, 17.0],
                fov_deg: 30.0,
            },
        ),
        (
            "far",
            Camera {
                elevation_deg: 60.0,
                azimuth_deg: 110.0,
                distance: 400.0,
                target: [-250.0, 90.0],
                fov_deg: 25.0,
            },
        ),
    ];
    let light = direction(0.7, 2.2);
    let (w, h) = (40, 28);
    let mut compared = 0;
    for name in [
        "default.ron",
        "moss.ron",
        // Knots every 0.3 driver units: the transfer mixture's bins split at them (#17).
        "terraces.ron",
        "dirt-in-crevices.ron",
        "grooves.ron",
        "snake-skin.ron",
        "snow-under-sky.ron",
    ] {
        let m = preset(name);
        let p = Evaluator::new(&m).unwrap();
        for (cam_name, camera) in cameras {
            let scene = Scene {
                camera,
                light,
                shape: Shape::Plane,
            };
            let gm = GpuMaterial::new(r.context(), &p, camera.target)
                .expect("the material fits the adapter");
            for mode in [
                ViewMode::Naive,
                ViewMode::ViewIndependent,
                ViewMode::Filtered,
            ] {
                let img = r.render(&gm, &scene, mode, (w, h), 1).expect("readback");
                // Pixels whose f32 (GPU) and f64 (core) rays land on different sides of a silhouette or
                // shadow edge of the level-of-detail relief legitimately differ; allow 1% of them.
                let mut off = vec![];
                for y in 0..h {
                    for x in 0..w {
                        let want = cpu_pixel(&p, &scene, mode, x, y, w, h);
                        let got = img.rgb(x, y);
                        // A NaN pixel is never a tolerated edge pixel (and fails any `>` test).
                        assert!(
                            got.iter().all(|v| v.is_finite()),
                            "{name} {mode:?} ({x}, {y}): {got:?}"
                        );
                        let bad = (0..3).any(|k| {
                            !((f64::from(got[k]) - want[k]).abs() <= 5e-3 * want[k].abs() + 2e-4)
                        });
                        if bad {
                            off.push((x, y, got, want));
                        }
                        compared += 3;
                    }
                }
                let allowed = (w * h) as usize / 100;
                assert!(
                    off.len() <= allowed,
                    "{name} {cam_name} {mode:?}: {} of {} pixels differ, e.g. {:?}",
                    off.len(),
                    w * h,
                    &off[..off.len().min(3)]
                );
            }
        }
    }
    assert!(compared >= 10_000);
}

#[test]
fn ground_truth_matches_the_cpu_ray_tracer_on_a_far_patch() {
    let Some(r) = renderer() else { return };
    let p = Evaluator::new(&preset("default.ron")).unwrap();
    far_truth_matches_cpu(&r, &p, "default", DVec3::Z);
    // Under oblique light, on both sides: shadow rays, the specular lobe off the normal (#16:
    // the GPU truth was compared with core's only under a light at the normal).
    far_truth_matches_cpu(&r, &p, "default, light 50° opposite", direction(0.87, PI));
    far_truth_matches_cpu(&r, &p, "default, light 50° along", direction(0.87, 0.0));
    // Slope colour, the colour-term combination and the sky's SH9 irradiance per micro-normal.
    let p = Evaluator::new(&preset("snow-under-sky.ron")).unwrap();
    far_truth_matches_cpu(&r, &p, "snow under sky", DVec3::Z);
}

/// The cylinder: analytic views equal core's tangent-plane evaluation pixel by pixel, and the GPU
/// ground truth equals core's ray tracer on the displaced cylinder, pixel by pixel, for the same rays.
#[test]
fn cylinder_views_match_core() {
    let Some(r) = renderer() else { return };
    for name in ["default.ron", "snake-skin.ron"] {
        cylinder_views_match_core_for(&r, name, [0.0, 0.0]);
    }
    // The cylinder's top line passes through the camera's target, its relief read at the surface
    // coordinates plus the target (the GPU moves its origin and noise phases there): core's
    // analytic views and their prediction followed a cylinder through the origin instead, a few
    // pixels off (the report's cylinder, target (0.3, 0.7), read a rank correlation of 0.2 between
    // predicted and measured deviation).
    cylinder_views_match_core_for(&r, "default.ron", [0.3, 0.7]);
}

/// On the cylinder the slope colour and the environment are looked up at world normals (the
/// tangent frame turns with the surface): snake-skin checks that the GPU turns them like core.
/// Ground truth is compared only with the target at the origin (core's ray tracer takes rays
/// around a cylinder through the origin).
fn cylinder_views_match_core_for(r: &Renderer, name: &str, target: [f64; 2]) {
    let m = preset(name);
    let p = Evaluator::new(&m).unwrap();
    let radius = 1.5;
    let camera = Camera {
        elevation_deg: 55.0,
        azimuth_deg: 70.0,
        distance: 6.0,
        target,
        fov_deg: 45.0,
    };
    let light = direction(0.8, 2.5);
    let scene = Scene {
        camera,
        light,
        shape: Shape::Cylinder { radius },
    };
    let gm =
        GpuMaterial::new(r.context(), &p, camera.target).expect("the material fits the adapter");
    let (w, h) = (48, 36);
    let mut sky = 0;
    for mode in [ViewMode::Naive, ViewMode::Filtered] {
        let img = r.render(&gm, &scene, mode, (w, h), 1).expect("readback");
        let method = if mode == ViewMode::Naive {
            Method::Naive
        } else {
            Method::Filtered
        };
        let mut off = vec![];
        for y in 0..h {
            for x in 0..w {
                let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                let want = p.cylinder_pixel(method, radius, &camera, c, (w, h), light);
                let got = img.rgb(x, y);
                assert!(
                    got.iter().all(|v| v.is_finite()),
                    "cylinder ({x}, {y}): {got:?}"
                );
                if want == [0.0; 3] {
                    sky += 1;
                }
                if (0..3)
                    .any(|k| !((f64::from(got[k]) - want[k]).abs() <= 5e-3 * want[k].abs() + 2e-4))
                {
                    off.push((x, y, got, want));
                }
            }
        }
        assert!(
            off.len() <= (w * h) as usize / 100,
            "{name} {mode:?}: {} of {} pixels differ, e.g. {:?}",
            off.len(),
            w * h,
            &off[..off.len().min(3)]
        );
    }
    assert!(
        sky > 50 && sky < (w * h) as usize,
        "the cylinder and the sky are both in view: {sky}"
    );
    if target != [0.0, 0.0] {
        return;
    }
    // Ground truth: the GPU averages 16 Gaussian-jittered rays per pixel (its pixel filter), core
    // traces 16 rays per pixel through the same filter (a 4×4 stratified grid mapped by
    // Box–Muller); over the image both estimate the same filtered radiance of the same geometry
    // (glints and the snake's thin red flanks make one ray per pixel too noisy to compare).
    let img = r
        .render(&gm, &scene, ViewMode::Truth, (w, h), 16)
        .expect("readback");
    let sigma = lodestone_core::scene::camera::PIXEL_SIGMA;
    let jitter: Vec<DVec2> = (0..16)
        .map(|k| {
            let (u1, u2) = (
                (f64::from(k % 4) + 0.5) / 4.0,
                (f64::from(k / 4) + 0.5) / 4.0,
            );
            let rad = (-2.0 * u1.ln()).sqrt() * sigma;
            DVec2::new(
                rad * (std::f64::consts::TAU * u2).cos(),
                rad * (std::f64::consts::TAU * u2).sin(),
            )
        })
        .collect();
    let mut gpu = [0.0f64; 3];
    let mut cpu = [0.0f64; 3];
    for y in 0..h {
        for x in 0..w {
            let g = img.rgb(x, y);
            for k in 0..3 {
                gpu[k] += f64::from(g[k]);
            }
            for j in &jitter {
                let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5) + *j;
                let ray = camera.ray(c, w, h);
                let t = p.cylinder_trace_ray(radius, ray.origin, ray.dir, light);
                for k in 0..3 {
                    cpu[k] += t[k] / jitter.len() as f64;
                }
            }
        }
    }
    // Relative to the brightest channel: the snake's blue is a few percent of its red.
    let top = cpu.iter().copied().fold(0.0, f64::max);
    for k in 0..3 {
        let rel = (gpu[k] - cpu[k]).abs() / top;
        eprintln!(
            "{name} channel {k}: GPU {} CPU {} ({:.2}% of the top channel)",
            gpu[k],
            cpu[k],
            100.0 * rel
        );
        // Measured: ≤ 0.6% (default), ≤ 1.6% (snake-skin).
        assert!(
            rel < 0.03,
            "{name} channel {k}: GPU {} vs CPU {}",
            gpu[k],
            cpu[k]
        );
    }
}

/// A small, non-Gaussian, tiling test image: rounded cells (a max of cosines) with a ridge.
fn test_image(n: usize) -> std::sync::Arc<lodestone_core::driver::image::ImageDriver> {
    use std::f64::consts::TAU;
    let values: Vec<f32> = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f64 / n as f64, (i / n) as f64 / n as f64);
            let a = (TAU * 3.0 * x).cos().max((TAU * 2.0 * y + 0.5).cos());
            let b = 0.4 * (TAU * (5.0 * x + 4.0 * y)).sin();
            (a * a * a + b) as f32
        })
        .collect();
    std::sync::Arc::new(lodestone_core::driver::image::ImageDriver::new(n, n, &values).unwrap())
}

/// An image driver: the analytic views equal core pixel by pixel (near, grazing, far), and the GPU
/// ground truth on the explicit bilinear surface equals core's on a far patch.
#[test]
fn image_driver_views_match_core() {
    let Some(r) = renderer() else { return };
    let mut m = preset("default.ron");
    m.driver = lodestone_core::material::Driver::Image {
        path: "test.png".into(),
        size: 0.8,
    };
    m.heights.sigma_h = 0.02;
    let p = Evaluator::with_image(&m, Some(test_image(64)), None).unwrap();
    let light = direction(0.7, 2.2);
    let (w, h) = (40, 28);
    for (cam_name, camera) in [
        (
            "near",
            Camera {
                elevation_deg: 35.0,
                azimuth_deg: 20.0,
                distance: 0.6,
                target: [1.3, -2.1],
                fov_deg: 40.0,
            },
        ),
        (
            "grazing",
            Camera {
                elevation_deg: 82.0,
                azimuth_deg: -40.0,
                distance: 3.0,
                target: [40.0, 17.0],
                fov_deg: 30.0,
            },
        ),
        (
            "far",
            Camera {
                elevation_deg: 60.0,
                azimuth_deg: 110.0,
                distance: 60.0,
                target: [-250.0, 90.0],
                fov_deg: 25.0,
            },
        ),
    ] {
        let scene = Scene {
            camera,
            light,
            shape: Shape::Plane,
        };
        let gm = GpuMaterial::new(r.context(), &p, camera.target)
            .expect("the material fits the adapter");
        for mode in [
            ViewMode::Naive,
            ViewMode::ViewIndependent,
            ViewMode::Filtered,
        ] {
            let img = r.render(&gm, &scene, mode, (w, h), 1).expect("readback");
            let mut off = vec![];
            for y in 0..h {
                for x in 0..w {
                    let want = cpu_pixel(&p, &scene, mode, x, y, w, h);
                    let got = img.rgb(x, y);
                    assert!(got.iter().all(|v| v.is_finite()), "({x}, {y}): {got:?}");
                    if (0..3).any(|k| {
                        !((f64::from(got[k]) - want[k]).abs() <= 5e-3 * want[k].abs() + 2e-4)
                    }) {
                        off.push((x, y, got, want));
                    }
                }
            }
            assert!(
                off.len() <= (w * h) as usize / 100,
                "image {cam_name} {mode:?}: {} of {} pixels differ, e.g. {:?}",
                off.len(),
                w * h,
                &off[..off.len().min(3)]
            );
        }
    }
    far_truth_matches_cpu(&r, &p, "image", DVec3::Z);
}

/// The fast march (octave march, Illinois refinement) and the reference march (global Lipschitz
/// steps, bisection) render the same images on the GPU: every mode of the default and sponge presets
/// at a grazing view (78°), and the default preset on a cylinder. The analytic views are identical,
/// except where core's f64 pixel sides with the fast march (at most 0.2% of the pixels: the sponge's
/// corner pixel (2, 39), whose shadow ray grazes a crest, is lit in core and the fast march since
/// the level-of-detail march steps by the transfer table's own slopes, and shadowed by the f32
/// reference);
/// in the ground truth at most 2% of the pixels differ by more than 1% of the image's peak (where
/// f32 resolves t to a sizeable fraction of a facet) and the means agree within 0.2%, leaving out
/// the band of rows next to the horizon (the top 30%) and pixels the reference leaves black and the
/// fast march does not: on
/// llvmpipe, whose loops stop after 65535 back-edges per invocation (see UNROLL in noise.wgsl), the
/// reference march gives up on horizon rays of the sponge that need 3 000–13 000 evaluations of the
/// height (core, uncapped, finds them lit there, as the fast march does, in a tenth of the work).
#[test]
fn fast_and_reference_marches_render_the_same_images() {
    use lodestone_core::scene::march::March;
    let Some(r) = renderer() else { return };
    let (w, h) = (64, 40);
    for (name, shape) in [
        ("default.ron", Shape::Plane),
        ("sponge.ron", Shape::Plane),
        ("default.ron", Shape::Cylinder { radius: 1.5 }),
    ] {
        let fast = Evaluator::new(&preset(name)).unwrap();
        let mut reference = fast.clone();
        reference.surface.march = March::Reference;
        assert_eq!(fast.surface.march, March::Fast, "the default march");
        let camera = Camera {
            elevation_deg: 78.0,
            azimuth_deg: 20.0,
            distance: 3.0,
            target: [0.3, -0.2],
            fov_deg: 35.0,
        };
        let scene = Scene {
            camera,
            light: direction(0.9, 2.0),
            shape,
        };
        let gf = GpuMaterial::new(r.context(), &fast, camera.target)
            .expect("the material fits the adapter");
        let gr = GpuMaterial::new(r.context(), &reference, camera.target)
            .expect("the material fits the adapter");
        for mode in [ViewMode::Naive, ViewMode::Filtered, ViewMode::Truth] {
            let a = r.render(&gf, &scene, mode, (w, h), 4).expect("fast");
            let b = r.render(&gr, &scene, mode, (w, h), 4).expect("reference");
            let (mut peak, mut sa, mut sb) = (0.0f64, 0.0f64, 0.0f64);
            for y in 0..h {
                for x in 0..w {
                    let (ca, cb) = (a.rgb(x, y), b.rgb(x, y));
                    for c in 0..3 {
                        peak = peak.max(f64::from(cb[c]));
                        sa += f64::from(ca[c]);
                        sb += f64::from(cb[c]);
                    }
                }
            }
            let (mut differ, mut given_up, mut reference_off) = (0, 0, 0);
            for y in 0..h {
                for x in 0..w {
                    let (ca, cb) = (a.rgb(x, y), b.rgb(x, y));
                    let horizon = mode == ViewMode::Truth && y < h * 3 / 10;
                    if horizon || mode == ViewMode::Truth && cb == [0.0; 3] && ca != [0.0; 3] {
                        // The reference may give up there (see the doc comment): leave the pixel
                        // out of both means.
                        given_up += 1;
                        for c in 0..3 {
                            sb -= f64::from(cb[c]);
                        }
                        for c in 0..3 {
                            sa -= f64::from(ca[c]);
                        }
                        continue;
                    }
                    let off = |a: [f32; 3], b: [f64; 3]| {
                        (0..3).any(|c| (f64::from(a[c]) - b[c]).abs() > 0.01 * peak)
                    };
                    if off(ca, cb.map(f64::from)) {
                        if std::env::var_os("MARCH_DEBUG").is_some() {
                            eprintln!("  ({x}, {y}): fast {ca:?} reference {cb:?}");
                        }
                        // An analytic pixel of the plane has core's f64 value to settle it: where
                        // the fast march agrees with core and the f32 reference march does not
                        // (a shadow ray grazing a crest), the reference is the one off.
                        let settled = mode != ViewMode::Truth
                            && shape == Shape::Plane
                            && !off(ca, cpu_pixel(&reference, &scene, mode, x, y, w, h))
                            && off(cb, cpu_pixel(&reference, &scene, mode, x, y, w, h));
                        if settled {
                            reference_off += 1;
                        } else {
                            differ += 1;
                        }
                    }
                }
            }
            let label = format!("{name} {shape:?} {mode:?}");
            eprintln!(
                "{label}: {differ} of {} pixels differ, {given_up} left out (horizon band, or black in the reference only), \
                 {reference_off} where the f32 reference march is off core's f64 value and the fast one is not, \
                 means {sa:.4} vs {sb:.4}",
                w * h
            );
            assert!(
                reference_off as f64 <= 0.002 * f64::from(w * h),
                "{label}: the reference march is off core at {reference_off} pixels"
            );
            assert!(
                given_up as f64 <= 0.35 * f64::from(w * h),
                "{label}: {given_up} pixels left out"
            );
            assert!(peak > 0.0, "{label}: black image");
            let allowed = if mode == ViewMode::Truth { 0.02 } else { 0.0 };
            assert!(
                differ as f64 <= allowed * f64::from(w * h),
                "{label}: {differ} pixels differ"
            );
            assert!((sa - sb).abs() <= 2e-3 * sb, "{label}: means {sa} vs {sb}");
        }
    }
}

/// The specular lobe over the noise's own slope density (#17) on the GPU: bumpy-specular far away
/// at 75° with the light at 30° on the view's side, where the half vector is 4.3σ out and the
/// saddlepoint density is 0.64 of the Gaussian's. GPU equals core pixel by pixel with either
/// density, and the two differ by more than 5% (so the saddlepoint really runs on the GPU).
/// The GPU's filtered image of `scene` equals core's pixel by pixel (0.5% + 2e-4 per channel);
/// returns core's pixels, row by row.
fn filtered_matches_core(
    r: &Renderer,
    p: &Evaluator,
    scene: &Scene,
    (w, h): (u32, u32),
    label: &str,
) -> Vec<[f64; 3]> {
    let gm = GpuMaterial::new(r.context(), p, scene.camera.target).expect("fits");
    let img = r
        .render(&gm, scene, ViewMode::Filtered, (w, h), 1)
        .expect("readback");
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let want = cpu_pixel(p, scene, ViewMode::Filtered, x, y, w, h);
            let got = img.rgb(x, y);
            for k in 0..3 {
                assert!(
                    (f64::from(got[k]) - want[k]).abs() <= 5e-3 * want[k].abs() + 2e-4,
                    "{label} ({x}, {y}): GPU {got:?}, core {want:?}"
                );
            }
            pixels.push(want);
        }
    }
    pixels
}

#[test]
fn noise_slope_density_on_the_gpu_matches_core() {
    use lodestone_core::microfacet::slope_density::NoiseSlopes;
    let Some(r) = renderer() else { return };
    let camera = Camera {
        elevation_deg: 75.0,
        azimuth_deg: 0.0,
        distance: 2000.0,
        target: [5.0, 3.0],
        fov_deg: 2.0,
    };
    let scene = Scene {
        camera,
        light: direction(30f64.to_radians(), 0.0),
        shape: Shape::Plane,
    };
    let (w, h) = (12, 8);
    let mut sums = vec![];
    for slopes in [NoiseSlopes::Exact, NoiseSlopes::Gaussian] {
        let mut m = preset("bumpy-specular.ron");
        m.filtering.noise_slopes = slopes;
        let p = Evaluator::new(&m).unwrap();
        let want = filtered_matches_core(&r, &p, &scene, (w, h), &format!("{slopes:?}"));
        sums.push(want.iter().map(|v| v[0]).sum::<f64>());
    }
    assert!(
        sums[1] > 1.05 * sums[0],
        "the Gaussian tail should be brighter: exact {} vs Gaussian {}",
        sums[0],
        sums[1]
    );
}

/// Slope-conditioned masking (#17) on the GPU equals core's, pixel by pixel, on a far grazing patch
/// and on a near grazing view (footprints across the table's levels), and it changes the image.
#[test]
fn slope_conditioned_masking_on_the_gpu_matches_core() {
    use lodestone_core::microfacet::slope_masking::SlopeMasking;
    let Some(r) = renderer() else { return };
    for (distance, fov, elevation) in [(2000.0, 2.0, 75.0), (4.0, 40.0, 80.0)] {
        let camera = Camera {
            elevation_deg: elevation,
            azimuth_deg: 20.0,
            distance,
            target: [5.0, 3.0],
            fov_deg: fov,
        };
        let scene = Scene {
            camera,
            light: direction(30f64.to_radians(), 0.4),
            shape: Shape::Plane,
        };
        let (w, h) = (12, 8);
        let mut sums = vec![];
        for masking in [SlopeMasking::Conditioned, SlopeMasking::Smith] {
            let mut m = preset("snake-skin.ron");
            m.filtering.slope_masking = masking;
            let p = Evaluator::new(&m).unwrap();
            assert_eq!(
                p.slope_masking.is_some(),
                masking == SlopeMasking::Conditioned
            );
            let label = format!("{masking:?}, distance {distance}");
            let want = filtered_matches_core(&r, &p, &scene, (w, h), &label);
            sums.push(want.iter().map(|v| v[0] + v[1] + v[2]).sum::<f64>());
        }
        assert!(
            (sums[0] / sums[1] - 1.0).abs() > 0.01,
            "distance {distance}: conditioned {} against Smith {}: no change",
            sums[0],
            sums[1]
        );
    }
}

/// Ground truth's squared sums (`ViewTarget::read_moments`) are the sums of the squares of the
/// rays it accumulated: drawn one ray per pixel at a time, each ray's colour is the difference of
/// consecutive sums, and its square is summed on the CPU (in f64) for comparison. A flat noise
/// colour map seen at a grazing angle (its pipeline compiles in seconds), so pixels hold sub-pixel
/// colour noise and horizon sky alike.
#[test]
fn truth_moments_are_the_sums_of_squared_rays() {
    let Some(r) = renderer() else { return };
    let p = Evaluator::new(&preset("colormapped-noise.ron")).unwrap();
    let scene = Scene {
        camera: Camera {
            elevation_deg: 78.0,
            azimuth_deg: 20.0,
            distance: 4.0,
            target: [0.3, -0.2],
            fov_deg: 40.0,
        },
        light: direction(40f64.to_radians(), 2.0),
        shape: Shape::Plane,
    };
    let gm = GpuMaterial::new(r.context(), &p, scene.camera.target).expect("fits");
    let (w, h, n) = (24u32, 16u32, 6u32);
    let mut target = lodestone_render::ViewTarget::new(&r, w, h).expect("target");
    let mut prev = vec![[0.0f32; 4]; (w * h) as usize];
    let mut want = vec![[0.0f64; 4]; (w * h) as usize];
    for _ in 0..n {
        r.draw(&mut target, &gm, &scene, ViewMode::Truth, 1);
        let now = target.read(&r).expect("readback").pixels;
        for (i, (a, b)) in now.iter().zip(&prev).enumerate() {
            let c: [f64; 3] = [0, 1, 2].map(|k| f64::from(a[k]) - f64::from(b[k]));
            let y = lodestone_render::truth_noise::luminance(c);
            for k in 0..3 {
                want[i][k] += c[k] * c[k];
            }
            want[i][3] += y * y;
        }
        prev = now;
    }
    let got = target.read_moments(&r).expect("readback");
    assert_eq!((got.width, got.height), (w, h));
    let mut varied = 0;
    for (i, (g, wnt)) in got.sum_sq.iter().zip(&want).enumerate() {
        for k in 0..4 {
            let tol = 1e-4 * (1.0 + wnt[k]);
            assert!(
                (f64::from(g[k]) - wnt[k]).abs() <= tol,
                "pixel {i} component {k}: GPU {} vs rays {}",
                g[k],
                wnt[k]
            );
        }
        // Count pixels whose rays differed, so the test sees noise and not only constant pixels.
        let mean = f64::from(prev[i][1]) / f64::from(n);
        if wnt[1] / f64::from(n) - mean * mean > 1e-6 {
            varied += 1;
        }
    }
    assert!(
        varied > (w * h) as usize / 4,
        "{varied} pixels with ray noise"
    );
    // A new accumulation starts its squares afresh too.
    target.reset();
    r.draw(&mut target, &gm, &scene, ViewMode::Truth, 1);
    let one = target.read(&r).expect("readback");
    let sq = target.read_moments(&r).expect("readback");
    for (a, q) in one.pixels.iter().zip(&sq.sum_sq) {
        let (q, a) = (f64::from(q[0]), f64::from(a[0]));
        assert!((q - a * a).abs() <= 1e-5 * (1.0 + q), "{q} vs {a}²");
    }
}

/// An adaptive ground truth's plan (#18 §1): a pixel brought to n rays by `draw_planned`, in one
/// call or two, holds exactly the sums of `draw`'s first n rays there (its own low-discrepancy
/// sequence), and a pixel with no ray reads 0. This camera sees no horizon: on llvmpipe a long
/// march's result can depend on the rays sharing its SIMD batch (Mesa's gallivm cuts any loop of a
/// shader after 65535 iterations over the batch; docs/design/software-adapter.md), and the two paths batch rays
/// differently. [`cut_rays_traced_again_alone_agree_across_paths`] covers the horizon.
#[test]
fn planned_truth_gives_each_pixel_its_own_first_rays() {
    let Some(r) = renderer() else { return };
    check_planned_against_uniform(&r, 55.0, 40);
}

/// Near the horizon, with cut rays traced again alone (`Renderer::set_retry_cut`), both paths
/// give each ray the march's own answer: the planned image equals the uniform one again, and on a
/// software adapter the same view without the retry has rays counted as cut.
#[test]
fn cut_rays_traced_again_alone_agree_across_paths() {
    let Some(mut r) = renderer() else { return };
    let software = r.context().is_software();
    let cut = check_planned_against_uniform(&r, 72.0, 0);
    r.set_retry_cut(true);
    let left = check_planned_against_uniform(&r, 72.0, 10);
    if software {
        assert!(
            cut > 0,
            "no ray cut at the horizon: the test no longer covers the retry"
        );
    }
    assert!(
        left <= cut,
        "{left} rays still cut with the retry, {cut} without"
    );
}

/// Uniform frames 1..=`frames` against two planned calls (ray counts up to `frames`) on a
/// 24×16 view of the default preset from `elevation` degrees; returns the rays the uniform
/// accumulation counted as cut. With `frames` = 0 only counts.
fn check_planned_against_uniform(r: &Renderer, elevation: f64, frames: u32) -> u32 {
    let p = Evaluator::new(&preset("default.ron")).unwrap();
    let scene = Scene {
        camera: Camera {
            elevation_deg: elevation,
            azimuth_deg: 10.0,
            distance: 3.0,
            target: [0.3, 0.7],
            fov_deg: 40.0,
        },
        light: direction(40f64.to_radians(), 2.0),
        shape: Shape::Plane,
    };
    let gm = GpuMaterial::new(r.context(), &p, scene.camera.target).expect("fits");
    let (w, h) = (24u32, 16u32);
    let n = (w * h) as usize;
    // Uniform references at every count the plans ask for.
    let mut uniform = lodestone_render::ViewTarget::new(r, w, h).expect("target");
    if frames == 0 {
        r.draw(&mut uniform, &gm, &scene, ViewMode::Truth, 8);
        return uniform.cut_count(r).expect("readback");
    }
    let mut at = vec![];
    for k in 1..=frames {
        r.draw(&mut uniform, &gm, &scene, ViewMode::Truth, 1);
        at.push((
            uniform.read(r).expect("readback").pixels,
            uniform.read_moments(r).expect("readback").sum_sq,
            uniform.read_work(r).expect("readback"),
        ));
        assert_eq!(uniform.samples, k);
    }
    let first: Vec<u32> = (0..n as u32).map(|p| (p * 7 + p / w) % 4).collect();
    let second: Vec<u32> = first
        .iter()
        .enumerate()
        .map(|(p, c)| match p {
            _ if p % 7 == 0 => frames / 2 + (p as u32 % (frames - frames / 2 + 1)),
            _ if p % 5 == 0 => *c,
            _ => c + (p as u32 % 3) + 1,
        })
        .map(|c| c.min(frames))
        .collect();
    let uncut = uniform.cut_count(r).expect("readback") == 0;
    let mut planned = lodestone_render::ViewTarget::new(r, w, h).expect("target");
    // A target that held something else starts afresh.
    r.draw(&mut planned, &gm, &scene, ViewMode::Truth, 2);
    for rays in [&first, &second] {
        r.draw_planned(&mut planned, &gm, &scene, rays);
        assert_eq!(planned.planned_rays(), Some(rays.as_slice()));
        let img = planned.read(r).expect("readback").pixels;
        let sq = planned.read_moments(r).expect("readback").sum_sq;
        let work = planned.read_work(r).expect("readback");
        for p in 0..n {
            let k = rays[p] as usize;
            // Each ray's work (march steps and waves summed) is counted once, whichever path
            // traced it: with no loop cut (which depends on a ray's batch) the sums are the
            // uniform ones.
            let want_work = if k == 0 { 0 } else { at[k - 1].2[p] };
            if uncut {
                assert_eq!(work[p], want_work, "pixel {p} ({k} rays): work");
            }
            let (want, want_sq) = if k == 0 {
                ([0.0; 4], [0.0; 4])
            } else {
                (at[k - 1].0[p], at[k - 1].1[p])
            };
            for c in 0..4 {
                assert!(
                    (img[p][c] - want[c]).abs() <= 1e-6 * (1.0 + want[c].abs()),
                    "pixel {p} ({k} rays) channel {c}: {} vs {}",
                    img[p][c],
                    want[c]
                );
                assert!((sq[p][c] - want_sq[c]).abs() <= 1e-6 * (1.0 + want_sq[c].abs()));
            }
        }
    }
    // Rays that meet the relief march: at least a step each on average over the view.
    let work: u64 = planned
        .read_work(r)
        .expect("readback")
        .iter()
        .map(|w| u64::from(*w))
        .sum();
    let rays: u64 = second.iter().map(|r| u64::from(*r)).sum();
    assert!(work > rays, "work {work} for {rays} rays");
    // Not every pixel is the same: the comparison saw the relief's noise.
    let distinct = (0..n)
        .filter(|p| second[*p] > 0)
        .map(|p| at[second[p] as usize - 1].0[p][1].to_bits())
        .collect::<std::collections::HashSet<_>>();
    assert!(distinct.len() > n / 2, "{} distinct pixels", distinct.len());
    uniform.cut_count(r).expect("readback")
}

/// A measured base BRDF (#18 §2): a MERL table of a coloured BRDF (red and green Lambertian, a
/// blue Beckmann lobe), on the default preset's colour map and relief. Naive looks the table up at
/// the filtered normal, filtered and view-independent use its fit, ground truth looks every facet
/// up in it: all equal core, the analytic views pixel by pixel, the truth on a far patch.
#[test]
fn measured_brdf_views_match_core() {
    use lodestone_core::material::measured::MeasuredBrdf;
    use lodestone_core::material::merl::MerlBrdf;
    let Some(r) = renderer() else { return };
    let table = MerlBrdf::tabulate(|wi, wo| {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return [0.0; 3];
        }
        let h = (wi + wo).normalize();
        let a2: f64 = 0.25 * 0.25;
        let c2 = h.z * h.z;
        let d = (-(1.0 - c2) / (c2 * a2)).exp() / (PI * a2 * c2 * c2);
        [
            0.7 / PI,
            0.35 / PI,
            0.1 / PI + 0.5 * d / (4.0 * wi.z * wo.z),
        ]
    });
    let mut m = preset("default.ron");
    m.brdf.measured = Some("test.binary".into());
    let mut p = Evaluator::new(&m).unwrap();
    p.set_measured(std::sync::Arc::new(MeasuredBrdf::new(table)));
    let light = direction(0.7, 2.2);
    let (w, h) = (40, 28);
    for camera in [
        Camera {
            elevation_deg: 35.0,
            azimuth_deg: 20.0,
            distance: 0.6,
            target: [1.3, -2.1],
            fov_deg: 40.0,
        },
        Camera {
            elevation_deg: 78.0,
            azimuth_deg: -40.0,
            distance: 3.0,
            target: [40.0, 17.0],
            fov_deg: 30.0,
        },
    ] {
        let scene = Scene {
            camera,
            light,
            shape: Shape::Plane,
        };
        let gm = GpuMaterial::new(r.context(), &p, camera.target).expect("fits the adapter");
        for mode in [
            ViewMode::Naive,
            ViewMode::ViewIndependent,
            ViewMode::Filtered,
        ] {
            let img = r.render(&gm, &scene, mode, (w, h), 1).expect("readback");
            let mut off = vec![];
            let mut blue = 0.0;
            for y in 0..h {
                for x in 0..w {
                    let want = cpu_pixel(&p, &scene, mode, x, y, w, h);
                    let got = img.rgb(x, y);
                    assert!(got.iter().all(|v| v.is_finite()), "{mode:?}: {got:?}");
                    blue += want[2];
                    // f32 and f64 may pick neighbouring bins of the table (naive), or land on
                    // either side of a shadow edge: 2% of the pixels may differ.
                    if (0..3).any(|k| {
                        !((f64::from(got[k]) - want[k]).abs() <= 5e-3 * want[k].abs() + 2e-4)
                    }) {
                        off.push((x, y, got, want));
                    }
                }
            }
            assert!(blue > 0.0, "{mode:?}: the lobe lights the image");
            assert!(
                off.len() <= (w * h) as usize / 50,
                "{:?} {mode:?}: {} of {} pixels differ, e.g. {:?}",
                camera.elevation_deg,
                off.len(),
                w * h,
                &off[..off.len().min(3)]
            );
        }
    }
    far_truth_matches_cpu_with(&r, &p, "measured", light, 40, 200_000);
}
