//! The explicit micro-geometry `h(x) = σ_h·g(f(x))` of a material (noise- or image-driven, see
//! [`DriverField`]), and ray marching on it that cannot step over a feature. This is what the ground
//! truth renders: no statistics here.
//!
//! The march ([`Surface::march`]) is the fast octave march for a noise driver
//! ([`crate::scene::octave_march`]) or the reference sphere tracing with the global Lipschitz
//! bound `K_d = σ_h · max|g′| · L_f(d̂_xy)` ([`crate::scene::march`]), as [`March`] selects.

use crate::driver::field::DriverField;
use crate::math::piecewise::PiecewisePoly;
use crate::microfacet::transfer::TransferFunction;
use crate::scene::bound_grid::{BoundGrid, GridView};
use crate::scene::camera::Camera;
use crate::scene::field_grid::{FieldGrid, FieldView};
use crate::scene::local_slope::LocalSlope;
use crate::scene::march::{March, march_heightfield};
use crate::scene::octave_march::OctaveSurface;
use glam::{DVec2, DVec3};

/// The eye's least height above the surface under it, as a fraction of `h_max` (a third of a
/// standard deviation of the relief for the default noise: [`Surface::clear_camera`]).
pub const EYE_MARGIN: f64 = 0.05;

/// The explicit heightfield of a material.
#[derive(Clone, Debug)]
pub struct Surface {
    /// The driver.
    pub driver: DriverField,
    /// σ_h.
    pub sigma_h: f64,
    /// g.
    pub transfer: TransferFunction,
    /// Rigorous bound on |h|.
    pub h_max: f64,
    /// max |g′| (Lipschitz constant of g).
    pub g_lip: f64,
    /// Minimum step length of the march.
    pub min_step: f64,
    /// How marches on this surface (and on its level-of-detail surface) step and refine a crossing.
    pub march: March,
    /// The nested octave levels of a noise driver's fast march ([`crate::driver::noise::SumOfSines::level_ends`]; empty
    /// for an image).
    pub levels: Vec<usize>,
    /// A transfer curve's [`crate::microfacet::transfer::Curve::moment_poly`], built once (`None` for the identity): g and the
    /// fast march's local Lipschitz constants of g ([`LocalSlope`]).
    pub transfer_poly: Option<PiecewisePoly>,
    /// Bounds of a noise driver over a region, which the octave march uses to skip what is clear
    /// ([`Surface::with_bound_grid`]; `None`: no skipping).
    pub grid: Option<BoundGrid>,
    /// A table of a noise driver's f over a region, which the octave march steps and settles on
    /// near the surface ([`Surface::with_field_grid`]; `None`: it sums the waves).
    pub field: Option<FieldGrid>,
}

/// Result of marching a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Trace {
    /// The ray crosses the surface at parameter t.
    Hit(f64),
    /// The ray leaves the slab without touching the surface.
    Escape,
}

impl Surface {
    /// The surface `h = σ_h·g(f)` of a driver under a transfer function (a material's:
    /// [`Surface::new`] and [`Surface::with_driver`], in `material::geometry`). A negative σ_h
    /// reads as 0.
    pub fn from_parts(sigma_h: f64, transfer: TransferFunction, driver: DriverField) -> Self {
        let sigma_h = sigma_h.max(0.0);
        let a = driver.amplitude_bound();
        let g_abs_max = match &transfer {
            TransferFunction::Identity => a,
            TransferFunction::Curve(c) => c.points.iter().map(|p| p[1].abs()).fold(0.0, f64::max),
        };
        let min_step = 1e-4 * driver.finest_scale();
        let levels = match &driver {
            DriverField::Noise(n) => n.level_ends(),
            DriverField::Image(_) => Vec::new(),
        };
        let transfer_poly = match &transfer {
            TransferFunction::Identity => None,
            TransferFunction::Curve(c) => Some(c.moment_poly()),
        };
        Self {
            levels,
            transfer_poly,
            grid: None,
            field: None,
            g_lip: transfer.max_derivative(),
            driver,
            sigma_h,
            transfer,
            h_max: sigma_h * g_abs_max,
            min_step,
            march: March::default(),
        }
    }

    /// `camera` lifted where needed so its eye is above the surface where it stands: at least
    /// [`EYE_MARGIN`]` · h_max` above `h` at the eye's (x, y) ([`Camera::clear_of`]). An eye inside
    /// the material sees nothing meaningful (#15: zoomed in to 0.15 at 77°, the default preset's
    /// views were flat grey or black, and the two marches disagreed); lifted, a camera zoomed in
    /// closer follows the relief it skims. Continuous in the camera (h is), the identity where the
    /// eye is clear, and only the height at one point: a crest in front of the eye is seen, as it
    /// should be. Views of the plane use it in core (`Evaluator::plane_pixel`) and on the GPU
    /// alike.
    pub fn clear_camera(&self, camera: &Camera) -> Camera {
        let e = camera.eye();
        camera.clear_of(self.height(DVec2::new(e.x, e.y)) + EYE_MARGIN * self.h_max)
    }

    /// [`Surface::clear_camera`] for the cylinder of radius `r` ([`crate::scene::cylinder`])
    /// whose top line passes through `camera`'s target (the views' cylinder: its coordinates are
    /// taken relative to the target, and its surface coordinates `(u, v)` read the relief at
    /// `(u, v) + target`, as the GPU's, whose origin and noise phases are moved to the target): the
    /// eye lifted straight up until its distance from the axis is `EYE_MARGIN · h_max` more than
    /// the displaced radius `r + h(u, v)` at its own surface coordinates. Lifting moves `v`, so the
    /// height is looked up again, three times at most (each step continuous in the camera). An eye
    /// beside the cylinder (|y| beyond the radius it needs) is left as it is: it is outside. The
    /// cylinder stays where the given camera's target put it.
    pub fn clear_cylinder_camera(&self, camera: &Camera, r: f64) -> Camera {
        let anchor = DVec3::new(camera.target[0], camera.target[1], 0.0);
        let mut c = *camera;
        for _ in 0..3 {
            let e = c.eye() - anchor;
            let (u, v, rho, _) = crate::scene::cylinder::to_surface(r, e);
            let need =
                r + self.height(DVec2::new(u + anchor.x, v + anchor.y)) + EYE_MARGIN * self.h_max;
            if !(rho < need && need > e.y.abs()) {
                break;
            }
            c = c.clear_of((need * need - e.y * e.y).sqrt() - r);
        }
        c
    }

    /// h(x).
    pub fn height(&self, x: DVec2) -> f64 {
        self.height_of(self.driver.value(x))
    }

    /// σ_h·g(f) (the same values as [`TransferFunction::eval`], from the poly built once).
    pub fn height_of(&self, f: f64) -> f64 {
        let g = match &self.transfer_poly {
            Some(p) => {
                let mut o = [0.0; 4];
                p.eval(f, &mut o);
                o[0]
            }
            None => self.transfer.eval(f),
        };
        self.sigma_h * g
    }

    /// f(x), h(x) and ∇h(x) = σ_h g′(f) ∇f.
    pub fn sample(&self, x: DVec2) -> (f64, f64, DVec2) {
        let (f, gf) = self.driver.value_and_gradient(x);
        let (g, gd) = match &self.transfer {
            TransferFunction::Identity => (f, 1.0),
            t => (t.eval(f), t.derivative(f)),
        };
        (f, self.sigma_h * g, gf * (self.sigma_h * gd))
    }

    /// Lipschitz constant of h along the horizontal unit direction `dir`.
    pub fn lipschitz_along(&self, dir: DVec2) -> f64 {
        self.sigma_h * self.g_lip * self.driver.lipschitz_along(dir)
    }

    /// A bound of |∇h| in every direction: σ_h·max|g′|·max|∇f| ([`DriverField::gradient_bound`]).
    pub fn slope_bound(&self) -> f64 {
        self.sigma_h * self.g_lip * self.driver.gradient_bound()
    }

    /// March `p(t) = o + t·d` (d unit) from t = 0 while it is above the surface; `Hit(t)` at the first
    /// crossing. `o` must be on or above the surface; a negative gap at `o` itself is taken as rounding
    /// (a shadow ray leaving a hit point), never as a crossing.
    pub fn march(&self, o: DVec3, d: DVec3) -> Trace {
        if let Some(os) = self.octaves(None) {
            return match os.march(o, d, |f| self.height_of(f), self.march) {
                Some(t) => Trace::Hit(t),
                None => Trace::Escape,
            };
        }
        let dxy = DVec2::new(d.x, d.y);
        let r = dxy.length();
        let k = if r > 0.0 {
            self.lipschitz_along(dxy / r)
        } else {
            0.0
        };
        let rate = d.z.abs() + k * r;
        let height = |x| self.height(x);
        match march_heightfield(o, d, rate, self.h_max, self.min_step, self.march, height) {
            Some(t) => Trace::Hit(t),
            None => Trace::Escape,
        }
    }

    /// The octave march's view of this surface (its waves times `attenuation`, for the
    /// level-of-detail surface), when it marches fast on a noise driver.
    pub fn octaves<'a>(&'a self, attenuation: Option<&'a [f64]>) -> Option<OctaveSurface<'a>> {
        let DriverField::Noise(n) = &self.driver else {
            return None;
        };
        (self.march == March::Fast).then_some(OctaveSurface {
            waves: &n.waves,
            attenuation,
            ends: &self.levels,
            sigma_h: self.sigma_h,
            g_lip: self.g_lip,
            linear: matches!(self.transfer, TransferFunction::Identity),
            monotone: match &self.transfer {
                TransferFunction::Identity => Some(true),
                TransferFunction::Curve(c) => c.monotone(),
            },
            h_max: self.h_max,
            min_step: self.min_step,
            g_slope: self.transfer_poly.as_ref().map(LocalSlope::Curve),
            grid: self.grid.as_ref().map(GridView::explicit),
            field: self.field.as_ref().map(FieldView::explicit),
            settle_width: 0.0,
        })
    }

    /// This surface with a [`BoundGrid`] of its noise driver over the square of half-width `half`
    /// around `centre` (unchanged for an image driver).
    pub fn with_bound_grid(mut self, centre: DVec2, half: f64) -> Self {
        if let DriverField::Noise(n) = &self.driver {
            self.grid = BoundGrid::build(n, centre, half);
        }
        self
    }

    /// This surface with a [`FieldGrid`] of `cells`² cells of its noise driver around `centre`
    /// (unchanged for an image driver).
    pub fn with_field_grid(mut self, centre: DVec2, cells: usize) -> Self {
        if let DriverField::Noise(n) = &self.driver {
            self.field = FieldGrid::around(n, centre, cells);
        }
        self
    }

    /// Whether the point p (on the surface) sees direction d (unit): false if d is at or below the
    /// horizon or the ray toward d hits the surface.
    pub fn sees(&self, p: DVec3, d: DVec3) -> bool {
        if d.z <= 0.0 {
            return false;
        }
        matches!(self.march(p, d), Trace::Escape)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Heights, Material, Slopes};

    fn surface() -> Surface {
        let m = Material {
            heights: Heights {
                sigma_h: 0.1,
                transfer: TransferFunction::Identity,
            },
            slopes: Slopes {
                sigma_nx: 0.5,
                sigma_ny: 0.5,
            },
            ..Material::default()
        };
        Surface::new(&m).unwrap()
    }

    /// A camera whose eye is inside the relief (or just above it) ends `EYE_MARGIN · h_max` above
    /// the surface under its eye, looking the same way; a camera well above is unchanged. Every
    /// primary ray of the lifted camera starts above the surface.
    #[test]
    fn a_camera_inside_the_relief_is_lifted_above_it() {
        let s = surface();
        let mut lifted_some = 0;
        for i in 0..64 {
            let c = Camera {
                elevation_deg: 60.0 + 0.45 * f64::from(i),
                azimuth_deg: 17.0 * f64::from(i),
                distance: 0.01 + 0.02 * f64::from(i % 8),
                target: [0.13 * f64::from(i), -0.07 * f64::from(i)],
                fov_deg: 35.0,
            };
            let l = s.clear_camera(&c);
            let e = l.eye();
            let ground = s.height(DVec2::new(e.x, e.y));
            assert!(
                e.z >= ground + EYE_MARGIN * s.h_max - 1e-12,
                "{i}: {e} over {ground}"
            );
            if l != c {
                lifted_some += 1;
                assert!((e.z - ground - EYE_MARGIN * s.h_max).abs() < 1e-12);
                assert!((l.basis().2 - c.basis().2).length() < 1e-12);
            }
        }
        assert!(
            lifted_some > 16,
            "the cases must include eyes inside the relief"
        );
        let high = Camera {
            distance: 50.0,
            ..Camera::default()
        };
        assert_eq!(s.clear_camera(&high), high);
    }

    /// The cylinder's eye ends outside the displaced cylinder (within the fixed point's last
    /// step), looking the same way; an eye far away is unchanged.
    #[test]
    fn a_camera_inside_the_cylinders_relief_is_lifted_out() {
        let s = surface();
        let r = 2.0;
        let mut lifted_some = 0;
        for i in 0..64 {
            let c = Camera {
                elevation_deg: 50.0 + 0.6 * f64::from(i),
                azimuth_deg: 23.0 * f64::from(i),
                distance: 0.01 + 0.02 * f64::from(i % 8),
                target: [0.13 * f64::from(i), 0.0],
                fov_deg: 35.0,
            };
            let l = s.clear_cylinder_camera(&c, r);
            let e = l.eye();
            let (u, v, rho, _) = crate::scene::cylinder::to_surface(r, e);
            let ground = r + s.height(DVec2::new(u, v));
            assert!(
                rho > ground + 0.5 * EYE_MARGIN * s.h_max,
                "{i}: ρ {rho} over {ground}"
            );
            if l != c {
                lifted_some += 1;
                assert!((l.basis().2 - c.basis().2).length() < 1e-12);
            }
        }
        assert!(
            lifted_some > 16,
            "the cases must include eyes inside the relief"
        );
        let high = Camera {
            distance: 50.0,
            ..Camera::default()
        };
        assert_eq!(s.clear_cylinder_camera(&high, r), high);
    }

    #[test]
    fn primary_rays_land_on_the_surface_at_their_first_crossing() {
        let s = surface();
        let d = DVec3::new(0.8, 0.3, -0.52).normalize();
        for i in 0..200 {
            let y = DVec2::new(0.37 * i as f64, 0.11 * i as f64);
            let o = DVec3::new(y.x, y.y, 0.0) - d * ((s.h_max + 0.01) / -d.z);
            let Trace::Hit(t) = s.march(o, d) else {
                panic!("a downward ray must hit")
            };
            let p = o + d * t;
            let gap = p.z - s.height(DVec2::new(p.x, p.y));
            assert!(gap.abs() < 1e-9, "hit point off the surface by {gap}");
            // No earlier crossing: dense brute-force scan of [0, t).
            let n = 20_000;
            for j in 0..n {
                let q = o + d * (t * j as f64 / n as f64);
                assert!(
                    q.z - s.height(DVec2::new(q.x, q.y)) > -1e-9,
                    "missed an earlier crossing"
                );
            }
        }
    }

    #[test]
    fn upward_rays_from_peaks_escape_and_from_pits_at_grazing_do_not() {
        let s = surface();
        // Find a high point and a low point on a grid.
        let (mut hi, mut lo) = ((f64::MIN, DVec2::ZERO), (f64::MAX, DVec2::ZERO));
        for i in 0..200 {
            for j in 0..200 {
                let x = DVec2::new(i as f64, j as f64) * 0.05;
                let h = s.height(x);
                if h > hi.0 {
                    hi = (h, x);
                }
                if h < lo.0 {
                    lo = (h, x);
                }
            }
        }
        let up = DVec3::new(0.0, 0.0, 1.0);
        assert!(s.sees(DVec3::new(hi.1.x, hi.1.y, hi.0), up));
        assert!(
            s.sees(DVec3::new(lo.1.x, lo.1.y, lo.0), up),
            "a heightfield never shadows straight up"
        );
        let grazing = DVec3::new(1.0, 0.0, 0.02).normalize();
        assert!(
            !s.sees(DVec3::new(lo.1.x, lo.1.y, lo.0), grazing),
            "the lowest pit cannot see the horizon"
        );
        assert!(!s.sees(DVec3::new(lo.1.x, lo.1.y, lo.0), DVec3::new(1.0, 0.0, -0.1)));
    }

    /// Both refinements find the same crossing (to the reference's bracket width) on 400 rays from
    /// 30° to 88°, the fast one in a fraction of the reference's 48 evaluations.
    #[test]
    fn fast_refinement_finds_the_reference_crossing_in_fewer_evaluations() {
        use std::cell::Cell;
        let s = surface();
        let evals = Cell::new(0usize);
        let height = |x: DVec2| {
            evals.set(evals.get() + 1);
            s.height(x)
        };
        let (mut fast_evals, mut ref_evals, mut hits) = (0, 0, 0);
        for i in 0..400 {
            let theta = (30.0 + 58.0 * (i % 20) as f64 / 19.0).to_radians();
            let phi = 0.7 * i as f64;
            let d = -crate::scene::direction::direction(theta, phi);
            let o = DVec3::new(0.31 * i as f64, -0.17 * i as f64, s.h_max + 0.01);
            let rate = d.z.abs()
                + s.sigma_h
                    * s.g_lip
                    * s.lipschitz_along(DVec2::new(d.x, d.y).normalize())
                    * d.x.hypot(d.y);
            let run = |march| {
                evals.set(0);
                let t = march_heightfield(o, d, rate, s.h_max, s.min_step, march, height);
                (t, evals.get())
            };
            let (tr, nr) = run(March::Reference);
            let (tf, nf) = run(March::Fast);
            let (Some(tr), Some(tf)) = (tr, tf) else {
                panic!("downward rays hit: {tr:?} {tf:?}")
            };
            assert!(
                (tr - tf).abs() <= 1e-12 * tr.max(1.0),
                "ray {i}: {tr} vs {tf}"
            );
            let p = o + d * tf;
            assert!(
                p.z - s.height(DVec2::new(p.x, p.y)) >= 0.0,
                "fast returns a point above"
            );
            ref_evals += nr;
            fast_evals += nf;
            hits += 1;
        }
        let saved = (ref_evals - fast_evals) as f64 / hits as f64;
        eprintln!("refinement evaluations saved per hit: {saved:.1} of 48");
        assert!(saved > 30.0, "saved only {saved:.1} evaluations per hit");
    }
}
