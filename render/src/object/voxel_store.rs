//! The voxel octree as the GPU reads it (#19, [HN12 Sec. 5.2]): every occupied voxel of every level
//! as 32 bytes ([`GPU_BYTES_PER_VOXEL`]), found through one open-addressing hash table keyed by
//! (level, x, y, z). HN12 store bricks under a node tree (GigaVoxels); a hash finds a voxel in one
//! probe (1.2 on average) at a load of at most ¼ without a descent, which is what the quadrilinear lookups of a cone
//! element (16 voxels) want, and it is built in one pass.
//!
//! A voxel's words (`shaders/object/voxel_field.wgsl` `voxel_at` unpacks them):
//! the mean plane's offset from the voxel's centre along its normal as f32, then as f16 pairs
//! (n̄x, n̄y), (n̄z, σ_h²), (σxx, σyy), (σxy, ā_r), (ā_g, ā_b), (a_s r, a_s g), (a_s b, α), the slope
//! covariance written in the frame `any_orthonormal_pair` of the stored normal (the GPU rebuilds
//! it). [`GpuVoxels::decode`] turns the words back into a [`VoxelField`]: the field the GPU sees,
//! so core's cone tracer over it is the reference the WGSL must reproduce to f32 precision, and the
//! quantisation's own effect is measured apart (against core's field in f64).
//!
//! Edge cases: values beyond f16's range are clamped to ±65504 (never infinite); a normal that
//! quantises to zero length keeps +z; an empty field gives an empty table (every lookup misses).

use glam::DVec3;
use half::f16;
use lodestone_core::microfacet::slopes::SlopeCov;
use lodestone_core::object::octree::GPU_BYTES_PER_VOXEL;
use lodestone_core::object::voxel_field::{VoxelField, in_frame, tensor};
use lodestone_core::object::voxel_stats::VoxelDescriptor;
use std::collections::HashMap;

/// Bytes of one hash slot (key words, voxel index, padding).
pub const BYTES_PER_SLOT: usize = 16;

/// Every key lies within this many slots of its hash (the table grows until it does), so the
/// shader's lookup is this many probes written out, with no loop (`voxel_field.wgsl`
/// `find_voxel`; a loop there spent the software adapter's loop budget).
pub const MAX_PROBES: usize = 8;

/// The octree's voxels and their hash table, as uploaded (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct GpuVoxels {
    /// Half the side of the root cube.
    pub half: f64,
    /// The finest level.
    pub depth: u32,
    /// Slots `[key x|y<<16, key z|level<<16|occupied, voxel index, 0]`; a power of two of them.
    pub slots: Vec<[u32; 4]>,
    /// Each voxel's eight words.
    pub voxels: Vec<[u32; 8]>,
    /// Each voxel's (level, coordinates), in the order of `voxels`.
    pub keys: Vec<(u32, [u32; 3])>,
}

/// The two key words of voxel `c` of `level` (the occupied bit set).
pub fn slot_key(level: u32, c: [u32; 3]) -> [u32; 2] {
    [c[0] | (c[1] << 16), c[2] | (level << 16) | 0x8000_0000]
}

/// The slot a key hashes to before probing (the WGSL `slot_hash`, the same wrapping steps).
pub fn slot_hash(k: [u32; 2]) -> u32 {
    let mut h = k[0].wrapping_mul(0x9E37_79B1) ^ k[1];
    h ^= h >> 15;
    h = h.wrapping_mul(0x85EB_CA77);
    h ^ (h >> 13)
}

fn to_f16(x: f64) -> f16 {
    f16::from_f64(if x.is_finite() {
        x.clamp(-65504.0, 65504.0)
    } else {
        0.0
    })
}

fn pack(a: f64, b: f64) -> u32 {
    u32::from(to_f16(a).to_bits()) | (u32::from(to_f16(b).to_bits()) << 16)
}

fn unpack(w: u32) -> (f64, f64) {
    (
        f16::from_bits((w & 0xffff) as u16).to_f64(),
        f16::from_bits((w >> 16) as u16).to_f64(),
    )
}

/// The normal as stored: f16 components, renormalised (+z when they vanish).
fn stored_normal(n: DVec3) -> DVec3 {
    DVec3::new(
        to_f16(n.x).to_f64(),
        to_f16(n.y).to_f64(),
        to_f16(n.z).to_f64(),
    )
    .try_normalize()
    .unwrap_or(DVec3::Z)
}

impl GpuVoxels {
    /// The centre of voxel `c` of `level`.
    pub fn centre(&self, level: u32, c: [u32; 3]) -> DVec3 {
        let size = 2.0 * self.half / f64::from(1u32 << level);
        (DVec3::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2])) + 0.5) * size
            - DVec3::splat(self.half)
    }

    /// Every voxel of `field`, packed and hashed.
    pub fn encode(field: &VoxelField) -> Self {
        let mut out = Self {
            half: field.half,
            depth: field.depth(),
            slots: vec![],
            voxels: vec![],
            keys: vec![],
        };
        for (level, map) in field.levels.iter().enumerate() {
            let mut keys: Vec<_> = map.keys().copied().collect();
            keys.sort_unstable();
            for c in keys {
                let words = out.encode_voxel(level as u32, c, &map[&c]);
                out.voxels.push(words);
                out.keys.push((level as u32, c));
            }
        }
        let mut n = (4 * out.voxels.len()).next_power_of_two().max(16);
        loop {
            match Self::hash_keys(&out.keys, n) {
                Some(slots) => {
                    out.slots = slots;
                    return out;
                }
                None => n *= 2,
            }
        }
    }

    /// The table of `keys` over `n` slots by linear probing, or `None` when a key would lie
    /// [`MAX_PROBES`] or more slots past its hash.
    fn hash_keys(keys: &[(u32, [u32; 3])], n: usize) -> Option<Vec<[u32; 4]>> {
        let mut slots = vec![[0u32; 4]; n];
        for (i, &(level, c)) in keys.iter().enumerate() {
            let k = slot_key(level, c);
            let home = slot_hash(k) as usize & (n - 1);
            let free = (0..MAX_PROBES).find(|p| slots[(home + p) & (n - 1)][1] == 0)?;
            slots[(home + free) & (n - 1)] = [k[0], k[1], i as u32, 0];
        }
        Some(slots)
    }

    fn encode_voxel(&self, level: u32, c: [u32; 3], d: &VoxelDescriptor) -> [u32; 8] {
        let n = stored_normal(d.normal);
        let offset = (self.centre(level, c) - d.centroid).dot(n);
        let (t1, t2) = n.any_orthonormal_pair();
        let s = in_frame(t1, t2, &tensor(d.tangents, &d.slope_cov));
        let (a, h) = (d.color_mean, d.color_height);
        [
            (offset as f32).to_bits(),
            pack(n.x, n.y),
            pack(n.z, d.height_var),
            pack(s.xx, s.yy),
            pack(s.xy, a[0]),
            pack(a[1], a[2]),
            pack(h[0], h[1]),
            pack(h[2], d.occupancy),
        ]
    }

    /// The field the GPU sees (module docs): every voxel unpacked into a descriptor whose mean plane,
    /// frame and statistics are the stored ones.
    pub fn decode(&self) -> VoxelField {
        let mut levels = vec![HashMap::new(); self.depth as usize + 1];
        for (w, &(level, c)) in self.voxels.iter().zip(&self.keys) {
            let (nx, ny) = unpack(w[1]);
            let (nz, height_var) = unpack(w[2]);
            let normal = DVec3::new(nx, ny, nz).try_normalize().unwrap_or(DVec3::Z);
            let offset = f64::from(f32::from_bits(w[0]));
            let (xx, yy) = unpack(w[3]);
            let (xy, r) = unpack(w[4]);
            let (g, b) = unpack(w[5]);
            let (hr, hg) = unpack(w[6]);
            let (hb, occupancy) = unpack(w[7]);
            let (t1, t2) = normal.any_orthonormal_pair();
            let d = VoxelDescriptor {
                area: 1.0,
                centroid: self.centre(level, c) - normal * offset,
                normal,
                agreement: 1.0,
                tangents: [t1, t2],
                height_var,
                slope_cov: SlopeCov { xx, yy, xy },
                color_mean: [r, g, b],
                color_height: [hr, hg, hb],
                occupancy,
            };
            levels[level as usize].insert(c, d);
        }
        VoxelField {
            half: self.half,
            levels,
        }
    }

    /// Bytes on the GPU: voxels and hash slots.
    pub fn gpu_bytes(&self) -> usize {
        self.voxels.len() * GPU_BYTES_PER_VOXEL + self.slots.len() * BYTES_PER_SLOT
    }

    /// The index of voxel `c` of `level` by the table, as the GPU probes it: at most
    /// [`MAX_PROBES`] slots from its hash (for tests).
    pub fn find(&self, level: u32, c: [u32; 3]) -> Option<usize> {
        let k = slot_key(level, c);
        let mask = self.slots.len() - 1;
        let home = slot_hash(k) as usize & mask;
        for p in 0..MAX_PROBES {
            let e = self.slots[(home + p) & mask];
            if e[0] == k[0] && e[1] == k[1] {
                return Some(e[2] as usize);
            }
            if e[1] == 0 {
                return None;
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lodestone_core::material::Material;
    use lodestone_core::object::base_shape::BaseShape;
    use lodestone_core::object::displaced::DisplacedObject;
    use lodestone_core::object::octree::VoxelOctree;

    fn field() -> VoxelField {
        let m = Material::default();
        let object = DisplacedObject::new(&m, BaseShape::Sphere { radius: 1.0 }).unwrap();
        let tree = VoxelOctree::of_object(&object, |f| [f, 0.5, 1.0 - f], 4, 4.0, 1);
        VoxelField::new(&tree)
    }

    /// Every voxel is found at its own index, and a voxel that is not there is not found.
    #[test]
    fn the_table_finds_every_voxel_and_no_other() {
        let f = field();
        let g = GpuVoxels::encode(&f);
        assert_eq!(
            g.voxels.len(),
            f.levels.iter().map(|l| l.len()).sum::<usize>()
        );
        assert!(g.slots.len() >= 4 * g.voxels.len() && g.slots.len().is_power_of_two());
        // A table too small for MAX_PROBES is refused, and encode grows past it.
        assert!(GpuVoxels::hash_keys(&g.keys, 16).is_none());
        for (i, &(level, c)) in g.keys.iter().enumerate() {
            assert_eq!(g.find(level, c), Some(i));
        }
        let depth = g.depth;
        let cells = 1u32 << depth;
        let missing = (0..cells)
            .flat_map(|x| (0..cells).map(move |y| [x, y, cells / 2]))
            .filter(|c| !f.levels[depth as usize].contains_key(c))
            .take(50)
            .collect::<Vec<_>>();
        assert!(!missing.is_empty());
        for c in missing {
            assert_eq!(g.find(depth, c), None);
        }
    }

    /// The decoded field is the encoded one to f16 precision: the same planes (distance at the
    /// voxel's corners), normals, slope tensors and colours.
    #[test]
    fn decoding_gives_the_field_to_half_precision() {
        let f = field();
        let g = GpuVoxels::encode(&f);
        let d = g.decode();
        for (level, map) in f.levels.iter().enumerate() {
            let size = f.voxel_size(level as u32);
            for (c, a) in map {
                let b = &d.levels[level][c];
                let x = g.centre(level as u32, *c) + DVec3::splat(0.5 * size);
                let dist = (a.plane_distance(x) - b.plane_distance(x)).abs();
                assert!(dist <= 2e-3 * size, "level {level} {c:?}: {dist}");
                assert!(a.normal.dot(b.normal) > 1.0 - 1e-6);
                let (ta, tb) = (
                    tensor(a.tangents, &a.slope_cov),
                    tensor(b.tangents, &b.slope_cov),
                );
                let scale = ta.to_cols_array().iter().fold(1e-4, |m, v| v.abs().max(m));
                let diff = (ta - tb)
                    .to_cols_array()
                    .iter()
                    .fold(0.0f64, |m, v| v.abs().max(m));
                assert!(diff <= 3e-3 * scale, "slopes {diff} of {scale}");
                for k in 0..3 {
                    assert!((a.color_mean[k] - b.color_mean[k]).abs() <= 1e-3);
                    assert!((a.color_height[k] - b.color_height[k]).abs() <= 1e-3);
                }
                let hv = (a.height_var - b.height_var).abs();
                assert!(hv <= 1e-3 * a.height_var + 1e-7, "{hv}");
            }
        }
    }

    /// What the f16 storage costs the image: core's cone tracer over the stored field against the
    /// same over the f64 field, a sphere at two distances with masks and shadow cones: the covered
    /// pixels' summed colour within 0.3%, coverage within a sub-ray on average.
    #[test]
    fn storage_leaves_the_image_alone() {
        use lodestone_core::object::cone_trace::{Compositing, ConeTracer};
        use lodestone_core::object::coverage_mask::MaskTable;
        use lodestone_core::object::object_truth::pixel_cone;
        use lodestone_core::object::shading::ObjectLighting;
        use lodestone_core::scene::camera::Camera;
        let m = Material::default();
        let f = field();
        let d = GpuVoxels::encode(&f).decode();
        let table = MaskTable::new();
        let lighting = ObjectLighting {
            light: DVec3::new(0.4, -0.3, 0.8).normalize(),
            sun: 1.0,
            brdf: m.brdf.clone(),
            correlation: m.filtering.correlation,
        };
        let tracer = |field| ConeTracer {
            field,
            table: &table,
            lighting: &lighting,
            shadows: true,
        };
        let (a, b) = (tracer(&f), tracer(&d));
        for distance in [6.0, 2.5] {
            let cam = Camera {
                elevation_deg: 60.0,
                azimuth_deg: 30.0,
                distance,
                target: [0.0, 0.0],
                fov_deg: 30.0,
            };
            let (w, h) = (24, 18);
            let (mut sa, mut sb, mut cov) = (0.0, 0.0, 0.0);
            for y in 0..h {
                for x in 0..w {
                    let cone = pixel_cone(&cam, x as f64 + 0.5, y as f64 + 0.5, w, h);
                    let (pa, pb) = (
                        a.trace(&cone, Compositing::Masks),
                        b.trace(&cone, Compositing::Masks),
                    );
                    sa += pa.color.iter().sum::<f64>();
                    sb += pb.color.iter().sum::<f64>();
                    cov += (pa.coverage - pb.coverage).abs() / f64::from(w * h);
                }
            }
            let rel = (sa - sb).abs() / sa;
            assert!(sa > 1.0 && rel < 3e-3, "distance {distance}: {rel}");
            assert!(cov < 1.0 / 64.0, "distance {distance}: coverage {cov}");
        }
    }

    /// The shader probes exactly MAX_PROBES slots.
    #[test]
    fn the_shader_probes_as_far_as_the_table_guarantees() {
        let src = crate::shaders::object();
        let f = &src[src.find("fn find_voxel(").unwrap()..];
        let body = &f[..f.find("\n}\n").unwrap()];
        assert_eq!(body.matches("probe_slot(k,").count(), MAX_PROBES);
        assert!(!body.contains("loop") && !body.contains("for ("));
    }

    /// Extreme values stay finite.
    #[test]
    fn extremes_pack_finite() {
        for x in [f64::NAN, f64::INFINITY, -1e30, 1e-30, -0.0] {
            let (a, b) = unpack(pack(x, x));
            assert!(a.is_finite() && b.is_finite(), "{x}");
        }
        assert_eq!(stored_normal(DVec3::ZERO), DVec3::Z);
    }
}
