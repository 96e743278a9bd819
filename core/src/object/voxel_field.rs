//! The octree's descriptors as a continuous field over space and scale [HN12 Secs. 5.2–5.3]
//! (#19): what a cone element samples at its centre and its level of detail.
//!
//! Within a level the eight voxels whose centres surround x are blended trilinearly; a voxel the
//! surface does not cross has no descriptor and drops out, the others' weights renormalised (so the
//! field reaches one voxel beyond the occupied shell and no further). Each voxel contributes its
//! mean plane as a distance *function*, `h̄_k(x) = (x − p̄_k)·n̄_k`, which is exact for a flat piece
//! wherever x is, so blending distances (not voxel-centre values) keeps the zero set in place.
//! Slope covariances live in each voxel's own tangent frame: they are blended as world-space
//! tensors `T = Σ σ_ij t_i t_jᵀ` and projected back onto the blended normal's frame. Between
//! levels (fractional level ℓ) the two neighbouring levels' samples are blended linearly
//! (quadrilinear interpolation, HN12).

use crate::microfacet::slopes::SlopeCov;
use crate::object::octree::VoxelOctree;
use crate::object::voxel_stats::VoxelDescriptor;
use glam::{DMat3, DVec3};
use std::collections::HashMap;

/// The field's value at a point and level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelSample {
    /// h̄: signed distance from the point to the blended mean plane (negative inside).
    pub distance: f64,
    /// n̄: unit normal.
    pub normal: DVec3,
    /// σ_h².
    pub height_var: f64,
    /// The slopes' covariance in the frame `tangents` of n̄.
    pub slope_cov: SlopeCov,
    /// The tangent frame of n̄ (`normal.any_orthonormal_pair()`).
    pub tangents: [DVec3; 2],
    /// ā per channel.
    pub color_mean: [f64; 3],
    /// a_s per channel.
    pub color_height: [f64; 3],
    /// The occupied voxels' share of the trilinear weight, in (0, 1].
    pub support: f64,
    /// α ∈ [0, 1]: the share of the blended mean plane the surface covers
    /// ([`VoxelDescriptor::occupancy`], blended like σ_h²).
    pub occupancy: f64,
}

/// The descriptors of every occupied voxel, per level (built once from a [`VoxelOctree`]).
#[derive(Clone, Debug)]
pub struct VoxelField {
    /// Half the side of the root cube.
    pub half: f64,
    /// Per level, the occupied voxels' descriptors.
    pub levels: Vec<HashMap<[u32; 3], VoxelDescriptor>>,
}

/// The world-space tensor `Σ σ_ij t_i t_jᵀ` of a slope covariance written in the frame (t₁, t₂).
pub fn tensor([t1, t2]: [DVec3; 2], c: &SlopeCov) -> DMat3 {
    let o = |a: DVec3, b: DVec3| DMat3::from_cols(a * b.x, a * b.y, a * b.z);
    o(t1, t1) * c.xx + o(t2, t2) * c.yy + (o(t1, t2) + o(t2, t1)) * c.xy
}

/// A tensor's covariance in the frame (t₁, t₂) (variances floored at 0).
pub fn in_frame(t1: DVec3, t2: DVec3, s: &DMat3) -> SlopeCov {
    SlopeCov {
        xx: t1.dot(*s * t1).max(0.0),
        yy: t2.dot(*s * t2).max(0.0),
        xy: t1.dot(*s * t2),
    }
}

impl VoxelField {
    /// The field of `tree`.
    pub fn new(tree: &VoxelOctree) -> Self {
        Self {
            half: tree.half,
            levels: tree
                .levels
                .iter()
                .enumerate()
                .map(|(level, l)| {
                    l.keys()
                        .filter_map(|k| Some((*k, tree.descriptor(level as u32, *k)?)))
                        .collect()
                })
                .collect(),
        }
    }

    /// The deepest level.
    pub fn depth(&self) -> u32 {
        self.levels.len() as u32 - 1
    }

    /// The side of a voxel at `level`.
    pub fn voxel_size(&self, level: u32) -> f64 {
        2.0 * self.half / f64::from(1u32 << level)
    }

    /// The descriptor of the voxel of `level` holding x (no blending: the "nearest voxel").
    pub fn nearest(&self, x: DVec3, level: u32) -> Option<&VoxelDescriptor> {
        let level = level.min(self.depth());
        let cells = f64::from(1u32 << level);
        let q = (x + DVec3::splat(self.half)) / (2.0 * self.half) * cells;
        if !(q.min_element() >= 0.0 && q.max_element() < cells) {
            return None;
        }
        self.levels[level as usize].get(&[q.x as u32, q.y as u32, q.z as u32])
    }

    /// The trilinear blend within one level (module docs); `None` where no surrounding voxel is
    /// occupied.
    pub fn sample_level(&self, x: DVec3, level: u32) -> Option<VoxelSample> {
        let level = level.min(self.depth());
        let cells = 1i64 << level;
        let q =
            (x + DVec3::splat(self.half)) / (2.0 * self.half) * cells as f64 - DVec3::splat(0.5);
        let base = q.floor();
        let frac = q - base;
        let map = &self.levels[level as usize];
        let (mut w_sum, mut dist, mut normal, mut hv, mut slopes) =
            (0.0, 0.0, DVec3::ZERO, 0.0, DMat3::ZERO);
        let (mut am, mut ah, mut occupancy) = ([0.0; 3], [0.0; 3], 0.0);
        for corner in 0..8 {
            let off = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
            let idx = [0, 1, 2].map(|a| base[a] as i64 + off[a] as i64);
            if idx.iter().any(|&i| i < 0 || i >= cells) {
                continue;
            }
            let Some(d) = map.get(&idx.map(|i| i as u32)) else {
                continue;
            };
            let w = (0..3)
                .map(|a| if off[a] == 1 { frac[a] } else { 1.0 - frac[a] })
                .product::<f64>();
            if w <= 0.0 {
                continue;
            }
            w_sum += w;
            dist += w * d.plane_distance(x);
            normal += w * d.normal;
            hv += w * d.height_var;
            occupancy += w * d.occupancy;
            slopes += tensor(d.tangents, &d.slope_cov) * w;
            for k in 0..3 {
                am[k] += w * d.color_mean[k];
                ah[k] += w * d.color_height[k];
            }
        }
        if !(w_sum > 1e-12) {
            return None;
        }
        let inv = 1.0 / w_sum;
        let normal = (normal * inv).try_normalize()?;
        let (t1, t2) = normal.any_orthonormal_pair();
        Some(VoxelSample {
            distance: dist * inv,
            normal,
            height_var: hv * inv,
            slope_cov: in_frame(t1, t2, &(slopes * inv)),
            tangents: [t1, t2],
            color_mean: am.map(|a| a * inv),
            color_height: ah.map(|a| a * inv),
            support: w_sum,
            occupancy: occupancy * inv,
        })
    }

    /// The quadrilinear sample at a fractional level (clamped to [0, depth]): the two levels'
    /// blends mixed linearly; where only one of them has support, that one.
    pub fn sample(&self, x: DVec3, level: f64) -> Option<VoxelSample> {
        let level = level.clamp(0.0, f64::from(self.depth()));
        let lo = level.floor() as u32;
        let f = level - f64::from(lo);
        let a = self.sample_level(x, lo);
        if f <= 1e-9 || lo == self.depth() {
            return a;
        }
        let b = self.sample_level(x, lo + 1);
        match (a, b) {
            (Some(a), Some(b)) => Some(mix(&a, &b, f)),
            (a, b) => a.or(b),
        }
    }
}

/// `(1 − f)·a + f·b`, the normal renormalised and the slopes carried through world tensors.
fn mix(a: &VoxelSample, b: &VoxelSample, f: f64) -> VoxelSample {
    let normal = (a.normal * (1.0 - f) + b.normal * f)
        .try_normalize()
        .unwrap_or(a.normal);
    let (t1, t2) = normal.any_orthonormal_pair();
    let s = tensor(a.tangents, &a.slope_cov) * (1.0 - f) + tensor(b.tangents, &b.slope_cov) * f;
    let lerp = |x: f64, y: f64| x * (1.0 - f) + y * f;
    VoxelSample {
        distance: lerp(a.distance, b.distance),
        normal,
        height_var: lerp(a.height_var, b.height_var),
        slope_cov: in_frame(t1, t2, &s),
        tangents: [t1, t2],
        color_mean: [0, 1, 2].map(|k| lerp(a.color_mean[k], b.color_mean[k])),
        color_height: [0, 1, 2].map(|k| lerp(a.color_height[k], b.color_height[k])),
        support: lerp(a.support, b.support),
        occupancy: lerp(a.occupancy, b.occupancy),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::object::base_shape::BaseShape;
    use crate::object::displaced::DisplacedObject;

    /// On a smooth sphere the field's distance is the sphere's signed distance near the surface
    /// (to a fraction of a voxel: the pieces' mean planes are chords of a curved surface) and its
    /// normal the radial direction, at every level and between levels; it has no support far from
    /// the surface.
    #[test]
    fn the_field_follows_a_smooth_sphere() {
        let mut m = Material::default();
        m.heights.sigma_h = 0.0;
        let obj = DisplacedObject::new(&m, BaseShape::Sphere { radius: 1.0 }).unwrap();
        let tree = VoxelOctree::of_object(&obj, |_| [0.5; 3], 5, 8.0, 1);
        let field = VoxelField::new(&tree);
        let mut rng = 3u64;
        for _ in 0..300 {
            let dir = DVec3::new(
                crate::math::random::standard_normal(&mut rng),
                crate::math::random::standard_normal(&mut rng),
                crate::math::random::standard_normal(&mut rng),
            )
            .normalize();
            // Levels whose voxels are at most a quarter of the radius (HN12's H6: locally planar).
            let level = 3.0 + 2.0 * crate::math::random::splitmix(&mut rng);
            let size = field.voxel_size(level.floor() as u32);
            let off = (crate::math::random::splitmix(&mut rng) - 0.5) * 0.5 * size;
            let x = dir * (1.0 + off);
            let s = field.sample(x, level).unwrap();
            // A chord of a piece of side s sits about s²/(12R) below the sphere on average.
            assert!(
                (s.distance - off).abs() < 0.08 * size,
                "ℓ {level}: {} vs {off}",
                s.distance
            );
            assert!(s.normal.dot(dir) > 0.99, "ℓ {level}: {}", s.normal.dot(dir));
            assert!(s.color_mean.iter().all(|c| (c - 0.5).abs() < 1e-12));
        }
        assert!(field.sample(DVec3::ZERO, 5.0).is_none());
        assert!(field.sample(DVec3::splat(5.0), 3.0).is_none());
    }
}
