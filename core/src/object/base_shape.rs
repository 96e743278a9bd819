//! The closed set of base shapes a whole object is made of (#19): its macro-surface before the
//! relief, given by an exact signed distance [HN12 Sec. 5.2: "volumetric objects as macroscopic
//! signed distance fields"].
//!
//! Edge cases: the distance is exact and 1-Lipschitz everywhere (sphere tracing relies on it). The
//! gradient is the unit outward normal wherever the closest point is unique; where it is not (a
//! sphere's centre, a torus's axis or its core circle) [`BaseShape::normal`] returns a fixed unit
//! vector, so it is finite on every input.

use crate::object::mesh::TriMesh;
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// A closed base shape, centred at the origin.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum BaseShape {
    /// A sphere of this radius.
    Sphere {
        /// Radius (world units, > 0).
        radius: f64,
    },
    /// A ring torus around the z axis: the circle of radius `major` in the z = 0 plane, swept by a
    /// disc of radius `minor`.
    Torus {
        /// Distance from the axis to the tube's centre (> `minor`).
        major: f64,
        /// Radius of the tube (> 0).
        minor: f64,
    },
    /// A closed triangle mesh (checked when it was loaded: [`TriMesh::new`]); a preset names its
    /// file, so the mesh itself is never written.
    #[serde(skip)]
    Mesh(Arc<TriMesh>),
}

impl Default for BaseShape {
    fn default() -> Self {
        Self::Sphere { radius: 1.0 }
    }
}

/// A base shape that cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShapeError {
    /// A radius that is not a finite positive number.
    #[error("{what} must be a finite number > 0 (got {value})")]
    Radius {
        /// Which radius.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// A torus whose tube reaches its axis (a horn or spindle torus, not a ring).
    #[error("the torus's minor radius ({minor}) must be below its major radius ({major})")]
    TorusNotRing {
        /// Major radius.
        major: f64,
        /// Minor radius.
        minor: f64,
    },
}

impl BaseShape {
    /// Checks the radii: finite, positive, and a ring torus.
    pub fn validate(&self) -> Result<(), ShapeError> {
        let positive = |what, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ShapeError::Radius { what, value })
            }
        };
        match *self {
            Self::Mesh(_) => Ok(()),
            Self::Sphere { radius } => positive("the sphere's radius", radius),
            Self::Torus { major, minor } => {
                positive("the torus's major radius", major)?;
                positive("the torus's minor radius", minor)?;
                if minor < major {
                    Ok(())
                } else {
                    Err(ShapeError::TorusNotRing { major, minor })
                }
            }
        }
    }

    /// The signed distance to the surface (negative inside), exact.
    pub fn distance(&self, p: DVec3) -> f64 {
        match *self {
            Self::Mesh(ref m) => m.distance(p),
            Self::Sphere { radius } => p.length() - radius,
            Self::Torus { major, minor } => {
                DVec2::new(DVec2::new(p.x, p.y).length() - major, p.z).length() - minor
            }
        }
    }

    /// The unit gradient of [`BaseShape::distance`]: the outward normal of the closest surface
    /// point. Where that point is not unique (module docs) a fixed unit vector: +z at a sphere's
    /// centre, +x from the torus's axis, and radially outward in the z = 0 plane on its core circle.
    pub fn normal(&self, p: DVec3) -> DVec3 {
        match *self {
            Self::Mesh(ref m) => m.normal(p),
            Self::Sphere { .. } => p.try_normalize().unwrap_or(DVec3::Z),
            Self::Torus { major, .. } => {
                let radial = DVec2::new(p.x, p.y).try_normalize().unwrap_or(DVec2::X);
                let rho = DVec2::new(p.x, p.y).length();
                let q = DVec2::new(rho - major, p.z)
                    .try_normalize()
                    .unwrap_or(DVec2::X);
                DVec3::new(q.x * radial.x, q.x * radial.y, q.y)
            }
        }
    }

    /// The radius of the smallest origin-centred sphere that holds the shape.
    pub fn bounding_radius(&self) -> f64 {
        match *self {
            Self::Mesh(ref m) => m.bounding_radius(),
            Self::Sphere { radius } => radius,
            Self::Torus { major, minor } => major + minor,
        }
    }

    /// The surface's area (for per-area statistics and tests).
    pub fn area(&self) -> f64 {
        use std::f64::consts::PI;
        match *self {
            Self::Mesh(ref m) => m.area(),
            Self::Sphere { radius } => 4.0 * PI * radius * radius,
            Self::Torus { major, minor } => 4.0 * PI * PI * major * minor,
        }
    }

    /// The smallest radius of curvature, or for a mesh half its least thickness
    /// ([`TriMesh::thickness`]): how far a relief may reach before the displaced surface folds.
    pub fn feature_radius(&self) -> f64 {
        match *self {
            Self::Mesh(ref m) => 0.5 * m.thickness(),
            Self::Sphere { radius } => radius,
            Self::Torus { major, minor } => minor.min(major - minor),
        }
    }

    /// The surface point at parameters (u, v) ∈ [0, 1)² (a sphere's longitude and the cosine of
    /// its colatitude, which is area-preserving; a torus's angles around the axis and around the
    /// tube): for sampling the surface in tests and statistics. Each call returns a point on the
    /// surface (distance 0 up to rounding). A mesh has no parameters: its first vertex.
    pub fn point_at(&self, u: f64, v: f64) -> DVec3 {
        use std::f64::consts::TAU;
        match *self {
            Self::Mesh(ref m) => m.vertices[0],
            Self::Sphere { radius } => {
                let (z, phi) = (1.0 - 2.0 * v, TAU * u);
                let s = (1.0 - z * z).max(0.0).sqrt();
                radius * DVec3::new(s * phi.cos(), s * phi.sin(), z)
            }
            Self::Torus { major, minor } => {
                let (a, b) = (TAU * u, TAU * v);
                let rho = major + minor * b.cos();
                DVec3::new(rho * a.cos(), rho * a.sin(), minor * b.sin())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::splitmix;

    fn shapes() -> [BaseShape; 3] {
        [
            BaseShape::Sphere { radius: 1.3 },
            BaseShape::Torus {
                major: 1.0,
                minor: 0.35,
            },
            BaseShape::Torus {
                major: 2.0,
                minor: 1.9,
            },
        ]
    }

    /// The distance is the brute-force distance to a dense sampling of the surface (which can only
    /// overestimate it, by at most the sampling's spacing), with the sign of inside.
    #[test]
    fn distance_is_the_distance_to_the_surface() {
        let mut rng = 5u64;
        for s in shapes() {
            let n = 600;
            let pts: Vec<DVec3> = (0..n * n)
                .map(|k| s.point_at((k % n) as f64 / n as f64, (k / n) as f64 / n as f64))
                .collect();
            let spacing = std::f64::consts::TAU * s.bounding_radius() / n as f64;
            for _ in 0..60 {
                let p = DVec3::new(
                    4.0 * splitmix(&mut rng) - 2.0,
                    4.0 * splitmix(&mut rng) - 2.0,
                    4.0 * splitmix(&mut rng) - 2.0,
                ) * s.bounding_radius();
                let brute = pts
                    .iter()
                    .map(|q| (*q - p).length())
                    .fold(f64::INFINITY, f64::min);
                let d = s.distance(p);
                assert!(
                    d.abs() <= brute + 1e-12 && d.abs() >= brute - spacing,
                    "{s:?} at {p}: {d} against {brute}"
                );
            }
            // Sign: the sample points pushed along their normal are outside, pulled in inside.
            for q in pts.iter().step_by(997) {
                let nrm = s.normal(*q);
                assert!(s.distance(*q + 0.01 * nrm) > 0.0 && s.distance(*q - 0.01 * nrm) < 0.0);
                assert!(s.distance(*q).abs() < 1e-12, "{s:?}: {}", s.distance(*q));
            }
        }
    }

    /// The normal is the distance's gradient (central differences), unit length, and finite at
    /// the points where the closest point is not unique.
    #[test]
    fn normal_is_the_unit_gradient_and_finite_everywhere() {
        let mut rng = 9u64;
        for s in shapes() {
            for _ in 0..200 {
                let p = DVec3::new(
                    3.0 * splitmix(&mut rng) - 1.5,
                    3.0 * splitmix(&mut rng) - 1.5,
                    3.0 * splitmix(&mut rng) - 1.5,
                ) * s.bounding_radius();
                let e = 1e-6;
                let fd = crate::object::central_gradient(|q| s.distance(q), p, e);
                let n = s.normal(p);
                assert!((n - fd).length() < 1e-5, "{s:?} at {p}: {n} against {fd}");
                assert!((n.length() - 1.0).abs() < 1e-12);
            }
            for p in [
                DVec3::ZERO,
                DVec3::new(0.0, 0.0, 0.7),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 2.0, 0.0),
            ] {
                let n = s.normal(p);
                assert!(
                    n.is_finite() && (n.length() - 1.0).abs() < 1e-12,
                    "{s:?} {p}"
                );
                assert!(s.distance(p).is_finite());
            }
        }
    }

    #[test]
    fn bad_radii_are_refused_with_a_reason() {
        assert!(BaseShape::Sphere { radius: 1.0 }.validate().is_ok());
        for bad in [
            BaseShape::Sphere { radius: 0.0 },
            BaseShape::Sphere { radius: f64::NAN },
            BaseShape::Sphere {
                radius: f64::INFINITY,
            },
            BaseShape::Torus {
                major: 1.0,
                minor: 1.0,
            },
            BaseShape::Torus {
                major: 1.0,
                minor: -0.1,
            },
        ] {
            let e = bad.validate().unwrap_err();
            assert!(e.to_string().contains("radius"), "{e}");
        }
    }
}
