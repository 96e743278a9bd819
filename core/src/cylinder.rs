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

use crate::brdf::normal_of;
use crate::camera::{Camera, PIXEL_SIGMA};
use crate::footprint::{Method, Prepared};
use crate::surface::sphere_trace;
use glam::{DMat2, DMat3, DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// Which object the views show.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
pub enum Shape {
    /// The unbounded plane z = 0.
    #[default]
    Plane,
    /// A cylinder of this radius around an axis parallel to x through (·, 0, −R).
    Cylinder {
        /// Radius R (world units, > 0).
        radius: f64,
    },
}

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
fn to_tangent(p: DVec3, p0: DVec3, uv: DVec2, fr: (DVec3, DVec3, DVec3)) -> DVec3 {
    let q = p - p0;
    DVec3::new(uv.x + q.dot(fr.0), uv.y + q.dot(fr.1), q.dot(fr.2))
}

/// A direction in the local frame.
fn local(d: DVec3, fr: (DVec3, DVec3, DVec3)) -> DVec3 {
    DVec3::new(d.dot(fr.0), d.dot(fr.1), d.dot(fr.2))
}

impl Prepared {
    /// Bound of the gap's rate along any unit ray for the cylinder of radius `r` (see the module docs).
    fn cylinder_rate(&self, r: f64) -> f64 {
        let s = &self.surface;
        let k = s.slope_bound();
        let rho_min = (r - s.h_max).max(1e-9 * r);
        (1.0 + (k * r / rho_min).powi(2)).sqrt()
    }

    /// March `o + t·d` (unit d, o outside or on the surface) against the displaced cylinder, up to
    /// `t_max`. The shared [`sphere_trace`] on the gap `ρ − R − h(u, v)`. Returns the last point above the surface at the crossing.
    pub fn cylinder_march(&self, r: f64, o: DVec3, d: DVec3, t_max: f64) -> Option<f64> {
        let s = &self.surface;
        sphere_trace(
            |t| {
                let (u, v, rho, _) = to_surface(r, o + d * t);
                rho - r - s.height(DVec2::new(u, v))
            },
            self.cylinder_rate(r),
            s.min_step,
            |t| t > t_max,
        )
    }

    /// Ground-truth radiance along a camera ray toward light ωi, for the cylinder of radius `r`:
    /// the explicit displaced surface, the true micro-normal, a real shadow ray.
    pub fn cylinder_trace_ray(&self, r: f64, origin: DVec3, dir: DVec3, wi: DVec3) -> [f64; 3] {
        let s = &self.surface;
        let outer = r + s.h_max * 1.001 + 1e-6;
        let Some((t0, t1)) = intersect(r, outer, origin, dir) else {
            return [0.0; 3];
        };
        let o = origin + dir * t0;
        let Some(t) = self.cylinder_march(r, o, dir, t1 - t0) else {
            return [0.0; 3];
        };
        let p = o + dir * t;
        let (u, v, rho, phi) = to_surface(r, p);
        let (f, _h, grad) = s.sample(DVec2::new(u, v));
        // ∇(ρ − R − h) in the local frame: (−h_u, −(R/ρ)·h_v, 1).
        let fr = frame(phi);
        let n = normal_of(DVec2::new(grad.x, grad.y * r / rho.max(1e-300)));
        let (wo_l, wi_l) = (local(-dir, fr), local(wi, fr));
        // Shadow ray: to where it leaves the bounding cylinder.
        let sees = || {
            intersect(r, outer, p, wi)
                .is_none_or(|(_, e1)| self.cylinder_march(r, p, wi, e1).is_none())
        };
        let m = DMat3::from_cols(fr.0, fr.1, fr.2);
        self.shade_hit(f, n, wo_l, wi_l, &m, sees)
    }

    /// One pixel of an analytic view of the cylinder: the ray meets the mean cylinder; the plane
    /// model runs in the tangent plane there with the pixel's footprint on that plane.
    pub fn cylinder_pixel(
        &self,
        method: Method,
        r: f64,
        camera: &Camera,
        p: DVec2,
        (width, height): (u32, u32),
        wi: DVec3,
    ) -> [f64; 3] {
        let ray = camera.ray(p, width, height);
        let Some((t, _)) = intersect(r, r, ray.origin, ray.dir) else {
            return [0.0; 3];
        };
        let hit = ray.origin + ray.dir * t;
        let (u, v, _, phi) = to_surface(r, hit);
        let fr = frame(phi);
        let Some(cov) = camera.tangent_footprint(p, width, height, hit, fr) else {
            return [0.0; 3];
        };
        let uv = DVec2::new(u, v);
        let o = to_tangent(ray.origin, hit, uv, fr);
        let d = local(ray.dir, fr);
        let fp = crate::noise::Footprint { cov };
        let m = DMat3::from_cols(fr.0, fr.1, fr.2);
        self.pixel_in_frame(method, o, d, local(wi, fr), fp, &m)
    }
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
    use crate::material::Material;

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

    /// A flat material (σ_h = 0) on a cylinder: ground truth and the analytic views agree, because
    /// the mean cylinder is then the exact surface; and the ray marcher finds the analytic hit.
    #[test]
    fn flat_material_on_a_cylinder_agrees_across_methods() {
        let mut m = Material::default();
        m.heights.sigma_h = 0.0;
        m.brdf.roughness = 0.3;
        let p = Prepared::new(&m).unwrap();
        let r = 1.5;
        let cam = Camera {
            elevation_deg: 50.0,
            azimuth_deg: 70.0,
            distance: 5.0,
            target: [0.0, 0.0],
            fov_deg: 40.0,
        };
        let wi = crate::smith::direction(0.6, 2.0);
        let (w, h) = (64, 48);
        let mut compared = 0;
        for (x, y) in [(32, 24), (10, 30), (50, 20), (20, 40), (40, 10)] {
            let px = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
            let ray = cam.ray(px, w, h);
            let truth = p.cylinder_trace_ray(r, ray.origin, ray.dir, wi);
            let naive = p.cylinder_pixel(Method::Naive, r, &cam, px, (w, h), wi);
            if let Some((t, _)) = intersect(r, r, ray.origin, ray.dir) {
                compared += 1;
                let hit = ray.origin + ray.dir * t;
                let (_, _, rho, _) = to_surface(r, hit);
                assert!((rho - r).abs() < 1e-9);
                for k in 0..3 {
                    // Naive shades the footprint-averaged colour; at these footprints the colour
                    // varies, so compare with a tolerance that covers colour filtering only.
                    assert!(
                        (truth[k] - naive[k]).abs() < 0.08 * truth[k].max(0.05),
                        "{truth:?} {naive:?}"
                    );
                }
            } else {
                assert_eq!(truth, [0.0; 3]);
                assert_eq!(naive, [0.0; 3]);
            }
        }
        assert!(compared >= 3);
    }

    /// The march finds the first crossing of the displaced cylinder that a brute-force scan with
    /// steps far below the feature size finds, for rays from every side, grazing ones included.
    #[test]
    fn march_finds_the_first_crossing_like_a_dense_scan() {
        let m = Material::default();
        let p = Prepared::new(&m).unwrap();
        let r = 1.2;
        let s = &p.surface;
        let outer = r + s.h_max * 1.001 + 1e-6;
        let gap = |q: DVec3| {
            let (u, v, rho, _) = to_surface(r, q);
            rho - r - s.height(DVec2::new(u, v))
        };
        let mut checked = 0;
        for i in 0..60 {
            let a = 0.37 * f64::from(i);
            let eye = DVec3::new(
                0.3 * a.sin(),
                4.0 * a.cos(),
                3.0 * (0.5 + 0.5 * (1.3 * a).sin()),
            );
            // Aim at points near the silhouette as well as the middle.
            let aim = DVec3::new(
                0.1 * f64::from(i % 7),
                (f64::from(i % 11) / 5.0 - 1.0) * (r + 0.04),
                -r * 0.3,
            );
            let d = (aim - eye).normalize();
            let Some((t0, t1)) = intersect(r, outer, eye, d) else {
                continue;
            };
            let o = eye + d * t0;
            let got = p.cylinder_march(r, o, d, t1 - t0);
            let n = 200_000;
            let dt = (t1 - t0) / f64::from(n);
            let want = (1..=n)
                .map(|k| f64::from(k) * dt)
                .find(|t| gap(o + d * *t) < 0.0);
            match (got, want) {
                (Some(g), Some(w)) => {
                    assert!((g - w).abs() <= 2.0 * dt, "ray {i}: march {g}, scan {w}");
                    assert!(gap(o + d * g) >= -1e-9);
                    checked += 1;
                }
                (None, None) => {}
                other => panic!("ray {i}: march and scan disagree: {other:?}"),
            }
        }
        assert!(checked > 20, "{checked}");
    }
}
