//! How many height evaluations the ground-truth march spends per ray, with the reference step
//! (global Lipschitz bound, `march_heightfield`) against a local second-order step (the exact slope
//! of the gap at the current point plus a bound on its curvature), and whether both find the same
//! first crossing. The measurement behind the octave march of issue #15 (`scene/octave_march.rs`,
//! which adds nested octave levels to this step and is what renders):
//! `cargo run --release -p lodestone-core --example march_steps [PRESET.ron]`.
//!
//! The second-order step: along `p(t) = o + t·d` with `u = d_xy`, the gap `γ(t) = z(t) − σ_h f(x(t))`
//! (identity transfer) has `γ′ = d_z − σ_h ∇f·u` and `|γ″| ≤ M = σ_h Σ|a_i| (2π k_i·u)²`. From a point
//! with gap γ₀ ≥ 0 and slope γ′₀, `γ(t₀ + s) ≥ γ₀ + γ′₀ s − M s²/2 > 0` for
//! `s < (γ′₀ + √(γ′₀² + 2Mγ₀))/M`: a step that cannot cross the surface.

use glam::{DVec2, DVec3};
use lodestone_core::driver::field::DriverField;
use lodestone_core::material::Material;
use lodestone_core::math::random::splitmix;
use lodestone_core::microfacet::transfer::TransferFunction;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::march::{March, march_heightfield};
use lodestone_core::scene::surface::Surface;
use std::cell::Cell;
use std::f64::consts::TAU;

fn main() {
    let path = std::env::args().nth(1);
    let text = match &path {
        Some(p) => std::fs::read_to_string(p).expect("preset"),
        None => include_str!("../../presets/default.ron").to_owned(),
    };
    let m = Material::from_ron(&text).expect("material");
    assert!(
        matches!(m.heights.transfer, TransferFunction::Identity),
        "the second-order bound here is written for the identity transfer"
    );
    let s = Surface::new(&m).expect("a noise driver");
    let DriverField::Noise(noise) = &s.driver else {
        unreachable!()
    };
    let max_abs = {
        // The largest |f| seen on a dense grid: how conservative h_max = σ_h Σ|a_i| is.
        let mut mx = 0.0f64;
        for i in 0..400 {
            for j in 0..400 {
                let x = DVec2::new(i as f64 * 0.05, j as f64 * 0.05);
                mx = mx.max(noise.value(x).abs());
            }
        }
        mx
    };
    println!(
        "{}: {} waves, h_max = σ_h·{:.2} (largest |f| on a 20×20 grid: {:.2})",
        m.name,
        noise.waves.len(),
        s.h_max / s.sigma_h,
        max_abs
    );
    println!(
        "march steps per ray (the 48 bisections of a hit not counted; WGSL does 24)\n\
         view   rays  reference  2nd-order  ratio  same hit  reference from max|f|"
    );
    let mut rng = 11u64;
    for view_deg in [30.0f64, 60.0, 80.0, 85.0] {
        let (mut n_ref, mut n_new, mut n_tight, mut same, rays) =
            (0usize, 0usize, 0usize, 0usize, 400);
        for _ in 0..rays {
            let phi = TAU * splitmix(&mut rng);
            let d = -direction(view_deg.to_radians(), phi);
            let start = DVec2::new(splitmix(&mut rng) * 50.0, splitmix(&mut rng) * 50.0);
            let top = s.h_max * 1.001 + 1e-6;
            let o = DVec3::new(start.x, start.y, top);
            let dxy = DVec2::new(d.x, d.y);
            let r = dxy.length();
            let rate =
                d.z.abs() + s.sigma_h * s.g_lip * s.driver.lipschitz_along(dxy / r.max(1e-300)) * r;
            let count = Cell::new(0usize);
            let height = |x: DVec2| {
                count.set(count.get() + 1);
                s.sigma_h * noise.value(x)
            };
            let t_ref =
                march_heightfield(o, d, rate, s.h_max, s.min_step, March::Reference, height);
            n_ref += count.replace(0) - if t_ref.is_some() { 48 } else { 0 };
            // The same reference march started at the tightest honest top we know here.
            let top2 = s.sigma_h * max_abs * 1.05;
            let o2 = o + d * ((o.z - top2) / -d.z);
            let t2 = march_heightfield(o2, d, rate, s.h_max, s.min_step, March::Reference, height);
            n_tight += count.replace(0) - if t2.is_some() { 48 } else { 0 };
            // Second-order march.
            let u = dxy;
            let m2: f64 = s.sigma_h
                * noise
                    .waves
                    .iter()
                    .map(|w| w.amplitude.abs() * (TAU * w.k.dot(u)).powi(2))
                    .sum::<f64>();
            let mut t = 0.0f64;
            let mut prev = 0.0f64;
            let mut evals = 0usize;
            let t_new = loop {
                let p = o + d * t;
                let (f, grad) = noise.value_and_gradient(DVec2::new(p.x, p.y));
                evals += 1;
                let gap = p.z - s.sigma_h * f;
                if gap < 0.0 {
                    // Bisect between prev (above) and t (below) (not counted).
                    let (mut a, mut b) = (prev, t);
                    for _ in 0..48 {
                        let mid = 0.5 * (a + b);
                        let q = o + d * mid;
                        if q.z - s.sigma_h * noise.value(DVec2::new(q.x, q.y)) >= 0.0 {
                            a = mid;
                        } else {
                            b = mid;
                        }
                    }
                    break Some(a);
                }
                if p.z < -s.h_max - 1.0 {
                    break None;
                }
                let slope = d.z - s.sigma_h * grad.dot(u);
                let step = if m2 > 0.0 {
                    (slope + (slope * slope + 2.0 * m2 * gap).sqrt()) / m2
                } else {
                    gap / d.z.abs()
                };
                prev = t;
                t += step.max(s.min_step);
            };
            n_new += evals;
            match (t_ref, t_new) {
                (Some(a), Some(b)) if (a - b).abs() < 1e-6 * a.max(1.0) => same += 1,
                (None, None) => same += 1,
                _ => {}
            }
        }
        let (a, b, c) = (
            n_ref as f64 / rays as f64,
            n_new as f64 / rays as f64,
            n_tight as f64 / rays as f64,
        );
        println!(
            "{view_deg:>4}°  {rays:>5}  {a:>9.1}  {b:>9.1}  {:>5.2}  {same:>4}/{rays}  {c:>10.1}",
            a / b
        );
    }
}
