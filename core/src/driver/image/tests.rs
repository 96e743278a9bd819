//! Tests of [`super`].

use super::*;
use crate::material::colormap::tests::Rng;
use crate::math::rounding::f32_up;

fn random_image(w: usize, h: usize, seed: u64) -> ImageDriver {
    let mut rng = Rng(seed);
    let values: Vec<f32> = (0..w * h)
        .map(|_| (rng.normal() * 2.0 + 5.0) as f32)
        .collect();
    ImageDriver::new(w, h, &values).unwrap()
}

/// A smooth tiling image: a few low harmonics of the tile.
fn smooth_image(w: usize, h: usize) -> ImageDriver {
    let values: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64 / w as f64, (i / w) as f64 / h as f64);
            let t = std::f64::consts::TAU;
            ((t * (2.0 * x + y)).sin() + 0.5 * (t * (3.0 * y - x) + 1.0).cos()) as f32
        })
        .collect();
    ImageDriver::new(w, h, &values).unwrap()
}

#[test]
fn levels_are_exact_box_statistics() {
    let (w, h) = (64, 32);
    let d = random_image(w, h, 11);
    assert_eq!(d.levels.len(), 7);
    // Level 3: each texel is the box statistics of an 8×8 block of level 0, for values and cells.
    let (l0, l3) = (&d.levels[0], &d.levels[3]);
    for (bx, by) in [(0, 0), (3, 2), (7, 3)] {
        let (mut m, mut m2, mut gxx) = (0.0, 0.0, 0.0);
        for y in 0..8 {
            for x in 0..8 {
                let i = (by * 8 + y) * w + bx * 8 + x;
                let v = f64::from(l0.value[i][0]);
                m += v / 64.0;
                m2 += v * v / 64.0;
                gxx += f64::from(l0.grad[i][2]) / 64.0;
            }
        }
        let t = &l3.value[by * l3.width + bx];
        assert!((f64::from(t[0]) - m).abs() < 1e-5);
        assert!((f64::from(t[1]) - m2).abs() < 1e-5);
        assert!((f64::from(l3.grad[by * l3.width + bx][2]) - gxx).abs() < 1e-4);
    }
    // The coarsest level holds the global statistics: mean 0, variance 1 after standardizing.
    let m = d.moments_at(DVec2::new(3.3, 7.1), 99.0);
    assert!(m.mean.abs() < 1e-5 && (m.std() - 1.0).abs() < 1e-4, "{m:?}");
    assert!((d.original_mean - 5.0).abs() < 0.2 && (d.original_std - 2.0).abs() < 0.1);
    assert!((d.mean_std(99.0) - 1.0).abs() < 1e-4);
    // Normal texels: skewness and excess kurtosis near 0 (2048 samples: s.e. 0.05 and 0.11).
    assert!(
        d.skewness.abs() < 0.2 && d.excess_kurtosis.abs() < 0.4,
        "{} {}",
        d.skewness,
        d.excess_kurtosis
    );
    // A two-valued image: skewness 0, excess kurtosis −2 exactly.
    let b = ImageDriver::new(2, 2, &[0.0, 1.0, 1.0, 0.0]).unwrap();
    assert!(b.skewness.abs() < 1e-12 && (b.excess_kurtosis + 2.0).abs() < 1e-12);
    assert!(d.mean_std(0.0) < 1e-3, "f32 rounding only");
}

#[test]
fn cell_gradient_moments_are_exact_averages_of_the_bilinear_surface() {
    let d = random_image(8, 8, 3);
    // Brute force over cell (2, 5): texel centres 2.5..3.5 and 5.5..6.5.
    let n = 200;
    let mut acc = [0.0f64; 5];
    for j in 0..n {
        for i in 0..n {
            let p = DVec2::new(
                2.5 + (i as f64 + 0.5) / n as f64,
                5.5 + (j as f64 + 0.5) / n as f64,
            );
            let (_, g) = d.value_and_gradient(p);
            for (a, v) in acc
                .iter_mut()
                .zip([g.x, g.y, g.x * g.x, g.y * g.y, g.x * g.y])
            {
                *a += v / (n * n) as f64;
            }
        }
    }
    let cellv = d.levels[0].grad[5 * 8 + 2];
    for k in 0..5 {
        assert!(
            (acc[k] - f64::from(cellv[k])).abs() < 2e-3 * (1.0 + acc[k].abs()),
            "{k}: brute force {} stored {}",
            acc[k],
            cellv[k]
        );
    }
    // At lod 0 the sampled gradient moments at the cell's centre are that cell's.
    let m = d.moments_at(DVec2::new(3.0, 6.0), 0.0);
    assert!((m.grad_sq.x_axis.x - f64::from(cellv[2])).abs() < 1e-5);
}

#[test]
fn bilinear_surface_gradient_and_lipschitz_bound() {
    let d = random_image(16, 12, 5);
    let mut rng = Rng(9);
    for _ in 0..2000 {
        let p = DVec2::new(rng.uniform() * 40.0 - 20.0, rng.uniform() * 40.0 - 20.0);
        let dir = DVec2::from_angle(rng.uniform() * 7.0);
        let (f0, g) = d.value_and_gradient(p);
        let e = 1e-6;
        let (f1, _) = d.value_and_gradient(p + dir * e);
        let bound = d.lipschitz.x * dir.x.abs() + d.lipschitz.y * dir.y.abs();
        assert!(((f1 - f0) / e).abs() <= bound * (1.0 + 1e-6) + 1e-6);
        // Away from cell edges the gradient is the derivative.
        let frac = (p - DVec2::splat(0.5)).fract();
        if frac.min_element() > 1e-3 && frac.max_element() < 1.0 - 1e-3 {
            assert!(((f1 - f0) / e - g.dot(dir)).abs() < 1e-4);
        }
        assert!(f0.abs() <= d.max_abs + 1e-12);
    }
    // Wrapping: the tile repeats.
    let a = d.value_and_gradient(DVec2::new(3.2, 4.7)).0;
    let b = d
        .value_and_gradient(DVec2::new(3.2 + 16.0 * 3.0, 4.7 - 12.0 * 2.0))
        .0;
    assert!((a - b).abs() < 1e-9);
}

#[test]
fn footprint_means_are_lipschitz_with_their_levels_constants() {
    // Non-power-of-two sides: levels 16×12, 8×6, 4×3, 2×2, 1×1.
    let d = random_image(16, 12, 5);
    assert_eq!(
        d.levels[0].lipschitz,
        d.lipschitz.map(|v| f64::from(f32_up(v)))
    );
    let coarse = d.levels[2].lipschitz;
    assert!(coarse.x < 0.7 * d.lipschitz.x && coarse.y < 0.7 * d.lipschitz.y);
    let last = d.levels.last().unwrap();
    assert_eq!(last.lipschitz, DVec2::ZERO);
    let mut rng = Rng(17);
    let mut tight: f64 = 0.0;
    for k in 0..3000 {
        let s1 = 0.2 + 8.0 * rng.uniform();
        let s2 = s1 * (0.1 + 0.9 * rng.uniform());
        let rot = DMat2::from_angle(rng.uniform() * 7.0);
        let cov = rot * DMat2::from_diagonal(DVec2::new(s1 * s1, s2 * s2)) * rot.transpose();
        let mut plan = d.plan(cov);
        if k % 3 == 0 {
            // Integer levels with one probe: at texel-centre rows the bound is attained.
            plan = ProbePlan {
                lod: f64::from(k % 5),
                probes: 1,
                step: DVec2::ZERO,
            };
        }
        let lip = d.lod_lipschitz(&plan);
        let p = DVec2::new(rng.uniform() * 40.0 - 20.0, rng.uniform() * 40.0 - 20.0);
        let dir = DVec2::from_angle(rng.uniform() * 7.0);
        let e = 1e-5;
        let slope = (d.footprint_mean(p + dir * e, &plan) - d.footprint_mean(p, &plan)) / e;
        let bound = lip.x * dir.x.abs() + lip.y * dir.y.abs();
        assert!(
            slope.abs() <= bound * (1.0 + 1e-6) + 1e-6,
            "{slope} > {bound}"
        );
        if bound > 0.0 {
            tight = tight.max(slope.abs() / bound);
        }
    }
    assert!(tight > 0.95, "the bound is attained somewhere: {tight}");
}

#[test]
fn probe_plans_follow_the_footprint() {
    let d = random_image(64, 64, 1);
    let iso = d.plan(DMat2::from_diagonal(DVec2::splat(4.0)));
    assert_eq!(iso.probes, 1);
    assert!((iso.lod - lod_for_std(2.0)).abs() < 1e-12);
    assert!((lod_for_std(2.0) - 2.0).abs() < 1e-12 && (lod_for_std(1.0) - 1.0).abs() < 1e-12);
    assert!((lod_for_std(1.5) - (1.0 + (9.0 / 4.0 - 1.0) / 3.0)).abs() < 1e-12);
    // 16:1 along the diagonal: 8 probes along (1, 1)/√2, lod from σ₁/8 = 2 texels.
    let r = DMat2::from_angle(std::f64::consts::FRAC_PI_4);
    let cov = r * DMat2::from_diagonal(DVec2::new(256.0, 1.0)) * r.transpose();
    let an = d.plan(cov);
    assert_eq!(an.probes, 8);
    assert!((an.lod - 2.0).abs() < 1e-9);
    assert_eq!(lod_for_std(0.3), 0.0);
    assert!(lod_for_std(f64::INFINITY).is_finite() && lod_for_std(f64::NAN) == 0.0);
    assert!((an.step.normalize().dot(DVec2::ONE.normalize()).abs() - 1.0).abs() < 1e-9);
    assert!((an.step.length() - 12f64.sqrt() * 2.0).abs() < 1e-9);
    let pt = d.plan(DMat2::ZERO);
    assert_eq!((pt.lod, pt.probes), (0.0, 1));
    let nan = d.plan(DMat2::from_diagonal(DVec2::new(f64::NAN, 1.0)));
    assert!(nan.lod.is_finite());
}

/// Footprint moments against brute-force Gaussian averages of the bilinear surface, averaged over
/// 48 footprint centres (a mip lookup's kernel changes shape with the position inside the texel
/// grid, as on any GPU; on average it has the footprint's variance): σ_f², slope variances within
/// 12%; the mean within 0.03 of the image's unit std on average for isotropic footprints, 0.08
/// along an 8:1 one, where the probes make a box of the Gaussian's variance (the box's sinc ringing
/// against the Gaussian's decay is largest at σ₁ ≈ λ/3, as in this case).
#[test]
fn footprint_moments_match_gaussian_averages() {
    let d = smooth_image(128, 128);
    let mut rng = Rng(4);
    for (sx, sy) in [(3.0, 3.0), (8.0, 2.0), (1.5, 12.0)] {
        let cov = DMat2::from_diagonal(DVec2::new(sx * sx, sy * sy));
        let (mut var_bf, mut var_mip, mut gxx_bf, mut gxx_mip, mut gyy_bf, mut gyy_mip) =
            (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut mean_err = 0.0;
        let centres = 48;
        for _ in 0..centres {
            let c = DVec2::new(rng.uniform() * 128.0, rng.uniform() * 128.0);
            let n = 4000;
            let (mut m, mut m2, mut gxx, mut gyy) = (0.0, 0.0, 0.0, 0.0);
            for _ in 0..n {
                let p = c + DVec2::new(rng.normal() * sx, rng.normal() * sy);
                let (f, g) = d.value_and_gradient(p);
                m += f / n as f64;
                m2 += f * f / n as f64;
                gxx += g.x * g.x / n as f64;
                gyy += g.y * g.y / n as f64;
            }
            let fm = d.footprint_moments(c, cov);
            var_bf += m2 - m * m;
            var_mip += fm.std().powi(2);
            gxx_bf += gxx;
            gxx_mip += fm.grad_sq.x_axis.x;
            gyy_bf += gyy;
            gyy_mip += fm.grad_sq.y_axis.y;
            mean_err += (fm.mean - m).abs() / centres as f64;
            assert!(
                (d.footprint_mean(c, &d.plan(cov)) - fm.mean).abs() < 1e-9,
                "the march's mean is the shading's"
            );
        }
        let rel = |a: f64, b: f64| (a - b).abs() / b;
        let tol = if sx == sy { 0.03 } else { 0.08 };
        assert!(mean_err < tol, "{sx},{sy}: mean error {mean_err}");
        assert!(
            rel(var_mip, var_bf) < 0.12,
            "{sx},{sy}: σ_f² {var_mip} vs {var_bf}"
        );
        assert!(
            rel(gxx_mip, gxx_bf) < 0.12,
            "{sx},{sy}: gxx {gxx_mip} vs {gxx_bf}"
        );
        assert!(
            rel(gyy_mip, gyy_bf) < 0.12,
            "{sx},{sy}: gyy {gyy_mip} vs {gyy_bf}"
        );
    }
}

#[test]
fn constant_image_has_zero_variance_everywhere() {
    let d = ImageDriver::new(5, 3, &[0.25; 15]).unwrap();
    for s in [0.0, 0.7, 3.0, 100.0] {
        let m = d.footprint_moments(
            DVec2::new(0.41, 0.77),
            DMat2::from_diagonal(DVec2::splat(s)),
        );
        assert_eq!((m.mean, m.std()), (0.0, 0.0));
        assert_eq!(m.grad_cov(), DMat2::ZERO);
    }
    assert_eq!(d.original_std, 0.0);
    assert_eq!(d.lipschitz, DVec2::ZERO);
    // Non-finite positions give finite values.
    let (f, g) = d.value_and_gradient(DVec2::new(f64::NAN, f64::INFINITY));
    assert!(f.is_finite() && g.is_finite());
}

#[test]
fn bad_images_are_errors() {
    assert!(matches!(
        ImageDriver::new(0, 4, &[]),
        Err(ImageDriverError::BadSize { .. })
    ));
    assert!(matches!(
        ImageDriver::new(2, 2, &[0.0; 3]),
        Err(ImageDriverError::BadSize { .. })
    ));
    assert_eq!(
        ImageDriver::new(2, 1, &[0.0, f32::NAN]),
        Err(ImageDriverError::NotFinite { x: 1, y: 0 })
    );
    assert!(matches!(
        ImageDriver::new(9000, 1, &vec![0.0; 9000]),
        Err(ImageDriverError::TooLarge { .. })
    ));
}
