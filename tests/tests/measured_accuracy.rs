//! #18 §2: how well the filtered views follow a measured base BRDF that their fit cannot match
//! exactly. Tables of BRDFs unlike the analytic base (GGX lobes with Smith masking and Schlick
//! Fresnel, a metal and a plastic) are read as measured BRDFs on the default preset; the
//! filtered and naive views (the fit and the table at the filtered normal) are compared with the
//! ground truth that looks every facet up in the table, far patch, views 0°–75°.
//!
//! `cargo test -p lodestone-tests --release --test measured_accuracy -- --ignored --nocapture`
//! prints the full grid; the default run checks a few configurations against the bounds measured
//! there. Measured 2026-12-03, 200 000 rays: plastic filtered −17% to +2% (mean |e| 6.6%), gold
//! −49% to +14% (mean 17%), both worst at 75° with the light on the viewer's side, too dark;
//! naive 20–930% off.

use lodestone_core::eval::{Evaluator, FootprintQuery};
use lodestone_core::material::Material;
use lodestone_core::material::measured::MeasuredBrdf;
use lodestone_core::material::merl::{MerlBrdf, ggx_reference};
use lodestone_core::scene::direction::direction;
use lodestone_tests::preset;
use std::sync::Arc;

/// The measured materials: (name, table).
fn tables() -> Vec<(&'static str, MerlBrdf)> {
    vec![
        (
            "gold-like metal (GGX α 0.25)",
            MerlBrdf::tabulate(ggx_reference([0.0; 3], [1.0, 0.78, 0.34], 0.25)),
        ),
        (
            "red plastic (GGX α 0.15)",
            MerlBrdf::tabulate(ggx_reference([0.5, 0.06, 0.05], [0.04; 3], 0.15)),
        ),
    ]
}

/// The default preset with a measured BRDF.
fn evaluator(table: MerlBrdf) -> Evaluator {
    let mut m: Material = preset("default.ron");
    m.brdf.measured = Some("table.binary".into());
    let mut p = Evaluator::new(&m).expect("evaluator");
    p.set_measured(Arc::new(MeasuredBrdf::new(table)));
    p
}

/// (filtered, naive) relative error against the truth, worst channel, and the truth's relative
/// standard error.
fn errors(p: &Evaluator, view: f64, light: (f64, f64), rays: usize) -> (f64, f64, f64) {
    let cfg = FootprintQuery::far(
        p,
        direction(view.to_radians(), 0.0),
        direction(light.0.to_radians(), light.1.to_radians()),
    );
    let t = p.ground_truth(&cfg, rays, 11);
    let (f, n) = (p.filtered(&cfg), p.naive(&cfg));
    let rel = |v: [f64; 3]| {
        (0..3)
            .map(|c| (v[c] - t.mean[c]) / t.mean[c].max(1e-9))
            .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a })
    };
    let se = (0..3)
        .map(|c| t.std_error[c] / t.mean[c].max(1e-9))
        .fold(0.0, f64::max);
    (rel(f), rel(n), se)
}

#[test]
#[ignore = "the full grid: minutes; run with --ignored --nocapture"]
fn measured_grid() {
    for (name, table) in tables() {
        let p = evaluator(table);
        let fit = &p.measured.as_ref().unwrap().fit;
        eprintln!(
            "{name}: fit kd {:.3?}, {} lobes, relative error {:.3?}",
            fit.kd,
            fit.lobes.len(),
            fit.relative_error
        );
        for view in [0.0, 45.0, 60.0, 75.0] {
            for light in [(0.0, 0.0), (30.0, 0.0), (30.0, 180.0), (60.0, 180.0)] {
                let (f, n, se) = errors(&p, view, light, 200_000);
                eprintln!(
                    "  view {view:>4}° light {:>4}°/{:>3}°: filtered {:+6.2}%  naive {:+6.2}%  (truth s.e. {:.2}%)",
                    light.0,
                    light.1,
                    100.0 * f,
                    100.0 * n,
                    100.0 * se
                );
            }
        }
    }
}

/// The red plastic where the fit and its facet-frame correction hold (full grid, 200 000 rays:
/// +0.7% at 0°, +1.4% at 45° and −1.9% at 60° with the light 30° opposite): the filtered view within
/// 5% of the truth that looks every facet up in the table, where naive is 22–390% off.
#[test]
fn the_filtered_view_follows_a_measured_plastic() {
    let (_, table) = tables().swap_remove(1);
    let p = evaluator(table);
    for (view, light) in [
        (0.0, (0.0, 0.0)),
        (45.0, (30.0, 180.0)),
        (60.0, (30.0, 180.0)),
    ] {
        let (f, n, se) = errors(&p, view, light, 20_000);
        eprintln!("view {view}° light {light:?}: filtered {f:+.4}, naive {n:+.4}, s.e. {se:.4}");
        assert!(
            f.abs() < 0.05,
            "view {view}° light {light:?}: filtered {f:+.4}"
        );
        assert!(n.abs() > 0.2, "view {view}° light {light:?}: naive {n:+.4}");
    }
}
