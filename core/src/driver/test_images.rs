//! Realistic non-Gaussian grayscale images for tests of image drivers (#17 item 6), generated
//! deterministically: bricks with mortar, cracked mud, gravel, tiles with grout, thresholded noise,
//! and smooth fractal noise as the Gaussian-like control. Values are heights in [0, 1].

/// Side of every test image (texels).
pub const SIDE: usize = 256;

/// A hash of integer lattice coordinates and a seed, uniform in [0, 1).
pub fn hash(x: i64, y: i64, seed: u64) -> f64 {
    let mut h = (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ seed.wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^= h >> 33;
    h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    h ^= h >> 33;
    h = h.wrapping_mul(0xC4CE_B9FE_1A85_EC53);
    h ^= h >> 33;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// Smooth value noise in [−1, 1] with lattice period `cell` texels, tiling the image.
fn value_noise(x: f64, y: f64, cell: f64, seed: u64) -> f64 {
    let period = (SIDE as f64 / cell).round().max(1.0) as i64;
    let (u, v) = (x / cell, y / cell);
    let (i, j) = (u.floor() as i64, v.floor() as i64);
    let (fu, fv) = (u - i as f64, v - j as f64);
    let s = |t: f64| t * t * (3.0 - 2.0 * t);
    let at = |a: i64, b: i64| 2.0 * hash(a.rem_euclid(period), b.rem_euclid(period), seed) - 1.0;
    let top = at(i, j) + s(fu) * (at(i + 1, j) - at(i, j));
    let bot = at(i, j + 1) + s(fu) * (at(i + 1, j + 1) - at(i, j + 1));
    top + s(fv) * (bot - top)
}

/// Fractal value noise: octaves from `cell` down to 4 texels, amplitudes halving.
fn fractal(x: f64, y: f64, cell: f64, seed: u64) -> f64 {
    let (mut sum, mut amp, mut c, mut k) = (0.0, 1.0, cell, 0);
    while c >= 4.0 {
        sum += amp * value_noise(x, y, c, seed + k);
        amp *= 0.5;
        c *= 0.5;
        k += 1;
    }
    sum
}

fn image(f: impl Fn(f64, f64) -> f64) -> Vec<f32> {
    let mut out = Vec::with_capacity(SIDE * SIDE);
    for y in 0..SIDE {
        for x in 0..SIDE {
            out.push(f(x as f64 + 0.5, y as f64 + 0.5).clamp(0.0, 1.0) as f32);
        }
    }
    out
}

/// Distance to the nearest and second-nearest of jittered feature points on a `cell` grid
/// (tiling), and the nearest point's cell id.
fn voronoi(x: f64, y: f64, cell: f64, seed: u64) -> (f64, f64, (i64, i64)) {
    let n = (SIDE as f64 / cell).round() as i64;
    let (ci, cj) = ((x / cell).floor() as i64, (y / cell).floor() as i64);
    let (mut d1, mut d2, mut id) = (f64::MAX, f64::MAX, (0, 0));
    for dj in -2..=2 {
        for di in -2..=2 {
            let (i, j) = (ci + di, cj + dj);
            let (wi, wj) = (i.rem_euclid(n), j.rem_euclid(n));
            let px = (i as f64 + 0.15 + 0.7 * hash(wi, wj, seed)) * cell;
            let py = (j as f64 + 0.15 + 0.7 * hash(wi, wj, seed + 1)) * cell;
            let d = ((px - x).powi(2) + (py - y).powi(2)).sqrt();
            if d < d1 {
                (d2, d1, id) = (d1, d, (wi, wj));
            } else if d < d2 {
                d2 = d;
            }
        }
    }
    (d1, d2, id)
}

/// Running-bond bricks 32 × 16 texels with 2-texel mortar (low), per-brick tone and grain.
pub fn bricks() -> Vec<f32> {
    image(|x, y| {
        let row = (y / 16.0).floor();
        let xs = x + if row as i64 % 2 == 1 { 16.0 } else { 0.0 };
        let (bx, by) = (xs.rem_euclid(32.0), y.rem_euclid(16.0));
        let edge = bx.min(32.0 - bx).min(by).min(16.0 - by);
        let brick = hash((xs / 32.0).floor() as i64 % 8, row as i64, 3);
        let body = 0.62 + 0.12 * (brick - 0.5) + 0.04 * fractal(x, y, 8.0, 5);
        // Mortar a texel either side of the joint, a bevel over the next texel.
        let t = ((edge - 1.0) / 1.0).clamp(0.0, 1.0);
        0.12 + 0.02 * fractal(x, y, 4.0, 9) + t * (body - 0.12)
    })
}

/// Cracked mud: domed Voronoi plates (~24 texels) split by dark cracks.
pub fn cracked_mud() -> Vec<f32> {
    image(|x, y| {
        let (d1, d2, _) = voronoi(x, y, 32.0, 11);
        let border = 0.5 * (d2 - d1);
        let crack = ((border - 0.8) / 1.5).clamp(0.0, 1.0);
        let dome = (border / 10.0).min(1.0).sqrt();
        0.05 + crack * (0.45 + 0.2 * dome + 0.05 * fractal(x, y, 16.0, 13))
    })
}

/// Gravel: round stones of radius 3–9 texels, domed, on low sand.
pub fn gravel() -> Vec<f32> {
    image(|x, y| {
        let (d1, _, id) = voronoi(x, y, 16.0, 21);
        let r = 3.0 + 6.0 * hash(id.0, id.1, 23);
        let sand = 0.2 + 0.05 * fractal(x, y, 8.0, 25);
        if d1 < r {
            let dome = (1.0 - (d1 / r).powi(2)).sqrt();
            sand.max(0.35 + 0.4 * dome + 0.1 * hash(id.0, id.1, 27))
        } else {
            sand
        }
    })
}

/// Square tiles 32 texels with 3-texel grout (low), glazed tops with a faint tone per tile.
pub fn tiles() -> Vec<f32> {
    image(|x, y| {
        let (bx, by) = (x.rem_euclid(32.0), y.rem_euclid(32.0));
        let edge = bx.min(32.0 - bx).min(by).min(32.0 - by);
        let tile = hash((x / 32.0).floor() as i64, (y / 32.0).floor() as i64, 31);
        let top = 0.8 + 0.05 * (tile - 0.5) + 0.01 * fractal(x, y, 8.0, 33);
        let t = ((edge - 1.5) / 1.0).clamp(0.0, 1.0);
        0.2 + 0.02 * fractal(x, y, 4.0, 35) + t * (top - 0.2)
    })
}

/// Smooth fractal noise thresholded into two levels (a soft edge of a few texels).
pub fn thresholded_noise() -> Vec<f32> {
    image(|x, y| {
        let v = fractal(x, y, 64.0, 41);
        let t = (v * 6.0).clamp(-1.0, 1.0);
        0.5 + 0.4 * t + 0.03 * fractal(x, y, 4.0, 43)
    })
}

/// Smooth fractal value noise (nearly Gaussian values): the control.
pub fn smooth_noise() -> Vec<f32> {
    image(|x, y| 0.5 + 0.25 * fractal(x, y, 64.0, 51))
}

/// Every test image with its name and whether its histogram is far from Gaussian.
pub fn all() -> Vec<(&'static str, Vec<f32>, bool)> {
    vec![
        ("bricks", bricks(), true),
        ("cracked mud", cracked_mud(), true),
        ("gravel", gravel(), true),
        ("tiles", tiles(), true),
        ("thresholded noise", thresholded_noise(), true),
        ("smooth noise", smooth_noise(), false),
    ]
}
