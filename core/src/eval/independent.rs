//! Independent checks: the filtered model against the ray-traced ground truth (which never uses
//! the statistical model) for each feature the shared formulas serve, beyond the Gaussian
//! identity-transfer material of `tests.rs`: the HN12 attribute model, specular under oblique
//! light, views past 60°, transfer curves with driver- and height-indexed colour, and the
//! cylinder. A wrong formula shared by core, the WGSL and the export passes every GPU-against-core
//! test; it fails these.
//!
//! Bounds are per channel, relative, plus three of the truth's standard errors. Where the model
//! is known to be off (transfer curves, grazing views: issue #17) the bound is the measured error
//! with a margin, so a regression (or a fix that should tighten it) shows.

use crate::eval::test_materials::gaussian_material;
use crate::eval::{Estimate, Evaluator, FootprintQuery, Method};
use crate::material::transfer::{Curve, TransferFunction};
use crate::material::{ColorModel, ColorSource, Material};
use crate::scene::camera::Camera;
use crate::scene::direction::direction;
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// Views (degrees from the normal, azimuth 0.3 rad) and lights: at the normal, 46° toward the
/// viewer's side (shadows face away) and 46° opposite (the specular side).
fn configs(views: &[f64]) -> Vec<(f64, &'static str, DVec3)> {
    let mut out = vec![];
    for &deg in views {
        for (name, wi) in [
            ("light at the normal", DVec3::Z),
            ("light along the view", direction(0.8, 0.3)),
            ("light opposite", direction(0.8, 0.3 + PI)),
        ] {
            out.push((deg, name, wi));
        }
    }
    out
}

fn far(deg: f64, wi: DVec3) -> FootprintQuery {
    crate::eval::test_materials::far_patch(direction(deg.to_radians(), 0.3), wi)
}

/// Largest |filtered − truth| / truth − 3·se/truth over channels (≤ 0: within noise), and the
/// relative errors for the message.
fn excess(fi: [f64; 3], gt: &Estimate) -> (f64, [f64; 3]) {
    let rel = [0, 1, 2].map(|k| (fi[k] - gt.mean[k]) / gt.mean[k]);
    let worst = (0..3)
        .map(|k| rel[k].abs() - 3.0 * gt.std_error[k] / gt.mean[k])
        .fold(f64::NEG_INFINITY, f64::max);
    (worst, rel)
}

/// Check `m` at `views` under the three lights: filtered within `tol(view)` (+3 s.e.) of the
/// truth from `samples` rays. Returns the largest relative error seen.
fn check(name: &str, m: &Material, views: &[f64], tol: impl Fn(f64) -> f64, samples: usize) -> f64 {
    let p = Evaluator::new(m).expect("valid test material");
    let mut worst = 0.0f64;
    let mut failures = vec![];
    for (deg, light, wi) in configs(views) {
        let cfg = far(deg, wi);
        let gt = p.ground_truth(&cfg, samples, 29);
        let fi = p.filtered(&cfg);
        let (over, rel) = excess(fi, &gt);
        worst = worst.max(rel.iter().fold(0.0f64, |a, r| a.max(r.abs())));
        let mixture = p
            .filtered_mixture(&cfg)
            .map(|v| [0, 1, 2].map(|k| 100.0 * (v[k] - gt.mean[k]) / gt.mean[k]));
        eprintln!(
            "{name}, {deg}°, {light}: filtered − truth {:+.2?}%, mixture {mixture:+.2?}%",
            rel.map(|r| 100.0 * r)
        );
        if over > tol(deg) {
            failures.push(format!(
                "{name}, view {deg}°, {light}: filtered {fi:.5?} vs truth {:.5?} ± {:.5?} ({:+.2?}%, bound {:.1}% + 3 s.e.)",
                gt.mean,
                gt.std_error,
                rel.map(|r| 100.0 * r),
                100.0 * tol(deg)
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    worst
}

/// The bound of the well-modelled range: 2.5% up to 45°, 5% at 60° (as for slope colours).
fn within_60(deg: f64) -> f64 {
    if deg > 45.0 { 0.05 } else { 0.025 }
}

/// [HN12 Eq. 17]: a colour correlated with height, ā + a_s·s(h), per channel (one negative).
/// Measured (20k rays): within 0.9% up to 60° but for blue under the opposite light at 60°
/// (+4.6%: blue's ā = 0.1 makes its relative error the largest). The mean shape 1 − 2/(L+2)
/// changed to 1 − 1.5/(L+2) fails it (and nothing else in core's tests).
#[test]
fn hn12_attribute_filters_to_ground_truth() {
    let mut m = gaussian_material();
    m.color = ColorModel::Attribute {
        mean: [0.4, 0.25, 0.1],
        correlation: [0.2, 0.1, -0.05],
    };
    check("HN12 attribute", &m, &[0.0, 30.0, 60.0], within_60, 20_000);
}

/// The Beckmann specular lobe widened by the slope distribution, under oblique light on both
/// sides, with micro-slopes (σ_n = 0.12) as wide as the base roughness so that both widths
/// matter (at 45° the opposite light is the mirror direction). Measured (20k rays): within 1.7%
/// everywhere; with the base roughness 20% too wide in the widening the opposite light is 5–14%
/// off and fails.
#[test]
fn specular_under_oblique_light_filters_to_ground_truth() {
    let mut m = gaussian_material();
    m.brdf.specular = 0.04;
    m.brdf.roughness = 0.15;
    m.slopes = crate::material::Slopes {
        sigma_nx: 0.12,
        sigma_ny: 0.12,
    };
    check("specular", &m, &[0.0, 30.0, 45.0, 60.0], within_60, 20_000);
}

/// Past 60° the Smith model's independence assumptions and the Gaussian slopes' tails show
/// (#17 measures 3–7% on the default preset at 75–85°). Measured here (20k rays, specular on):
/// up to 5.8% at 75°. Bound 8% at 75°, 12% at 85°: a wrong Λ or masking formula is far
/// beyond either.
#[test]
fn views_past_60_degrees_filter_to_ground_truth() {
    let mut m = gaussian_material();
    m.brdf.specular = 0.04;
    m.brdf.roughness = 0.15;
    let worst = check(
        "grazing",
        &m,
        &[75.0, 85.0],
        |deg| if deg > 80.0 { 0.12 } else { 0.08 },
        20_000,
    );
    assert!(
        worst > 1e-3,
        "a grazing view agreeing to 0.1% is suspicious: {worst}"
    );
}

/// Transfer curves (moss) with the colour indexed by the driver and by the transformed height.
/// One Gaussian (`transfer_slopes: Gaussian`, the papers' model) was off by up to 23% with the
/// driver's colour and 34% with the height's (#17: the colour of g(f) averaged as if g(f) were
/// Gaussian, colour and slope correlated through g′(f)). The binned mixture the model now uses
/// (`crate::eval::mixture_bins`): ≤ 2.8% up to 30° (blue, whose map values are smallest),
/// ≤ 7.1% at 60° (red under the opposite light: the 241-node mixture is 8.8% there, so the
/// residual is not the binning). Bounds: 4% up to 30°, 9% at 60°, plus 3 s.e. (10k rays).
#[test]
fn transfer_curves_against_ground_truth() {
    let mut m = gaussian_material();
    m.heights.transfer = TransferFunction::Curve(Curve::moss());
    let a = check(
        "moss curve, driver colour",
        &m,
        &[0.0, 30.0, 60.0],
        moss_bound,
        10_000,
    );
    assert!(a > 1e-3, "suspiciously exact: {a}");
    if let ColorModel::Gradient { source, .. } = &mut m.color {
        *source = ColorSource::Height;
    }
    let b = check(
        "moss curve, height colour",
        &m,
        &[0.0, 30.0, 60.0],
        moss_bound,
        10_000,
    );
    assert!(b > 1e-3, "suspiciously exact: {b}");
}

/// The moss bounds: 4% up to 30°, 9% at 60°.
fn moss_bound(deg: f64) -> f64 {
    if deg > 45.0 { 0.09 } else { 0.04 }
}

/// The cylinder (radius 60, seen from 1500 units: each pixel spans ~10 features): the analytic
/// filtered view in the tangent plane against the displaced cylinder ray traced, as the mean of
/// a 6×6 block of pixels (the mean of 36 pixel footprints against rays spread uniformly over the
/// block), under oblique light. Measured: within 1%.
#[test]
fn cylinder_filters_to_ground_truth() {
    let mut m = gaussian_material();
    m.brdf.specular = 0.04;
    m.brdf.roughness = 0.15;
    let p = Evaluator::new(&m).expect("valid");
    let r = 60.0;
    let size = (16u32, 16u32);
    let wi = direction(0.6, 2.0);
    for (elevation, azimuth) in [(30.0, 20.0), (55.0, 80.0)] {
        let camera = Camera {
            elevation_deg: elevation,
            azimuth_deg: azimuth,
            distance: 1500.0,
            target: [0.0, 0.0],
            fov_deg: 8.0,
        };
        let block = 5..11u32;
        let mut filtered = [0.0f64; 3];
        for y in block.clone() {
            for x in block.clone() {
                let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                let v = p.cylinder_pixel(Method::Filtered, r, &camera, c, size, wi);
                for k in 0..3 {
                    filtered[k] += v[k] / 36.0;
                }
            }
        }
        let n = 12_000;
        let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
        let mut rng = 0x5EED_u64;
        for _ in 0..n {
            let u = crate::math::random::splitmix(&mut rng);
            let v = crate::math::random::splitmix(&mut rng);
            let c = DVec2::new(5.0 + 6.0 * u, 5.0 + 6.0 * v);
            let ray = camera.ray(c, size.0, size.1);
            let s = p.cylinder_trace_ray(r, ray.origin, ray.dir, wi);
            for k in 0..3 {
                sum[k] += s[k];
                sum2[k] += s[k] * s[k];
            }
        }
        let nf = n as f64;
        let mean = sum.map(|s| s / nf);
        let se = [0, 1, 2].map(|k| ((sum2[k] / nf - mean[k] * mean[k]).max(0.0) / nf).sqrt());
        let gt = Estimate {
            mean,
            std_error: se,
            samples: n,
        };
        let (over, rel) = excess(filtered, &gt);
        eprintln!(
            "cylinder at {elevation}°/{azimuth}°: filtered − truth {:+.2?}% (s.e. {:.2?}%)",
            rel.map(|r| 100.0 * r),
            [0, 1, 2].map(|k| 100.0 * se[k] / mean[k])
        );
        assert!(
            over < 0.025,
            "cylinder at {elevation}°: filtered {filtered:.5?} vs truth {mean:.5?} ± {se:.5?}"
        );
    }
}

/// Why the specular lobe is off in the slope distribution's tails (#17, bumpy-specular): the
/// density of the noise's slopes (σ_h ∇f of a sum of sinusoids, phases uniform: the footprint's
/// statistics far away) at the half vectors of the failing configurations, by Monte Carlo over the
/// phases, against the Gaussian of the same covariance that the filtered lobe uses. Measurement
/// (`cargo test -- --ignored`), printed.
#[test]
#[ignore = "a measurement for the closing note, prints a table"]
fn slope_density_of_the_noise_in_its_tails() {
    use crate::microfacet::slopes::slope_of;
    let text = std::fs::read_to_string(format!(
        "{}/../presets/bumpy-specular.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("preset");
    let m = Material::from_ron(&text).expect("valid");
    let noise = m.noise().expect("a noise driver");
    let sh = m.heights.sigma_h;
    // Slope contributions c_i k̂_i sin ψ_i, c_i = σ_h 2π a_i |k_i|.
    let terms: Vec<(f64, DVec2)> = noise
        .waves
        .iter()
        .map(|w| {
            (
                sh * 2.0 * PI * w.amplitude * w.k.length(),
                w.k.normalize_or_zero(),
            )
        })
        .collect();
    let (mut xx, mut yy, mut xy) = (0.0, 0.0, 0.0);
    for (c, d) in &terms {
        xx += 0.5 * c * c * d.x * d.x;
        yy += 0.5 * c * c * d.y * d.y;
        xy += 0.5 * c * c * d.x * d.y;
    }
    let det = xx * yy - xy * xy;
    let gauss = |s: DVec2| {
        let q = (yy * s.x * s.x - 2.0 * xy * s.x * s.y + xx * s.y * s.y) / det;
        (-0.5 * q).exp() / (2.0 * PI * det.sqrt())
    };
    let max_slope: f64 = terms.iter().map(|(c, _)| c.abs()).sum();
    eprintln!(
        "σ_n {:.3} {:.3}, slopes bounded by Σ c_i = {max_slope:.2}",
        xx.sqrt(),
        yy.sqrt()
    );
    let configs = [
        ("45° / 30° same side", 45.0, 30.0, 0.0),
        ("75° / 30° same side", 75.0, 30.0, 0.0),
        ("85° / 30° opposite", 85.0, 30.0, 180.0),
        ("45° / 60° opposite", 45.0, 60.0, 180.0),
        ("60° / 0°", 60.0, 0.0, 0.0),
    ];
    let samples = 20_000_000u64;
    let r = 0.03;
    let mut counts = vec![0u64; configs.len()];
    let centres: Vec<DVec2> = configs
        .iter()
        .map(|(_, v, l, az)| {
            let wo = direction(f64::to_radians(*v), 0.0);
            let wi = direction(f64::to_radians(*l), f64::to_radians(*az));
            slope_of((wo + wi).normalize())
        })
        .collect();
    let mut rng = 0x1234_5678_u64;
    for _ in 0..samples {
        let mut s = DVec2::ZERO;
        for (c, d) in &terms {
            let psi = 2.0 * PI * crate::math::random::splitmix(&mut rng);
            s += *d * (c * psi.sin());
        }
        for (i, c) in centres.iter().enumerate() {
            if (s - *c).length_squared() < r * r {
                counts[i] += 1;
            }
        }
    }
    for (i, (name, ..)) in configs.iter().enumerate() {
        let exact = counts[i] as f64 / (samples as f64 * PI * r * r);
        let g = gauss(centres[i]);
        let sigmas = (centres[i].length_squared() / xx).sqrt();
        let v: Vec<DVec2> = terms.iter().map(|(c, d)| *d * *c).collect();
        let sp = crate::microfacet::slope_density::sinusoid_density_ratio(&v, 0.0, centres[i]);
        eprintln!(
            "{name:22} half-vector slope {:.3} ({sigmas:.1}σ): noise density {exact:.4e} ({} hits), Gaussian {g:.4e}, ratio {:.3}, saddlepoint ratio {sp:.3}",
            centres[i].length(),
            counts[i],
            exact / g
        );
    }
}

/// The sponge and terraces presets (steep pits, treads and risers) against the ray-traced truth:
/// one Gaussian is 34–47% off at these configurations, the binned mixture within 2% (measured
/// with 200k rays: sponge −0.32% at 0°, +1.02% at 75°; terraces −2.00% at 30°, +0.85% at 60°).
/// Bounds 3% plus 3 s.e. of 20k rays.
#[test]
fn transfer_presets_filter_to_ground_truth() {
    for (name, view, light, az) in [
        ("sponge", 0.0, 0.0, 0.0),
        ("sponge", 75.0, 30.0, 180.0),
        ("terraces", 30.0, 30.0, 180.0),
        ("terraces", 60.0, 30.0, 0.0),
    ] {
        let text = std::fs::read_to_string(format!(
            "{}/../presets/{name}.ron",
            env!("CARGO_MANIFEST_DIR")
        ))
        .expect("preset");
        let p = Evaluator::new(&Material::from_ron(&text).expect("valid")).expect("prepared");
        let wi = direction(f64::to_radians(light), f64::to_radians(az));
        let cfg = FootprintQuery::far(&p, direction(f64::to_radians(view), 0.0), wi);
        let gt = p.ground_truth(&cfg, 20_000, 43);
        let (over, rel) = excess(p.filtered(&cfg), &gt);
        assert!(
            over < 0.03,
            "{name} {view}°/{light}°/{az}°: {:+.2?}% (± {:.2?})",
            rel.map(|r| 100.0 * r),
            gt.std_error
        );
    }
}

/// The library's transfer-curve presets against the ray-traced truth: the binned mixture the
/// views run, one Gaussian and the 241-node mixture (measurement for #17's closing note, far
/// patch, 200k rays; `cargo test --release -- --ignored --nocapture transfer_presets`).
#[test]
#[ignore = "a measurement, prints a table"]
fn transfer_presets_against_ground_truth() {
    use crate::microfacet::height_mixture::TransferSlopes;
    for name in ["moss", "sponge", "terraces"] {
        let text = std::fs::read_to_string(format!(
            "{}/../presets/{name}.ron",
            env!("CARGO_MANIFEST_DIR")
        ))
        .expect("preset");
        let m = Material::from_ron(&text).expect("valid");
        let p = Evaluator::new(&m).expect("prepared");
        let mut g = m.clone();
        g.filtering.transfer_slopes = TransferSlopes::Gaussian;
        let pg = Evaluator::new(&g).expect("prepared");
        for (view, light, az) in [
            (0.0, 0.0, 0.0),
            (30.0, 30.0, 180.0),
            (45.0, 60.0, 0.0),
            (60.0, 30.0, 0.0),
            (75.0, 30.0, 180.0),
            (85.0, 0.0, 0.0),
        ] {
            let wi = if light == 0.0 {
                DVec3::Z
            } else {
                direction(f64::to_radians(light), f64::to_radians(az))
            };
            let cfg = FootprintQuery::far(&p, direction(f64::to_radians(view), 0.0), wi);
            let gt = p.ground_truth(&cfg, 200_000, 41);
            let rel = |v: [f64; 3]| {
                (0..3)
                    .map(|k| 100.0 * (v[k] - gt.mean[k]) / gt.mean[k])
                    .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a })
            };
            let se = (0..3)
                .map(|k| 100.0 * gt.std_error[k] / gt.mean[k])
                .fold(0.0f64, f64::max);
            eprintln!(
                "{name:9} view {view:2} light {light:2}/{az:3}: bins {:+6.2}%  gaussian {:+6.2}%  fine {:+6.2}%  (truth s.e. {se:.2}%)",
                rel(p.filtered(&cfg)),
                rel(pg.filtered(&cfg)),
                rel(p.filtered_mixture(&cfg).expect("applies")),
            );
        }
    }
}

/// Where the grazing specular error of bumpy-specular lives (#17): over points of the explicit
/// surface (uniform on the mean plane, so area-weighted), the unmasked specular per unit visible
/// area against the Gaussian lobe the model integrates, the mean visibility (view, view and light)
/// over visible area against Smith's, and the same visibility weighted by the specular lobe: if the
/// lobe's facets are masked unlike the average facet, the last two differ. Measurement
/// (`cargo test --release -- --ignored --nocapture grazing_specular_decomposition`).
#[test]
#[ignore = "a measurement, prints a table"]
fn grazing_specular_decomposition() {
    use crate::math::random::splitmix;
    use crate::microfacet::brdf::filtered_specular;
    use crate::microfacet::masking_shadowing::G2;
    use crate::microfacet::slopes::{SlopeCov, normal_of};
    let text = std::fs::read_to_string(format!(
        "{}/../presets/bumpy-specular.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("preset");
    let m = Material::from_ron(&text).expect("valid");
    let p = Evaluator::new(&m).expect("prepared");
    let s = &p.surface;
    let n_points = 400_000;
    for (view, light, az) in [
        (45.0, 30.0, 0.0),
        (60.0, 0.0, 0.0),
        (75.0, 30.0, 0.0),
        (85.0, 30.0, 180.0),
    ] {
        let wo = direction(f64::to_radians(view), 0.0);
        let wi = direction(f64::to_radians(light), f64::to_radians(az));
        let cfg = FootprintQuery::far(&p, wo, wi);
        let loc = p.footprint_stats(&cfg);
        let (mut u_sum, mut spec_u, mut u_vo, mut u_vovi, mut spec_u_vovi, mut spec_u_vo) =
            (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut rng = 99u64;
        for _ in 0..n_points {
            let x = DVec2::new(
                200.0 * splitmix(&mut rng) - 100.0,
                200.0 * splitmix(&mut rng) - 100.0,
            );
            let (_f, h, grad) = s.sample(x);
            let n = normal_of(grad);
            let u = wo.z - grad.x * wo.x - grad.y * wo.y;
            if u <= 0.0 {
                continue;
            }
            let spec = m.brdf.specular_with(n, wo, wi, SlopeCov::default());
            let pt = DVec3::new(x.x, x.y, h);
            let vo = if s.sees(pt, wo) { 1.0 } else { 0.0 };
            let vi = if vo > 0.0 && s.sees(pt, wi) { 1.0 } else { 0.0 };
            u_sum += u;
            spec_u += spec * u;
            u_vo += u * vo;
            u_vovi += u * vo * vi;
            spec_u_vovi += spec * u * vo * vi;
            spec_u_vo += spec * u * vo;
        }
        let b = &m.brdf;
        let lobe = filtered_specular(
            b.specular,
            b.roughness,
            loc.stats.slope_mean,
            &loc.stats.slope_cov,
            wo,
            wi,
        );
        let ms = G2::from_directions(wo, wi, &loc.stats.slope_cov, m.filtering.correlation);
        eprintln!(
            "view {view} light {light}/{az}: unmasked lobe truth {:.4e} model {lobe:.4e} ({:+.1}%); \
             G1 truth {:.4} Smith {:.4}; shadowing|visible truth {:.4} model {:.4}; \
             lobe-weighted: G1 {:.4}, shadowing|visible {:.4}; spec/visible area truth {:.4e} model {:.4e} ({:+.1}%)",
            spec_u / u_sum,
            100.0 * (lobe / (spec_u / u_sum) - 1.0),
            u_vo / u_sum,
            1.0 / (1.0 + ms.lambda_o),
            u_vovi / u_vo,
            ms.mean_shadowing(),
            spec_u_vo / spec_u,
            spec_u_vovi / spec_u_vo,
            spec_u_vovi / u_vo,
            lobe * ms.mean_shadowing(),
            100.0 * (lobe * ms.mean_shadowing() / (spec_u_vovi / u_vo) - 1.0),
        );
    }
}

/// The presets with a specular lobe against the ray-traced truth, the lobe over the noise's own
/// slope density and over the Gaussian (measurement for #17, far patch, up to 400k rays;
/// `cargo test --release -- --ignored --nocapture specular_presets_against`).
#[test]
#[ignore = "a measurement, prints a table"]
fn specular_presets_against_ground_truth() {
    use crate::microfacet::slope_density::NoiseSlopes;
    for name in ["bumpy-specular", "default", "snake-skin"] {
        let text = std::fs::read_to_string(format!(
            "{}/../presets/{name}.ron",
            env!("CARGO_MANIFEST_DIR")
        ))
        .expect("preset");
        let m = Material::from_ron(&text).expect("valid");
        if m.brdf.specular <= 0.0 {
            eprintln!("{name}: no specular");
            continue;
        }
        let p = Evaluator::new(&m).expect("prepared");
        let mut g = m.clone();
        g.filtering.noise_slopes = NoiseSlopes::Gaussian;
        let pg = Evaluator::new(&g).expect("prepared");
        for (view, light, az) in [
            (0.0, 30.0, 0.0),
            (45.0, 30.0, 0.0),
            (45.0, 60.0, 180.0),
            (60.0, 0.0, 0.0),
            (60.0, 30.0, 180.0),
            (75.0, 30.0, 0.0),
            (75.0, 60.0, 180.0),
            (85.0, 30.0, 180.0),
            (85.0, 0.0, 0.0),
        ] {
            let wi = if light == 0.0 {
                DVec3::Z
            } else {
                direction(f64::to_radians(light), f64::to_radians(az))
            };
            let cfg = FootprintQuery::far(&p, direction(f64::to_radians(view), 0.0), wi);
            let gt = p.ground_truth(&cfg, 400_000, 47);
            let rel = |v: [f64; 3]| {
                (0..3)
                    .map(|k| 100.0 * (v[k] - gt.mean[k]) / gt.mean[k])
                    .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a })
            };
            let se = (0..3)
                .map(|k| 100.0 * gt.std_error[k] / gt.mean[k])
                .fold(0.0f64, f64::max);
            eprintln!(
                "{name:15} view {view:2} light {light:2}/{az:3}: exact {:+7.2}%  gaussian {:+7.2}%  (truth s.e. {se:.2}%)",
                rel(p.filtered(&cfg)),
                rel(pg.filtered(&cfg)),
            );
        }
    }
}
