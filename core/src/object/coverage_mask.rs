//! Sub-pixel occupancy masks of a cone element [HN12 Sec. 5.4] (#19): which of a pixel's
//! [`MASK_BITS`] sub-rays a half-space crosses, as bits of an integer, so that occlusion along a
//! cone combines A-buffer style (`L += L_d·popcount(m_d & !α)/N`, `α |= m_d`, HN12 Alg. 1) and
//! correlated fragments at a silhouette are not counted twice [HN12 Fig. 4].
//!
//! The sub-rays sit at [`sub_ray`] points of the unit disc (the cone's cross-section, radius 1): a
//! Vogel spiral, so every half-plane through the disc holds a share of them close to its share of
//! the area. A cone element of radius r and half-length l, whose mean plane has unit normal
//! `(n_x, n_y, n_z)` in the element's frame (z along the cone) and signed distance h̄ at its centre,
//! covers the sub-ray at ω when some point `(rω, t)`, |t| ≤ l, is behind the plane:
//! `r ω·(n_x, n_y) + h̄ − l|n_z| ≤ 0`, i.e. `ω·(cos θ, sin θ) ≤ v` with
//! `v = (l|n_z| − h̄)/(r|n_xy|)` ([`element_mask_params`], HN12's test with |n_z| so either facing
//! works). The mask depends on (θ, v) only, so it is tabulated ([`MaskTable`], looked up nearest
//! as HN12 do).
//!
//! A voxel whose surface covers only a share α of its mean plane (its occupancy, `voxel_stats.rs`)
//! shows its half-space on that share of the sub-rays: the element's mask is intersected with a
//! [`thinning_mask`], the sub-rays whose fixed threshold ξ_i is below α. The thresholds are the
//! same for every element, so thinned masks nest: an element behind fills exactly the sub-rays a
//! thinner one in front left open, and a pixel's coverage stays a union of sub-rays. They are a
//! fixed scramble of the spiral's order ([`sub_ray_rank`]): the spiral runs outward with i, so
//! thinning by i would keep the disc's centre and drop its rim.
//!
//! Edge cases: `|n_xy| → 0` (the plane faces the cone) gives v = ±∞, all bits or none; v ≤ −1 is
//! empty and v ≥ 1 full for every θ; an occupancy ≥ 1 (or NaN) thins nothing, one ≤ 0 everything.

use glam::DVec2;
use std::f64::consts::{PI, TAU};

/// Sub-rays per pixel: the bits of a `u64`.
pub const MASK_BITS: usize = 64;

/// The table's angles over [0, 2π).
pub const MASK_ANGLES: usize = 128;

/// The table's offsets v over [−1, 1] (cell centres).
pub const MASK_OFFSETS: usize = 128;

/// Sub-ray i's position in the unit disc: radius `√((i + ½)/N)`, angle `i·φ_golden` (equal areas
/// per ray, no two on a line through the centre).
pub fn sub_ray(i: usize) -> DVec2 {
    let golden = PI * (3.0 - 5f64.sqrt());
    let r = ((i as f64 + 0.5) / MASK_BITS as f64).sqrt();
    let a = golden * i as f64;
    DVec2::new(r * a.cos(), r * a.sin())
}

/// The exact mask: bit i set when sub-ray i satisfies `ω·(cos θ, sin θ) ≤ v`.
pub fn half_plane_mask(theta: f64, v: f64) -> u64 {
    let d = DVec2::new(theta.cos(), theta.sin());
    (0..MASK_BITS).fold(0u64, |m, i| {
        if sub_ray(i).dot(d) <= v {
            m | (1u64 << i)
        } else {
            m
        }
    })
}

/// Sub-ray i's rank in the thinning order (module docs): the rank of a fixed hash of i among the
/// 64 hashes, so `(rank + ½)/64` are the thresholds ξ_i, one per sixty-fourth of [0, 1].
pub fn sub_ray_rank(i: usize) -> usize {
    let key = |j: usize| {
        let mut state = (j as u64).wrapping_mul(0x9E37_79B9).wrapping_add(12345);
        crate::math::random::splitmix(&mut state)
    };
    let k = key(i);
    (0..MASK_BITS)
        .filter(|&j| {
            let kj = key(j);
            kj < k || (kj == k && j < i)
        })
        .count()
}

/// The sub-rays an element of occupancy α keeps: the `round(64α)` first in the thinning order
/// (those whose threshold `ξ_i = (rank_i + ½)/64` is below α; module docs). Every bit for α ≥ 1 or
/// NaN, none for α ≤ 0.
pub fn thinning_mask(occupancy: f64) -> u64 {
    let kept = thinning_count(occupancy);
    (0..MASK_BITS).fold(0u64, |m, i| {
        if sub_ray_rank(i) < kept {
            m | (1u64 << i)
        } else {
            m
        }
    })
}

/// How many sub-rays an occupancy keeps, `round(64α)` clamped to [0, 64] (64 for NaN).
pub fn thinning_count(occupancy: f64) -> usize {
    if !(occupancy < 1.0) {
        return MASK_BITS;
    }
    (occupancy * MASK_BITS as f64 + 0.5).floor().max(0.0) as usize
}

/// The area fraction of the unit disc with `ω·d ≤ v` (|d| = 1): what a mask's popcount/N
/// approximates.
pub fn half_plane_area(v: f64) -> f64 {
    let v = v.clamp(-1.0, 1.0);
    // Segment beyond the chord at distance v from the centre, subtracted from the whole disc.
    let beyond = (v.acos() - v * (1.0 - v * v).max(0.0).sqrt()) / PI;
    1.0 - beyond
}

/// `(θ, v)` of a cone element (module docs): its radius r, half-length l, the mean plane's unit
/// normal in the element's frame (z along the cone) and its signed distance h̄ at the centre.
/// Finite on every input: a plane facing the cone gives v = ±1e30.
pub fn element_mask_params(r: f64, l: f64, n: glam::DVec3, h: f64) -> (f64, f64) {
    let nxy = DVec2::new(n.x, n.y).length();
    let reach = l * n.z.abs() - h;
    if !(nxy * r > 1e-12 * (reach.abs() + r)) {
        return (0.0, if reach >= 0.0 { 1e30 } else { -1e30 });
    }
    (n.y.atan2(n.x), reach / (r * nxy))
}

/// Where the thinning masks start in [`MaskTable::masks`]: after the half-plane table.
pub const THINNING_BASE: usize = MASK_ANGLES * MASK_OFFSETS;

/// The tabulated masks, `MASK_ANGLES × MASK_OFFSETS` entries of 8 bytes (128 KiB), then the 65
/// thinning masks (one per count of kept sub-rays, 0 to 64).
#[derive(Clone, Debug)]
pub struct MaskTable {
    /// Row-major by angle, then offset; from [`THINNING_BASE`], [`thinning_mask`] by count.
    pub masks: Vec<u64>,
}

impl Default for MaskTable {
    fn default() -> Self {
        Self::new()
    }
}

impl MaskTable {
    /// Every entry's exact mask at its cell centre.
    pub fn new() -> Self {
        let mut masks = Vec::with_capacity(MASK_ANGLES * MASK_OFFSETS);
        for a in 0..MASK_ANGLES {
            let theta = TAU * (a as f64 + 0.5) / MASK_ANGLES as f64;
            for o in 0..MASK_OFFSETS {
                let v = -1.0 + 2.0 * (o as f64 + 0.5) / MASK_OFFSETS as f64;
                masks.push(half_plane_mask(theta, v));
            }
        }
        for kept in 0..=MASK_BITS {
            masks.push(thinning_mask((kept as f64) / MASK_BITS as f64));
        }
        Self { masks }
    }

    /// [`thinning_mask`] from the table.
    pub fn thinning(&self, occupancy: f64) -> u64 {
        self.masks[THINNING_BASE + thinning_count(occupancy)]
    }

    /// The mask of the half-plane `ω·(cos θ, sin θ) ≤ v`, nearest entry; exact (empty or full)
    /// beyond |v| ≥ 1.
    pub fn lookup(&self, theta: f64, v: f64) -> u64 {
        if !(v > -1.0) {
            return 0;
        }
        if v >= 1.0 {
            return u64::MAX;
        }
        let t = theta.rem_euclid(TAU) / TAU * MASK_ANGLES as f64;
        let a = (t as usize).min(MASK_ANGLES - 1);
        let o = (((v + 1.0) * 0.5 * MASK_OFFSETS as f64) as usize).min(MASK_OFFSETS - 1);
        self.masks[a * MASK_OFFSETS + o]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::splitmix;

    /// The table's masks against the direct half-plane test at the same (θ, v): they differ only in
    /// sub-rays within the cell's reach of the line (half a cell in v, plus the turn of half an
    /// angle cell), and their coverage is the disc's area share within the spiral's discrepancy.
    #[test]
    fn the_table_matches_direct_half_plane_coverage() {
        let table = MaskTable::new();
        let mut rng = 8u64;
        let (mut worst_area, mut mean_area) = (0.0f64, 0.0);
        let count = 20_000;
        for _ in 0..count {
            let theta = TAU * splitmix(&mut rng);
            let v = 2.4 * splitmix(&mut rng) - 1.2;
            let direct = half_plane_mask(theta, v);
            let looked = table.lookup(theta, v);
            let d = DVec2::new(theta.cos(), theta.sin());
            let reach = 1.0 / MASK_OFFSETS as f64 + PI / MASK_ANGLES as f64;
            for i in 0..MASK_BITS {
                if (direct ^ looked) >> i & 1 == 1 {
                    assert!(
                        (sub_ray(i).dot(d) - v).abs() <= reach + 1e-12,
                        "θ {theta} v {v}: sub-ray {i} far from the line"
                    );
                }
            }
            let share = f64::from(looked.count_ones()) / MASK_BITS as f64;
            let e = (share - half_plane_area(v)).abs();
            worst_area = worst_area.max(e);
            mean_area += e / count as f64;
        }
        // 64 sub-rays resolve a coverage to 1/64 ≈ 0.016 at best.
        assert!(
            worst_area < 0.06 && mean_area < 0.015,
            "{worst_area} {mean_area}"
        );
    }

    /// The thinning order is a permutation; thinned masks nest, keep round(64α) sub-rays, and
    /// keep α of a half-plane's sub-rays on average over the table's half-planes (the order does
    /// not favour the disc's centre or any side: the kept share of the table's masks is α within
    /// 0.02 on average and 0.25 for any one), and the table's copies are the direct ones.
    #[test]
    fn thinning_keeps_the_occupancys_share() {
        let table = MaskTable::new();
        let mut ranks: Vec<usize> = (0..MASK_BITS).map(sub_ray_rank).collect();
        ranks.sort_unstable();
        assert_eq!(ranks, (0..MASK_BITS).collect::<Vec<_>>());
        let mut previous = 0u64;
        for kept in 0..=MASK_BITS {
            let alpha = kept as f64 / MASK_BITS as f64;
            let m = thinning_mask(alpha);
            assert_eq!(m.count_ones() as usize, kept);
            assert_eq!(m & previous, previous, "not nested at {kept}");
            assert_eq!(table.thinning(alpha), m);
            assert_eq!(table.thinning(alpha + 0.4 / MASK_BITS as f64), m);
            previous = m;
        }
        assert_eq!(thinning_mask(f64::NAN), u64::MAX);
        assert_eq!(thinning_mask(7.0), u64::MAX);
        assert_eq!(thinning_mask(-1.0), 0);
        for alpha in [0.1, 0.3, 0.5, 0.8] {
            let keep = thinning_mask(alpha);
            let (mut sum, mut count, mut worst) = (0.0, 0.0, 0.0f64);
            for &m in &table.masks[..THINNING_BASE] {
                let n = m.count_ones();
                if n >= 16 {
                    let share = f64::from((m & keep).count_ones()) / f64::from(n);
                    sum += share;
                    count += 1.0;
                    worst = worst.max((share - alpha).abs());
                }
            }
            assert!(
                (sum / count - alpha).abs() < 0.02,
                "{alpha}: {}",
                sum / count
            );
            assert!(worst < 0.25, "{alpha}: {worst}");
        }
    }

    #[test]
    fn element_params_cover_what_the_geometry_says() {
        let table = MaskTable::new();
        // A plane through the element's centre, tilted 90° (its normal across the cone): half.
        let (t, v) = element_mask_params(1.0, 1.0, glam::DVec3::X, 0.0);
        assert!(v.abs() < 1e-12 && t.abs() < 1e-12);
        assert_eq!(table.lookup(t, v).count_ones(), 32);
        // A plane facing the cone: all when the element reaches it, none when it does not.
        assert_eq!(element_mask_params(1.0, 0.5, glam::DVec3::Z, 0.4).1, 1e30);
        assert_eq!(element_mask_params(1.0, 0.5, glam::DVec3::Z, 0.6).1, -1e30);
        assert_eq!(table.lookup(0.0, 1e30), u64::MAX);
        assert_eq!(table.lookup(0.0, -1e30), 0);
        assert_eq!(table.lookup(0.0, f64::NAN), 0);
        // A sub-ray covered in the mask does meet the half-space in the element, checked pointwise.
        let mut rng = 2u64;
        for _ in 0..500 {
            let n = glam::DVec3::new(
                splitmix(&mut rng) - 0.5,
                splitmix(&mut rng) - 0.5,
                splitmix(&mut rng) - 0.5,
            )
            .normalize();
            let (r, l, h) = (
                0.5 + splitmix(&mut rng),
                0.5 + splitmix(&mut rng),
                splitmix(&mut rng) - 0.5,
            );
            let (t, v) = element_mask_params(r, l, n, h);
            let m = half_plane_mask(t, v);
            for i in 0..MASK_BITS {
                let w = sub_ray(i) * r;
                let behind = |z: f64| n.dot(glam::DVec3::new(w.x, w.y, z)) + h <= 1e-9;
                assert_eq!(
                    m >> i & 1 == 1,
                    behind(l) || behind(-l),
                    "{n} {r} {l} {h} ray {i}"
                );
            }
        }
    }
}
