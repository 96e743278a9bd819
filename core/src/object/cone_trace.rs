//! Cone tracing an object's voxel field [HN12 Alg. 1] (#19): the CPU reference of the voxel
//! views, with three ways to combine what the cone meets ([`Compositing`]).
//!
//! A pixel is a cone from the eye (radius `r(t) = r₀ + t·spread`, r₀ the lens radius for depth of
//! field). It is cut into elements whose length equals their diameter; each samples the field at
//! its centre at the level whose voxels are as wide as the element
//! (`ℓ = log₂(2·half / 2r)`, fractional: [`VoxelField::sample`]), builds the half-space of the
//! sample's mean plane in the element's frame and looks up which of the pixel's 64 sub-rays it
//! covers ([`MaskTable`]). With masks ([`Compositing::Masks`], HN12) the element adds its radiance
//! ([`ObjectLighting::element_radiance`]) on the sub-rays no earlier element covered,
//! `L += L_d·|m_d ∖ α|/64`, `α ∪= m_d`, so fragments of one silhouette seen by successive elements
//! are counted once [HN12 Fig. 4]; the pixel's coverage is `|α|/64`. Alpha blending
//! ([`Compositing::AlphaBlend`], [CNLE09]) takes the same coverage as an opacity and composites
//! `L += (1 − A)·α_d·L_d`, `A += (1 − A)·α_d`, which treats successive elements as uncorrelated and
//! thickens silhouettes. Nearest voxels ([`Compositing::Nearest`]) stop at the first finest-level
//! voxel the surface crosses and shade it whole: what a blocky voxel renderer shows.
//!
//! Occupancy [our addition; HN12 have none]: a voxel whose surface covers a share α of its mean
//! plane (the tips of peaks rising into it) shows that plane on α of the sub-rays
//! ([`crate::object::coverage_mask::thinning_mask`], the same sub-rays for every element, so
//! masks nest); the sub-rays it leaves open go on to the elements behind. An element more than its
//! radius inside the blended surface is never thinned: the floor that stops open sub-rays leaking
//! through the object (the field's α is below 1 on curved fine pieces too). Alpha blending takes
//! the thinned mask's popcount as its opacity, so both baselines see the same occupancy.
//!
//! Shadows: from each element that contributes, a shadow cone of the element's radius toward the
//! sun (a directional light keeps its width), starting one element length out, composited the
//! same way; the sun's share is what it leaves uncovered.
//!
//! Empty space: where a level has no support the march skips to the far side of the largest empty
//! cube it is in, less one voxel of its level (the field reaches that far beyond occupied voxels).

use crate::object::coverage_mask::{MASK_BITS, MaskTable, element_mask_params};
use crate::object::shading::ObjectLighting;
use crate::object::voxel_field::{VoxelField, VoxelSample};
use glam::DVec3;

/// How a cone combines the elements it meets (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Compositing {
    /// HN12: sub-pixel masks combined A-buffer style (ours).
    Masks,
    /// [CNLE09]: the masks' coverage as an opacity, alpha blended.
    AlphaBlend,
    /// The first occupied finest voxel, whole.
    Nearest,
}

/// A cone from the eye through a pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Apex (the eye).
    pub origin: DVec3,
    /// Unit axis.
    pub dir: DVec3,
    /// Radius at the apex (0 for a pixel's cone; a shadow cone's starting radius).
    pub radius0: f64,
    /// Radius gained per unit distance (the pixel's angular radius).
    pub spread: f64,
    /// The thin lens's radius (world units; 0 for a pinhole: no depth of field).
    pub lens: f64,
    /// The distance along the axis that is in focus (used when `lens` > 0; must be > 0).
    pub focus: f64,
}

impl Cone {
    /// The cone's radius at distance t along its axis [HN12 Sec. 4.1, Fig. 1d: depth of field by
    /// wider cones]: the pixel's footprint `radius0 + spread·t` and the lens's circle of confusion
    /// `lens·|1 − t/focus|` (a disc of the lens seen through the focus point) combined as independent
    /// discs, whose second moments add: `√(a² + b²)`. A pinhole (lens 0) gives the footprint alone;
    /// a focus of 0 or less is taken as no lens.
    pub fn radius(&self, t: f64) -> f64 {
        let a = self.radius0 + self.spread * t;
        if !(self.lens > 0.0 && self.focus > 0.0) {
            return a;
        }
        let b = self.lens * (1.0 - t / self.focus);
        (a * a + b * b).sqrt()
    }

    /// The cone with a thin lens of radius `lens` focused at distance `focus`.
    #[must_use]
    pub fn with_lens(self, lens: f64, focus: f64) -> Self {
        Self {
            lens: lens.max(0.0),
            focus,
            ..self
        }
    }
}

/// What a cone returns.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConePixel {
    /// Radiance (linear RGB), already weighted by coverage (the background is black).
    pub color: [f64; 3],
    /// The covered share of the pixel, in [0, 1].
    pub coverage: f64,
    /// The variance of `color` as an estimate of the pixel's expectation, per channel (a
    /// supersampled truth's `s²/n` over its rays; 0 for a cone, which is deterministic).
    pub variance: [f64; 3],
}

/// The cone tracer's inputs.
#[derive(Clone, Copy, Debug)]
pub struct ConeTracer<'a> {
    /// The object's voxel field.
    pub field: &'a VoxelField,
    /// The masks.
    pub table: &'a MaskTable,
    /// Sun and BRDF.
    pub lighting: &'a ObjectLighting,
    /// Shadow cones toward the sun (off: the sun is always visible).
    pub shadows: bool,
}

/// At most this many elements per cone (a bound on the work, never reached by a cone that
/// crosses the field's cube: each element advances by its own diameter).
const MAX_ELEMENTS: usize = 1 << 16;

/// What a cone has covered so far: the sub-rays' mask (masks, nearest) or the opacity (alpha
/// blending).
#[derive(Clone, Copy, Debug, Default)]
struct Coverage {
    covered: u64,
    opacity: f64,
}

impl Coverage {
    /// Adds an element's mask; the share of the pixel it newly contributes (module docs).
    fn add(&mut self, mask: u64, mode: Compositing) -> f64 {
        match mode {
            Compositing::Masks | Compositing::Nearest => {
                let fresh = mask & !self.covered;
                self.covered |= mask;
                f64::from(fresh.count_ones()) / MASK_BITS as f64
            }
            Compositing::AlphaBlend => {
                let a = f64::from(mask.count_ones()) / MASK_BITS as f64;
                let w = (1.0 - self.opacity) * a;
                self.opacity += w;
                w
            }
        }
    }

    /// The covered share of the pixel.
    fn share(&self, mode: Compositing) -> f64 {
        match mode {
            Compositing::AlphaBlend => self.opacity,
            _ => f64::from(self.covered.count_ones()) / MASK_BITS as f64,
        }
    }

    /// Whether nothing behind can show any more.
    fn full(&self, mode: Compositing) -> bool {
        match mode {
            Compositing::AlphaBlend => self.opacity >= 1.0 - 1e-6,
            _ => self.covered == u64::MAX,
        }
    }
}

impl ConeTracer<'_> {
    /// The sub-rays an element of radius r covers, its sample's mean plane written in the cone's
    /// frame (e₁, e₂ across it, d along it), thinned to the sample's occupancy (module docs); all
    /// of them for nearest voxels. The floor: an element whose centre lies more than its radius
    /// inside the blended surface is not thinned (it is wholly inside the object, whatever the
    /// voxels' occupancies say), so sub-rays that thinner elements in front left open end on it
    /// rather than leaking to the background.
    fn element_mask(
        &self,
        s: &VoxelSample,
        [e1, e2, d]: [DVec3; 3],
        r: f64,
        mode: Compositing,
    ) -> u64 {
        if mode == Compositing::Nearest {
            return u64::MAX;
        }
        let n = DVec3::new(s.normal.dot(e1), s.normal.dot(e2), s.normal.dot(d));
        let (theta, v) = element_mask_params(r, r, n, s.distance);
        let mask = self.table.lookup(theta, v);
        if s.distance < -r {
            mask
        } else {
            mask & self.table.thinning(s.occupancy)
        }
    }

    /// The pixel of `cone` (module docs).
    pub fn trace(&self, cone: &Cone, mode: Compositing) -> ConePixel {
        let mut out = ConePixel::default();
        let (e1, e2) = cone.dir.any_orthonormal_pair();
        let frame = [e1, e2, cone.dir];
        let light = self.lighting.light;
        let mut cover = Coverage::default();
        self.march(cone, mode, |s, c, r, _level| {
            let mask = self.element_mask(s, frame, r, mode);
            if mask == 0 {
                return false;
            }
            let weight = cover.add(mask, mode);
            // An element facing away from the eye or the sun sends nothing
            // (`element_radiance`): no shadow cone for it.
            let lit = s.normal.dot(-cone.dir) > 0.0 && s.normal.dot(light) > 0.0;
            if weight > 0.0 && lit {
                let sun = if self.shadows {
                    self.sun_visibility(c - s.normal * s.distance, s.normal, r, mode)
                } else {
                    1.0
                };
                let l = self.lighting.element_radiance(s, -cone.dir, sun);
                for k in 0..3 {
                    out.color[k] += weight * l[k];
                }
            }
            cover.full(mode)
        });
        out.coverage = cover.share(mode);
        out
    }

    /// The share of the sun an element of radius r sees from c, the point of its mean plane under
    /// its centre: a shadow cone of the same radius toward the sun, from where the element clears
    /// its own mean plane, composited as the view's cone is.
    fn sun_visibility(&self, c: DVec3, normal: DVec3, r: f64, mode: Compositing) -> f64 {
        let light = self.lighting.light;
        // Start where the element's own mean plane can no longer cover the shadow cone's disc
        // (its micro-shadowing is V̄(l)'s): an element of radius r whose centre is t along the
        // light clears a plane at cosine c to the light once `t·c ≥ r·c + r·√(1 − c²)`.
        let cos = normal.dot(light).max(1.0 / 16.0);
        let start = r * (1.0 + (1.0 - cos * cos).max(0.0).sqrt() / cos);
        let shadow = Cone {
            origin: c + light * start,
            dir: light,
            radius0: r,
            spread: 0.0,
            lens: 0.0,
            focus: 1.0,
        };
        let (e1, e2) = light.any_orthonormal_pair();
        let frame = [e1, e2, light];
        let mut cover = Coverage::default();
        self.march(&shadow, mode, |s, _c, rr, _l| {
            cover.add(self.element_mask(s, frame, rr, mode), mode);
            cover.full(mode)
        });
        1.0 - cover.share(mode)
    }

    /// Steps the elements of `cone` through the field's cube, calling `visit(sample, centre,
    /// radius, level)` on each element with support until it returns true.
    fn march(
        &self,
        cone: &Cone,
        mode: Compositing,
        mut visit: impl FnMut(&VoxelSample, DVec3, f64, f64) -> bool,
    ) {
        let f = self.field;
        let depth = f64::from(f.depth());
        let Some((t0, t1)) = cube_span(cone.origin, cone.dir, f.half) else {
            return;
        };
        let mut t = t0;
        for _ in 0..MAX_ELEMENTS {
            if t >= t1 {
                return;
            }
            let r = cone.radius(t).max(1e-9 * f.half);
            let c = cone.origin + cone.dir * (t + r);
            let level = (f.half / r).log2().clamp(0.0, depth);
            let sample = match mode {
                Compositing::Nearest => f.nearest(c, level.round() as u32).map(|d| VoxelSample {
                    distance: -1.0,
                    normal: d.normal,
                    height_var: d.height_var,
                    slope_cov: d.slope_cov,
                    tangents: d.tangents,
                    color_mean: d.color_mean,
                    color_height: d.color_height,
                    support: 1.0,
                    occupancy: 1.0,
                }),
                _ => f.sample(c, level),
            };
            match sample {
                Some(s) => {
                    if visit(&s, c, r, level) {
                        return;
                    }
                    t += 2.0 * r;
                }
                None => t = self.skip(cone, t, r, level).max(t + 2.0 * r),
            }
        }
    }

    /// Where the cone may next find support after an element at t without any: the exit of the
    /// coarsest empty voxel holding the element's centre, less one voxel of the sampled level.
    /// Emptiness only grows with the level (a voxel holds surface only if its parent does), so the
    /// coarsest empty level is found by bisection (four lookups for the deepest octree, where a
    /// walk from the root took up to thirteen).
    fn skip(&self, cone: &Cone, t: f64, r: f64, level: f64) -> f64 {
        let f = self.field;
        let c = cone.origin + cone.dir * (t + r);
        let fine = level.floor().clamp(0.0, f64::from(f.depth())) as u32;
        let (mut lo, mut hi) = (0u32, fine + 1);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if f.nearest(c, mid).is_none() {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        if lo > fine {
            return t;
        }
        let l = lo;
        let size = f.voxel_size(l);
        let lo = ((c + DVec3::splat(f.half)) / size).floor() * size - DVec3::splat(f.half);
        let exit = box_exit(cone.origin, cone.dir, lo, lo + DVec3::splat(size));
        exit - f.voxel_size(fine) - r
    }
}

/// The ray's parameter span inside the cube `[−half, half]³` (from 0 if it starts inside).
fn cube_span(o: DVec3, d: DVec3, half: f64) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        if d[a].abs() < 1e-300 {
            if o[a].abs() > half {
                return None;
            }
            continue;
        }
        let (u, v) = ((-half - o[a]) / d[a], (half - o[a]) / d[a]);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    (t1 > t0).then_some((t0, t1))
}

/// Where the ray leaves the box [lo, hi] (the box holds o + t d for some t).
fn box_exit(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> f64 {
    let mut t1 = f64::INFINITY;
    for a in 0..3 {
        if d[a].abs() > 1e-300 {
            let (u, v) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
            t1 = t1.min(u.max(v));
        }
    }
    t1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::microfacet::brdf::BaseBrdf;
    use crate::object::coverage_mask::{MASK_BITS, MaskTable, thinning_count};
    use crate::object::octree::VoxelOctree;
    use crate::object::surface_samples::SurfaceSample;

    /// A layer of tips over a plane, seen from above: a blue floor at the
    /// centre of one voxel layer and red plates covering a quarter of the layer above (squares of
    /// side 0.025 every 0.05), as the peaks' tips over a valley floor. The plates' voxels hold a
    /// quarter of their mean plane (occupancy ¼ from the samples), so a cone straight down must see
    /// red on a quarter of its sub-rays and the floor on the rest, whatever its position across the
    /// voxels; without the occupancy (every α = 1) the plates' voxels covered the whole pixel red.
    #[test]
    fn a_layer_of_tips_shows_its_covered_share() {
        let step = 0.005;
        let cells = (2.0 / step) as usize;
        let mut samples = vec![];
        for i in 0..cells {
            for j in 0..cells {
                let (x, y) = (
                    -1.0 + (i as f64 + 0.5) * step,
                    -1.0 + (j as f64 + 0.5) * step,
                );
                let sample = |z: f64, f: f64| SurfaceSample {
                    p: DVec3::new(x, y, z),
                    n: DVec3::Z,
                    m: DVec3::Z,
                    area: step * step,
                    f,
                };
                // Depth 3 over [−1, 1]³: voxels 0.25 wide, layer 3 centred at −0.125, layer 4 at
                // 0.125.
                samples.push(sample(-0.125, 0.0));
                if (x + 1.0).rem_euclid(0.05) < 0.025 && (y + 1.0).rem_euclid(0.05) < 0.025 {
                    samples.push(sample(0.125, 1.0));
                }
            }
        }
        let color = |f: f64| {
            if f > 0.5 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 0.0, 1.0]
            }
        };
        let tree = VoxelOctree::from_samples(&samples, color, 1.0, 3);
        let plates = tree.descriptor(3, [4, 4, 4]).unwrap();
        assert!(
            (plates.occupancy - 0.25).abs() < 1e-9,
            "{}",
            plates.occupancy
        );
        assert!((tree.descriptor(3, [4, 4, 3]).unwrap().occupancy - 1.0).abs() < 1e-9);
        let lighting = ObjectLighting {
            light: DVec3::Z,
            sun: 1.0,
            brdf: BaseBrdf {
                specular: 0.0,
                ..BaseBrdf::default()
            },
            correlation: Default::default(),
        };
        let table = MaskTable::new();
        let red_share = |field: &VoxelField| {
            let tracer = ConeTracer {
                field,
                table: &table,
                lighting: &lighting,
                shadows: false,
            };
            let mut rng = 4u64;
            let mut shares = vec![];
            for _ in 0..20 {
                // From the top of the plates' layer, elements as wide as a voxel: their centres
                // fall on the layers' centres (level 3 exactly), anywhere across.
                let (x, y) = (
                    crate::math::random::splitmix(&mut rng) - 0.5,
                    crate::math::random::splitmix(&mut rng) - 0.5,
                );
                let cone = Cone {
                    origin: DVec3::new(x, y, 0.25),
                    dir: -DVec3::Z,
                    radius0: 0.125,
                    spread: 0.0,
                    lens: 0.0,
                    focus: 1.0,
                };
                let p = tracer.trace(&cone, Compositing::Masks);
                assert_eq!(p.coverage, 1.0);
                shares.push(p.color[0] / (p.color[0] + p.color[2]));
            }
            shares
        };
        let expect = thinning_count(0.25) as f64 / MASK_BITS as f64;
        for s in red_share(&VoxelField::new(&tree)) {
            assert!((s - expect).abs() < 1e-9, "{s} vs {expect}");
        }
        let mut solid = VoxelField::new(&tree);
        for level in &mut solid.levels {
            for d in level.values_mut() {
                d.occupancy = 1.0;
            }
        }
        for s in red_share(&solid) {
            assert!(s > 0.999, "{s}");
        }
    }
}
