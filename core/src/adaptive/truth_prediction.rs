//! What an adaptive ground truth plans from (#18 §1): per pixel of a view of the plane, the
//! truth's expected value (the filtered view) and one ray's predicted standard deviation
//! ([`Evaluator::predicted_ray_moments`]), both from the statistical model, before any ray is
//! traced. [`crate::adaptive::sampling_plan::SamplingPlan`] turns them into ray counts.

use crate::driver::footprint::Footprint;
use crate::eval::{Evaluator, FootprintQuery};
use crate::material::colormap::LUMINANCE;
use crate::scene::camera::Camera;
use crate::scene::shape::Shape;
use glam::{DMat3, DVec2, DVec3};
use rayon::prelude::*;

/// The model's prediction of a ground-truth image.
#[derive(Clone, Debug, PartialEq)]
pub struct TruthPrediction {
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// The filtered view per pixel, linear RGB, row-major (0 for the sky): the truth's expected
    /// value there.
    pub mean: Vec<[f64; 3]>,
    /// One truth ray's predicted luminance standard deviation per pixel (0 for the sky).
    pub sd: Vec<f64>,
}

impl TruthPrediction {
    /// The mean's luminance per pixel.
    pub fn luminance(&self) -> Vec<f64> {
        self.mean
            .iter()
            .map(|c| (0..3).map(|k| LUMINANCE[k] * c[k]).sum())
            .collect()
    }

    /// The mean's channel `k` (0, 1, 2) per pixel.
    pub fn channel(&self, k: usize) -> Vec<f64> {
        self.mean.iter().map(|c| c[k.min(2)]).collect()
    }
}

impl Evaluator {
    /// Where the analytic views evaluate pixel centre `px` of a `width × height` view of
    /// `shape`: the footprint query, whether the sun reaches it, and the tangent frame (the
    /// identity on the plane). `plane_camera` is `camera` lifted clear of the relief
    /// ([`crate::scene::surface::Surface::clear_camera`]); the cylinder lifts its own. `None` for
    /// the sky.
    pub fn view_pixel_query(
        &self,
        shape: Shape,
        plane_camera: &Camera,
        camera: &Camera,
        px: DVec2,
        (width, height): (u32, u32),
        wi: DVec3,
    ) -> Option<(FootprintQuery, bool, DMat3)> {
        match shape {
            Shape::Plane => {
                let (_, cov) = plane_camera.plane_footprint(px, width, height)?;
                let ray = plane_camera.ray(px, width, height);
                let (cfg, visible) =
                    self.pixel_query(ray.origin, ray.dir, wi, Footprint { cov })?;
                Some((cfg, visible, DMat3::IDENTITY))
            }
            Shape::Cylinder { radius } => {
                let (o, d, wi, fp, frame) =
                    self.cylinder_query(radius, camera, px, (width, height), wi)?;
                let (cfg, visible) = self.pixel_query(o, d, wi, fp)?;
                Some((cfg, visible, frame))
            }
        }
    }

    /// The prediction for a `width × height` view of the plane by `camera` (lifted clear of the
    /// relief as every view is: [`crate::scene::surface::Surface::clear_camera`]) under the sun
    /// direction `wi`: each pixel's centre ray meets the level-of-detail surface where the
    /// analytic views evaluate it ([`Evaluator::pixel_query`]). Rows run in parallel. Finite for
    /// every input; pixels that see the sky, and every pixel of an empty image, predict 0.
    pub fn predict_truth(&self, camera: &Camera, size: (u32, u32), wi: DVec3) -> TruthPrediction {
        self.predict_truth_of(Shape::Plane, camera, size, wi)
    }

    /// [`Evaluator::predict_truth`] for a view of `shape`: on a cylinder each pixel is
    /// predicted where [`Evaluator::cylinder_pixel`] evaluates it, in the tangent plane where its
    /// centre ray meets the mean cylinder (the environment looked up at world normals).
    pub fn predict_truth_of(
        &self,
        shape: Shape,
        camera: &Camera,
        (width, height): (u32, u32),
        wi: DVec3,
    ) -> TruthPrediction {
        let plane_camera = self.surface.clear_camera(camera);
        let (w, h) = (width as usize, height as usize);
        let pixels: Vec<([f64; 3], f64)> = (0..w * h)
            .into_par_iter()
            .map(|p| {
                let px = DVec2::new((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
                let query =
                    self.view_pixel_query(shape, &plane_camera, camera, px, (width, height), wi);
                let Some((cfg, visible, frame)) = query else {
                    return ([0.0; 3], 0.0);
                };
                let v = if visible { 1.0 } else { 0.0 };
                let mean = self
                    .filtered_lit(&cfg, v, &frame)
                    .map(|c| if c.is_finite() { c } else { 0.0 });
                let sd = self.predicted_ray_moments(&cfg).luminance_variance().sqrt();
                (mean, if sd.is_finite() { sd } else { 0.0 })
            })
            .collect();
        let mut out = TruthPrediction {
            width: w,
            height: h,
            mean: pixels.iter().map(|p| p.0).collect(),
            sd: pixels.iter().map(|p| p.1).collect(),
        };
        out.sd = pixel_spread(&out.luminance(), &out.sd, w, h);
        out
    }
}

/// One ray's deviation with the image's own variation across the pixel added (#18 §1): the
/// footprint's statistics ([`Evaluator::predicted_ray_moments`]) hold what varies *within* the
/// level-of-detail footprint; a truth ray also lands anywhere in the pixel, where the expected
/// radiance itself varies: the resolved relief, the shading of a curved object, a silhouette or
/// the horizon, where the sky (0) meets the surface. Over a box pixel a ramp of D per pixel
/// spreads by `D²/12` per axis [BSSBH13 Sec. 2.4: the integrand's variance over the pixel
/// footprint]; D is the larger one-sided difference of the predicted `mean` luminance along the
/// axis (neighbours outside the image left out), so a step to the sky counts whole on the pixel on
/// either side of it (a pixel half covered spreads by `D²/4`: this is a lower estimate there).
/// Returns `√(sd² + (D_x² + D_y²)/12)` per pixel; non-finite inputs count as 0. Sizes that do not
/// match return `sd` unchanged.
pub fn pixel_spread(mean: &[f64], sd: &[f64], width: usize, height: usize) -> Vec<f64> {
    if mean.len() != width * height || sd.len() != mean.len() {
        return sd.to_vec();
    }
    let clean = |x: f64| if x.is_finite() { x } else { 0.0 };
    let at = |x: usize, y: usize| clean(mean[y * width + x]);
    (0..width * height)
        .map(|p| {
            let (x, y) = (p % width, p / width);
            let c = at(x, y);
            let mut d = [0.0f64; 2];
            if x > 0 {
                d[0] = d[0].max((c - at(x - 1, y)).abs());
            }
            if x + 1 < width {
                d[0] = d[0].max((at(x + 1, y) - c).abs());
            }
            if y > 0 {
                d[1] = d[1].max((c - at(x, y - 1)).abs());
            }
            if y + 1 < height {
                d[1] = d[1].max((at(x, y + 1) - c).abs());
            }
            let own = clean(sd[p]).max(0.0);
            (own * own + (d[0] * d[0] + d[1] * d[1]) / 12.0).sqrt()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::Method;
    use crate::fixtures::preset;
    use crate::math::correlation::{pearson, spearman};
    use crate::scene::direction::direction;

    /// The mean is the filtered view pixel for pixel; the sky predicts 0; the deviation follows
    /// the truth's own per-pixel deviation across an image (correlation over pixels, measured
    /// with 600 truth rays a pixel).
    #[test]
    fn the_prediction_is_the_filtered_view_and_tracks_the_truths_noise() {
        let p = Evaluator::new(&preset("default")).unwrap();
        let camera = Camera {
            elevation_deg: 80.0,
            distance: 3.0,
            ..Default::default()
        };
        let wi = direction(30f64.to_radians(), 90f64.to_radians());
        let (w, h) = (12u32, 10u32);
        let pred = p.predict_truth(&camera, (w, h), wi);
        assert_eq!((pred.width, pred.height), (12, 10));
        // What a pixel's deviation holds beyond its footprint's: the image's spread across it.
        let spread = pixel_spread(&pred.luminance(), &vec![0.0; pred.sd.len()], 12, 10);
        let lifted = p.surface.clear_camera(&camera);
        let mut sky = 0;
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let px = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                let want = p.plane_pixel(Method::Filtered, &camera, px, (w, h), wi);
                for k in 0..3 {
                    assert!((pred.mean[i][k] - want[k]).abs() <= 1e-12, "pixel {i}");
                }
                if lifted.plane_footprint(px, w, h).is_none() {
                    sky += 1;
                    assert_eq!((pred.mean[i], pred.sd[i]), ([0.0; 3], spread[i]));
                } else {
                    assert!(pred.sd[i] > 0.0, "pixel {i}");
                }
            }
        }
        assert!(sky > 0 && sky < (w * h) as usize / 2, "{sky} sky pixels");
        // Predicted against measured deviation over the pixels that see the surface.
        let (mut xs, mut ys) = (vec![], vec![]);
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let px = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                let Some((_, cov)) = lifted.plane_footprint(px, w, h) else {
                    continue;
                };
                let ray = lifted.ray(px, w, h);
                let (cfg, _) = p
                    .pixel_query(
                        ray.origin,
                        ray.dir,
                        wi,
                        crate::driver::footprint::Footprint { cov },
                    )
                    .unwrap();
                let e = p.ground_truth(&cfg, 600, 3);
                let lum = |v: [f64; 3]| (0..3).map(|k| LUMINANCE[k] * v[k]).sum::<f64>();
                xs.push(pred.sd[i]);
                ys.push(lum(e.std_error) * 600f64.sqrt());
            }
        }
        let r = pearson(&xs, &ys);
        assert!(r > 0.6, "correlation {r}");
    }

    /// On a cylinder the mean is the filtered cylinder view pixel for pixel (the environment
    /// looked up at world normals); pixels beside the cylinder predict 0; the deviation of one
    /// ray follows the truth's across the image (400 rays a pixel at its tangent footprint).
    #[test]
    fn the_cylinder_is_predicted_where_its_views_evaluate_it() {
        let mut p = Evaluator::new(&preset("default")).unwrap();
        p.set_environment_radiance(&crate::math::sh::Sh9::default());
        let radius = 1.0;
        let camera = Camera {
            elevation_deg: 50.0,
            distance: 2.5,
            ..Default::default()
        };
        let wi = direction(40f64.to_radians(), 30f64.to_radians());
        let (w, h) = (10u32, 8u32);
        let shape = Shape::Cylinder { radius };
        let pred = p.predict_truth_of(shape, &camera, (w, h), wi);
        let spread = pixel_spread(&pred.luminance(), &vec![0.0; pred.sd.len()], 10, 8);
        let (mut beside, mut xs, mut ys) = (0, vec![], vec![]);
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let px = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                let want = p.cylinder_pixel(Method::Filtered, radius, &camera, px, (w, h), wi);
                for k in 0..3 {
                    assert!((pred.mean[i][k] - want[k]).abs() <= 1e-12, "pixel {i}");
                }
                let Some((o, d, wl, fp, _)) = p.cylinder_query(radius, &camera, px, (w, h), wi)
                else {
                    beside += 1;
                    assert_eq!((pred.mean[i], pred.sd[i]), ([0.0; 3], spread[i]));
                    continue;
                };
                let Some((cfg, _)) = p.pixel_query(o, d, wl, fp) else {
                    continue;
                };
                let e = p.ground_truth(&cfg, 400, 5);
                let lum = |v: [f64; 3]| (0..3).map(|k| LUMINANCE[k] * v[k]).sum::<f64>();
                xs.push(pred.sd[i]);
                ys.push(lum(e.std_error) * 400f64.sqrt());
            }
        }
        assert!(
            beside > 0 && beside < (w * h) as usize / 2,
            "{beside} beside"
        );
        // Rank correlation: one glint pixel (measured 0.22 against 0.05 predicted) would rule
        // a linear one.
        let r = spearman(&xs, &ys);
        assert!(r > 0.5, "rank correlation {r} over {} pixels", xs.len());
    }

    /// The pixel spread: a ramp of 0.3 a pixel along x adds 0.09/12 to every pixel's variance
    /// (one-sided at the borders); a step of 1 between two columns adds 1/12 on both sides of it
    /// and nothing beyond; a flat image keeps its deviations; NaN counts as 0.
    #[test]
    fn the_pixel_spread_adds_the_images_own_variation() {
        let (w, h) = (5, 3);
        let ramp: Vec<f64> = (0..w * h).map(|p| 0.3 * (p % w) as f64).collect();
        let sd = vec![0.2; w * h];
        for v in pixel_spread(&ramp, &sd, w, h) {
            assert!((v * v - (0.04 + 0.09 / 12.0)).abs() < 1e-12, "{v}");
        }
        let step: Vec<f64> = (0..w * h)
            .map(|p| if p % w < 2 { 0.0 } else { 1.0 })
            .collect();
        let out = pixel_spread(&step, &vec![0.0; w * h], w, h);
        for p in 0..w * h {
            let want = if p % w == 1 || p % w == 2 {
                1.0 / 12.0
            } else {
                0.0
            };
            assert!((out[p] * out[p] - want).abs() < 1e-12, "{p}: {}", out[p]);
        }
        assert_eq!(pixel_spread(&vec![0.7; w * h], &sd, w, h), sd);
        let mut nan = vec![0.0; w * h];
        nan[7] = f64::NAN;
        assert!(pixel_spread(&nan, &sd, w, h).iter().all(|v| v.is_finite()));
        assert_eq!(pixel_spread(&ramp[..3], &sd, w, h), sd);
    }

    /// Degenerate cameras and images predict zeros, never NaN.
    #[test]
    fn degenerate_views_predict_finite_values() {
        let p = Evaluator::new(&preset("bumpy-specular")).unwrap();
        for (elev, dist) in [(0.0, 1e-6), (90.0, 3.0), (89.9, 1e6)] {
            let camera = Camera {
                elevation_deg: elev,
                distance: dist,
                ..Default::default()
            };
            for wi in [DVec3::Z, direction(1.6, 0.0), DVec3::new(0.0, 0.0, -1.0)] {
                let pred = p.predict_truth(&camera, (4, 3), wi);
                assert!(pred.sd.iter().all(|s| s.is_finite() && *s >= 0.0));
                assert!(pred.mean.iter().flatten().all(|c| c.is_finite()));
            }
        }
        assert!(
            p.predict_truth(&Camera::default(), (0, 0), DVec3::Z)
                .sd
                .is_empty()
        );
    }
}
