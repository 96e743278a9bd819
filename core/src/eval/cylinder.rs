//! The cylinder's pixels: ground truth on the explicit displaced cylinder (its gap `ρ − R − h(u, v)`
//! marched with the rate bound of [`crate::scene::cylinder`]), and the analytic views in the tangent
//! plane where the ray meets the mean cylinder.

use crate::driver::footprint::Footprint;
use crate::eval::{Evaluator, Method};
use crate::microfacet::slopes::normal_of;
use crate::scene::camera::Camera;
use crate::scene::cylinder::{frame, intersect, local, to_surface, to_tangent};
use crate::scene::march::sphere_trace;
use glam::{DMat3, DVec2, DVec3};

impl Evaluator {
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
            s.march,
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

    /// One pixel of an analytic view of the cylinder (the camera lifted clear of the relief:
    /// [`crate::scene::surface::Surface::clear_cylinder_camera`]): the ray meets the mean
    /// cylinder; the plane model runs in the tangent plane there with the pixel's footprint on
    /// that plane.
    pub fn cylinder_pixel(
        &self,
        method: Method,
        r: f64,
        camera: &Camera,
        p: DVec2,
        (width, height): (u32, u32),
        wi: DVec3,
    ) -> [f64; 3] {
        match self.cylinder_query(r, camera, p, (width, height), wi) {
            Some((o, d, wi, fp, m)) => self.pixel_in_frame(method, o, d, wi, fp, &m),
            None => [0.0; 3],
        }
    }

    /// Where [`Evaluator::cylinder_pixel`] evaluates pixel centre `p`: the ray's origin and
    /// direction and the light in the tangent frame where it meets the mean cylinder, the pixel's
    /// footprint on that plane, and the frame (its axes in the world as columns). None where the
    /// ray misses the cylinder or has no footprint there.
    pub fn cylinder_query(
        &self,
        r: f64,
        camera: &Camera,
        p: DVec2,
        (width, height): (u32, u32),
        wi: DVec3,
    ) -> Option<(DVec3, DVec3, DVec3, Footprint, DMat3)> {
        // The cylinder's top line passes through the camera's target: work relative to it, the
        // surface coordinates moved by it (`Surface::clear_cylinder_camera`, the GPU's view).
        let anchor = DVec2::from(camera.target);
        let lifted = self.surface.clear_cylinder_camera(camera, r);
        let camera = &Camera {
            target: [lifted.target[0] - anchor.x, lifted.target[1] - anchor.y],
            ..lifted
        };
        let ray = camera.ray(p, width, height);
        let (t, _) = intersect(r, r, ray.origin, ray.dir)?;
        let hit = ray.origin + ray.dir * t;
        let (u, v, _, phi) = to_surface(r, hit);
        let fr = frame(phi);
        let cov = camera.tangent_footprint(p, width, height, hit, fr)?;
        let uv = DVec2::new(u, v) + anchor;
        let o = to_tangent(ray.origin, hit, uv, fr);
        let d = local(ray.dir, fr);
        let m = DMat3::from_cols(fr.0, fr.1, fr.2);
        Some((o, d, local(wi, fr), Footprint { cov }, m))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;

    /// A flat material (σ_h = 0) on a cylinder: ground truth and the analytic views agree, because
    /// the mean cylinder is then the exact surface; and the ray marcher finds the analytic hit.
    #[test]
    fn flat_material_on_a_cylinder_agrees_across_methods() {
        let mut m = Material::default();
        m.heights.sigma_h = 0.0;
        m.brdf.roughness = 0.3;
        let p = Evaluator::new(&m).unwrap();
        let r = 1.5;
        let cam = Camera {
            elevation_deg: 50.0,
            azimuth_deg: 70.0,
            distance: 5.0,
            target: [0.0, 0.0],
            fov_deg: 40.0,
        };
        let wi = crate::scene::direction::direction(0.6, 2.0);
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
        let p = Evaluator::new(&m).unwrap();
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
