//! A voxel's statistics of the surface inside it [HN12 Sec. 5.2], kept as sums that add under
//! union ([`SurfaceMoments`]), so a parent voxel's are exactly the sum of its children's and the
//! octree is pre-filtered bottom-up without approximation; the descriptors the cone tracer reads
//! ([`VoxelDescriptor`]: the mean plane, σ_h², the slope covariance, ā and a_s) are derived from the
//! sums at each level "with the usual statistic formulas" (HN12), never by averaging children's
//! descriptors (an average of unit normals is not a normal, and an average of variances leaves out
//! the spread of the children's means: the law of total variance does not).
//!
//! Definitions, for the area-weighted surface points p with unit normals n and colour a in a voxel:
//! - the mean plane passes through the centroid `p̄ = E[p]` with normal `n̄ = E[n]/|E[n]|`;
//! - `σ_h² = n̄ᵀ Cov(p) n̄`, the variance of the heights `h = (p − p̄)·n̄` above it;
//! - the slope covariance is that of the projected normals `(n·t₁, n·t₂)` in a tangent frame of n̄,
//!   divided by `|E[n]|²` (a facet's slope is `−(n·t)/(n·n̄)`, and `E[n·n̄] = |E[n]|`: exact for
//!   the mean, first order in the tilt for the spread);
//! - `ā = E[a]` and `a_s` the projection of a on `s(h) = 2Φ(h/σ_h) − 1` [HN12 H5bis], taking a linear
//!   in h over Gaussian heights: `Cov(h, s) = σ_h/√π`, `Var(s) = ⅓`, so `a_s = 3 Cov(a, h)/(√π σ_h)`
//!   (0 when σ_h = 0).
//!
//! - the occupancy `α = min(1, |Σ A n| / A_section)`, where `A_section` is the area of the mean
//!   plane's section of the voxel ([`plane_section_area`]): the share of the voxel's mean plane the
//!   surface covers, seen along n̄ (`|Σ A n|` is the surface's area projected on that plane, folds
//!   counted once). A flat piece has α = 1 however it clips the voxel; a voxel that holds only the
//!   tips of peaks rising into it has α well below 1, and the cone tracer shows its mean plane on
//!   that share of a pixel's sub-rays only (`cone_trace.rs`). Without it such a voxel presents its
//!   whole half-space and the tips, whose colour goes with height, get 1.3–2× their visible area
//!   (docs/design/objects.md, "Attributed per voxel"). This is our addition: HN12 store no occupancy beyond
//!   the distance field.
//!
//! Edge cases: an empty voxel (no area) has no descriptor; normals that cancel (`|E[n]| < 1e-9`, a
//! thin double-sided sliver) fall back to the principal axis of least position spread; a
//! descriptor made without its voxel ([`SurfaceMoments::descriptor`]) has occupancy 1 until
//! [`VoxelDescriptor::with_occupancy_in`] gives it the voxel.

use crate::microfacet::slopes::SlopeCov;
use crate::object::cube_section::plane_section_area;
use glam::{DMat3, DVec3};

/// Additive sums of a piece of surface (module docs). `Default` is the empty piece (all sums 0;
/// glam's own matrix default would be the identity).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceMoments {
    /// Σ A.
    pub area: f64,
    /// Σ A·p.
    pub p: DVec3,
    /// Σ A·p pᵀ.
    pub pp: DMat3,
    /// Σ A·n.
    pub n: DVec3,
    /// Σ A·m, m the base surface's normal under the point.
    pub m: DVec3,
    /// Σ A·m mᵀ.
    pub mm: DMat3,
    /// Σ A·s, s the facet's slope against m as a world-space tangent vector (module docs).
    pub s: DVec3,
    /// Σ A·s sᵀ.
    pub ss: DMat3,
    /// Σ A·a per channel.
    pub a: [f64; 3],
    /// Σ A·a·p per channel.
    pub ap: [DVec3; 3],
}

impl Default for SurfaceMoments {
    fn default() -> Self {
        Self {
            area: 0.0,
            p: DVec3::ZERO,
            pp: DMat3::ZERO,
            n: DVec3::ZERO,
            m: DVec3::ZERO,
            mm: DMat3::ZERO,
            s: DVec3::ZERO,
            ss: DMat3::ZERO,
            a: [0.0; 3],
            ap: [DVec3::ZERO; 3],
        }
    }
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

impl SurfaceMoments {
    /// The sums of one surface sample: point p, unit normal n, the base surface's unit normal m
    /// under it, area, colour a. A facet at or beyond 90° from m (none on a valid displaced
    /// surface) counts its slope as 0.
    pub fn of_sample(p: DVec3, n: DVec3, m: DVec3, area: f64, a: [f64; 3]) -> Self {
        let c = n.dot(m);
        let slope = if c > 1e-9 {
            -(n - m * c) / c
        } else {
            DVec3::ZERO
        };
        Self {
            area,
            p: p * area,
            pp: outer(p, p) * area,
            n: n * area,
            m: m * area,
            mm: outer(m, m) * area,
            s: slope * area,
            ss: outer(slope, slope) * area,
            a: a.map(|x| x * area),
            ap: a.map(|x| p * (x * area)),
        }
    }

    /// Adds another piece of surface (the union of the two).
    pub fn add(&mut self, o: &Self) {
        self.area += o.area;
        self.p += o.p;
        self.pp += o.pp;
        self.n += o.n;
        self.m += o.m;
        self.mm += o.mm;
        self.s += o.s;
        self.ss += o.ss;
        for k in 0..3 {
            self.a[k] += o.a[k];
            self.ap[k] += o.ap[k];
        }
    }

    /// The descriptors (module docs), occupancy 1 (the voxel is not known here:
    /// [`VoxelDescriptor::with_occupancy_in`]); `None` for an empty piece.
    pub fn descriptor(&self) -> Option<VoxelDescriptor> {
        if !(self.area > 0.0) {
            return None;
        }
        let w = 1.0 / self.area;
        let centroid = self.p * w;
        let cov_p = self.pp * w - outer(centroid, centroid);
        let mean_n = self.n * w;
        let agreement = mean_n.length();
        let normal = if agreement > 1e-9 {
            mean_n / agreement
        } else {
            least_spread_axis(&cov_p)
        };
        let (t1, t2) = normal.any_orthonormal_pair();
        let mean_m = self.m * w;
        let mean_s = self.s * w;
        let tilt =
            (self.mm * w - outer(mean_m, mean_m)) * (1.0 / mean_m.length_squared().max(1e-18));
        let cov = self.ss * w - outer(mean_s, mean_s) + tilt;
        let slope_cov = SlopeCov {
            xx: t1.dot(cov * t1).max(0.0),
            yy: t2.dot(cov * t2).max(0.0),
            xy: t1.dot(cov * t2),
        };
        let height_var = normal.dot(cov_p * normal).max(0.0);
        let sigma_h = height_var.sqrt();
        let mut color_mean = [0.0; 3];
        let mut color_height = [0.0; 3];
        for k in 0..3 {
            color_mean[k] = self.a[k] * w;
            let cov_ah = (self.ap[k] * w - centroid * color_mean[k]).dot(normal);
            color_height[k] = if sigma_h > 1e-12 {
                3.0 * cov_ah / (std::f64::consts::PI.sqrt() * sigma_h)
            } else {
                0.0
            };
        }
        Some(VoxelDescriptor {
            area: self.area,
            centroid,
            normal,
            agreement,
            tangents: [t1, t2],
            height_var,
            slope_cov,
            color_mean,
            color_height,
            occupancy: 1.0,
        })
    }
}

/// The unit eigenvector of the smallest eigenvalue of a symmetric 3×3 matrix, by cyclic Jacobi
/// rotations (robust where eigenvalues are close, unlike power iteration); +z for a zero matrix.
fn least_spread_axis(m: &DMat3) -> DVec3 {
    let mut a = m.to_cols_array_2d();
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..32 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off < 1e-300 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = 0.5 * (a[q][q] - a[p][p]) / a[p][q];
            let sign = if theta >= 0.0 { 1.0 } else { -1.0 };
            let t = sign / (theta.abs() + (theta * theta + 1.0).sqrt());
            let (c, s) = (1.0 / (t * t + 1.0).sqrt(), t / (t * t + 1.0).sqrt());
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let k = (0..3)
        .min_by(|&i, &j| a[i][i].total_cmp(&a[j][j]))
        .unwrap_or(2);
    DVec3::new(v[0][k], v[1][k], v[2][k])
        .try_normalize()
        .unwrap_or(DVec3::Z)
}

/// What the cone tracer reads of a voxel [HN12 Sec. 5.2, Fig. 6] (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelDescriptor {
    /// The surface area inside.
    pub area: f64,
    /// The centroid p̄ of the surface, a point of the mean plane.
    pub centroid: DVec3,
    /// n̄, the mean plane's unit normal.
    pub normal: DVec3,
    /// |E[n]| ∈ [0, 1]: how much the normals agree (1 on a flat piece).
    pub agreement: f64,
    /// The tangent frame (t₁, t₂) of n̄ the slope covariance is written in.
    pub tangents: [DVec3; 2],
    /// σ_h², the variance of the heights above the mean plane.
    pub height_var: f64,
    /// The slopes' covariance in the tangent frame (the micro-NDF, σ_n² per axis).
    pub slope_cov: SlopeCov,
    /// ā per channel.
    pub color_mean: [f64; 3],
    /// a_s per channel, the colour's correlation with height [HN12 Eq. 17].
    pub color_height: [f64; 3],
    /// α ∈ [0, 1], the share of the mean plane's section of the voxel the surface covers (module
    /// docs); 1 for a flat piece.
    pub occupancy: f64,
}

impl VoxelDescriptor {
    /// The descriptor with its occupancy in the voxel `[lo, lo + size]³` (module docs): 1 where the
    /// section has no area (the mean plane only touches the voxel) or the quotient is not finite.
    #[must_use]
    pub fn with_occupancy_in(self, lo: DVec3, size: f64) -> Self {
        let section = plane_section_area(self.centroid, self.normal, lo, size);
        let alpha = self.agreement * self.area / section;
        Self {
            occupancy: if section > 0.0 && alpha.is_finite() {
                alpha.clamp(0.0, 1.0)
            } else {
                1.0
            },
            ..self
        }
    }

    /// The signed distance from x to the mean plane (HN12's macroscopic distance field h̄).
    pub fn plane_distance(&self, x: DVec3) -> f64 {
        (x - self.centroid).dot(self.normal)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::{splitmix, standard_normal};

    /// A weighted sample: point, normal, base normal, area, colour.
    type Sample = (DVec3, DVec3, DVec3, f64, [f64; 3]);
    /// A piece of surface as weighted samples.
    type Piece = Vec<Sample>;

    /// The descriptor by two-pass formulas straight from the samples (the brute force the sums
    /// must reproduce).
    fn brute(s: &Piece) -> VoxelDescriptor {
        let area: f64 = s.iter().map(|q| q.3).sum();
        let mean =
            |f: &dyn Fn(&Sample) -> DVec3| s.iter().map(|q| f(q) * q.3).sum::<DVec3>() / area;
        let c = mean(&|q| q.0);
        let mn = mean(&|q| q.1);
        let mm = mean(&|q| q.2);
        let slope = |q: &Sample| {
            let k = q.1.dot(q.2);
            -(q.1 - q.2 * k) / k
        };
        let ms = mean(&|q| slope(q));
        let n = mn.normalize();
        let (t1, t2) = n.any_orthonormal_pair();
        let hv = s
            .iter()
            .map(|q| q.3 * (q.0 - c).dot(n).powi(2))
            .sum::<f64>()
            / area;
        let mut cov = [0.0; 3];
        for q in s {
            let (ds, dm) = (slope(q) - ms, (q.2 - mm) / mm.length());
            for (k, (a, b)) in [(t1, t1), (t2, t2), (t1, t2)].into_iter().enumerate() {
                cov[k] += q.3 * (ds.dot(a) * ds.dot(b) + dm.dot(a) * dm.dot(b)) / area;
            }
        }
        let mut am = [0.0; 3];
        let mut asl = [0.0; 3];
        for k in 0..3 {
            am[k] = s.iter().map(|q| q.3 * q.4[k]).sum::<f64>() / area;
            let cah = s
                .iter()
                .map(|q| q.3 * (q.4[k] - am[k]) * (q.0 - c).dot(n))
                .sum::<f64>()
                / area;
            asl[k] = 3.0 * cah / (std::f64::consts::PI.sqrt() * hv.sqrt());
        }
        VoxelDescriptor {
            area,
            centroid: c,
            normal: n,
            agreement: mn.length(),
            tangents: [t1, t2],
            height_var: hv,
            slope_cov: SlopeCov {
                xx: cov[0],
                yy: cov[1],
                xy: cov[2],
            },
            color_mean: am,
            color_height: asl,
            occupancy: 1.0,
        }
    }

    /// A tilted patch of Gaussian relief with colour correlated to height, around `centre`.
    fn patch(centre: DVec3, normal: DVec3, seed: u64, count: usize) -> Piece {
        let mut rng = seed;
        let (t1, t2) = normal.any_orthonormal_pair();
        (0..count)
            .map(|_| {
                let (u, v) = (splitmix(&mut rng) - 0.5, splitmix(&mut rng) - 0.5);
                let h = 0.01 * standard_normal(&mut rng);
                let (sx, sy) = (
                    0.2 * standard_normal(&mut rng),
                    0.1 * standard_normal(&mut rng),
                );
                let n = (normal - t1 * sx - t2 * sy).normalize();
                let a = [0.5 + 10.0 * h, 0.3, 0.2 - 5.0 * h];
                (
                    centre + (t1 * u + t2 * v) * 0.1 + normal * h,
                    n,
                    normal,
                    0.5 + splitmix(&mut rng),
                    a,
                )
            })
            .collect()
    }

    fn sums(s: &Piece) -> SurfaceMoments {
        let mut m = SurfaceMoments::default();
        for q in s {
            m.add(&SurfaceMoments::of_sample(q.0, q.1, q.2, q.3, q.4));
        }
        m
    }

    fn close(d: &VoxelDescriptor, b: &VoxelDescriptor) {
        let rel = |x: f64, y: f64| (x - y).abs() <= 1e-7 * (x.abs() + y.abs()) + 1e-12;
        assert!((d.centroid - b.centroid).length() < 1e-12);
        assert!((d.normal - b.normal).length() < 1e-12);
        assert!(
            rel(d.height_var, b.height_var),
            "{} {}",
            d.height_var,
            b.height_var
        );
        assert!(rel(d.slope_cov.xx, b.slope_cov.xx) && rel(d.slope_cov.yy, b.slope_cov.yy));
        assert!((d.slope_cov.xy - b.slope_cov.xy).abs() < 1e-9);
        for k in 0..3 {
            assert!(rel(d.color_mean[k], b.color_mean[k]));
            assert!(
                (d.color_height[k] - b.color_height[k]).abs() < 1e-7,
                "{k}: {} {}",
                d.color_height[k],
                b.color_height[k]
            );
        }
    }

    /// A parent's descriptor from its children's summed sums is the brute-force descriptor of the
    /// union of their surfaces: the bottom-up pre-filtering is exact, also where the children lean
    /// differently (whose mean normals an average of descriptors would get wrong).
    #[test]
    fn summed_children_give_the_parents_statistics() {
        let a = patch(
            DVec3::new(0.9, 0.1, 0.2),
            DVec3::new(0.2, 0.1, 1.0).normalize(),
            1,
            3000,
        );
        let b = patch(
            DVec3::new(1.0, 0.1, 0.25),
            DVec3::new(-0.3, 0.0, 1.0).normalize(),
            2,
            2000,
        );
        let mut ab = sums(&a);
        ab.add(&sums(&b));
        let union: Piece = a.iter().chain(b.iter()).copied().collect();
        close(&ab.descriptor().unwrap(), &brute(&union));
        close(&sums(&a).descriptor().unwrap(), &brute(&a));
        // What averaging the children's descriptors would give instead differs from the truth:
        // their σ_h² leave out the spread between the two mean planes.
        let (da, db) = (brute(&a), brute(&b));
        let averaged = 0.5 * (da.height_var + db.height_var);
        assert!(ab.descriptor().unwrap().height_var > 1.5 * averaged);
    }

    /// On a patch of known relief the descriptors recover it: σ_h = 0.01, slope std 0.2 and 0.1
    /// along the patch's tangents (here the frame's own axes may differ: compare the trace and
    /// determinant), colour slopes 10 and −5 per unit height.
    #[test]
    fn a_known_patch_is_recovered() {
        let n = DVec3::new(0.2, -0.4, 1.0).normalize();
        let s = patch(DVec3::new(0.0, 2.0, 1.0), n, 7, 40_000);
        let d = sums(&s).descriptor().unwrap();
        assert!((d.normal - n).length() < 0.01, "{}", d.normal);
        assert!(
            (d.height_var.sqrt() / 0.01 - 1.0).abs() < 0.03,
            "{}",
            d.height_var.sqrt()
        );
        let c = d.slope_cov;
        let (tr, det) = (c.xx + c.yy, c.xx * c.yy - c.xy * c.xy);
        // Exact slopes against the base normal (module docs): the normals' spread alone gave the
        // trace 6% low and the determinant 10%.
        assert!((tr / (0.04 + 0.01) - 1.0).abs() < 0.02, "{tr}");
        assert!((det / (0.04 * 0.01) - 1.0).abs() < 0.04, "{det}");
        // a = ā + β h with β = 10: a_s = 3·β·σ_h/√π.
        let expect = 3.0 * 10.0 * 0.01 / std::f64::consts::PI.sqrt();
        assert!(
            (d.color_height[0] / expect - 1.0).abs() < 0.05,
            "{:?}",
            d.color_height
        );
        assert!((d.color_height[2] / (-0.5 * expect) - 1.0).abs() < 0.05);
        assert!(d.color_height[1].abs() < 1e-9);
    }

    /// The least-spread axis of rotated diagonal matrices, close eigenvalues included.
    #[test]
    fn least_spread_axis_finds_the_smallest_eigenvector() {
        let mut rng = 17u64;
        for (a, b, c) in [
            (3.0, 2.0, 1.0),
            (1.0, 1.0 + 1e-9, 1e-6),
            (0.08, 0.0004, 0.0),
        ] {
            let q = glam::DQuat::from_axis_angle(
                DVec3::new(splitmix(&mut rng), splitmix(&mut rng), 0.3).normalize(),
                6.0 * splitmix(&mut rng),
            );
            let r = DMat3::from_quat(q);
            let m = r * DMat3::from_diagonal(DVec3::new(a, b, c)) * r.transpose();
            let axis = least_spread_axis(&m);
            assert!(axis.dot(r.z_axis).abs() > 1.0 - 1e-9, "{a} {b} {c}: {axis}");
        }
        assert_eq!(least_spread_axis(&DMat3::ZERO).length(), 1.0);
    }

    #[test]
    fn empty_and_degenerate_pieces() {
        assert!(SurfaceMoments::default().descriptor().is_none());
        // Two opposite faces of a thin sliver: normals cancel, the plane is the sliver's.
        let mut m = SurfaceMoments::default();
        for k in 0..100 {
            let p = DVec3::new(k as f64 * 0.01, (k % 7) as f64 * 0.01, 0.0);
            m.add(&SurfaceMoments::of_sample(
                p,
                DVec3::Z,
                DVec3::Z,
                1.0,
                [0.5; 3],
            ));
            m.add(&SurfaceMoments::of_sample(
                p,
                -DVec3::Z,
                -DVec3::Z,
                1.0,
                [0.5; 3],
            ));
        }
        let d = m.descriptor().unwrap();
        assert!(d.normal.z.abs() > 0.999, "{}", d.normal);
        assert!(d.slope_cov.xx.is_finite() && d.color_height == [0.0; 3]);
    }
}
