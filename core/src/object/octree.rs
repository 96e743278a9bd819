//! The sparse voxel octree of a displaced object [HN12 Sec. 5.2] (#19): the cube `[−half, half]³`
//! cut into `2^l` voxels per axis at level l (0 the root, `depth` the finest), holding only the
//! voxels the surface passes through, each with the additive sums of its surface
//! ([`SurfaceMoments`]). The finest level is summed from surface samples
//! ([`DisplacedObject::surface_samples`]), every coarser one from its children: exact pre-filtering
//! bottom-up, from which each level's descriptors (mean plane, σ_h², slope covariance, ā, a_s) follow
//! ([`SurfaceMoments::descriptor`]).
//!
//! This is the CPU reference of the structure. What the GPU will hold per voxel is the descriptor,
//! not the sums: [`GPU_BYTES_PER_VOXEL`] (HN12 quote 15–20 bytes with 8–16-bit channels and no
//! slope correlation), against the build's 296 bytes of f64 sums. Lookups between voxels (HN12's
//! quadrilinear interpolation over space and scale) are the cone tracer's, not the store's.

use crate::object::displaced::DisplacedObject;
use crate::object::surface_samples::SurfaceSample;
use crate::object::voxel_stats::{SurfaceMoments, VoxelDescriptor};
use glam::DVec3;
use std::collections::HashMap;

/// Bytes of one voxel's descriptor on the GPU: h̄ as f32, and as f16 σ_h², n̄ (3), the slope
/// covariance (3), ā (3), a_s (3) and the occupancy α (HN12 Sec. 5.2: 15–20 with 8-bit colours
/// and no occupancy).
pub const GPU_BYTES_PER_VOXEL: usize = 32;

/// Deepest level accepted (2^12 = 4096 voxels per axis).
pub const MAX_DEPTH: u32 = 12;

/// The octree (module docs).
#[derive(Clone, Debug)]
pub struct VoxelOctree {
    /// Half the side of the root cube, centred at the origin.
    pub half: f64,
    /// Per level (0 = root), the occupied voxels by their integer coordinates.
    pub levels: Vec<HashMap<[u32; 3], SurfaceMoments>>,
}

/// One level's storage.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LevelMemory {
    /// The level (0 = root).
    pub level: u32,
    /// Voxel side, world units.
    pub voxel_size: f64,
    /// Occupied voxels.
    pub voxels: usize,
    /// Their descriptors' bytes on the GPU ([`GPU_BYTES_PER_VOXEL`] each).
    pub gpu_bytes: usize,
}

impl VoxelOctree {
    /// The octree of `samples` (each with its colour) over `[−half, half]³` down to `depth`
    /// (clamped to [`MAX_DEPTH`]). Samples outside the cube are left out.
    pub fn from_samples(
        samples: &[SurfaceSample],
        color: impl Fn(f64) -> [f64; 3],
        half: f64,
        depth: u32,
    ) -> Self {
        let depth = depth.min(MAX_DEPTH);
        let mut tree = Self {
            half,
            levels: vec![HashMap::new(); depth as usize + 1],
        };
        for s in samples {
            if let Some(key) = tree.voxel_of(depth, s.p) {
                tree.levels[depth as usize].entry(key).or_default().add(
                    &SurfaceMoments::of_sample(s.p, s.n, s.m, s.area, color(s.f)),
                );
            }
        }
        for l in (0..depth as usize).rev() {
            let (coarse, fine) = tree.levels.split_at_mut(l + 1);
            for (k, m) in &fine[0] {
                coarse[l].entry(k.map(|c| c / 2)).or_default().add(m);
            }
        }
        tree
    }

    /// The octree of `object` down to `depth`, its surface sampled so that a finest voxel the
    /// surface crosses gets about `per_voxel` samples (the cube holds the object's bounding sphere).
    pub fn of_object(
        object: &DisplacedObject,
        color: impl Fn(f64) -> [f64; 3],
        depth: u32,
        per_voxel: f64,
        seed: u64,
    ) -> Self {
        let depth = depth.min(MAX_DEPTH);
        let half = object.bounding_radius() * 1.001;
        let size = 2.0 * half / f64::from(1u32 << depth);
        // Lines `spacing` apart cross a voxel's face (size²) about size²/spacing² times per grid.
        let spacing = size / per_voxel.clamp(1.0, 64.0).sqrt();
        Self::from_samples(&object.surface_samples(spacing, seed), color, half, depth)
    }

    /// The deepest level.
    pub fn depth(&self) -> u32 {
        self.levels.len() as u32 - 1
    }

    /// The side of a voxel at `level`.
    pub fn voxel_size(&self, level: u32) -> f64 {
        2.0 * self.half / f64::from(1u32 << level)
    }

    /// The integer coordinates of the voxel of `level` that holds p; `None` outside the cube.
    pub fn voxel_of(&self, level: u32, p: DVec3) -> Option<[u32; 3]> {
        let cells = f64::from(1u32 << level);
        let q = (p + DVec3::splat(self.half)) / (2.0 * self.half) * cells;
        if !(q.min_element() >= 0.0 && q.max_element() < cells) {
            return None;
        }
        Some([q.x as u32, q.y as u32, q.z as u32])
    }

    /// The centre of a voxel.
    pub fn center(&self, level: u32, key: [u32; 3]) -> DVec3 {
        let s = self.voxel_size(level);
        DVec3::new(key[0] as f64, key[1] as f64, key[2] as f64) * s
            + DVec3::splat(0.5 * s - self.half)
    }

    /// A voxel's sums (`None`: the surface does not pass through it).
    pub fn moments(&self, level: u32, key: [u32; 3]) -> Option<&SurfaceMoments> {
        self.levels.get(level as usize)?.get(&key)
    }

    /// A voxel's descriptors, its occupancy in the voxel included.
    pub fn descriptor(&self, level: u32, key: [u32; 3]) -> Option<VoxelDescriptor> {
        let size = self.voxel_size(level);
        let lo = self.center(level, key) - DVec3::splat(0.5 * size);
        Some(
            self.moments(level, key)?
                .descriptor()?
                .with_occupancy_in(lo, size),
        )
    }

    /// Occupied voxels and GPU bytes per level.
    pub fn memory(&self) -> Vec<LevelMemory> {
        self.levels
            .iter()
            .enumerate()
            .map(|(l, m)| LevelMemory {
                level: l as u32,
                voxel_size: self.voxel_size(l as u32),
                voxels: m.len(),
                gpu_bytes: m.len() * GPU_BYTES_PER_VOXEL,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::object::base_shape::BaseShape;

    fn object() -> (DisplacedObject, impl Fn(f64) -> [f64; 3]) {
        let m = crate::object::bumpy_material(0.25);
        let obj = DisplacedObject::new(&m, BaseShape::Sphere { radius: 1.0 }).unwrap();
        (obj, |f: f64| [0.5 + 0.2 * f, 0.4, 0.3 - 0.1 * f])
    }

    /// A voxel's statistics at every level are those of the object's surface inside it, measured
    /// independently: a denser sampling with another seed, restricted to the voxel's cube, gives
    /// the same area, mean plane, σ_h, slope covariance, ā and a_s within the tree's own sampling
    /// error (bounds from the number of tree samples in the voxel, 4 standard errors).
    #[test]
    fn every_level_holds_the_statistics_of_its_surface() {
        let (obj, color) = object();
        let samples = obj.surface_samples(0.02, 1);
        let sample_area = samples.iter().map(|s| s.area).sum::<f64>() / samples.len() as f64;
        let tree = VoxelOctree::from_samples(&samples, &color, obj.bounding_radius(), 4);
        let dense = obj.surface_samples(0.008, 99);
        let mut checked = 0;
        for level in 1..=tree.depth() - 1 {
            let mut keys: Vec<_> = tree.levels[level as usize].keys().copied().collect();
            keys.sort_unstable();
            for key in keys.iter().step_by((keys.len() / 6).max(1)).take(6) {
                let mut m = SurfaceMoments::default();
                for s in &dense {
                    if tree.voxel_of(level, s.p) == Some(*key) {
                        m.add(&SurfaceMoments::of_sample(
                            s.p,
                            s.n,
                            s.m,
                            s.area,
                            color(s.f),
                        ));
                    }
                }
                let size = tree.voxel_size(level);
                let lo = tree.center(level, *key) - DVec3::splat(0.5 * size);
                let (Some(a), Some(b)) = (tree.descriptor(level, *key), m.descriptor()) else {
                    continue;
                };
                let b = b.with_occupancy_in(lo, size);
                let count = a.area / sample_area;
                if count < 30.0 {
                    continue; // a corner clipped by the surface: too few samples to compare
                }
                checked += 1;
                let se = 4.0 / count.sqrt();
                assert!(
                    (a.occupancy - b.occupancy).abs() < se,
                    "l{level} occupancy {} {}",
                    a.occupancy,
                    b.occupancy
                );
                assert!(
                    (a.area / b.area - 1.0).abs() < se,
                    "l{level} area {} {}",
                    a.area,
                    b.area
                );
                assert!((a.centroid - b.centroid).length() < se * size);
                assert!(
                    a.normal.dot(b.normal) > 1.0 - se * se,
                    "l{level}: {} {}",
                    a.normal,
                    b.normal
                );
                let (sa, sb) = (a.height_var.sqrt(), b.height_var.sqrt());
                assert!((sa - sb).abs() < se * sb, "l{level} σ_h {sa} {sb}");
                let trace = |d: &VoxelDescriptor| d.slope_cov.xx + d.slope_cov.yy;
                let (ta, tb) = (trace(&a), trace(&b));
                assert!((ta - tb).abs() < se * tb, "l{level} slopes {ta} {tb}");
                for k in 0..3 {
                    // Colours spread by 0.2·std(f) = 0.2 (red) and 0.1 (blue).
                    let (x, y) = (a.color_mean[k], b.color_mean[k]);
                    assert!((x - y).abs() < 0.2 * se, "l{level} ā{k} {x} {y}");
                    let (x, y) = (a.color_height[k], b.color_height[k]);
                    assert!(
                        (x - y).abs() < 0.2 * se + 0.1 * y.abs(),
                        "l{level} a_s{k} {x} {y}"
                    );
                }
            }
        }
        assert!(checked >= 10, "{checked}");
    }

    /// Geometry: on a sphere without relief a voxel's descriptors are the spherical piece's, computed
    /// here on the analytic surface `z = √(R² − x² − y²)` (area element R/z) over the voxel's square:
    /// σ_h² of the heights above the mean plane and the normals' slope variance per axis.
    #[test]
    fn a_smooth_sphere_gives_its_pieces_geometry() {
        let mut m = Material::default();
        m.heights.sigma_h = 0.0;
        let r = 1.0;
        let obj = DisplacedObject::new(&m, BaseShape::Sphere { radius: r }).unwrap();
        let tree = VoxelOctree::of_object(&obj, |_| [0.5; 3], 4, 600.0, 2);
        let level = 3;
        let size = tree.voxel_size(level);
        // The voxel just beside the pole in +x, +y whose z range holds the cap.
        let key = tree
            .voxel_of(level, DVec3::new(0.5 * size, 0.5 * size, r - 1e-3))
            .unwrap();
        let d = tree.descriptor(level, key).unwrap();
        let lo = tree.center(level, key) - DVec3::splat(0.5 * size);
        let k = 400;
        let mut piece = SurfaceMoments::default();
        for j in 0..k {
            for i in 0..k {
                let (x, y) = (
                    lo.x + (i as f64 + 0.5) / k as f64 * size,
                    lo.y + (j as f64 + 0.5) / k as f64 * size,
                );
                let z = (r * r - x * x - y * y).sqrt();
                if z < lo.z || z >= lo.z + size {
                    continue;
                }
                let p = DVec3::new(x, y, z);
                piece.add(&SurfaceMoments::of_sample(
                    p,
                    p / r,
                    p / r,
                    (size / k as f64).powi(2) * r / z,
                    [0.5; 3],
                ));
            }
        }
        let e = piece.descriptor().unwrap();
        assert!(
            (d.area / e.area - 1.0).abs() < 0.01,
            "{} {}",
            d.area,
            e.area
        );
        // (The tree's 2400 samples here are jittered in longitude and height, not in x and y: the
        // edge terms of the variance carry a few per cent of sampling error.)
        assert!(
            (d.height_var / e.height_var - 1.0).abs() < 0.04,
            "{} {}",
            d.height_var,
            e.height_var
        );
        let (tr_d, tr_e) = (
            d.slope_cov.xx + d.slope_cov.yy,
            e.slope_cov.xx + e.slope_cov.yy,
        );
        assert!((tr_d / tr_e - 1.0).abs() < 0.02, "{tr_d} {tr_e}");
        // And the piece's slope spread is its span of tilts: var(x)/R² per axis, for a square of side s.
        assert!(
            (tr_e / (2.0 * size * size / 12.0) - 1.0).abs() < 0.05,
            "{tr_e}"
        );
    }

    #[test]
    fn levels_sum_their_children_and_report_memory() {
        let (obj, color) = object();
        let tree = VoxelOctree::of_object(&obj, &color, 4, 4.0, 5);
        let total = |l: usize| tree.levels[l].values().map(|m| m.area).sum::<f64>();
        for l in 0..=4 {
            assert!((total(l) / total(4) - 1.0).abs() < 1e-12);
        }
        let mem = tree.memory();
        assert_eq!(mem[0].voxels, 1);
        // The surface crosses about (area / size²)·1.5 voxels of a level (a sphere's occupancy).
        for w in mem.windows(2) {
            assert!(w[1].voxels > 2 * w[0].voxels || w[0].voxels < 8);
        }
        assert_eq!(mem[4].gpu_bytes, mem[4].voxels * GPU_BYTES_PER_VOXEL);
        assert!(tree.voxel_of(2, DVec3::splat(10.0)).is_none());
    }
}
