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

use crate::eval::{Estimate, Evaluator, FootprintQuery, Method};
use crate::fixtures::gaussian_material;
use crate::material::{ColorModel, ColorSource, Material};
use crate::microfacet::transfer::{Curve, TransferFunction};
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
    crate::fixtures::far_patch(direction(deg.to_radians(), 0.3), wi)
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
        let p = Evaluator::new(&crate::fixtures::preset(name)).expect("prepared");
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
