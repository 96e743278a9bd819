//! The explicit micro-geometry of a whole object (#19): the base shape's signed distance less the
//! material's relief, `F(p) = d_B(p) − σ_h·g(f(p))`, its surface `F = 0`, and a ray trace on it that
//! cannot step over a feature. This is what the object's ground truth renders: no statistics here.
//!
//! `f` is the material's noise extended to space ([`SolidNoise`]), so the relief needs no
//! parametrisation of the object and has no seam; near the surface (σ_h ≪ the shape's radii of
//! curvature, which [`DisplacedObject::new`] checks) `F = 0` is the base surface displaced along its
//! normal by `h = σ_h·g(f)` evaluated at the displaced point.
//!
//! Step rule: `|∇F| ≤ 1 + σ_h·max|g′|·max|∇f|` (d_B is 1-Lipschitz), so along a unit ray a step of
//! `F/rate` cannot cross the surface: [`crate::scene::march::sphere_trace`], the rigorous march the
//! plane's surface uses, with its relaxation, minimum step and refinement. Rays start where they
//! enter the bounding sphere `|p| ≤ R_B + h_max` and leave where they exit it.

use crate::material::Material;
use crate::object::base_shape::{BaseShape, ShapeError};
use crate::object::solid_noise::SolidNoise;
use crate::scene::march::{March, sphere_trace};
use crate::scene::surface::Surface;
use glam::DVec3;

/// The relief may reach at most this fraction of the shape's smallest radius of curvature: beyond
/// it `F = 0` folds over itself inside concave parts and no longer reads as a displaced surface.
/// The relief's reach is taken as 4σ_h under the identity transfer (the rigorous `Σ|a_i|` of 48
/// waves is 8.6σ_h, reached nowhere in practice) and the curve's largest |g| under a curve.
pub const MAX_RELIEF_FRACTION: f64 = 0.25;

/// Why an object cannot be built from a material.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ObjectError {
    /// The base shape is invalid.
    #[error(transparent)]
    Shape(#[from] ShapeError),
    /// The material's driver is an image, which needs a parametrisation of the object.
    #[error(
        "whole objects take a noise driver for now (an image driver needs a parametrisation of the object)"
    )]
    ImageDriver,
    /// The relief is too tall for the shape.
    #[error(
        "the relief (reaching {h_max}) exceeds {MAX_RELIEF_FRACTION} of the shape's smallest radius of curvature or half its thickness ({radius}): lower σ_h or grow the shape"
    )]
    ReliefTooTall {
        /// How far the relief reaches ([`MAX_RELIEF_FRACTION`]'s docs).
        h_max: f64,
        /// The smallest radius of curvature.
        radius: f64,
    },
}

/// A base shape displaced by a material's relief (module docs).
#[derive(Clone, Debug)]
pub struct DisplacedObject {
    /// The macro-surface.
    pub shape: BaseShape,
    /// The driver in space.
    pub noise: SolidNoise,
    /// The material's plane surface: σ_h, the transfer function g and its bounds (`height_of`,
    /// `h_max`, `g_lip`), and how marches refine a crossing.
    pub surface: Surface,
    /// A bound of |∇F| (module docs).
    pub rate: f64,
    /// The least step of a march (1e-4 of the finest wavelength, as on the plane).
    pub min_step: f64,
}

/// Where a ray meets an object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjectHit {
    /// Ray parameter of the hit (distance, for a unit direction).
    pub t: f64,
    /// The point (on the outside of the surface, within the march's final bracket).
    pub p: DVec3,
}

impl DisplacedObject {
    /// `shape` displaced by `material`'s relief; the noise is extended to space with the material's
    /// seed.
    pub fn new(material: &Material, shape: BaseShape) -> Result<Self, ObjectError> {
        shape.validate()?;
        let surface = Surface::new(material).ok_or(ObjectError::ImageDriver)?;
        let plane = match &surface.driver {
            crate::driver::field::DriverField::Noise(n) => n,
            crate::driver::field::DriverField::Image(_) => return Err(ObjectError::ImageDriver),
        };
        let seed = match &material.driver {
            crate::material::Driver::Noise(p) => p.seed,
            crate::material::Driver::Image { .. } => 0,
        };
        let noise = SolidNoise::from_plane(plane, seed);
        let radius = shape.feature_radius();
        let reach = match &surface.transfer {
            crate::microfacet::transfer::TransferFunction::Identity => {
                surface.h_max.min(4.0 * surface.sigma_h)
            }
            crate::microfacet::transfer::TransferFunction::Curve(_) => surface.h_max,
        };
        if reach > MAX_RELIEF_FRACTION * radius {
            return Err(ObjectError::ReliefTooTall {
                h_max: reach,
                radius,
            });
        }
        let rate = 1.0 + surface.sigma_h * surface.g_lip * noise.gradient_bound();
        let fine = noise.finest_wavelength();
        let min_step = 1e-4 * if fine.is_finite() { fine } else { radius };
        Ok(Self {
            shape,
            noise,
            surface,
            rate,
            min_step,
        })
    }

    /// How marches on the object refine a crossing.
    pub fn with_march(mut self, march: March) -> Self {
        self.surface.march = march;
        self
    }

    /// The driver's value f(p).
    pub fn value(&self, p: DVec3) -> f64 {
        self.noise.value(p)
    }

    /// The relief h(p) = σ_h·g(f(p)).
    pub fn height(&self, p: DVec3) -> f64 {
        self.surface.height_of(self.noise.value(p))
    }

    /// F(p) = d_B(p) − h(p): positive outside.
    pub fn gap(&self, p: DVec3) -> f64 {
        self.shape.distance(p) - self.height(p)
    }

    /// ∇F = ∇d_B − σ_h g′(f) ∇f.
    pub fn gap_gradient(&self, p: DVec3) -> DVec3 {
        let (f, grad_f) = self.noise.value_and_gradient(p);
        let gd = self.surface.sigma_h * self.surface.transfer.derivative(f);
        self.shape.normal(p) - grad_f * gd
    }

    /// The outward unit normal of the level set of F through p: `∇d_B − σ_h g′(f)∇f`, normalised
    /// (the base normal where that vanishes).
    pub fn normal(&self, p: DVec3) -> DVec3 {
        self.gap_gradient(p)
            .try_normalize()
            .unwrap_or_else(|| self.shape.normal(p))
    }

    /// The radius of the sphere that holds the object.
    pub fn bounding_radius(&self) -> f64 {
        self.shape.bounding_radius() + self.surface.h_max
    }

    /// The first crossing of `o + t·d` (`d` unit) into the object, for `t ≥ 0`. A ray from inside
    /// the bounding sphere must start outside the object (F ≥ 0; a negative F at the origin is
    /// taken as rounding, as for a shadow ray leaving a hit). `None` when it leaves the bounding
    /// sphere without a crossing.
    pub fn trace(&self, o: DVec3, d: DVec3) -> Option<ObjectHit> {
        let r = self.bounding_radius() * (1.0 + 1e-9);
        // Entry and exit of |o + t d| = r.
        let b = o.dot(d);
        let c = o.length_squared() - r * r;
        let disc = b * b - c;
        if !(disc > 0.0) {
            return None;
        }
        let root = disc.sqrt();
        let (t_in, t_out) = ((-b - root).max(0.0), -b + root);
        if !(t_out > t_in) {
            return None;
        }
        let start = o + d * t_in;
        let t = sphere_trace(
            |t| self.gap(start + d * t),
            self.rate,
            self.min_step,
            |t| t > t_out - t_in,
            self.surface.march,
        )?;
        Some(ObjectHit {
            t: t_in + t,
            p: start + d * t,
        })
    }

    /// Whether the point `p` of the surface sees along `d` (unit) out of the bounding sphere: a
    /// shadow or visibility ray. The ray leaves from `p` lifted along the normal by a few minimum
    /// steps, so it does not find the surface it starts on.
    pub fn sees(&self, p: DVec3, d: DVec3) -> bool {
        let lift = self.normal(p) * (4.0 * self.min_step);
        self.trace(p + lift, d).is_none()
    }

    /// Every crossing of the surface by the segment `o + t·d`, `0 ≤ t ≤ length` (`d` unit), in
    /// order, into the object and out of it alike: the same rigorous march as [`Self::trace`]
    /// on `F` while outside and on `−F` while inside (|∇F| bounds both), each crossing the last
    /// point before the sign changes. Two crossings closer than the march's least step may be
    /// taken as none (a sliver thinner than 10⁻⁴ of the finest wavelength); at most
    /// [`MAX_CROSSINGS`] are returned.
    pub fn crossings(&self, o: DVec3, d: DVec3, length: f64) -> Vec<DVec3> {
        let mut out = Vec::new();
        let mut t0 = 0.0;
        let mut sign = if self.gap(o) < 0.0 { -1.0 } else { 1.0 };
        while out.len() < MAX_CROSSINGS {
            let start = o + d * t0;
            let Some(t) = sphere_trace(
                |t| sign * self.gap(start + d * t),
                self.rate,
                self.min_step,
                |t| t0 + t > length,
                self.surface.march,
            ) else {
                break;
            };
            out.push(start + d * t);
            // Just past the crossing (the march's bracket is far narrower than this): the next
            // march starts on the other side, where a rounding-level gap of the wrong sign at its
            // start is taken as zero.
            t0 += t + 1e-3 * self.min_step;
            sign = -sign;
        }
        out
    }
}

/// The most crossings [`DisplacedObject::crossings`] returns for one segment.
pub const MAX_CROSSINGS: usize = 4096;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::splitmix;

    fn object(shape: BaseShape) -> DisplacedObject {
        DisplacedObject::new(&crate::object::bumpy_material(0.3), shape).unwrap()
    }

    fn shapes() -> [BaseShape; 2] {
        [
            BaseShape::Sphere { radius: 1.0 },
            BaseShape::Torus {
                major: 1.0,
                minor: 0.4,
            },
        ]
    }

    /// Rays toward the object from outside: the hit is on the surface (F ≈ 0), the ray is outside
    /// all the way to it (F ≥ 0 on a fine sampling, so no earlier crossing was skipped), and F < 0
    /// just past it.
    #[test]
    fn the_trace_finds_the_first_crossing() {
        let mut rng = 21u64;
        for shape in shapes() {
            let obj = object(shape.clone());
            let mut hits = 0;
            for _ in 0..150 {
                let dir = |rng: &mut u64| {
                    DVec3::new(
                        splitmix(rng) - 0.5,
                        splitmix(rng) - 0.5,
                        splitmix(rng) - 0.5,
                    )
                    .normalize()
                };
                let o = dir(&mut rng) * 3.0;
                // Aim near the object, with grazing rays among them.
                let target = dir(&mut rng) * (shape.bounding_radius() * splitmix(&mut rng));
                let d = (target - o).normalize();
                let Some(hit) = obj.trace(o, d) else {
                    // A miss: the ray stays outside all the way (sampled finely).
                    for k in 0..4000 {
                        let p = o + d * (6.0 * k as f64 / 4000.0);
                        assert!(obj.gap(p) > -1e-9, "{shape:?}: missed a crossing at {p}");
                    }
                    continue;
                };
                hits += 1;
                assert!(obj.gap(hit.p).abs() < 1e-6, "{}", obj.gap(hit.p));
                assert!(obj.gap(hit.p) >= 0.0);
                assert!(obj.gap(o + d * (hit.t + 1e-5)) < 0.0);
                let samples = 4000;
                for k in 0..samples {
                    let t = hit.t * k as f64 / samples as f64;
                    assert!(
                        obj.gap(o + d * t) >= -1e-12,
                        "{shape:?}: crossed at {t} < {}",
                        hit.t
                    );
                }
            }
            assert!(hits > 40, "{shape:?}: {hits} hits");
        }
    }

    /// The fast march (Illinois refinement) finds the reference march's crossings (bisection):
    /// the same number on every line through a bumpy sphere, torus and cube, each within the
    /// refinements' brackets of the other, and the same first hit.
    #[test]
    fn the_fast_march_finds_the_reference_crossings() {
        let cube = BaseShape::Mesh(std::sync::Arc::new(
            crate::object::mesh::TriMesh::from_obj(&crate::object::cube_obj()).unwrap(),
        ));
        let mut rng = 9u64;
        for shape in [shapes()[0].clone(), shapes()[1].clone(), cube] {
            let fast = object(shape.clone());
            let reference = fast.clone().with_march(March::Reference);
            let r = fast.bounding_radius();
            let mut total = 0;
            for _ in 0..200 {
                let u = DVec3::new(
                    splitmix(&mut rng) - 0.5,
                    splitmix(&mut rng) - 0.5,
                    splitmix(&mut rng) - 0.5,
                );
                let d = u.normalize();
                let across = d.any_orthonormal_pair().0 * (r * (2.0 * splitmix(&mut rng) - 1.0));
                let o = across - d * (1.5 * r);
                let a = fast.crossings(o, d, 3.0 * r);
                let b = reference.crossings(o, d, 3.0 * r);
                assert_eq!(a.len(), b.len(), "{shape:?}: {o} {d}");
                for (p, q) in a.iter().zip(&b) {
                    assert!((*p - *q).length() < 1e-7, "{shape:?}: {p} vs {q}");
                }
                total += a.len();
                match (fast.trace(o, d), reference.trace(o, d)) {
                    (Some(x), Some(y)) => assert!((x.t - y.t).abs() < 1e-7),
                    (None, None) => {}
                    (x, y) => panic!("{shape:?}: {x:?} vs {y:?}"),
                }
            }
            assert!(total > 200, "{shape:?}: {total} crossings");
        }
    }

    /// Without relief the trace is the exact intersection with the sphere.
    #[test]
    fn a_flat_sphere_is_hit_where_the_formula_says() {
        let mut m = Material::default();
        m.heights.sigma_h = 0.0;
        let obj = DisplacedObject::new(&m, BaseShape::Sphere { radius: 1.5 }).unwrap();
        let o = DVec3::new(0.3, -4.0, 0.2);
        let d = DVec3::Y;
        let hit = obj.trace(o, d).unwrap();
        let exact = 4.0 - (1.5f64 * 1.5 - 0.3 * 0.3 - 0.2 * 0.2).sqrt();
        assert!((hit.t - exact).abs() < 1e-9, "{} {exact}", hit.t);
        assert!(obj.trace(o, DVec3::X).is_none());
    }

    /// The normal is the normalised gradient of F, and a surface point sees outward along it.
    #[test]
    fn the_normal_is_the_gradient_of_the_gap() {
        let obj = object(BaseShape::Sphere { radius: 1.0 });
        let mut rng = 4u64;
        for _ in 0..100 {
            let p =
                BaseShape::Sphere { radius: 1.0 }.point_at(splitmix(&mut rng), splitmix(&mut rng));
            let e = 1e-6;
            let fd = crate::object::central_gradient(|q| obj.gap(q), p, e);
            assert!((obj.normal(p) - fd.normalize()).length() < 1e-5);
        }
        let hit = obj.trace(DVec3::new(0.0, 0.0, 3.0), -DVec3::Z).unwrap();
        assert!(obj.sees(hit.p, DVec3::Z));
        assert!(!obj.sees(hit.p, -DVec3::Z), "through the object");
    }

    #[test]
    fn objects_that_cannot_be_built_say_why() {
        let mut m = Material::default();
        m.heights.sigma_h = 0.5;
        let e = DisplacedObject::new(&m, BaseShape::Sphere { radius: 1.0 }).unwrap_err();
        assert!(matches!(e, ObjectError::ReliefTooTall { .. }), "{e}");
        let e = DisplacedObject::new(
            &Material::default(),
            BaseShape::Torus {
                major: 1.0,
                minor: 2.0,
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("minor radius"), "{e}");
    }
}
