//! The curved test object: a cylinder of radius R around an axis parallel to x, its top line on the
//! plane z = 0 (axis through (·, 0, −R)), so the camera frames it like the plane. The material is
//! wrapped isometrically: surface coordinates `(u, v) = (x, R·φ)`, φ the angle from +z toward +y, and
//! the micro-geometry displaces along the outward normal, radius `ρ = R + h(u, v)` [HN12 Fig. 5],
//! [HNPN14 Fig. 1].
//!
//! Ground truth marches the explicit displaced cylinder with the gap `ρ(p) − R − h(u(p), v(p))`,
//! whose rate of change along a unit ray is bounded by `√(1 + (K·R/ρ_min)²)`, K a bound of |∇h|
//! and `ρ_min = R − h_max`; it is shaded at the true micro-normal in the local frame. The analytic
//! views meet the mean cylinder and evaluate the plane's model in the tangent plane there (local
//! frame, tangent-plane pixel footprint): exact where R is large against the footprint, and the
//! relief's own silhouette is left to the ground truth.

use crate::scene::camera::{Camera, PIXEL_SIGMA};
use glam::{DMat2, DVec2, DVec3};

/// The local frame at angle φ: tangents ∂/∂u, ∂/∂v and the outward normal (right-handed).
pub fn frame(phi: f64) -> (DVec3, DVec3, DVec3) {
    let (s, c) = phi.sin_cos();
    (DVec3::X, DVec3::new(0.0, c, -s), DVec3::new(0.0, s, c))
}

/// `(u, v, ρ, φ)` of a world point for a cylinder of radius `r`.
pub fn to_surface(r: f64, p: DVec3) -> (f64, f64, f64, f64) {
    let (y, z) = (p.y, p.z + r);
    let rho = (y * y + z * z).sqrt();
    let phi = y.atan2(z);
    (p.x, r * phi, rho, phi)
}

/// Entry and exit of the ray `o + t·d` (unit d) through the cylinder of radius `a` around the
/// axis of a cylinder of radius `r`; `None` when it misses.
pub fn intersect(r: f64, a: f64, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
    let (oy, oz) = (o.y, o.z + r);
    let qa = d.y * d.y + d.z * d.z;
    if !(qa > 1e-300) {
        return None;
    }
    let qb = oy * d.y + oz * d.z;
    let qc = oy * oy + oz * oz - a * a;
    let disc = qb * qb - qa * qc;
    if !(disc >= 0.0) {
        return None;
    }
    let sq = disc.sqrt();
    // Stable roots of qa t² + 2 qb t + qc.
    let q = -(qb + sq.copysign(qb));
    let (t1, t2) = if q != 0.0 {
        let (x, y) = (q / qa, qc / q);
        (x.min(y), x.max(y))
    } else {
        (0.0, 0.0)
    };
    if t2 < 0.0 {
        None
    } else {
        Some((t1.max(0.0), t2))
    }
}

/// A point of the world expressed in the tangent plane at surface point (u, v) with frame
/// (t_u, t_v, n) anchored at world point `p0`: plane coordinates (x, y) = (u, v) + offsets, z the
/// height above the tangent plane.
pub fn to_tangent(p: DVec3, p0: DVec3, uv: DVec2, fr: (DVec3, DVec3, DVec3)) -> DVec3 {
    let q = p - p0;
    DVec3::new(uv.x + q.dot(fr.0), uv.y + q.dot(fr.1), q.dot(fr.2))
}

/// A direction in the local frame.
pub fn local(d: DVec3, fr: (DVec3, DVec3, DVec3)) -> DVec3 {
    DVec3::new(d.dot(fr.0), d.dot(fr.1), d.dot(fr.2))
}

impl Camera {
    /// Footprint covariance, in the coordinates of the tangents (t_u, t_v), of the pixel at `p` on
    /// the plane through `point` with frame `(t_u, t_v, n)`: `PIXEL_SIGMA² J Jᵀ`, J the Jacobian of the
    /// plane position with respect to pixel position. `None` when the ray is parallel to the plane.
    pub fn tangent_footprint(
        &self,
        p: DVec2,
        width: u32,
        height: u32,
        point: DVec3,
        (tu, tv, n): (DVec3, DVec3, DVec3),
    ) -> Option<DMat2> {
        let e = self.eye();
        let d = self.raw_dir(p, width, height);
        let dn = d.dot(n);
        if !(dn.abs() > 1e-300) {
            return None;
        }
        let (dx, dy) = self.pixel_steps(width, height);
        // x(p) = e + s·d, s = (point − e)·n / d·n  ⇒  ∂x = s (∂d − d (∂d·n)/(d·n)).
        let s = (point - e).dot(n) / dn;
        let jac = |dd: DVec3| (dd - d * (dd.dot(n) / dn)) * s;
        let (jx, jy) = (jac(dx), jac(dy));
        let j = DMat2::from_cols(
            DVec2::new(jx.dot(tu), jx.dot(tv)),
            DVec2::new(jy.dot(tu), jy.dot(tv)),
        );
        let cov = j * j.transpose() * (PIXEL_SIGMA * PIXEL_SIGMA);
        cov.is_finite().then_some(cov)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surface_coordinates_and_frame() {
        let r = 2.0;
        // The top line: φ = 0, normal +z.
        let (u, v, rho, phi) = to_surface(r, DVec3::new(0.3, 0.0, 0.0));
        assert!(
            (u - 0.3).abs() < 1e-15 && v.abs() < 1e-15 && (rho - r).abs() < 1e-15 && phi == 0.0
        );
        // A quarter turn toward +y: arc length πR/2, normal +y.
        let (_, v, rho, phi) = to_surface(r, DVec3::new(0.0, 2.5, -r));
        assert!((v - r * std::f64::consts::FRAC_PI_2).abs() < 1e-12 && (rho - 2.5).abs() < 1e-12);
        let (tu, tv, n) = frame(phi);
        assert!((n - DVec3::Y).length() < 1e-12 && (tu.cross(tv) - n).length() < 1e-12);
        // ∂/∂v of the surface point is t_v: finite difference of the parameterisation.
        let point = |v: f64| {
            let phi = v / r;
            DVec3::new(0.0, r * phi.sin(), -r + r * phi.cos())
        };
        let (v0, e) = (0.7, 1e-6);
        let dv = (point(v0 + e) - point(v0 - e)) / (2.0 * e);
        assert!((dv - frame(v0 / r).1).length() < 1e-8);
    }

    #[test]
    fn ray_cylinder_intersection() {
        let r = 1.0;
        // Straight down onto the top line.
        let (t0, t1) = intersect(r, r, DVec3::new(0.0, 0.0, 5.0), -DVec3::Z).unwrap();
        assert!((t0 - 5.0).abs() < 1e-12 && (t1 - 7.0).abs() < 1e-12);
        // Grazing past at y = 1.0001: a miss; at 0.9999: a hit.
        assert!(intersect(r, r, DVec3::new(0.0, 1.0001, 5.0), -DVec3::Z).is_none());
        assert!(intersect(r, r, DVec3::new(0.0, 0.9999, 5.0), -DVec3::Z).is_some());
        // Parallel to the axis: never.
        assert!(intersect(r, r, DVec3::new(0.0, 0.0, 5.0), DVec3::X).is_none());
        // From inside: entry clamps to 0.
        let (t0, _) = intersect(r, r, DVec3::new(0.0, 0.0, -1.0), DVec3::Z).unwrap();
        assert_eq!(t0, 0.0);
    }

    #[test]
    fn tangent_footprint_on_z0_equals_the_plane_footprint() {
        let c = Camera {
            elevation_deg: 60.0,
            azimuth_deg: 20.0,
            distance: 3.0,
            target: [0.0, 0.0],
            fov_deg: 40.0,
        };
        let p = DVec2::new(100.5, 80.5);
        let (x0, want) = c.plane_footprint(p, 200, 150).unwrap();
        let got = c
            .tangent_footprint(
                p,
                200,
                150,
                DVec3::new(x0.x, x0.y, 0.0),
                (DVec3::X, DVec3::Y, DVec3::Z),
            )
            .unwrap();
        assert!(
            (got - want)
                .abs()
                .to_cols_array()
                .iter()
                .all(|e| *e < 1e-12 * want.x_axis.x)
        );
    }
}
