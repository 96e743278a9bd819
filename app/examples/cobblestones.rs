//! Writes `presets/images/cobblestones.png`, the non-Gaussian image driver of the `cobblestones`
//! preset [HNPN14 Fig. 6]: rounded stones on a jittered, tiling grid with mortar between them and a
//! fine grain on top. Its height histogram is strongly skewed (flat tops, a tail of mortar), which is
//! what the paper's Gaussian approximation of explicit data has to survive.
//!
//! `cargo run -p lodestone --example cobblestones` (deterministic; rerun after changing it).

use std::f64::consts::TAU;

const N: u32 = 256;
const CELLS: i64 = 6;

fn hash(x: i64, y: i64, k: u64) -> f64 {
    let mut z = (x as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F))
        .wrapping_add(k.wrapping_mul(0x1656_67B1_9E37_79F9));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// The stone centre of cell (cx, cy), wrapped onto the tile.
fn centre(cx: i64, cy: i64) -> (f64, f64) {
    let (wx, wy) = (cx.rem_euclid(CELLS), cy.rem_euclid(CELLS));
    (
        (cx as f64 + 0.2 + 0.6 * hash(wx, wy, 1)) / CELLS as f64,
        (cy as f64 + 0.2 + 0.6 * hash(wx, wy, 2)) / CELLS as f64,
    )
}

fn height(u: f64, v: f64) -> f64 {
    let (gx, gy) = (
        (u * CELLS as f64).floor() as i64,
        (v * CELLS as f64).floor() as i64,
    );
    // Nearest and second-nearest stone centres (F1, F2) and the nearest stone's cell.
    let (mut f1, mut f2, mut best) = (f64::MAX, f64::MAX, (0, 0));
    for dy in -2..=2 {
        for dx in -2..=2 {
            let (cx, cy) = (gx + dx, gy + dy);
            let (px, py) = centre(cx, cy);
            let d = ((px - u).powi(2) + (py - v).powi(2)).sqrt();
            if d < f1 {
                f2 = f1;
                f1 = d;
                best = (cx.rem_euclid(CELLS), cy.rem_euclid(CELLS));
            } else if d < f2 {
                f2 = d;
            }
        }
    }
    // Distance to the mortar line, in tile units; the stone rises over ~0.03 and is domed.
    let edge = 0.5 * (f2 - f1);
    let rise = 1.0 - (-edge / 0.018).exp();
    let dome = 1.0 - 4.0 * f1 * f1;
    let stone = 0.75 + 0.5 * hash(best.0, best.1, 3);
    let grain = 0.04
        * ((TAU * (23.0 * u + 7.0 * v)).sin() * (TAU * (5.0 * u - 19.0 * v)).cos()
            + 0.5 * (TAU * (41.0 * u + 37.0 * v) + 1.3).sin());
    stone * rise * dome + grain
}

fn main() {
    let img = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(N, N, |x, y| {
        let (u, v) = ((x as f64 + 0.5) / N as f64, (y as f64 + 0.5) / N as f64);
        image::Luma([((height(u, v) * 0.5 + 0.25).clamp(0.0, 1.0) * 65535.0).round() as u16])
    });
    let out =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../presets/images/cobblestones.png");
    img.save(&out).expect("writing the image");
    // Report the statistics the preset's σ_h and colour map were chosen for.
    let v: Vec<f64> = img.pixels().map(|p| f64::from(p.0[0]) / 65535.0).collect();
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let s = (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt();
    let skew = v.iter().map(|x| ((x - m) / s).powi(3)).sum::<f64>() / n;
    let kurt = v.iter().map(|x| ((x - m) / s).powi(4)).sum::<f64>() / n - 3.0;
    println!(
        "wrote {}: mean {m:.4}, std {s:.4}, skewness {skew:.3}, excess kurtosis {kurt:.3}",
        out.display()
    );
}
