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

/// Why cobblestones at 85° with the light at the normal is still 7–9% bright (its specular +69%
/// of itself): the explicit surface sampled on a 400² grid of the tile, split into 8 bins of equal
/// probability of the value, each bin's specular lobe without masking against the Gaussian of
/// that bin's own slopes ([`filtered_specular`]), and the visibility along the view of the facets
/// under the lobe (lobe-weighted) against the bin's average facet. Measurement (docs/design/image-drivers.md,
/// "Cobblestones at 85°: the grooves' far walls"): `cargo test --release -p lodestone-tests --test
/// image_slopes -- --ignored --nocapture grazing_specular_by_value`.
#[test]
#[ignore = "a measurement: prints the specular lobe and its masking per value bin"]
fn grazing_specular_by_value() {
    use glam::{DVec2, DVec3};
    use lodestone_core::microfacet::brdf::filtered_specular;
    use lodestone_core::microfacet::slopes::{SlopeCov, normal_of};
    let path = presets_dir().join("cobblestones.ron");
    let path = path.to_string_lossy().into_owned();
    let m = Material::from_ron(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let p = prepare(&path, &m);
    let s = &p.surface;
    let n = 400;
    let mut samples: Vec<(f64, f64, DVec2, DVec2)> = (0..n * n)
        .map(|k| {
            let x = DVec2::new(
                ((k % n) as f64 + 0.37) / n as f64,
                ((k / n) as f64 + 0.61) / n as f64,
            );
            let (f, h, g) = s.sample(x);
            (f, h, g, x)
        })
        .collect();
    samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (view, light, az) in [
        (85.0f64, 0.0f64, 0.0f64),
        (85.0, 30.0, 180.0),
        (75.0, 0.0, 0.0),
    ] {
        let wo = direction(view.to_radians(), 0.0);
        let wi = direction(light.to_radians(), az.to_radians());
        eprintln!("view {view}°, light {light}°/{az}°:");
        let bins = 8;
        for b in 0..bins {
            let part = &samples[b * samples.len() / bins..(b + 1) * samples.len() / bins];
            let k = part.len() as f64;
            let mean = part.iter().map(|q| q.2).sum::<DVec2>() / k;
            let (mut xx, mut yy, mut xy) = (0.0, 0.0, 0.0);
            let (mut area, mut lobe, mut lobe_seen, mut area_seen) = (0.0, 0.0, 0.0, 0.0);
            for &(_f, h, g, x) in part {
                let d = g - mean;
                xx += d.x * d.x / k;
                yy += d.y * d.y / k;
                xy += d.x * d.y / k;
                // Projected area toward the eye per unit of the mean plane.
                let u = wo.z - g.x * wo.x - g.y * wo.y;
                if u <= 0.0 {
                    continue;
                }
                let spec = m
                    .brdf
                    .specular_with(normal_of(g), wo, wi, SlopeCov::default());
                let seen = if s.sees(DVec3::new(x.x, x.y, h), wo) {
                    1.0
                } else {
                    0.0
                };
                area += u;
                lobe += spec * u;
                lobe_seen += spec * u * seen;
                area_seen += u * seen;
            }
            let gauss = filtered_specular(
                m.brdf.specular,
                m.brdf.roughness,
                mean,
                &SlopeCov { xx, yy, xy },
                wo,
                wi,
            );
            eprintln!(
                "  bin {b} (f {:+.2} … {:+.2}, slope std {:.3}): lobe truth {:.3e}, its bin's Gaussian {:.3e} \
                 ({:+.0}%); visibility along the view: lobe-weighted {:.3}, the bin's {:.3}",
                part[0].0,
                part[part.len() - 1].0,
                (0.5 * (xx + yy)).sqrt(),
                lobe / area,
                gauss,
                100.0 * (gauss * area / lobe - 1.0),
                lobe_seen / lobe.max(1e-300),
                area_seen / area,
            );
        }
    }
}
