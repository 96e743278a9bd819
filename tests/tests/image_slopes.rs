//! #17, cobblestones: an image's slopes depend on its value (flat stone tops, steep flanks), and a
//! model that gives every value the footprint's one slope covariance (`TransferSlopes::Gaussian`)
//! is 1.5–2% off at 0–60° and 8–17% at 85°. The filtered model's binned mixture splits the
//! footprint's slope covariance among values by the image's own conditional
//! ([`lodestone_core::driver::conditional_slopes`]): measured against the ray-traced truth here,
//! with the 241-node prototype ([`Evaluator::filtered_mixture`]) printed beside it.

use lodestone_core::eval::{Evaluator, FootprintQuery};
use lodestone_core::material::Material;
use lodestone_core::microfacet::height_mixture::TransferSlopes;
use lodestone_core::scene::direction::direction;
use lodestone_tests::{prepare, presets_dir};

/// Ground-truth rays per configuration (seeded: deterministic).
const RAYS: usize = 50_000;

/// `(|estimate − truth| − 3 s.e.)⁺ / truth`, worst channel, and the signed error of the worst one.
fn excess(p: &Evaluator, cfg: &FootprintQuery, estimate: [f64; 3]) -> (f64, f64) {
    let t = p.ground_truth(cfg, RAYS, 1);
    let mut worst = (0.0f64, 0.0f64);
    for k in 0..3 {
        let beyond = ((estimate[k] - t.mean[k]).abs() - 3.0 * t.std_error[k]).max(0.0) / t.mean[k];
        if beyond >= worst.0 {
            worst = (beyond, (estimate[k] - t.mean[k]) / t.mean[k]);
        }
    }
    worst
}

/// Where the one-Gaussian model misses by 1.4–17% (view, light angle, light azimuth), the
/// value-conditioned slopes come within the goal of #17 (1% to 60°, here 1% at 85° too), and at
/// least three times closer than the one Gaussian. Fails with the conditional switched off (the
/// bins are then the one Gaussian: 2.2%, 2.2%, 7.8%, 17.4%).
#[test]
fn value_conditioned_slopes_put_cobblestones_near_the_truth() {
    let path = presets_dir().join("cobblestones.ron");
    let path = path.to_string_lossy().into_owned();
    let m = Material::from_ron(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let p = prepare(&path, &m);
    let mut one = m.clone();
    one.filtering.transfer_slopes = TransferSlopes::Gaussian;
    let pg = prepare(&path, &one);
    // (view, light, azimuth, the mixture's excess allowed).
    for (view, light, azimuth, allowed) in [
        (0.0, 0.0, 0.0, 0.01),
        (60.0, 30.0, 180.0, 0.01),
        (85.0, 30.0, 0.0, 0.01),
        (85.0, 30.0, 180.0, 0.025),
    ] {
        let cfg = FootprintQuery::far(
            &p,
            direction(f64::to_radians(view), 0.0),
            direction(f64::to_radians(light), f64::to_radians(azimuth)),
        );
        let (model, model_signed) = excess(&p, &cfg, pg.filtered(&cfg));
        let (mixture, mixture_signed) = excess(&p, &cfg, p.filtered(&cfg));
        let (_, prototype) = excess(&p, &cfg, p.filtered_mixture(&cfg).unwrap());
        eprintln!(
            "view {view}° light {light}°/{azimuth}°: one Gaussian {:+.2}% (beyond 3 s.e. {:.2}%), \
             value-conditioned bins {:+.2}% ({:.2}%), prototype {:+.2}%",
            100.0 * model_signed,
            100.0 * model,
            100.0 * mixture_signed,
            100.0 * mixture,
            100.0 * prototype
        );
        assert!(mixture <= allowed, "{view}/{light}/{azimuth}: {mixture}");
        assert!(
            mixture_signed.abs() * 3.0 <= model_signed.abs(),
            "{view}/{light}/{azimuth}: {mixture_signed} against {model_signed}"
        );
    }
}
