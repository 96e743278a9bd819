//! Area-weighted samples of a displaced object's surface (#19): what the voxel octree's statistics
//! are summed from, and what tests measure those statistics against.
//!
//! The base surface is spread with `n × n` points ([`BaseShape::surface_points`]: jittered
//! parameter cells, or a mesh's triangles by area). Each base point b with normal m is carried to the
//! displaced surface by tracing from `b + (reach + margin)·m` back along −m
//! ([`DisplacedObject::trace`]: the outermost crossing, the point a ray along the normal sees).
//! Its area is the base cell's times the displaced surface's area element, `|∇F|/(m·∇F)` (the
//! height-field element `√(1 + |∇h|²)` for a displacement along m; the base's own curvature
//! factor `1 + κh` is left out: O(σ_h/R), 2% at the relief's limit of a quarter radius).
//! Cells whose trace finds nothing (none on a valid object) are dropped. The traces run in parallel
//! (rayon); the samples keep the base points' order.

use crate::object::displaced::DisplacedObject;
use glam::DVec3;

/// One sample of the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceSample {
    /// The point on the displaced surface.
    pub p: DVec3,
    /// Its outward unit normal.
    pub n: DVec3,
    /// The base surface's unit normal under it (what its slope is measured against).
    pub m: DVec3,
    /// The surface area it stands for.
    pub area: f64,
    /// The driver's value there.
    pub f: f64,
}

impl DisplacedObject {
    /// `n × n` samples of the surface (module docs), jittered with `seed`.
    pub fn surface_samples(&self, n: usize, seed: u64) -> Vec<SurfaceSample> {
        use rayon::prelude::*;
        let reach = self.surface.h_max + 1e-3 * self.shape.bounding_radius();
        self.shape
            .surface_points(n, seed)
            .into_par_iter()
            .filter_map(|(b, base_area)| {
                let m = self.shape.normal(b);
                let hit = self.trace(b + m * reach, -m)?;
                let grad = self.gap_gradient(hit.p);
                let cosine = m.dot(grad);
                (cosine > 1e-6).then(|| SurfaceSample {
                    p: hit.p,
                    n: grad.normalize(),
                    m,
                    area: base_area * grad.length() / cosine,
                    f: self.value(hit.p),
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::object::base_shape::BaseShape;

    /// The samples lie on the surface, their normals are the surface's, and their areas add up to
    /// the base's area when the relief is flat and to more (the relief's area element, 1 + σ²/2 to
    /// first order in the slope variance) when it is not.
    #[test]
    fn samples_cover_the_surface_with_its_area() {
        for shape in [
            BaseShape::Sphere { radius: 1.0 },
            BaseShape::Torus {
                major: 1.0,
                minor: 0.4,
            },
        ] {
            let mut m = Material::default();
            m.heights.sigma_h = 0.0;
            let flat = DisplacedObject::new(&m, shape.clone()).unwrap();
            let s = flat.surface_samples(120, 1);
            let total: f64 = s.iter().map(|q| q.area).sum();
            assert!(
                (total / shape.area() - 1.0).abs() < 2e-3,
                "{shape:?}: {total}"
            );

            m.heights.sigma_h = 0.02;
            m.slopes.sigma_nx = 0.25;
            m.slopes.sigma_ny = 0.25;
            let bumpy = DisplacedObject::new(&m, shape.clone()).unwrap();
            let s = bumpy.surface_samples(200, 2);
            assert!(s.len() == 200 * 200, "{}", s.len());
            for q in &s {
                assert!(bumpy.gap(q.p).abs() < 1e-6);
                assert!((q.n - bumpy.normal(q.p)).length() < 1e-9);
            }
            let total: f64 = s.iter().map(|q| q.area).sum();
            // Mean √(1 + |∇h|²) for slopes of variance 2·0.25²: about 1 + 0.25² = 1.0625.
            let ratio = total / shape.area();
            assert!(ratio > 1.03 && ratio < 1.10, "{shape:?}: {ratio}");
        }
    }
}
