//! Property tests: every public function stays finite (and in range) on every input the UI can
//! produce, grazing angles and σ → 0 included (docs/numerics.md).

use glam::{DVec2, DVec3};
use lodestone_core::driver::footprint::Footprint;
use lodestone_core::eval::{Evaluator, FootprintQuery};
use lodestone_core::material::{Material, Slopes};
use lodestone_core::math::preconvolved::TableSpec;
use lodestone_core::math::{special, special_f32};
use lodestone_core::microfacet::attribute::mean_attribute_shape;
use lodestone_core::microfacet::effective_height::{HeightFilter, height_moments};
use lodestone_core::microfacet::masking_shadowing::{Correlation, MaskingShadowing};
use lodestone_core::microfacet::slopes::SlopeCov;
use lodestone_core::microfacet::smith::{lambda, visibility_dir};
use lodestone_core::scene::direction::direction;
use proptest::prelude::*;

/// σ in [0, 1e6]: exact zeros, tiny, ordinary and huge values, log-uniformly.
fn sigma() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        Just(1e-9),
        Just(1e6),
        (-12.0f64..6.0).prop_map(|e| 10f64.powf(e))
    ]
}

/// θ in [0°, 90°] with the dangerous ends over-represented, plus a little below the horizon.
fn theta() -> impl Strategy<Value = f64> {
    let half_pi = std::f64::consts::FRAC_PI_2;
    prop_oneof![
        Just(0.0),
        Just(1e-7),
        Just(half_pi),
        Just(89.9f64.to_radians()),
        Just(89.999f64.to_radians()),
        (0.0..half_pi),
        (half_pi - 1e-6..half_pi + 0.3),
    ]
}

fn big_l() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        Just(1e12),
        (-12.0f64..12.0).prop_map(|e| 10f64.powf(e))
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn special_functions_are_finite(x in -1e6f64..1e6, small in -40.0f64..40.0) {
        for v in [x, small] {
            prop_assert!(special::erf(v).is_finite());
            prop_assert!(special::erfc(v).is_finite());
            prop_assert!(special::erfcx(v).is_finite());
            prop_assert!(special::norm_cdf(v).is_finite());
            prop_assert!(special::log_norm_cdf(v).is_finite());
            prop_assert!(special::smith_lambda(v).is_finite());
            let f = v as f32;
            prop_assert!(special_f32::erf(f).is_finite());
            prop_assert!(special_f32::erfc(f).is_finite());
            prop_assert!(special_f32::erfcx(f).is_finite());
            prop_assert!(special_f32::log_norm_cdf(f).is_finite());
            prop_assert!(special_f32::smith_lambda(f).is_finite());
        }
        let p = (small / 80.0 + 0.5).clamp(0.0, 1.0);
        prop_assert!(special::norm_quantile(p).is_finite());
    }

    #[test]
    fn masking_is_finite_and_in_range(
        to in theta(), ti in theta(), po in 0.0f64..6.3, pi in 0.0f64..6.3,
        sx in sigma(), sy in sigma(), t in -50.0f64..50.0,
    ) {
        let s = SlopeCov::from_std(sx, sy);
        let (wo, wi) = (direction(to, po), direction(ti, pi));
        let (lo, li) = (lambda(wo, &s), lambda(wi, &s));
        prop_assert!(lo.is_finite() && lo >= 0.0 && li.is_finite() && li >= 0.0);
        let v = visibility_dir(wo, t, &s);
        prop_assert!((0.0..=1.0).contains(&v));
        for c in [Correlation::Uncorrelated, Correlation::HeightDirection] {
            let m = MaskingShadowing::from_directions(wo, wi, &s, c);
            prop_assert!(m.total.is_finite());
            prop_assert!((0.0..=1.0).contains(&m.mean_shadowing()));
        }
    }

    #[test]
    fn height_distribution_is_finite(l in big_l()) {
        for model in [HeightFilter::Exact, HeightFilter::PaperFit] {
            let h = height_moments(l, model);
            prop_assert!(h.mean.is_finite() && h.std.is_finite() && h.std > 0.0);
        }
        prop_assert!((0.0..=1.0).contains(&mean_attribute_shape(l)));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn footprint_evaluation_is_finite(
        to in theta(), ti in theta(), po in 0.0f64..6.3, pi in 0.0f64..6.3,
        sh in sigma(), sx in sigma(), sy in sigma(), r in (-6.0f64..4.0).prop_map(|e| 10f64.powf(e)),
    ) {
        let mut m = Material::default();
        m.heights.sigma_h = sh;
        m.slopes = Slopes { sigma_nx: sx, sigma_ny: sy };
        m.filtering.table = TableSpec { size_m: 16, size_sigma: 16, sigma_max: 1.0 };
        let p = Evaluator::new(&m).unwrap();
        let cfg = FootprintQuery { wo: direction(to, po), wi: direction(ti, pi), x0: DVec2::new(0.3, -1.7), footprint: Footprint::isotropic(r) };
        for v in [p.naive(&cfg), p.view_independent(&cfg), p.filtered(&cfg)] {
            prop_assert!(v.iter().all(|c| c.is_finite() && *c >= 0.0), "{v:?}");
        }
        let _ = DVec3::Z;
    }
}
