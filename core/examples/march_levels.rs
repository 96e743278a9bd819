//! Experiment (#15): wave evaluations per ray of march strategies on the explicit surface.
//! `cargo run --release -p lodestone-core --example march_levels [PRESET.ron]`.

use glam::{DVec2, DVec3};
use lodestone_core::driver::field::DriverField;
use lodestone_core::material::Material;
use lodestone_core::material::transfer::TransferFunction;
use lodestone_core::math::random::splitmix;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::march::{March, march_heightfield};
use lodestone_core::scene::surface::Surface;
use std::cell::Cell;
use std::f64::consts::TAU;

struct Levels {
    ends: Vec<usize>, // exclusive end index of each prefix level
    resid: Vec<f64>,  // Σ|a_i| beyond the level
    lip: Vec<f64>,    // Σ|a_i| 2π|k_i·dxy| up to the level
    curv: Vec<f64>,   // Σ|a_i| (2π k_i·dxy)² up to the level
}

fn main() {
    let path = std::env::args().nth(1);
    let text = match &path {
        Some(p) => std::fs::read_to_string(p).expect("preset"),
        None => include_str!("../../presets/default.ron").to_owned(),
    };
    let m = Material::from_ron(&text).expect("material");
    let s = Surface::new(&m).expect("a noise driver");
    let DriverField::Noise(noise) = &s.driver else {
        unreachable!()
    };
    let identity = matches!(m.heights.transfer, TransferFunction::Identity);
    let n = noise.waves.len();
    let NoiseParamsLike { octaves } = octaves_of(&m);
    let kappa: f64 = std::env::var("KAPPA")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1.0);
    let split: usize = std::env::var("SPLIT")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    // Level ends: octave boundaries, each octave split into `split` parts.
    let groups = octaves * split;
    let mut ends: Vec<usize> = (1..=groups).map(|g| (g * n).div_ceil(groups)).collect();
    ends.dedup();
    println!(
        "{}: {n} waves, {} levels, identity {identity}",
        m.name,
        ends.len()
    );
    println!("view  ref(waves)  2nd  levels1  levels2   hits same");
    let mut rng = 11u64;
    for view_deg in [30.0f64, 60.0, 80.0, 85.0] {
        let rays = 300;
        let mut tay = [(0.0f64, 0.0f64, 0usize); 4];
        let (mut c_ref, mut c_so, mut c_l1, mut c_l2, mut same) = (0.0, 0.0, 0.0, 0.0, 0);
        for _ in 0..rays {
            let phi = TAU * splitmix(&mut rng);
            let d = -direction(view_deg.to_radians(), phi);
            let start = DVec2::new(splitmix(&mut rng) * 50.0, splitmix(&mut rng) * 50.0);
            let top = s.h_max * 1.001 + 1e-6;
            let o = DVec3::new(start.x, start.y, top);
            let dxy = DVec2::new(d.x, d.y);
            let r = dxy.length();
            let rate = d.z.abs() + s.lipschitz_along(dxy / r.max(1e-300)) * r;
            let count = Cell::new(0usize);
            let height = |x: DVec2| {
                count.set(count.get() + 1);
                s.height(x)
            };
            let t_ref = march_heightfield(o, d, rate, s.h_max, s.min_step, March::Fast, height);
            c_ref += (count.get() * n) as f64;
            let lv = Levels {
                resid: ends
                    .iter()
                    .map(|&e| noise.waves[e..].iter().map(|w| w.amplitude.abs()).sum())
                    .collect(),
                lip: ends
                    .iter()
                    .map(|&e| {
                        noise.waves[..e]
                            .iter()
                            .map(|w| w.amplitude.abs() * TAU * w.k.dot(dxy).abs())
                            .sum()
                    })
                    .collect(),
                curv: ends
                    .iter()
                    .map(|&e| {
                        noise.waves[..e]
                            .iter()
                            .map(|w| w.amplitude.abs() * (TAU * w.k.dot(dxy)).powi(2))
                            .sum()
                    })
                    .collect(),
                ends: ends.clone(),
            };
            let full = Levels {
                ends: vec![n],
                resid: vec![0.0],
                lip: vec![*lv.lip.last().unwrap()],
                curv: vec![*lv.curv.last().unwrap()],
            };
            let (t_so, c) = level_march(&s, noise, identity, o, d, &full, true, kappa);
            c_so += c;
            let (_t1, c) = level_march(&s, noise, identity, o, d, &lv, false, kappa);
            c_l1 += c;
            let (t2, c) = level_march(&s, noise, identity, o, d, &lv, true, kappa);
            c_l2 += c;
            for (slot, nn) in [(0usize, 3usize), (1, 4), (2, 6), (3, 8)] {
                let (tt, c, st) = taylor_march(&s, noise, identity, o, d, nn);
                tay[slot].0 += c;
                tay[slot].1 += st as f64;
                if match (t_ref, tt) {
                    (Some(a), Some(b)) => (a - b).abs() < 1e-6 * a.max(1.0),
                    (None, None) => true,
                    _ => false,
                } {
                    tay[slot].2 += 1;
                }
            }
            let ok = |a: Option<f64>, b: Option<f64>| match (a, b) {
                (Some(a), Some(b)) => (a - b).abs() < 1e-6 * a.max(1.0),
                (None, None) => true,
                _ => false,
            };
            if ok(t_ref, t_so) && ok(t_ref, t2) && ok(t_ref, _t1) {
                same += 1;
            } else if std::env::var("SHOW").is_ok() {
                println!("  ref {t_ref:?} so {t_so:?} l1 {_t1:?} l2 {t2:?}");
            }
        }
        let k = rays as f64;
        println!(
            "{view_deg:>4}  {:>8.0}  {:>6.0} {:>7.0} {:>7.0}   {same}/{rays}",
            c_ref / k,
            c_so / k,
            c_l1 / k,
            c_l2 / k
        );
        for (slot, nn) in [(0usize, 3usize), (1, 4), (2, 6), (3, 8)] {
            println!(
                "      taylor{nn}: {:>7.0} waves, {:>5.1} steps, same {}",
                tay[slot].0 / k,
                tay[slot].1 / k,
                tay[slot].2
            );
        }
    }
}

struct NoiseParamsLike {
    octaves: usize,
}
fn octaves_of(m: &Material) -> NoiseParamsLike {
    match &m.driver {
        lodestone_core::material::Driver::Noise(p) => NoiseParamsLike {
            octaves: p.octaves.clamp(1, 12) as usize,
        },
        _ => unreachable!(),
    }
}

/// Level march; cost counted in wave evaluations (value+gradient counted 1.5 when `second`).
#[allow(clippy::too_many_arguments)]
fn level_march(
    s: &Surface,
    noise: &lodestone_core::driver::noise::SumOfSines,
    identity: bool,
    o: DVec3,
    d: DVec3,
    lv: &Levels,
    second: bool,
    kappa: f64,
) -> (Option<f64>, f64) {
    let dxy = DVec2::new(d.x, d.y);
    let nl = lv.ends.len();
    let last = nl - 1;
    let sig = s.sigma_h;
    let gl = s.g_lip;
    let mut j = 0usize;
    let mut t = 0.0f64;
    let mut cost = 0.0;
    let unit = if second { 1.5 } else { 1.0 };
    let mut prev = (0.0f64, 0.0f64);
    for _ in 0..100_000 {
        let p = o + d * t;
        if (d.z < 0.0 && p.z < -s.h_max - 1.0) || (d.z >= 0.0 && p.z > s.h_max * 1.001 + 1e-6) {
            return (None, cost);
        }
        let x = DVec2::new(p.x, p.y);
        // Prefix sums up to level j.
        let mut f = 0.0;
        let mut fd = 0.0;
        let mut best = (f64::NEG_INFINITY, 0usize, 0.0f64);
        let mut start = 0;
        for (i, &e) in lv.ends.iter().enumerate().take(j + 1) {
            for w in &noise.waves[start..e] {
                let (sn, c) = (TAU * w.k.dot(x) + w.phase).sin_cos();
                f += w.amplitude * c;
                fd -= w.amplitude * TAU * sn * w.k.dot(dxy);
            }
            cost += (e - start) as f64 * unit;
            start = e;
            let h = sig * s.transfer.eval(f);
            let gap = p.z - h - sig * gl * lv.resid[i];
            if i == last && gap < 0.0 && t > 0.0 {
                // Crossing: Illinois refinement, counted at 1 per wave.
                let gapf = |tt: f64| {
                    let q = o + d * tt;
                    q.z - s.height(DVec2::new(q.x, q.y))
                };
                let c0 = Cell::new(0);
                let g2 = |tt: f64| {
                    c0.set(c0.get() + 1);
                    gapf(tt)
                };
                let tt = lodestone_core::scene::march::refine(&g2, prev, (t, gap), March::Fast);
                cost += (c0.get() * noise.waves.len()) as f64;
                return (Some(tt), cost);
            }
            if gap < 0.0 && i < last {
                continue;
            }
            let gap = gap.max(0.0);
            let first = {
                let rate = sig * gl * lv.lip[i] - d.z;
                if rate > 0.0 {
                    gap / rate
                } else {
                    f64::INFINITY
                }
            };
            let mut step = first;
            if second {
                let beta = if identity {
                    sig * fd
                } else {
                    sig * gl * fd.abs()
                } - d.z;
                let c = 0.5 * sig * gl * lv.curv[i];
                let s2 = if c > 0.0 {
                    if beta >= 0.0 {
                        2.0 * gap / (beta + (beta * beta + 4.0 * c * gap).sqrt())
                    } else {
                        ((beta * beta + 4.0 * c * gap).sqrt() - beta) / (2.0 * c)
                    }
                } else if beta > 0.0 {
                    gap / beta
                } else {
                    f64::INFINITY
                };
                step = step.max(s2);
            }
            if step > best.0 {
                best = (step, i, gap);
            }
        }
        if best.0 == f64::NEG_INFINITY {
            j = (j + 1).min(last);
            continue;
        }
        let (step, i, gap) = best;
        let step = step.min(1e3);
        // Level for the next point.
        if i < j {
            j = i;
        } else if j < last && gap < kappa * sig * gl * (lv.resid[j] - lv.resid[j + 1]) {
            j += 1;
        }
        if i == last || j == last {
            prev = (t, gap);
        }
        let step = if i == last {
            step.max(s.min_step)
        } else {
            step
        };
        if step < s.min_step && i < last {
            j = last;
            prev = (t, 0.0);
            continue;
        }
        t += step;
    }
    (None, cost)
}

/// Taylor-model march of order `n` (exact derivatives below n, remainder Σ|a_i||ω_i|ⁿ sⁿ/n!).
pub fn taylor_march(
    s: &Surface,
    noise: &lodestone_core::driver::noise::SumOfSines,
    identity: bool,
    o: DVec3,
    d: DVec3,
    n: usize,
) -> (Option<f64>, f64, usize) {
    let dxy = DVec2::new(d.x, d.y);
    let sig = s.sigma_h;
    let gl = s.g_lip;
    let mut fact = 1.0;
    for k in 1..=n {
        fact *= k as f64;
    }
    let rem: f64 = noise
        .waves
        .iter()
        .map(|w| w.amplitude.abs() * (TAU * w.k.dot(dxy)).abs().powi(n as i32))
        .sum::<f64>()
        / fact;
    let mut t = 0.0f64;
    let mut cost = 0.0;
    let mut steps = 0;
    let mut prev = (0.0, 0.0);
    let mut last_step = 0.0f64;
    let lipk: f64 = noise
        .waves
        .iter()
        .map(|w| w.amplitude.abs() * (TAU * w.k.dot(dxy)).abs())
        .sum();
    let m2: f64 = noise
        .waves
        .iter()
        .map(|w| w.amplitude.abs() * (TAU * w.k.dot(dxy)).powi(2))
        .sum();
    for _ in 0..100_000 {
        let p = o + d * t;
        if (d.z < 0.0 && p.z < -s.h_max - 1.0) || (d.z >= 0.0 && p.z > s.h_max * 1.001 + 1e-6) {
            return (None, cost, steps);
        }
        steps += 1;
        let x = DVec2::new(p.x, p.y);
        // Taylor coefficients of f along the ray.
        let mut fk = [0.0f64; 12];
        for w in &noise.waves {
            let om = TAU * w.k.dot(dxy);
            let (sn, c) = (TAU * w.k.dot(x) + w.phase).sin_cos();
            let mut p = w.amplitude;
            let mut f = 1.0;
            for (k, fk) in fk.iter_mut().enumerate().take(n) {
                if k > 0 {
                    f *= k as f64;
                }
                let v = match k % 4 {
                    0 => c,
                    1 => -sn,
                    2 => -c,
                    _ => sn,
                };
                *fk += p * v / f;
                p *= om;
            }
        }
        cost += noise.waves.len() as f64 * 1.5;
        let gap = p.z - sig * s.transfer.eval(fk[0]);
        if gap < 0.0 && t > 0.0 {
            let gapf = |tt: f64| {
                let q = o + d * tt;
                q.z - s.height(DVec2::new(q.x, q.y))
            };
            let c0 = Cell::new(0);
            let g2 = |tt: f64| {
                c0.set(c0.get() + 1);
                gapf(tt)
            };
            let tt = lodestone_core::scene::march::refine(&g2, prev, (t, gap), March::Fast);
            cost += (c0.get() * noise.waves.len()) as f64;
            return (Some(tt), cost, steps);
        }
        let gap = gap.max(0.0);
        let pp1 = sig * fk[1] - d.z;
        // Polynomials in u (per sign for a non-identity transfer): P(u) = gap + d_z u − σ g_lip (±Σ f_k u^k + R u^n).
        let mut polys = [[0.0f64; 13]; 2];
        let signs: &[f64] = if identity { &[1.0] } else { &[1.0, -1.0] };
        for (pi, &sg) in signs.iter().enumerate() {
            let pp = &mut polys[pi];
            pp[0] = gap;
            for k in 1..n {
                pp[k] = -sig * gl * sg * fk[k];
            }
            pp[1] += d.z;
            pp[n] = -sig * gl * rem;
        }
        let positive = |u: f64| -> bool {
            for pp in polys.iter().take(signs.len()) {
                // Bernstein coefficients of pp on [0, u].
                let mut sc = [0.0f64; 13];
                let mut uk = 1.0;
                for k in 0..=n {
                    sc[k] = pp[k] * uk;
                    uk *= u;
                }
                for j in 0..=n {
                    let mut b = 0.0;
                    for k in 0..=j {
                        b += binom(j, k) / binom(n, k) * sc[k];
                    }
                    if b < 0.0 {
                        return false;
                    }
                }
            }
            true
        };
        let lip_step = gap / (sig * gl * lipk - d.z).max(1e-300);
        let so_step = {
            let beta = pp1;
            let c = 0.5 * sig * gl * m2;
            if identity {
                ((beta * beta + 4.0 * c * gap).sqrt() - beta) / (2.0 * c)
            } else {
                0.0
            }
        };
        let mut a = (4.0 * last_step).max(1e-3).max(so_step);
        let mut tries = 0;
        while !positive(a) && tries < 30 {
            a *= 0.5;
            tries += 1;
        }
        if tries == 30 {
            a = 0.0;
        }
        a = a.max(lip_step).max(so_step);
        last_step = a;
        prev = (t, gap);
        t += a.max(s.min_step);
    }
    (None, cost, steps)
}

fn binom(n: usize, k: usize) -> f64 {
    let mut r = 1.0;
    for i in 0..k {
        r = r * (n - i) as f64 / (i + 1) as f64;
    }
    r
}
