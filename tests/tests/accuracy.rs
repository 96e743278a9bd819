//! #17's accuracy grid in test-sized form: every preset of the library, far patch, views 0°, 60°
//! and 85° × the light at the normal, 30° and 60° on the view's side and opposite; the filtered
//! model against the ray-traced ground truth (20 000 seeded rays: deterministic).
//!
//! The error that counts is what lies beyond the truth's own noise, `(|F − T| − 3·s.e.)⁺ / T`,
//! worst channel. The goal of #17 is ≤ 1% up to 60° and ≤ 4% at 85°. Where a preset does not meet
//! it yet, [`KNOWN`] holds its measured excess (rounded up by about a tenth): the test fails when a
//! configuration that met the goal stops meeting it, and when a known shortfall grows. Shrink or
//! remove a `KNOWN` entry when a change improves it (the test prints every configuration).

use lodestone_core::eval::FootprintQuery;
use lodestone_core::material::Material;
use lodestone_core::scene::direction::direction;
use lodestone_tests::{prepare, presets};

/// Ground-truth rays per configuration.
const RAYS: usize = 20_000;

/// Views from the normal (degrees).
const VIEWS: [f64; 3] = [0.0, 60.0, 85.0];

/// Lights: (angle from the normal, azimuth; the view's azimuth is 0), degrees. The 60° lights are
/// where the transfer curves miss (docs/design/transfer-curves.md, "Masking that knows the
/// driver's slope").
const LIGHTS: [(f64, f64); 5] = [
    (0.0, 0.0),
    (30.0, 0.0),
    (30.0, 180.0),
    (60.0, 0.0),
    (60.0, 180.0),
];

/// Open shortfalls of #17: (preset file, view, light angle, light azimuth, largest excess allowed),
/// measured 2026-12-03 (the excess ×1.1). Cobblestones at 85° with the light at the normal: the
/// specular (+69% of itself, 12% of the light) of the value-conditioned slope mixture, not
/// diagnosed further (its four other entries, 1.3–17%
/// with one slope Gaussian, met the goal once the slopes were conditioned on the image's value,
/// docs/design/slope-masking.md). (Snow under sky at 85°, 5–6% beyond the truth's noise with Smith's masking,
/// met the goal once the masking was conditioned on height and slope jointly: 1.4–1.5%. Terraces, 1.3–1.6% at 0° and
/// 60° with the transfer mixture's 8 bins, met the goal once the mixture had 16: 0.6–0.9%.)
///
/// With the light at 60° (measured 2026-12-05, ×1.1): the transfer curves' bins now take the
/// masking conditioned on the driver's value and slope (docs/design/transfer-curves.md, "Masking
/// that knows the driver's slope"), which met the goal on terraces at 85° and on sponge at 60°
/// and 85° with the light along the view (Smith's bins were up to 12.8% beyond the truth's
/// noise there). Left: terraces at 60° with the light 60° opposite (1.8% beyond; Smith's 4.8%),
/// and sponge at 85°
/// with the light 30° opposite, which the conditioned bins take from 0 to −5% (sponge at 85° is
/// −4 to −5% with the light at the normal and opposite: its pits are hidden a little too much).
/// Snake-skin at 60° with the light opposite is session 21's 45–60° joint-masking shortfall.
const KNOWN: &[(&str, f64, f64, f64, f64)] = &[
    ("cobblestones.ron", 85.0, 0.0, 0.0, 0.087),
    ("snake-skin.ron", 60.0, 60.0, 180.0, 0.0151),
    ("sponge.ron", 85.0, 30.0, 180.0, 0.0447),
    ("terraces.ron", 60.0, 60.0, 180.0, 0.0198),
];

/// The goal of #17 at a view angle.
fn goal(view_deg: f64) -> f64 {
    if view_deg <= 60.0 { 0.01 } else { 0.04 }
}

#[test]
fn every_preset_meets_the_accuracy_goal_or_its_known_bound() {
    let mut failures = vec![];
    let mut rows = 0;
    for (path, text) in presets() {
        let name = std::path::Path::new(&path)
            .file_name()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let m = Material::from_ron(&text).unwrap();
        let p = prepare(&path, &m);
        for view in VIEWS {
            for (light, azimuth) in LIGHTS {
                let cfg = FootprintQuery::far(
                    &p,
                    direction(view.to_radians(), 0.0),
                    direction(light.to_radians(), azimuth.to_radians()),
                );
                let f = p.filtered(&cfg);
                let t = p.ground_truth(&cfg, RAYS, 1);
                let peak = t.mean.iter().copied().fold(0.0f64, f64::max);
                let mut excess = 0.0f64;
                let mut signed = [0.0; 3];
                for k in 0..3 {
                    // Channels far below the brightest (a black colour stop) carry no share.
                    if t.mean[k] <= 1e-3 * peak {
                        continue;
                    }
                    signed[k] = (f[k] - t.mean[k]) / t.mean[k];
                    let beyond = ((f[k] - t.mean[k]).abs() - 3.0 * t.std_error[k]).max(0.0);
                    excess = excess.max(beyond / t.mean[k]);
                }
                let known = KNOWN
                    .iter()
                    .find(|k| k.0 == name && k.1 == view && k.2 == light && k.3 == azimuth)
                    .map(|k| k.4);
                let allowed = known.unwrap_or_else(|| goal(view));
                // Where a glint as bright as the lobe's peak may still be unseen, the truth's
                // standard error cannot be trusted (Evaluator::glint_rays): say so.
                let glint_rays = p.glint_rays(&cfg, t.mean, 0.01);
                eprintln!(
                    "{name:<24} view {view:>2}° light {light:>2}°/{azimuth:>3}°: filtered − truth \
                     {:+.2}% {:+.2}% {:+.2}%, beyond 3 s.e. {:.2}% (allowed {:.2}%{}){}",
                    100.0 * signed[0],
                    100.0 * signed[1],
                    100.0 * signed[2],
                    100.0 * excess,
                    100.0 * allowed,
                    if known.is_some() { ", known" } else { "" },
                    if (RAYS as f64) < glint_rays {
                        format!(" [glints unresolved: {glint_rays:.1e} rays for 1%]")
                    } else {
                        String::new()
                    }
                );
                if known.is_some() && excess <= goal(view) {
                    eprintln!("  (meets the goal now: remove its KNOWN entry)");
                }
                rows += 1;
                if !(excess <= allowed) {
                    failures.push(format!(
                        "({name:?}, {view:.1}, {light:.1}, {azimuth:.1}, {excess:.4})"
                    ));
                }
            }
        }
    }
    assert!(rows >= 4 * VIEWS.len() * LIGHTS.len(), "the preset library");
    assert!(
        failures.is_empty(),
        "beyond the goal or the known bound (as KNOWN entries):\n{}",
        failures.join(",\n")
    );
}

/// #17's grid in full form, for its closing note: every preset × views 0, 30, 45, 60, 75, 85° ×
/// the light at the normal, at 30° and 60° on the view's side and opposite; the filtered model with
/// Smith's masking and with the material's own (the joint slope-conditioned masking for noise
/// drivers) against one ray-traced truth per configuration (`Evaluator::converged_truth`: batches of 50 000
/// rays until its relative standard error is 0.4% and a glint could have shown, at most 2·10⁶). Prints a row per
/// configuration and a summary per preset: the worst excess beyond 3 standard errors in each view
/// band, and how many configurations meet the goal. `cargo test --release -p lodestone-tests --test
/// accuracy -- --ignored --nocapture full_grid`.
#[test]
#[ignore = "a measurement: prints #17's full grid (several minutes)"]
fn full_grid() {
    use lodestone_core::eval::Evaluator;
    use lodestone_core::microfacet::slope_masking::SlopeMasking;
    const FULL_VIEWS: [f64; 6] = [0.0, 30.0, 45.0, 60.0, 75.0, 85.0];
    const FULL_LIGHTS: [(f64, f64); 5] = [
        (0.0, 0.0),
        (30.0, 0.0),
        (30.0, 180.0),
        (60.0, 0.0),
        (60.0, 180.0),
    ];
    let excess = |f: [f64; 3], t: &lodestone_core::eval::Estimate| {
        let peak = t.mean.iter().copied().fold(0.0f64, f64::max);
        let mut e = 0.0f64;
        for k in 0..3 {
            if t.mean[k] <= 1e-3 * peak {
                continue;
            }
            let beyond = ((f[k] - t.mean[k]).abs() - 3.0 * t.std_error[k]).max(0.0);
            e = e.max(beyond / t.mean[k]);
        }
        e
    };
    let mut summary = vec![];
    for (path, text) in presets() {
        let name = std::path::Path::new(&path)
            .file_stem()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let m = Material::from_ron(&text).unwrap();
        let own = prepare(&path, &m);
        let mut ms = m.clone();
        ms.filtering.slope_masking = SlopeMasking::Smith;
        let smith: Evaluator = prepare(&path, &ms);
        // (worst Smith, worst own, met Smith, met own, count) for views ≤ 60° and 75–85°.
        let mut bands = [(0.0f64, 0.0f64, 0, 0, 0); 2];
        for view in FULL_VIEWS {
            for (light, azimuth) in FULL_LIGHTS {
                let cfg = FootprintQuery::far(
                    &own,
                    direction(view.to_radians(), 0.0),
                    direction(light.to_radians(), azimuth.to_radians()),
                );
                let t = own.converged_truth(&cfg, 0.004, 2_000_000);
                let (es, eo) = (
                    excess(smith.filtered(&cfg), &t),
                    excess(own.filtered(&cfg), &t),
                );
                let b = &mut bands[usize::from(view > 60.0)];
                b.0 = b.0.max(es);
                b.1 = b.1.max(eo);
                b.2 += usize::from(es <= goal(view));
                b.3 += usize::from(eo <= goal(view));
                b.4 += 1;
                eprintln!(
                    "{name:<18} view {view:>2}° light {light:>2}°/{azimuth:>3}°: beyond 3 s.e. Smith {:.2}%, own {:.2}%",
                    100.0 * es,
                    100.0 * eo
                );
            }
        }
        summary.push(format!(
            "| {name} | {:.2}% → {:.2}% ({}→{} of {}) | {:.2}% → {:.2}% ({}→{} of {}) |",
            100.0 * bands[0].0,
            100.0 * bands[0].1,
            bands[0].2,
            bands[0].3,
            bands[0].4,
            100.0 * bands[1].0,
            100.0 * bands[1].1,
            bands[1].2,
            bands[1].3,
            bands[1].4,
        ));
    }
    eprintln!("| preset | worst excess 0–60°, Smith → own (met) | 75–85° |");
    eprintln!("|---|---|---|");
    for s in summary {
        eprintln!("{s}");
    }
}
