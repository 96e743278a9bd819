//! The orbit camera shared by every view, its pixel rays, and the Gaussian footprint a pixel covers
//! on the mean plane z = 0 (ray differentials).
//!
//! The pixel filter is an isotropic Gaussian of standard deviation [`PIXEL_SIGMA`] pixels. Mapped to
//! the plane through the Jacobian J of the screen-to-plane map at the pixel centre, it becomes the
//! texture-space covariance `Σ_p = PIXEL_SIGMA² · J Jᵀ` used by the filtered and naive views. The
//! ground truth draws its sub-pixel rays from the same Gaussian, so both see the same footprint.

use glam::{DMat2, DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// Standard deviation of the Gaussian pixel filter, in pixels.
pub const PIXEL_SIGMA: f64 = 0.5;

/// An orbit camera looking at a point of the plane z = 0.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Angle between the view direction and the plane's normal, degrees, in [0, 89.5].
    pub elevation_deg: f64,
    /// Azimuth of the eye around the normal, degrees.
    pub azimuth_deg: f64,
    /// Distance from the target to the eye (world units, > 0).
    pub distance: f64,
    /// The looked-at point on the plane.
    pub target: [f64; 2],
    /// Vertical field of view, degrees, in (0, 120].
    pub fov_deg: f64,
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            elevation_deg: 55.0,
            azimuth_deg: 0.0,
            distance: 4.0,
            target: [0.0, 0.0],
            fov_deg: 35.0,
        }
    }
}

/// A ray through a pixel: origin and unit direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin (the eye).
    pub origin: DVec3,
    /// Unit direction.
    pub dir: DVec3,
}

impl Camera {
    /// Largest elevation the camera accepts (degrees).
    pub const MAX_ELEVATION_DEG: f64 = 89.5;

    /// tan(fov/2), with the field of view clamped to (0, 120°]: the scale of the image plane.
    pub fn tan_half_fov(&self) -> f64 {
        (self.fov_deg.clamp(1e-3, 120.0).to_radians() * 0.5).tan()
    }

    /// Unit vector from the target toward the eye.
    pub fn to_eye(&self) -> DVec3 {
        let e = self
            .elevation_deg
            .clamp(0.0, Self::MAX_ELEVATION_DEG)
            .to_radians();
        crate::scene::direction::direction(e, self.azimuth_deg.to_radians())
    }

    /// Eye position.
    pub fn eye(&self) -> DVec3 {
        DVec3::new(self.target[0], self.target[1], 0.0) + self.to_eye() * self.distance.max(1e-9)
    }

    /// This camera moved straight up where needed so that its eye is at least `clearance` above
    /// the mean plane ([`crate::scene::surface::Surface::clear_camera`] keeps it above the relief).
    ///
    /// Elevation, azimuth, field of view and so the view direction are unchanged; the target
    /// slides along the view so it stays on z = 0 (it moves away: the new distance is
    /// `clearance / cos θ`). The identity when the eye is already clear or `clearance` is not a
    /// positive finite number. Continuous in the distance and the clearance: no jump where the
    /// lift starts.
    pub fn clear_of(&self, clearance: f64) -> Camera {
        let to_eye = self.to_eye();
        let eye = self.eye();
        if !(clearance.is_finite() && clearance > 0.0 && eye.z < clearance && to_eye.z > 0.0) {
            return *self;
        }
        let distance = clearance / to_eye.z;
        let target = DVec3::new(eye.x, eye.y, clearance) - to_eye * distance;
        Camera {
            distance,
            target: [target.x, target.y],
            ..*self
        }
    }

    /// Right, up and forward unit vectors (right-handed; up has a positive z component).
    pub fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let f = -self.to_eye();
        let r = f.cross(DVec3::Z);
        let r = if r.length_squared() > 1e-24 {
            r.normalize()
        } else {
            // Looking straight down: keep the azimuth's orientation.
            let a = self.azimuth_deg.to_radians();
            DVec3::new(a.sin(), -a.cos(), 0.0)
        };
        let u = r.cross(f);
        (r, u, f)
    }

    /// Unnormalised direction through continuous pixel coordinates (x right, y down, pixel centres at
    /// +0.5) of a `width × height` image.
    pub fn raw_dir(&self, p: DVec2, width: u32, height: u32) -> DVec3 {
        let (r, u, f) = self.basis();
        let t = self.tan_half_fov();
        let aspect = f64::from(width) / f64::from(height.max(1));
        let nx = (p.x / f64::from(width)) * 2.0 - 1.0;
        let ny = 1.0 - (p.y / f64::from(height)) * 2.0;
        f + r * (nx * t * aspect) + u * (ny * t)
    }

    /// Change of the unnormalised ray direction per pixel in x and in y.
    pub fn pixel_steps(&self, width: u32, height: u32) -> (DVec3, DVec3) {
        let (r, u, _) = self.basis();
        let t = self.tan_half_fov();
        let aspect = f64::from(width) / f64::from(height.max(1));
        (
            r * (2.0 * t * aspect / f64::from(width)),
            u * (-2.0 * t / f64::from(height)),
        )
    }

    /// The ray through continuous pixel coordinates `p`.
    pub fn ray(&self, p: DVec2, width: u32, height: u32) -> Ray {
        Ray {
            origin: self.eye(),
            dir: self.raw_dir(p, width, height).normalize(),
        }
    }

    /// Where the ray through `p` meets the plane z = 0, and the footprint covariance there
    /// (`PIXEL_SIGMA² J Jᵀ`, J the Jacobian of plane position with respect to pixel position).
    /// `None` when the ray misses the plane (sky).
    pub fn plane_footprint(&self, p: DVec2, width: u32, height: u32) -> Option<(DVec2, DMat2)> {
        let e = self.eye();
        let d = self.raw_dir(p, width, height);
        if !(d.z < 0.0) {
            return None;
        }
        let (dx, dy) = self.pixel_steps(width, height);
        // x(p) = e − e_z/d_z · d  ⇒  ∂x = −e_z (∂d·d_z − d·∂d_z)/d_z².
        let hit = e - d * (e.z / d.z);
        let jac = |dd: DVec3| -(dd * d.z - d * dd.z) * (e.z / (d.z * d.z));
        let (jx, jy) = (jac(dx), jac(dy));
        let j = DMat2::from_cols(DVec2::new(jx.x, jx.y), DVec2::new(jy.x, jy.y));
        let cov = j * j.transpose() * (PIXEL_SIGMA * PIXEL_SIGMA);
        Some((DVec2::new(hit.x, hit.y), cov))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn looking_straight_down_gives_an_isotropic_footprint() {
        let c = Camera {
            elevation_deg: 0.0,
            distance: 10.0,
            fov_deg: 90.0,
            ..Camera::default()
        };
        let (x, cov) = c.plane_footprint(DVec2::new(50.0, 50.0), 100, 100).unwrap();
        assert!(x.length() < 1e-9);
        // The image spans 2·10·tan(45°) = 20 units over 100 pixels: 0.2 per pixel.
        let s = 0.2 * PIXEL_SIGMA;
        assert!((cov.x_axis.x - s * s).abs() < 1e-12 && (cov.y_axis.y - s * s).abs() < 1e-12);
        assert!(cov.x_axis.y.abs() < 1e-15);
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let c = Camera {
            elevation_deg: 72.0,
            azimuth_deg: 30.0,
            distance: 3.0,
            target: [0.4, -0.2],
            fov_deg: 40.0,
        };
        let (w, h) = (320, 200);
        for p in [
            DVec2::new(10.5, 150.5),
            DVec2::new(160.0, 100.0),
            DVec2::new(300.2, 20.7),
        ] {
            let (x0, cov) = c.plane_footprint(p, w, h).unwrap();
            let e = 1e-4;
            let hit = |q: DVec2| c.plane_footprint(q, w, h).unwrap().0;
            let jx = (hit(p + DVec2::new(e, 0.0)) - hit(p - DVec2::new(e, 0.0))) / (2.0 * e);
            let jy = (hit(p + DVec2::new(0.0, e)) - hit(p - DVec2::new(0.0, e))) / (2.0 * e);
            let j = DMat2::from_cols(jx, jy);
            let want = j * j.transpose() * (PIXEL_SIGMA * PIXEL_SIGMA);
            for (a, b) in [
                (cov.x_axis.x, want.x_axis.x),
                (cov.x_axis.y, want.x_axis.y),
                (cov.y_axis.y, want.y_axis.y),
            ] {
                assert!(
                    (a - b).abs() < 1e-6 * want.x_axis.x.abs().max(want.y_axis.y.abs()),
                    "{a} vs {b}"
                );
            }
            // The ray through p does hit x0.
            let r = c.ray(p, w, h);
            let q = r.origin + r.dir * (-r.origin.z / r.dir.z);
            assert!((DVec2::new(q.x, q.y) - x0).length() < 1e-9);
        }
    }

    /// The lifted eye is exactly at the clearance, straight above the old eye, looking the same
    /// way; an eye already clear, or a clearance that is not a positive number, changes nothing;
    /// the lift is continuous where it starts.
    #[test]
    fn a_camera_below_the_clearance_is_lifted_straight_up() {
        let c = Camera {
            elevation_deg: 77.0,
            azimuth_deg: 40.0,
            distance: 0.15,
            target: [0.3, -0.2],
            fov_deg: 35.0,
        };
        let lifted = c.clear_of(0.1);
        let (e, l) = (c.eye(), lifted.eye());
        assert!(e.z < 0.1);
        assert!((l.z - 0.1).abs() < 1e-12, "{l}");
        assert!((l.x - e.x).abs() < 1e-12 && (l.y - e.y).abs() < 1e-12);
        let (_, _, f) = c.basis();
        let (_, _, g) = lifted.basis();
        assert!((f - g).length() < 1e-12);
        assert_eq!(c.clear_of(0.01), c);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(c.clear_of(bad), c);
        }
        // Continuity: at the distance where the eye reaches the clearance, lifted = unlifted.
        let at = Camera {
            distance: 0.1 / c.to_eye().z,
            ..c
        };
        let just_below = Camera {
            distance: at.distance * (1.0 - 1e-9),
            ..c
        };
        assert!((just_below.clear_of(0.1).eye() - at.eye()).length() < 1e-9);
    }

    #[test]
    fn sky_pixels_and_extremes() {
        let c = Camera {
            elevation_deg: 89.5,
            distance: 1.0,
            fov_deg: 60.0,
            ..Camera::default()
        };
        assert!(
            c.plane_footprint(DVec2::new(50.0, 0.5), 100, 100).is_none(),
            "top row sees the sky"
        );
        assert!(
            c.plane_footprint(DVec2::new(50.0, 99.5), 100, 100)
                .is_some()
        );
        let down = Camera {
            elevation_deg: 0.0,
            azimuth_deg: 123.0,
            ..Camera::default()
        };
        let (r, u, f) = down.basis();
        assert!((r.cross(u) + f).length() < 1e-12 || (r.cross(u) - -f).length() < 1e-12);
        assert!(r.is_finite() && u.is_finite());
    }
}
