//! Tests of [`super`].

use super::*;

/// A smooth image is interpolated between lattice points and costs only their rays; a
/// reconstruction of exact lattice values is exact for a bilinear image.
#[test]
fn a_bilinear_image_is_reconstructed_exactly_from_its_lattice() {
    let (w, h) = (9, 7);
    let f = |x: usize, y: usize| 1.0 + 0.3 * x as f64 - 0.2 * y as f64 + 0.01 * (x * y) as f64;
    let mean: Vec<f64> = (0..w * h).map(|p| f(p % w, p / w)).collect();
    let sd = vec![0.5; w * h];
    let plan = SamplingPlan::new(w, h, &mean, &sd, 16.0, 4, u32::MAX);
    // Lattice: x ∈ {0, 4, 8}, y ∈ {0, 4, 6}: nine pixels, nothing else shaded.
    assert_eq!(plan.rays.iter().filter(|r| **r > 0).count(), 9);
    let rec = plan.reconstruct(&mean, None);
    for p in 0..w * h {
        assert!((rec[p] - mean[p]).abs() < 1e-12, "pixel {p}");
    }
    // The whole budget on the nine: 16·63/9 = 112 rays each.
    assert_eq!(plan.total_rays(), 9 * 112);
    // No bias; the variance of each shaded pixel shrinks by its 112 rays.
    let mse = plan.expected_mse(&mean, &sd, None);
    assert!(mse < 0.25 / 112.0 + 1e-15 && mse > 0.0);
}

/// An edge the lattice cannot interpolate is shaded; equal σ̂ with step 1 is uniform sampling.
#[test]
fn edges_are_shaded_and_step_one_is_uniform() {
    let (w, h) = (9, 9);
    let mean: Vec<f64> = (0..w * h)
        .map(|p| if p % w < 5 { 0.0 } else { 1.0 })
        .collect();
    let sd = vec![0.1; w * h];
    let plan = SamplingPlan::new(w, h, &mean, &sd, 4.0, 4, u32::MAX);
    for y in 0..h {
        // Pixel x = 5 lies between lattice columns 4 (0) and 8 (1): interpolated 0.25, off by 0.75.
        assert!(plan.rays[y * w + 5] > 0);
        // x = 1 lies between 0 and 4, both 0: interpolated exactly.
        assert_eq!(plan.rays[y * w + 1], 0);
    }
    let uniform = SamplingPlan::new(w, h, &mean, &sd, 4.0, 1, u32::MAX);
    assert!(uniform.rays.iter().all(|r| *r == 4));
    assert!((uniform.expected_mse(&mean, &sd, None) - 0.01 / 4.0).abs() < 1e-15);
}

/// Rays follow σ̂: a pixel predicted three times as noisy gets three times the rays.
#[test]
fn rays_are_in_proportion_to_the_predicted_deviation() {
    let mean = vec![0.0; 4];
    let sd = [1.0, 3.0, 1.0, 3.0];
    let plan = SamplingPlan::new(2, 2, &mean, &sd, 8.0, 1, u32::MAX);
    assert_eq!(plan.rays, vec![4, 12, 4, 12]);
}

/// Garbage predictions and empty images give a plan, not a panic.
#[test]
fn hostile_predictions_give_a_plan() {
    let mean = [f64::NAN, f64::INFINITY, -1.0, 0.0];
    let sd = [f64::NAN, -2.0, f64::INFINITY, 0.0];
    let plan = SamplingPlan::new(2, 2, &mean, &sd, f64::NAN, 0, u32::MAX);
    assert!(plan.rays.iter().all(|r| *r >= 1));
    let empty = SamplingPlan::new(0, 0, &[], &[], 4.0, 2, u32::MAX);
    assert_eq!(empty.total_rays(), 0);
    assert_eq!(empty.expected_mse(&[], &[], None), 0.0);
}

/// With the true image as the guide, interpolation has no bias whatever the image: an edge
/// the lattice misses is reconstructed exactly from exact lattice values.
#[test]
fn a_guide_carries_what_the_lattice_misses() {
    let (w, h) = (9, 9);
    let mean: Vec<f64> = (0..w * h)
        .map(|p| if p % w < 5 { 0.2 } else { 1.0 } + 0.05 * (p / w) as f64)
        .collect();
    let sd = vec![0.0; w * h];
    // Zero deviations: the rule interpolates wherever the plain bilinear error is 0 only.
    let plan = SamplingPlan::new(w, h, &mean, &sd, 4.0, 4, u32::MAX);
    let guide: Vec<f64> = mean.iter().map(|m| m + 0.3).collect();
    let rec = plan.reconstruct(&mean, Some(&guide));
    for p in 0..w * h {
        assert!((rec[p] - mean[p]).abs() < 1e-12, "pixel {p}");
    }
    // Only the lattice shaded (a flat prediction): 8·81/9 = 72 rays on each of its nine.
    let sd = vec![0.2; w * h];
    let coarse = SamplingPlan::new(w, h, &vec![0.0; w * h], &sd, 8.0, 4, u32::MAX);
    assert_eq!(coarse.rays.iter().filter(|r| **r > 0).count(), 9);
    // Unguided, the edge is blurred; guided, only the lattice's noise is left.
    let blurred = coarse.expected_mse(&mean, &sd, None);
    let guided = coarse.expected_mse(&mean, &sd, Some(&guide));
    assert!(guided <= 0.04 / 72.0 + 1e-15, "{guided}");
    assert!(blurred > 10.0 * guided, "{blurred} {guided}");
}

/// A residual the prediction misses inside one cell gets that cell shaded; a residual the
/// noise explains does not.
#[test]
fn refinement_shades_cells_whose_residual_is_not_smooth() {
    let (w, h) = (9, 9);
    let guide = vec![0.5; w * h];
    let sd = vec![0.1; w * h];
    let first = SamplingPlan::new(w, h, &guide, &sd, 2.0, 4, u32::MAX);
    assert_eq!(first.rays.iter().filter(|r| **r > 0).count(), 9);
    // The truth's residual from the guide: 0 except +0.4 at corner (4, 4), which the four
    // cells around it share.
    let mut est = guide.clone();
    est[4 * w + 4] += 0.4;
    let refined = first.refine(&est, &sd, &guide, 16.0, u32::MAX);
    assert!(
        refined.rays.iter().all(|r| *r > 0),
        "all four cells touch (4, 4)"
    );
    // The same bump at noise level (0.1/√18 a corner) leaves the lattice alone.
    let mut quiet = guide.clone();
    quiet[4 * w + 4] += 0.01;
    let kept = first.refine(&quiet, &sd, &guide, 16.0, u32::MAX);
    assert_eq!(kept.rays.iter().filter(|r| **r > 0).count(), 9);
    assert!(kept.rays.iter().zip(&first.rays).all(|(a, b)| a >= b));
    assert!(kept.total_rays() >= 16 * 81 - 9 && kept.total_rays() <= 16 * 81 + 9);
}

/// A first pass over a flat guide whose truth departs from it by an independent realisation
/// per pixel (variance κ·sd², sd = 0.2), its estimates carrying their rays' noise.
fn realisation(kappa: f64, rpp: f64, max_rays: u32, seed: u64) -> RealisationCase {
    let (w, h, sd) = (33, 33, 0.2);
    let mut rng = seed;
    let guide = vec![0.5; w * h];
    let truth: Vec<f64> = guide
        .iter()
        .map(|g| g + kappa.sqrt() * sd * crate::math::random::standard_normal(&mut rng))
        .collect();
    let sds = vec![sd; w * h];
    let first = SamplingPlan::new(w, h, &guide, &sds, rpp / 4.0, 4, max_rays);
    assert_eq!(first.rays.iter().filter(|r| **r > 0).count(), 81);
    let est: Vec<f64> = (0..w * h)
        .map(|p| {
            let n = f64::from(first.rays[p].max(1));
            truth[p] + sd / n.sqrt() * crate::math::random::standard_normal(&mut rng)
        })
        .collect();
    let refined = first.refine(&est, &sds, &guide, rpp, max_rays);
    RealisationCase {
        guide,
        truth,
        sds,
        first,
        refined,
    }
}

struct RealisationCase {
    guide: Vec<f64>,
    truth: Vec<f64>,
    sds: Vec<f64>,
    first: SamplingPlan,
    refined: SamplingPlan,
}

/// The realisation sets where the lattice stops paying: at 4 rays a pixel the lattice's
/// interpolation error (κ sd² (1 + Σw²) ≈ 5.9e-4) is far below uniform noise (sd²/4 = 0.01),
/// so the lattice is kept; at 1024 rays uniform noise (3.9e-5) is far below it, so (nearly)
/// every pixel is shaded. Over eight realisations the refined plan's error is within 10% of
/// the better of the two plans the first pass leaves (the lattice alone; every pixel, the
/// lattice keeping its first-pass rays), and never 30% above it.
#[test]
fn the_realisation_decides_between_lattice_and_every_pixel() {
    let n = 33 * 33;
    for (rpp, want_all) in [(4.0, false), (1024.0, true)] {
        let mut ratios = Vec::new();
        for seed in 1_u64..=8 {
            let c = realisation(0.01, rpp, u32::MAX, seed);
            let shaded = c.refined.rays.iter().filter(|r| **r > 0).count();
            if want_all {
                assert!(shaded >= n * 19 / 20, "rpp {rpp} seed {seed}: {shaded}");
            } else {
                assert!(shaded < n / 4, "rpp {rpp} seed {seed}: {shaded}");
            }
            let g = Some(c.guide.as_slice());
            let mse = |plan: &SamplingPlan| plan.expected_mse(&c.truth, &c.sds, g);
            let lattice = c.first.refine(&c.guide, &c.sds, &c.guide, rpp, u32::MAX);
            let every = SamplingPlan {
                rays: allocate(&vec![true; n], &c.sds, rpp, &c.first.rays, u32::MAX),
                ..c.first.clone()
            };
            let ratio = mse(&c.refined) / mse(&lattice).min(mse(&every));
            assert!(ratio < 1.3, "rpp {rpp} seed {seed}: {ratio}");
            ratios.push(ratio);
            let total = c.refined.total_rays() as f64;
            assert!((total - rpp * n as f64).abs() <= 1.0, "{total}");
        }
        let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
        assert!(mean < 1.1, "rpp {rpp}: {ratios:?}");
    }
}

/// Rays the caps would leave unspent go to more pixels where the realisation says shading
/// them helps; with no realisation the lattice is (nearly) kept, and what its caps cannot
/// take is not traced.
#[test]
fn capped_rays_spill_onto_more_pixels_only_where_it_helps() {
    let mse = |c: &RealisationCase, plan: &SamplingPlan| {
        plan.expected_mse(&c.truth, &c.sds, Some(c.guide.as_slice()))
    };
    // κ = 0.1: an interpolated pixel misses by about 0.1·0.04·1.47 = 5.9e-3, a pixel shaded
    // with the cap's 64 rays by 0.04/64 = 6.3e-4.
    let spilled = realisation(0.1, 64.0, 64, 4);
    let shaded = spilled.refined.rays.iter().filter(|r| **r > 0).count();
    assert!(shaded >= 1089 * 9 / 10, "{shaded}");
    assert!(spilled.refined.rays.iter().all(|r| *r <= 64));
    assert!(spilled.refined.total_rays() as f64 > 60.0 * 1089.0);
    let kept = spilled
        .first
        .refine(&spilled.guide, &spilled.sds, &spilled.guide, 64.0, 64);
    assert!(mse(&spilled, &spilled.refined) < 0.3 * mse(&spilled, &kept));
    let mut ratios = Vec::new();
    for seed in 1..=16 {
        let quiet = realisation(0.0, 64.0, 64, seed);
        let kept = quiet
            .first
            .refine(&quiet.guide, &quiet.sds, &quiet.guide, 64.0, 64);
        assert_eq!(kept.total_rays(), 81 * 64);
        ratios.push(mse(&quiet, &quiet.refined) / mse(&quiet, &kept));
    }
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    assert!(mean < 1.05 && ratios.iter().all(|r| *r < 1.3), "{ratios:?}");
}
