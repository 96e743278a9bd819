//! Tests of [`super`].

use super::*;
use crate::fixtures::preset;

fn terraces_table() -> (crate::material::Material, Arc<TransferMaskingTable>) {
    let m = preset("terraces");
    let t = TransferMaskingTable::shared(&m.noise().expect("noise"), &m.heights.transfer)
        .expect("a table");
    (m, t)
}

/// At an azimuth node and a ν node the lookup is the direct conditioned masking at every
/// (value, slope) node (the layout, the stored logarithm and its f32 round trip), back faces
/// hold the last front value, and nothing is NaN between or beyond the nodes.
#[test]
fn the_lookup_at_nodes_is_the_direct_masking() {
    let (m, table) = terraces_table();
    let noise = m.noise().expect("noise");
    let barrier = TransferBarrier::new(&m.heights.transfer, table.sigma_f);
    for (a, j) in [(0usize, 3usize), (3, 8), (6, 11)] {
        let dir = DVec2::from_angle(PI * a as f64 / TABLE_AZIMUTHS as f64);
        let nu = NU_MIN * NU_RATIO.powi(j as i32);
        let process = LineProcess::new(
            noise
                .waves
                .iter()
                .map(|w| (0.5 * w.amplitude * w.amplitude, TAU * w.k.dot(dir))),
        )
        .expect("a process");
        let grid = ProcessGrid::new(&process, NU_MIN);
        let entry = table.lookup(dir, nu);
        let mut checked = 0;
        for i in (0..VALUE_NODES).step_by(3) {
            for s in 0..SLOPE_NODES {
                let (x, t) = (value_node(i), slope_node(s));
                let got = entry[i * SLOPE_NODES + s];
                if barrier.back_face(x, t, nu) {
                    assert_eq!(got, entry[i * SLOPE_NODES + s - 1], "({x}, {t})");
                    continue;
                }
                let want = barrier_log_g1(&grid, &barrier, x, t, nu).max(-MAX_LOG_G1);
                let tol = 1e-4 * (1.0 + want.abs()) + MIN_EXPONENT;
                assert!(
                    (got - want).abs() <= tol,
                    "({x}, {t}), ν {nu}: {got} vs {want}"
                );
                checked += 1;
            }
        }
        assert!(checked > 50, "{checked}");
    }
    for dir in [DVec2::new(f64::NAN, 0.0), DVec2::new(0.3, -0.95)] {
        for nu in [f64::NAN, -1.0, 0.0, 1e-9, 0.77, 1e9, f64::INFINITY] {
            let e = table.lookup(dir, nu);
            assert!(e.iter().all(|v| v.is_finite() && *v <= 0.0), "{dir} {nu}");
            assert!(entry_at(&e, f64::NAN, 0.3).is_finite());
        }
    }
}

/// With no masking (ln G1 ≡ 0) every value is seen and lit; with G1 falling as the driver
/// rises toward the ray, the joint term of a light opposite the eye is below the product of
/// the two means (one slope makes a start hard to see and easy to light: Chebyshev's
/// inequality for a decreasing and an increasing function of t), and along the eye it is
/// above it; a sun below the horizon lights nothing.
#[test]
fn the_bin_visibility_follows_the_hidden_slope() {
    let ray = |entry: [f64; TRANSFER_ENTRY], p: DVec2| RayMasking {
        entry,
        moments: Vec::new(),
        nu: 1.0,
        projection: p,
    };
    let flat = ray([0.0; TRANSFER_ENTRY], DVec2::X);
    assert_eq!(
        bin_visibility(&flat, Some(&flat), 0.3, 0.0, 1.0),
        Some((1.0, 1.0))
    );
    let mut falling = [0.0; TRANSFER_ENTRY];
    for i in 0..VALUE_NODES {
        for s in 0..SLOPE_NODES {
            falling[i * SLOPE_NODES + s] = -0.4 * (slope_node(s) + 4.0);
        }
    }
    let o = ray(falling, DVec2::X);
    let (vo, _) = bin_visibility(&o, None, 0.0, 0.0, 1.0).expect("front faces");
    assert!(vo > 0.0 && vo < 1.0, "{vo}");
    let opposite = ray(falling, -DVec2::X);
    let (_, v_opp) = bin_visibility(&o, Some(&opposite), 0.0, 0.0, 1.0).expect("lit");
    let (_, v_same) = bin_visibility(&o, Some(&o), 0.0, 0.0, 1.0).expect("lit");
    assert!(v_opp < 0.95 * vo * vo, "{v_opp} vs {}", vo * vo);
    assert!(v_same > 1.05 * vo * vo, "{v_same} vs {}", vo * vo);
    // A flat tread (G′ = 0) weighs every slope alike; no node faces the eye → None.
    assert!(bin_visibility(&o, None, 0.0, 1e6, 1.0).is_some());
    let steep = RayMasking {
        projection: DVec2::ZERO,
        nu: 1e-9,
        ..o.clone()
    };
    assert!(bin_visibility(&steep, None, 0.0, 1.0, 1.0).is_some());
    assert_eq!(far_weight(1.0, 1.0), 1.0);
    assert_eq!(far_weight(0.5, 1.0), 0.25);
    assert_eq!(far_weight(f64::NAN, 1.0), 0.0);
    assert_eq!(far_weight(3.0, 0.0), 0.0);
}

/// A ray's weight at the table's value nodes against a dense quadrature of its column (its
/// mass and tilt along the projection); the joint term of a light along the eye is the eye's weight, and
/// of a light opposite it below the product of the two masses where anything is masked (a slope that hides a start
/// from the eye turns it toward the light: Chebyshev's inequality); a sun below the horizon
/// lights nothing.
#[test]
fn visibility_weights_follow_the_table() {
    use crate::driver::footprint::FilteredDriver;
    use crate::microfacet::masking_shadowing::Correlation;
    use crate::scene::direction::direction;
    let (m, table) = terraces_table();
    let [xx, xy, yy] = table.gradient;
    let d = FilteredDriver {
        mean: 0.0,
        std: table.sigma_f,
        mean_gradient: DVec2::ZERO,
        gradient_cov: crate::microfacet::slopes::SlopeCov { xx, xy, yy },
    };
    let sigma_h = m.heights.sigma_h;
    let rays = |l: f64, az: f64| {
        let (wo, wi) = (direction(1.3, 0.0), direction(l, az));
        TransferRays::new(
            &table,
            d,
            (wo, wi),
            wi.z > 0.0,
            sigma_h,
            Correlation::HeightDirection,
        )
    };
    let (along, opposite, down) = (rays(1.3, 0.0), rays(1.0, PI), rays(1.8, 0.0));
    let (mut checked, mut ratio) = (0, 1.0f64);
    for x in [-1.5, -0.75, 0.0, 0.5, 1.0, 2.0] {
        let o = along.ray_weight(x, false).expect("seen");
        let (mass, mean, _) = o.tilted().expect("a Gaussian");
        let p = along.o.projection;
        // A dense midpoint rule over ±9σ of the standard projection.
        let (mut m0, mut m1) = (0.0, 0.0);
        let n = 40_000;
        for k in 0..n {
            let a = -9.0 + 18.0 * (k as f64 + 0.5) / n as f64;
            let g = 18.0 / n as f64
                * crate::math::special::norm_pdf(a)
                * entry_at(&along.o.entry, x, p.length() * a).exp();
            m0 += g;
            m1 += g * a;
        }
        // At value nodes the moments are the column's; the ray's azimuth and ν between the
        // table's nodes blend moments (measured within 0.6% and 0.01 here).
        assert!((mass - m0).abs() <= 0.01 * m0, "x {x}: {mass} vs {m0}");
        let tilt = mean.dot(p.normalize());
        assert!(
            (tilt - m1 / m0).abs() <= 0.02,
            "x {x}: {tilt} vs {}",
            m1 / m0
        );
        checked += usize::from(m0 < 0.9);
        let [eye, joint] = along.visibility_weights(x);
        assert_eq!(eye, Some(o));
        assert_eq!(
            joint,
            Some(o),
            "a light along the eye is seen where the eye sees"
        );
        let [eye, joint] = opposite.visibility_weights(x);
        let (me, mj) = (
            eye.expect("seen").tilted().unwrap().0,
            joint.map_or(0.0, |j| j.tilted().unwrap().0),
        );
        let mi = opposite
            .ray_weight(x, true)
            .map_or(0.0, |w| w.tilted().unwrap().0);
        // Where a value is masked at all the joint term is well below the product (x = −1.5:
        // 0.044 against 0.094); the Gaussian functions' product may exceed it by a rounding
        // where both are nearly 1 (0.08% at x = 0.4).
        ratio = ratio.min(mj / (me * mi));
        assert!(mj <= me * mi * 1.002, "x {x}: {mj} vs {me}·{mi}");
        assert!(down.visibility_weights(x)[1].is_none());
    }
    assert!(checked >= 3, "only {checked} values are masked at all");
    assert!(
        ratio < 0.6,
        "the joint term is never below the product: {ratio}"
    );
}

/// The filtered view with the conditioned bins: at the normal, where nothing is masked or
/// shadowed, it is the per-value mixture (each sub-value's g′), at least as close to it as
/// Smith's bins; everywhere else finite and non-negative, grazing and below the horizon
/// included.
#[test]
fn the_conditioned_bins_are_smiths_where_nothing_is_masked() {
    use crate::eval::{Evaluator, FootprintQuery};
    use crate::scene::direction::direction;
    for name in ["terraces", "sponge"] {
        let m = preset(name);
        let own = Evaluator::new(&m).expect("prepared");
        assert!(own.transfer_masking.is_some(), "{name} conditions its bins");
        let mut smith = own.clone();
        smith.transfer_masking = None;
        let at = |e: &Evaluator, v: f64, l: f64, az: f64| {
            let cfg = FootprintQuery::far(
                e,
                direction(v.to_radians(), 0.0),
                direction(l.to_radians(), az.to_radians()),
            );
            e.filtered(&cfg)
        };
        let (a, b) = (at(&smith, 0.0, 0.0, 0.0), at(&own, 0.0, 0.0, 0.0));
        // At the normal nothing is masked: what differs is the slope scale, each sub-value's
        // own g′ instead of the bin's root mean square, which the 241-node mixture (every
        // value its own g′) evaluates exactly; measured 0.55% from it on terraces, Smith's
        // bins 1.2%.
        let cfg = FootprintQuery::far(&own, glam::DVec3::Z, glam::DVec3::Z);
        let x = own.filtered_mixture(&cfg).expect("mixture");
        for k in 0..3 {
            assert!((b[k] - x[k]).abs() <= 8e-3 * x[k], "{name}: {b:?} vs {x:?}");
            assert!(
                (b[k] - x[k]).abs() <= (a[k] - x[k]).abs() + 1e-3 * x[k],
                "{name}: {b:?} vs {x:?}, Smith's bins {a:?}"
            );
        }
        // Shadowing moves it: the light at 60° opposite the eye at 60°.
        let (a, b) = (at(&smith, 60.0, 60.0, 180.0), at(&own, 60.0, 60.0, 180.0));
        if name == "terraces" {
            assert!(b[0] < 0.95 * a[0], "{a:?} vs {b:?}");
        }
        for v in [0.0, 45.0, 85.0, 89.5] {
            for (l, az) in [(0.0, 0.0), (60.0, 180.0), (89.9, 0.0), (120.0, 90.0)] {
                let r = at(&own, v, l, az);
                assert!(
                    r.iter().all(|c| c.is_finite() && *c >= 0.0),
                    "{v} {l} {az}: {r:?}"
                );
            }
        }
    }
}
