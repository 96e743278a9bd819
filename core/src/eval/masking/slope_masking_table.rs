//! A noise material's table of slope-conditioned masking
//! ([`crate::microfacet::slope_masking::JointMasking`], #17): `ln r` at every (height, slope) node,
//! over the ray's azimuth, the footprint's scale and the ray's slope ν, in f32 as the GPU reads
//! them. Core's filtered model looks up the same values, so the views and core agree; the direct
//! computation stays the definition of each entry (tested against the lookup between nodes).
//!
//! Axes:
//! - **azimuth** φ of the ray's horizontal direction, [`TABLE_AZIMUTHS`] nodes over [0, π)
//!   (periodic: the process along −d is the one along d, and the slope is measured along the ray);
//! - **level**: the footprint's standard deviation along the ray's azimuth, `r = √(dᵀΣ_p d)`, on
//!   [`TABLE_LEVELS`] geometric nodes from `r₀ = 1/|k|_min` (every wave unresolved to 3e-9) down
//!   to `0.1/|k|_max`; each node's process is what an isotropic footprint of that r leaves,
//!   `½a_i²(1 − g_i²)` (`g_i = exp(−2π²|k_i|²r²)`). Between nodes, linear in ln r; clamped at the
//!   ends;
//! - **ν** = μ/σ_t, [`TABLE_NUS`] nodes `NU_MIN·NU_RATIO^j` (0.08 to 6.9), linear in ln ν, clamped.

use crate::driver::noise::SumOfSines;
use crate::microfacet::slope_masking::{
    HEIGHT_NODES, JointMasking, LineProcess, ProcessGrid, SLOPE_NODES, joint_masking_on, slope_node,
};
use glam::DVec2;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};
use std::sync::{Arc, Mutex};

/// Azimuth nodes over [0, π).
pub const TABLE_AZIMUTHS: usize = 8;
/// Footprint-scale nodes.
pub const TABLE_LEVELS: usize = 8;
/// ν nodes.
pub const TABLE_NUS: usize = 12;
/// The smallest ν node.
pub const NU_MIN: f64 = 0.08;
/// The ratio of successive ν nodes.
pub const NU_RATIO: f64 = 1.5;
/// f32 values per entry: `ln r` of [`JointMasking`] at every (height, slope) node, height-major.
pub const ENTRY: usize = HEIGHT_NODES * SLOPE_NODES;

/// The table (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct SlopeMaskingTable {
    /// The footprint scale of level 0.
    pub r0: f64,
    /// ln of the ratio of successive levels' scales (> 0).
    pub level_step: f64,
    /// `ENTRY` values per (azimuth, level, ν), ν fastest.
    pub data: Vec<f32>,
}

/// Tables built in this process, by their waves' shape, with the first wave vector's length they
/// were built for (at most [`CACHE_SIZE`]; a material edited back and forth, and the tests' many
/// evaluators of the same presets, build each once).
static CACHE: Mutex<Vec<CacheEntry>> = Mutex::new(Vec::new());

/// A cached table: the waves' shape, the table, the first wave vector's length it was built for.
type CacheEntry = (Vec<u64>, Arc<SlopeMaskingTable>, f64);

/// Tables the process keeps ([`SlopeMaskingTable::shared`]).
const CACHE_SIZE: usize = 16;

impl SlopeMaskingTable {
    /// [`SlopeMaskingTable::new`] through a process-wide cache keyed by the waves' shape: their
    /// wave vectors over the first one's length and amplitudes over the first one's, exactly.
    /// The table does not depend on the scale of either (each process is normalised to unit
    /// height and slope variance, and the footprint levels scale with `1/|k|`), so a material
    /// whose σ_h or feature size changed reuses it with `r0` rescaled: about a second of CPU
    /// saved for each such material, and for each material seen again.
    pub fn shared(noise: &SumOfSines) -> Option<Arc<Self>> {
        let first = noise.waves.first()?;
        let (k_ref, a_ref) = (first.k.length(), first.amplitude);
        if !(k_ref > 0.0 && k_ref.is_finite() && a_ref != 0.0 && a_ref.is_finite()) {
            return Self::new(noise).map(Arc::new);
        }
        let key: Vec<u64> = noise
            .waves
            .iter()
            .flat_map(|w| {
                let k = w.k / k_ref;
                [
                    k.x.to_bits(),
                    k.y.to_bits(),
                    (w.amplitude / a_ref).to_bits(),
                ]
            })
            .collect();
        let lock = || {
            CACHE
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
        };
        let found = lock()
            .iter()
            .find(|(k, _, _)| *k == key)
            .map(|(_, t, k_old)| (t.clone(), *k_old));
        if let Some((t, k_old)) = found {
            if k_old == k_ref {
                return Some(t);
            }
            return Some(Arc::new(Self {
                r0: t.r0 * k_old / k_ref,
                ..(*t).clone()
            }));
        }
        let table = Arc::new(Self::new(noise)?);
        let mut cache = lock();
        if cache.len() >= CACHE_SIZE {
            cache.remove(0);
        }
        cache.push((key, table.clone(), k_ref));
        Some(table)
    }

    /// Tabulate the noise's profiles (in parallel over azimuths and levels). `None` without waves.
    pub fn new(noise: &SumOfSines) -> Option<Self> {
        let (k_min, k_max) = noise
            .waves
            .iter()
            .map(|w| w.k.length())
            .filter(|k| k.is_finite() && *k > 0.0)
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), k| {
                (lo.min(k), hi.max(k))
            });
        if !(k_min.is_finite() && k_max > 0.0) {
            return None;
        }
        let r0 = 1.0 / k_min;
        let r_last = 0.1 / k_max;
        let level_step = ((r0 / r_last).ln() / (TABLE_LEVELS - 1) as f64).max(1e-3);
        let rows: Vec<Vec<f32>> = (0..TABLE_AZIMUTHS * TABLE_LEVELS)
            .into_par_iter()
            .map(|row| {
                let (a, l) = (row / TABLE_LEVELS, row % TABLE_LEVELS);
                let dir = DVec2::from_angle(PI * a as f64 / TABLE_AZIMUTHS as f64);
                let r = r0 * (-(l as f64) * level_step).exp();
                let process = LineProcess::new(noise.waves.iter().map(|w| {
                    let g = (-2.0 * PI * PI * w.k.length_squared() * r * r).exp();
                    (
                        0.5 * w.amplitude * w.amplitude * (1.0 - g * g).max(0.0),
                        TAU * w.k.dot(dir),
                    )
                }));
                let grid = process.as_ref().map(|p| ProcessGrid::new(p, nu_node(0)));
                let mut out = Vec::with_capacity(TABLE_NUS * ENTRY);
                for j in 0..TABLE_NUS {
                    let c = match &grid {
                        Some(g) => joint_masking_on(g, nu_node(j)),
                        None => JointMasking::none(),
                    };
                    out.extend(c.log_ratio.iter().flatten().map(|v| *v as f32));
                }
                out
            })
            .collect();
        Some(Self {
            r0,
            level_step,
            data: rows.concat(),
        })
    }

    /// The masking for a ray of horizontal direction `dir` (unit), a footprint of standard
    /// deviation `r` along it and slope `nu`: `ln r` multilinear between the nodes (module
    /// docs), at the height rows `rows.0..=rows.1` ([`crate::microfacet::slope_masking::height_rows`]
    /// of the heights the caller reads; the others stay 0: on the GPU the lookup is the filtered
    /// view's largest cost, and a grazing view's D_h covers 4–7 of the 10 rows). Of each entry
    /// only the front slopes are read ([`front_columns`]); the back faces hold the last front
    /// value in the table, so they get it without reading it again (the same sum). Non-finite
    /// inputs are clamped to the first nodes.
    pub fn lookup(&self, dir: DVec2, r: f64, nu: f64, rows: (usize, usize)) -> JointMasking {
        let (a0, a1, fa) = azimuth_coordinate(dir);
        let lv = if r > 0.0 && r.is_finite() {
            ((self.r0 / r).ln() / self.level_step).clamp(0.0, (TABLE_LEVELS - 1) as f64)
        } else if r > 0.0 {
            0.0
        } else {
            (TABLE_LEVELS - 1) as f64
        };
        let (l0, fl) = split(lv, TABLE_LEVELS);
        let (n0, fn_) = nu_coordinate(nu);
        let (first, last) = (rows.0.min(HEIGHT_NODES - 1), rows.1.min(HEIGHT_NODES - 1));
        let span = first * SLOPE_NODES..(last + 1) * SLOPE_NODES;
        let mut acc = [0.0f64; ENTRY];
        for (a, wa) in [(a0, 1.0 - fa), (a1, fa)] {
            for (l, wl) in [(l0, 1.0 - fl), (l0 + 1, fl)] {
                for (n, wn) in [(n0, 1.0 - fn_), (n0 + 1, fn_)] {
                    let w = wa * wl * wn;
                    if w == 0.0 {
                        continue;
                    }
                    let base = ((a * TABLE_LEVELS + l) * TABLE_NUS + n) * ENTRY;
                    let front = front_columns(n);
                    for row in span.clone().step_by(SLOPE_NODES) {
                        let entry = &self.data[base + row..base + row + SLOPE_NODES];
                        for (j, o) in acc[row..row + SLOPE_NODES].iter_mut().enumerate() {
                            *o += w * f64::from(entry[j.min(front - 1)]);
                        }
                    }
                }
            }
        }
        let mut out = JointMasking::none();
        for (i, row) in out.log_ratio.iter_mut().enumerate() {
            row.copy_from_slice(&acc[i * SLOPE_NODES..(i + 1) * SLOPE_NODES]);
        }
        out
    }
}

/// ν of node `j`.
pub fn nu_node(j: usize) -> f64 {
    NU_MIN * NU_RATIO.powi(j as i32)
}

/// The slope columns of ν node `n` that are front faces, `z_j < ν_n` (`z_j = j − 4`): the first
/// `⌈ν_n + 4⌉` (5 to 9, since ν > 0); the rest hold the last of them
/// ([`crate::microfacet::slope_masking::joint_masking_on`]).
pub fn front_columns(n: usize) -> usize {
    ((nu_node(n) - slope_node(0)).ceil() as usize).clamp(1, SLOPE_NODES)
}

/// The two azimuth nodes around `dir` and the weight of the second (periodic over π).
pub(in crate::eval) fn azimuth_coordinate(dir: DVec2) -> (usize, usize, f64) {
    let phi = dir.y.atan2(dir.x).rem_euclid(PI);
    let x = if phi.is_finite() {
        phi / PI * TABLE_AZIMUTHS as f64
    } else {
        0.0
    };
    let i = (x.floor() as usize).min(TABLE_AZIMUTHS - 1);
    let f = (x - i as f64).clamp(0.0, 1.0);
    (i, (i + 1) % TABLE_AZIMUTHS, f)
}

/// The ν nodes `n, n + 1` around `nu` and the weight of `n + 1`, linear in ln ν and clamped to
/// the end nodes (NaN and ν ≤ 0 read the first node, +∞ the last).
pub(in crate::eval) fn nu_coordinate(nu: f64) -> (usize, f64) {
    let nv = if nu > 0.0 && nu.is_finite() {
        ((nu / NU_MIN).ln() / NU_RATIO.ln()).clamp(0.0, (TABLE_NUS - 1) as f64)
    } else if nu > 0.0 {
        (TABLE_NUS - 1) as f64
    } else {
        0.0
    };
    split(nv, TABLE_NUS)
}

/// A clamped coordinate in `[0, n − 1]` as the lower node (at most n − 2) and the fraction.
fn split(x: f64, n: usize) -> (usize, f64) {
    let i = (x as usize).min(n - 2);
    (i, x - i as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::masking::slope_weights::{SlopeWeights, height_span};
    use crate::fixtures::preset;
    use crate::microfacet::effective_height::HeightMoments;
    use crate::microfacet::slope_masking::{MAX_LOG_RATIO, height_node};

    /// The shared table of a noise scaled in feature size and amplitude is the one built for it.
    #[test]
    fn a_scaled_noise_shares_its_table() {
        let noise = preset("grooves").noise().expect("noise");
        let base = SlopeMaskingTable::shared(&noise).expect("table");
        let mut scaled = noise.clone();
        for w in &mut scaled.waves {
            w.k *= 2.7;
            w.amplitude *= 0.03;
        }
        let shared = SlopeMaskingTable::shared(&scaled).expect("table");
        let built = SlopeMaskingTable::new(&scaled).expect("table");
        assert!(
            (shared.r0 / built.r0 - 1.0).abs() < 1e-12,
            "{} {}",
            shared.r0,
            built.r0
        );
        assert!((shared.r0 * 2.7 / base.r0 - 1.0).abs() < 1e-12);
        assert_eq!(shared.level_step.to_bits(), built.level_step.to_bits());
        let worst = shared
            .data
            .iter()
            .zip(&built.data)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-4, "{worst}");
    }

    #[test]
    fn the_lookup_between_nodes_follows_the_direct_masking() {
        let m = preset("snake-skin");
        let noise = m.noise().expect("noise");
        let t0 = std::time::Instant::now();
        let table = SlopeMaskingTable::new(&noise).expect("table");
        eprintln!("table built in {:.0} ms", t0.elapsed().as_secs_f64() * 1e3);
        // Off every node: an azimuth between two, a footprint between levels, ν between nodes.
        for (phi, level, nu) in [(0.3, 0.0, 0.5), (1.9, 2.5, 1.1), (2.9, 5.3, 0.25)] {
            let dir = DVec2::from_angle(phi);
            let r = table.r0 * (-level * table.level_step).exp();
            let process = LineProcess::new(noise.waves.iter().map(|w| {
                let g = (-2.0 * PI * PI * w.k.length_squared() * r * r).exp();
                (
                    0.5 * w.amplitude * w.amplitude * (1.0 - g * g),
                    TAU * w.k.dot(dir),
                )
            }))
            .expect("process");
            let direct = joint_masking_on(&ProcessGrid::new(&process, nu), nu);
            let looked = table.lookup(dir, r, nu, (0, HEIGHT_NODES - 1));
            // From −0.5σ up and on the front slopes, the ratio r within 6% (ln r within 0.06).
            // Below, the interpolation in ν is off by up to 0.07 at ν = 0.25 (h = −1.5σ), where
            // D_h of L = Λo holds 8% of its mass.
            for i in 4..HEIGHT_NODES {
                for j in (0..SLOPE_NODES).filter(|j| slope_node(*j) < nu - 0.5) {
                    let (d, l) = (direct.log_ratio[i][j], looked.log_ratio[i][j]);
                    assert!(
                        (d - l).abs() < 0.06,
                        "φ {phi}, level {level}, ν {nu}, h {}, z {}: direct {d:.3}, table {l:.3}",
                        height_node(i),
                        slope_node(j)
                    );
                }
            }
        }
        // The rows a D_h reads are those its lookup fills: restricted and full lookups give the
        // same heights at every slope node.
        let dir = DVec2::from_angle(0.7);
        for (mean, std) in [(0.56, 0.83), (2.4, 0.35), (-0.2, 1.0), (5.0, 0.2)] {
            let hm = HeightMoments { mean, std };
            let weights = |joint| SlopeWeights {
                dir,
                mean: 0.0,
                sd: 1.0,
                joint,
            };
            let full = weights(table.lookup(dir, table.r0, 0.4, (0, HEIGHT_NODES - 1)));
            let part = weights(table.lookup(dir, table.r0, 0.4, height_span([hm; 2])));
            assert_eq!(full.heights(hm), part.heights(hm), "D_h ({mean}, {std})");
        }
        // Every back-face column of the table holds its entry's last front value (what the lookup
        // relies on to skip reading them).
        for (e, entry) in table.data.chunks(ENTRY).enumerate() {
            let front = front_columns(e % TABLE_NUS);
            for row in entry.chunks(SLOPE_NODES) {
                assert!(row[front..].iter().all(|v| *v == row[front - 1]), "{row:?}");
            }
        }
        // Every entry is finite and within the bound.
        assert!(
            table
                .data
                .iter()
                .all(|v| v.is_finite() && v.abs() <= MAX_LOG_RATIO as f32)
        );
        let c = table.lookup(DVec2::new(f64::NAN, 1.0), f64::NAN, f64::NAN, (0, 99));
        assert!(c.log_ratio.iter().flatten().all(|v| v.is_finite()));
    }
}
