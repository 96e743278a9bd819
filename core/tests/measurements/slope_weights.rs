//! Measurements of the filtered view's slope-conditioned masking (#17) against the ground truth,
//! and of the slope dependence of shadowing (all `#[ignore]`d: they print tables; run with
//! `cargo test --release -p lodestone-core --test measurements -- --ignored --nocapture NAME`; docs/design/slope-masking.md, "In the
//! filtered view").

use crate::evaluation::{FrontPoint, front_point, worst_error};
use glam::{DVec2, DVec3};
use lodestone_core::eval::{Evaluator, FootprintQuery};
use lodestone_core::fixtures::preset;
use lodestone_core::scene::direction::direction;
use std::f64::consts::PI;

/// The filtered view with Smith's masking and with slope-conditioned masking and shadowing
/// ([`lodestone_core::microfacet::slope_masking`]) against the ground truth's far patch, per channel (the
/// worst channel's relative error). `cargo test --release -p lodestone-core -- --ignored
/// --nocapture slope_conditioned_filtered`.
#[test]
#[ignore = "a measurement, prints a table"]
fn slope_conditioned_filtered() {
    use lodestone_core::microfacet::slope_masking::SlopeMasking;
    for (name, view, light, az, no_specular) in [
        ("default", 60.0, 0.0, 0.0, false),
        ("default", 75.0, 75.0, 0.0, true),
        ("default", 85.0, 85.0, 0.0, true),
        ("default", 75.0, 30.0, 0.0, false),
        ("default", 85.0, 30.0, 180.0, false),
        ("snake-skin", 75.0, 30.0, 0.0, false),
        ("snake-skin", 75.0, 30.0, 0.0, true),
        ("snake-skin", 75.0, 30.0, 180.0, false),
        ("snow-under-sky", 85.0, 30.0, 0.0, false),
        ("snow-under-sky", 85.0, 0.0, 0.0, false),
        ("snow-under-sky", 75.0, 30.0, 0.0, false),
        ("bumpy-specular", 75.0, 30.0, 0.0, false),
    ] {
        let mut m = preset(name);
        if no_specular {
            m.brdf.specular = 0.0;
        }
        let wo = direction(f64::to_radians(view), 0.0);
        let wi = if light == 0.0 {
            DVec3::Z
        } else {
            direction(f64::to_radians(light), f64::to_radians(az))
        };
        m.filtering.slope_masking = SlopeMasking::Smith;
        let smith = Evaluator::new(&m).expect("prepared");
        m.filtering.slope_masking = SlopeMasking::Conditioned;
        let cond = Evaluator::new(&m).expect("prepared");
        let cfg = FootprintQuery::far(&smith, wo, wi);
        let gt = smith.ground_truth(&cfg, 100_000, 5);
        let t0 = std::time::Instant::now();
        let c = cond.filtered(&cfg);
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let rel = |v: [f64; 3]| {
            (0..3)
                .map(|k| 100.0 * (v[k] - gt.mean[k]) / gt.mean[k])
                .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a })
        };
        let per = |v: [f64; 3]| {
            (0..3)
                .map(|k| format!("{:+.1}", 100.0 * (v[k] - gt.mean[k]) / gt.mean[k]))
                .collect::<Vec<_>>()
                .join("/")
        };
        eprintln!(
            "    per channel: Smith {}, conditioned {}",
            per(smith.filtered(&cfg)),
            per(c)
        );
        eprintln!(
            "{name:15} view {view} light {light}/{az}{}: Smith {:+6.2}%, conditioned {:+6.2}% ({ms:.0} ms); truth s.e. {:.2}%",
            if no_specular { " (no specular)" } else { "" },
            rel(smith.filtered(&cfg)),
            rel(c),
            worst_error(gt.mean, &gt).1,
        );
    }
}

#[test]
#[ignore = "a measurement"]
fn slope_conditioned_gaussian() {
    use lodestone_core::fixtures::{far_patch, gaussian_material};
    use lodestone_core::microfacet::slope_masking::SlopeMasking;
    let mut m = gaussian_material();
    m.brdf.specular = 0.04;
    m.brdf.roughness = 0.15;
    for spec in [0.04, 0.0] {
        m.brdf.specular = spec;
        for view in [45.0, 60.0, 75.0f64, 85.0] {
            for (name, wi) in [
                ("normal", DVec3::Z),
                ("along", direction(0.8, 0.3)),
                ("opposite", direction(0.8, 0.3 + PI)),
            ] {
                let wo = direction(view.to_radians(), 0.3);
                m.filtering.slope_masking = SlopeMasking::Smith;
                let smith = Evaluator::new(&m).expect("p");
                m.filtering.slope_masking = SlopeMasking::Conditioned;
                let cond = Evaluator::new(&m).expect("p");
                let cfg = far_patch(wo, wi);
                let gt = smith.ground_truth(&cfg, 40_000, 5);
                eprintln!(
                    "spec {spec} view {view} light {name}: Smith {:+.2}%, conditioned {:+.2}% (s.e. {:.2}%)",
                    worst_error(smith.filtered(&cfg), &gt).0,
                    worst_error(cond.filtered(&cfg), &gt).0,
                    worst_error(gt.mean, &gt).1
                );
            }
        }
    }
}

/// Does the shadowing of the seen points depend on their slope along the light's azimuth, and how
/// much? Over points of the explicit surface (as `slope_conditioned_visibility`), the seen ones
/// binned by t_i (slope along the light's azimuth, in its standard deviations): P(lit | seen, t_i)
/// over P(lit | seen), against the height-averaged conditioned profile toward the light
/// normalised over the seen points (what a product of masking and shadowing factors assumes).
/// Also P(lit | seen, t_i) within two height bands. `cargo test --release -p lodestone-core --
/// --ignored --nocapture slope_conditioned_shadowing`.
#[test]
#[ignore = "a measurement, prints a table"]
fn slope_conditioned_shadowing() {
    use lodestone_core::fixtures::gaussian_material;
    use lodestone_core::microfacet::slope_masking::{LineProcess, conditioned_masking, profile_at};
    use lodestone_core::microfacet::slopes::normal_of;
    let n_points = 200_000;
    for (name, view, light, az) in [
        ("gaussian", 75.0, 46.0, 180.0),
        ("gaussian", 60.0, 46.0, 180.0),
        ("gaussian", 75.0, 46.0, 0.0),
        ("default", 85.0, 30.0, 180.0),
    ] {
        let m = if name == "gaussian" {
            gaussian_material()
        } else {
            preset(name)
        };
        let p = Evaluator::new(&m).expect("prepared");
        let s = &p.surface;
        let noise = m.noise().expect("noise");
        let wo = direction(f64::to_radians(view), 0.0);
        let wi = direction(f64::to_radians(light), f64::to_radians(az));
        let di = DVec2::new(wi.x, wi.y).normalize();
        let sh = m.heights.sigma_h;
        let process = LineProcess::new(
            noise
                .waves
                .iter()
                .map(|w| (0.5 * (sh * w.amplitude).powi(2), 2.0 * PI * w.k.dot(di))),
        )
        .expect("process");
        let sd_t: f64 = noise
            .waves
            .iter()
            .map(|w| 0.5 * (sh * w.amplitude * 2.0 * PI * w.k.dot(di)).powi(2))
            .sum::<f64>()
            .sqrt();
        let sd_h: f64 = noise
            .waves
            .iter()
            .map(|w| 0.5 * (sh * w.amplitude).powi(2))
            .sum::<f64>()
            .sqrt();
        let nu = wi.z / wi.x.hypot(wi.y) / sd_t;
        let profile = conditioned_masking(&process, nu).slopes;
        let mut rng = 3u64;
        // Bins of z_i: (−∞,−1.5), (−1.5,−0.5), (−0.5,0.5), (0.5,1.5), (1.5,∞); and heights below
        // and above the mean.
        let (mut seen_w, mut lit_w, mut model_w) = ([0.0; 5], [0.0; 5], [0.0; 5]);
        let (mut band_seen, mut band_lit) = ([[0.0; 5]; 2], [[0.0; 5]; 2]);
        for _ in 0..n_points {
            let Some(FrontPoint { x, h, grad, u, .. }) = front_point(s, wo, &mut rng) else {
                continue;
            };
            let pt = DVec3::new(x.x, x.y, h);
            if !s.sees(pt, wo) {
                continue;
            }
            let n = normal_of(grad);
            let lit = n.dot(wi) > 0.0 && s.sees(pt, wi);
            let z = grad.dot(di) / sd_t;
            let b = [-1.5, -0.5, 0.5, 1.5].iter().filter(|e| z > **e).count();
            let band = usize::from(h > 0.0);
            seen_w[b] += u;
            band_seen[band][b] += u;
            model_w[b] += u * profile_at(&profile, z);
            // Self-shadowed facets (n·ωi ≤ 0) are not what the factor is about: count them lit
            // when the ray clears, as Smith's V̄ does.
            let clear = s.sees(pt, wi);
            if clear {
                lit_w[b] += u;
                band_lit[band][b] += u;
            }
            let _ = lit;
        }
        let all_lit: f64 = lit_w.iter().sum::<f64>() / seen_w.iter().sum::<f64>();
        let all_model: f64 = model_w.iter().sum::<f64>() / seen_w.iter().sum::<f64>();
        let row = |num: &[f64; 5], den: &[f64; 5], k: f64| {
            (0..5)
                .map(|b| format!("{:.2}", num[b] / den[b].max(1e-300) / k))
                .collect::<Vec<_>>()
                .join(" ")
        };
        eprintln!(
            "{name:9} view {view} light {light}/{az}: P(clear | seen) {all_lit:.3}, ν_i {nu:.2}, σ_h {sd_h:.3}"
        );
        eprintln!(
            "    P(clear | seen, t_i)/P(clear | seen): truth {}",
            row(&lit_w, &seen_w, all_lit)
        );
        eprintln!(
            "    height-averaged profile (product model):  {}",
            row(&model_w, &seen_w, all_model)
        );
        for band in 0..2 {
            eprintln!(
                "    heights {}: truth {}",
                if band == 0 {
                    "below the mean"
                } else {
                    "above the mean"
                },
                row(&band_lit[band], &band_seen[band], all_lit)
            );
        }
    }
}
