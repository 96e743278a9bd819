//! Tests of [`super`].

use super::*;
use crate::material::colormap::tests::Rng;
use crate::material::validation::Problems;

#[test]
fn monotone_cubic_interpolates_and_does_not_overshoot() {
    for c in [Curve::moss(), Curve::sponge(), Curve::terraces(4)] {
        let t = TransferFunction::Curve(c.clone());
        for p in &c.points {
            assert!(
                (t.eval(p[0]) - p[1]).abs() < 1e-12,
                "passes through its points"
            );
        }
        let mut prev = f64::NEG_INFINITY;
        for i in 0..=2000 {
            let f = -4.0 + 8.0 * f64::from(i) / 2000.0;
            let g = t.eval(f);
            assert!(g >= prev - 1e-12, "monotone at f={f}");
            prev = g;
            // g′ agrees with a finite difference.
            let fd = (t.eval(f + 1e-6) - t.eval(f - 1e-6)) / 2e-6;
            let knot_near = c.points.iter().any(|p| (p[0] - f).abs() < 2e-6);
            if !knot_near {
                assert!(
                    (fd - t.derivative(f)).abs() < 1e-5 * (1.0 + fd.abs()),
                    "g′ at {f}"
                );
            }
        }
    }
}

#[test]
fn named_shapes_are_normalised() {
    for c in [Curve::moss(), Curve::sponge(), Curve::terraces(5)] {
        let m = TransferFunction::Curve(c).moments(0.0, 1.0);
        assert!(m.mean.abs() < 1e-12 && (m.std - 1.0).abs() < 1e-12, "{m:?}");
    }
}

#[test]
fn moments_match_monte_carlo_and_tables() {
    let t = TransferFunction::Curve(Curve::moss());
    let table = t
        .preconvolve(TableSpec::default())
        .expect("curve has a table");
    let mut rng = Rng(3);
    for &(m, s) in &[(0.0, 1.0), (0.5, 0.3), (-1.0, 0.6)] {
        let n = 400_000;
        let (mut a, mut b, mut c, mut d) = (0.0, 0.0, 0.0, 0.0);
        for _ in 0..n {
            let f = m + s * rng.normal();
            let (g, gd) = (t.eval(f), t.derivative(f));
            a += g;
            b += g * g;
            c += gd;
            d += gd * gd;
        }
        let nf = n as f64;
        let (mg, md) = (a / nf, c / nf);
        let want = [mg, (b / nf - mg * mg).sqrt(), md, (d / nf - md * md).sqrt()];
        let exact = t.moments(m, s);
        let got = [exact.mean, exact.std, exact.mean_deriv, exact.std_deriv];
        let tab = table.sample(m, s);
        for k in 0..4 {
            assert!(
                (got[k] - want[k]).abs() < 6e-3,
                "m={m} σ={s} moment {k}: {} vs MC {}",
                got[k],
                want[k]
            );
            assert!(
                (tab[k] - got[k]).abs() < 3e-3,
                "table vs exact, moment {k}: {} vs {}",
                tab[k],
                got[k]
            );
        }
    }
}

#[test]
fn identity_gives_gaussian_statistics() {
    let st = transformed_statistics(
        TransferFunction::Identity.moments(0.2, 0.7),
        2.0,
        DVec2::new(0.1, -0.3),
        SlopeCov {
            xx: 0.04,
            yy: 0.09,
            xy: 0.01,
        },
    );
    assert!((st.height_mean - 0.4).abs() < 1e-15 && (st.height_std - 1.4).abs() < 1e-15);
    assert!((st.slope_mean - DVec2::new(0.2, -0.6)).length() < 1e-15);
    assert!((st.slope_cov.xx - 0.16).abs() < 1e-15 && (st.slope_cov.xy - 0.04).abs() < 1e-15);
}

#[test]
fn vertical_segments_and_validation() {
    let c = Curve {
        points: vec![[-1.0, 0.0], [0.0, 0.0], [0.0, 1.0], [1.0, 1.0]],
        interpolation: CurveInterpolation::Linear,
    };
    let t = TransferFunction::Curve(c.clone());
    assert_eq!(t.eval(-0.5), 0.0);
    assert_eq!(t.eval(0.5), 1.0);
    let m = t.moments(0.0, 0.5);
    assert!((m.mean - 0.5).abs() < 1e-12 && m.mean_deriv == 0.0);
    let mut p = Problems::default();
    Curve {
        points: vec![[1.0, f64::NAN], [0.0, 0.0]],
        interpolation: CurveInterpolation::Linear,
    }
    .validate("t", &mut p);
    assert_eq!(p.0.len(), 2);
}

#[test]
fn shape_of_identity_and_curves() {
    let id = TransferFunction::Identity.shape();
    assert!(
        id.skewness.abs() < 1e-9 && id.excess_kurtosis.abs() < 1e-6,
        "{id:?}"
    );
    assert!(id.slope_excess_kurtosis.abs() < 1e-9);
    assert!(!id.far_from_gaussian());
    // A curve with flats: slopes concentrate at 0 with a tail (positive slope kurtosis).
    let moss = TransferFunction::Curve(Curve::moss()).shape();
    assert!(moss.slope_excess_kurtosis > 1.0, "{moss:?}");
    assert!(moss.far_from_gaussian());
    // Brute force of the slope kurtosis by sampling f on a fine grid.
    let t = TransferFunction::Curve(Curve::moss());
    let (mut d2, mut d4, mut w) = (0.0, 0.0, 0.0);
    for i in 0..200_000 {
        let f = -8.0 + 16.0 * (i as f64 + 0.5) / 200_000.0;
        let p = crate::math::special::norm_pdf(f);
        let d = t.derivative(f);
        d2 += p * d * d;
        d4 += p * d.powi(4);
        w += p;
    }
    let brute = 3.0 * ((d4 / w) / (d2 / w).powi(2) - 1.0);
    assert!(
        (brute - moss.slope_excess_kurtosis).abs() < 1e-3 * brute.abs(),
        "{brute} vs {moss:?}"
    );
}
