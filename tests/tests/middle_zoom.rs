//! #17 at middle zoom: the views' pixels ([`Evaluator::plane_pixel`]: the level-of-detail march,
//! the filtered model at the pixel's footprint, a shadow ray on h̄) against the explicit surface
//! traced through random points of the same pixels, image means over a 48 × 36 image of 10°
//! field of view (its views within ±5° of the named one), diffuse only (the glints of a truth at
//! a few rays a pixel would bury it). The far-patch grid (`accuracy.rs`) cannot see this zoom:
//! where a footprint resolves part of the relief, the march masks the resolved part and the model
//! the rest, and the unresolved relief stops rays on the crests they pass
//! ([`lodestone_core::eval::interception`]; docs/design/accuracy.md, "The views at middle zoom").
//!
//! As in `accuracy.rs`, the error that counts is beyond 3 standard errors of the truth, worst
//! channel, against #17's goal (1% up to 60°, 4% beyond); [`KNOWN`] holds the measured shortfalls
//! (×1.1), so the test fails when a configuration that met the goal stops meeting it or a known
//! shortfall grows. Shrink or remove an entry when a change improves it.

use glam::{DVec2, DVec3};
use lodestone_core::eval::{Evaluator, Method};
use lodestone_core::material::Material;
use lodestone_core::math::random::splitmix;
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_tests::{prepare, presets};

const W: u32 = 48;
const H: u32 = 36;
/// Truth rays per pixel.
const RAYS: usize = 32;

/// (preset file, view, light angle, light azimuth, distance): distances 10, 35 and 350 put the
/// far weight `(σ_f,footprint/σ_f)²` at the image's centre near 0.07, 0.45 and 1 on these presets.
const CONFIGS: &[(&str, f64, f64, f64, f64)] = &[
    ("default.ron", 60.0, 0.0, 0.0, 10.0),
    ("default.ron", 60.0, 0.0, 0.0, 35.0),
    ("default.ron", 60.0, 60.0, 180.0, 10.0),
    ("default.ron", 60.0, 60.0, 180.0, 35.0),
    ("default.ron", 80.0, 60.0, 0.0, 10.0),
    ("default.ron", 80.0, 60.0, 0.0, 35.0),
    ("default.ron", 80.0, 60.0, 0.0, 350.0),
    ("sponge.ron", 60.0, 0.0, 0.0, 10.0),
    ("sponge.ron", 60.0, 60.0, 180.0, 10.0),
    ("sponge.ron", 60.0, 60.0, 180.0, 350.0),
];

/// Open shortfalls: (preset, view, light, azimuth, distance, largest excess allowed), measured
/// 2026-12-05 with camera rays stopped on crests (`Interception::Crests`; ×1.1). All at distance
/// 10 (far weight about 0.07), the bottom of the dip; the same configurations at 35 and 350 meet
/// the goal. Default at 80° (−8.05% with rays meeting h̄) now meets it: −2.20%.
const KNOWN: &[(&str, f64, f64, f64, f64, f64)] = &[
    // −2.59% (−2.93% on h̄): the light opposite.
    ("default.ron", 60.0, 60.0, 180.0, 10.0, 0.0177),
    // −2.48% (−4.60%) with the light at the normal: the masking alone.
    ("sponge.ron", 60.0, 0.0, 0.0, 10.0, 0.0197),
    // −5.81% (−8.69%).
    ("sponge.ron", 60.0, 60.0, 180.0, 10.0, 0.0529),
];

/// The image mean of the filtered view of `p` and `others`, and of the truth (traced on `p`),
/// with the truth's standard error.
fn image_means(
    p: &Evaluator,
    others: &[&Evaluator],
    camera: &Camera,
    wi: DVec3,
) -> (Vec<[f64; 3]>, [f64; 3], [f64; 3]) {
    let clear = p.surface.clear_camera(camera);
    let mut f = vec![[0.0f64; 3]; 1 + others.len()];
    let (mut t, mut t2) = ([0.0f64; 3], [0.0f64; 3]);
    let mut rng = 5u64;
    for y in 0..H {
        for x in 0..W {
            let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
            for (e, sum) in std::iter::once(p).chain(others.iter().copied()).zip(&mut f) {
                let v = e.plane_pixel(Method::Filtered, camera, c, (W, H), wi);
                for k in 0..3 {
                    sum[k] += v[k];
                }
            }
            for _ in 0..RAYS {
                let j = DVec2::new(splitmix(&mut rng), splitmix(&mut rng));
                let r = clear.ray(DVec2::new(f64::from(x), f64::from(y)) + j, W, H);
                let v = p.trace_ray(r.origin, r.dir, wi);
                for k in 0..3 {
                    t[k] += v[k];
                    t2[k] += v[k] * v[k];
                }
            }
        }
    }
    let (np, nt) = (f64::from(W * H), (W * H) as f64 * RAYS as f64);
    let tm = t.map(|s| s / nt);
    let se = [0, 1, 2].map(|k| ((t2[k] / nt - tm[k] * tm[k]).max(0.0) / nt).sqrt());
    (f.iter().map(|s| s.map(|v| v / np)).collect(), tm, se)
}

/// The camera of a configuration.
fn camera(view: f64, distance: f64) -> Camera {
    Camera {
        elevation_deg: view,
        azimuth_deg: 0.0,
        distance,
        target: [3.0, -7.0],
        fov_deg: 10.0,
    }
}

/// A preset of the library, diffuse only, prepared.
fn diffuse(name: &str) -> (Material, Evaluator) {
    let (path, text) = presets()
        .into_iter()
        .find(|(p, _)| p.ends_with(name))
        .unwrap_or_else(|| panic!("{name} is in presets/"));
    let mut m = Material::from_ron(&text).unwrap();
    m.brdf.specular = 0.0;
    let p = prepare(&path, &m);
    (m, p)
}

/// Filtered − truth over truth, the worst channel, and that channel's excess beyond 3 s.e.
fn worst(f: [f64; 3], t: [f64; 3], se: [f64; 3]) -> (f64, f64) {
    let peak = t.iter().copied().fold(0.0f64, f64::max);
    let (mut excess, mut signed) = (0.0f64, 0.0f64);
    for k in 0..3 {
        if t[k] <= 1e-3 * peak {
            continue;
        }
        let e = ((f[k] - t[k]).abs() - 3.0 * se[k]).max(0.0) / t[k];
        if e >= excess {
            excess = e;
            signed = (f[k] - t[k]) / t[k];
        }
    }
    (signed, excess)
}

#[test]
fn middle_zoom_meets_the_accuracy_goal_or_its_known_bound() {
    let mut failures = vec![];
    for &(name, view, light, azimuth, distance) in CONFIGS {
        let (_, p) = diffuse(name);
        let wi = direction(light.to_radians(), azimuth.to_radians());
        let (f, t, se) = image_means(&p, &[], &camera(view, distance), wi);
        let (signed, excess) = worst(f[0], t, se);
        let goal = if view <= 60.0 { 0.01 } else { 0.04 };
        let known = KNOWN
            .iter()
            .find(|k| {
                k.0 == name && k.1 == view && k.2 == light && k.3 == azimuth && k.4 == distance
            })
            .map(|k| k.5);
        let bound = known.unwrap_or(goal);
        eprintln!(
            "{name:<12} view {view:>2}° light {light:>2}°/{azimuth:>3}° distance {distance:>5}: {:+.2}%, beyond 3 s.e. {:.2}% (bound {:.2}%)",
            100.0 * signed,
            100.0 * excess,
            100.0 * bound
        );
        if excess > bound {
            failures.push(format!(
                "{name} view {view} light {light}/{azimuth} distance {distance}: {:.2}% beyond the truth's noise, bound {:.2}%",
                100.0 * excess,
                100.0 * bound
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join(",\n"));
}

/// The sweep behind the test (docs/design/accuracy.md, "The views at middle zoom"): per preset and
/// configuration, five zooms from a resolved driver to the far field, the material's own masking
/// and Smith's, and the far weight `(σ_f,footprint/σ_f)²` at the image's centre, with which the
/// transfer curves' conditioned bins blend toward Smith's. `LODESTONE_PRESETS=a.ron,b.ron` and
/// `LODESTONE_CONFIGS="view,light,azimuth;…"` (degrees) choose what it runs.
#[test]
#[ignore = "a measurement, prints a table (minutes)"]
fn middle_zoom_sweep() {
    use lodestone_core::driver::footprint::Footprint;
    use lodestone_core::eval::interception::Interception;
    use lodestone_core::microfacet::slope_masking::SlopeMasking;
    let names: Vec<String> = std::env::var("LODESTONE_PRESETS")
        .map(|s| s.split(',').map(str::to_owned).collect())
        .unwrap_or_else(|_| {
            vec![
                "terraces.ron".into(),
                "sponge.ron".into(),
                "default.ron".into(),
            ]
        });
    let configs: Vec<(f64, f64, f64)> = match std::env::var("LODESTONE_CONFIGS") {
        Ok(v) => v
            .split(';')
            .map(|c| {
                let x: Vec<f64> = c.split(',').map(|t| t.parse().expect("a number")).collect();
                (x[0], x[1], x[2])
            })
            .collect(),
        Err(_) => vec![(60.0, 0.0, 0.0), (60.0, 60.0, 180.0), (80.0, 60.0, 0.0)],
    };
    for name in &names {
        let (m, own) = diffuse(name);
        let mut ms = m.clone();
        ms.filtering.slope_masking = SlopeMasking::Smith;
        let smith = Evaluator::new(&ms).expect("prepared");
        let mut off = own.clone();
        off.interception = Interception::Off;
        for &(view, light, az) in &configs {
            let wi = direction(light.to_radians(), az.to_radians());
            for distance in [3.5, 10.0, 35.0, 100.0, 350.0] {
                let cam = camera(view, distance);
                let (f, t, se) = image_means(&own, &[&smith, &off], &cam, wi);
                let centre = DVec2::new(f64::from(W) / 2.0 + 0.5, f64::from(H) / 2.0 + 0.5);
                let far = own
                    .surface
                    .clear_camera(&cam)
                    .plane_footprint(centre, W, H)
                    .map_or(f64::NAN, |(hit, cov)| {
                        let d = own.surface.driver.filtered(hit, Footprint { cov });
                        let g = own.surface.driver.filtered(hit, Footprint::isotropic(1e6));
                        (d.std / g.std.max(1e-12)).powi(2)
                    });
                let rel = |k: usize| worst(f[k], t, [0.0; 3]).0;
                let se_max = (0..3)
                    .map(|k| se[k] / t[k].max(1e-12))
                    .fold(0.0f64, f64::max);
                eprintln!(
                    "{name:<14} view {view:>2}° light {light:>2}°/{az:>3}° distance {distance:>5}: far {far:.3}, own {:+.2}%, Smith {:+.2}%, rays on h̄ {:+.2}%, truth s.e. {:.2}%",
                    100.0 * rel(0),
                    100.0 * rel(1),
                    100.0 * rel(2),
                    100.0 * se_max
                );
            }
        }
    }
}
