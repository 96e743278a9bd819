//! What an adaptive ground truth plans from (#18 §1): per pixel of a view of the plane, the
//! truth's expected value (the filtered view) and one ray's predicted standard deviation
//! ([`Evaluator::predicted_ray_moments`]), both from the statistical model, before any ray is
//! traced. [`crate::eval::sampling_plan::SamplingPlan`] turns them into ray counts.

use crate::eval::Evaluator;
use crate::material::colormap::LUMINANCE;
use crate::scene::camera::Camera;
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
    /// The prediction for a `width × height` view of the plane by `camera` (lifted clear of the
    /// relief as every view is: [`crate::scene::surface::Surface::clear_camera`]) under the sun
    /// direction `wi`: each pixel's centre ray meets the level-of-detail surface where the
    /// analytic views evaluate it ([`Evaluator::pixel_query`]). Rows run in parallel. Finite for
    /// every input; pixels that see the sky, and every pixel of an empty image, predict 0.
    pub fn predict_truth(
        &self,
        camera: &Camera,
        (width, height): (u32, u32),
        wi: DVec3,
    ) -> TruthPrediction {
        let camera = self.surface.clear_camera(camera);
        let (w, h) = (width as usize, height as usize);
        let pixels: Vec<([f64; 3], f64)> = (0..w * h)
            .into_par_iter()
            .map(|p| {
                let px = DVec2::new((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
                let query = camera
                    .plane_footprint(px, width, height)
                    .and_then(|(_, cov)| {
                        let ray = camera.ray(px, width, height);
                        self.pixel_query(
                            ray.origin,
                            ray.dir,
                            wi,
                            crate::driver::footprint::Footprint { cov },
                        )
                    });
                let Some((cfg, visible)) = query else {
                    return ([0.0; 3], 0.0);
                };
                let v = if visible { 1.0 } else { 0.0 };
                let mean = self
                    .filtered_lit(&cfg, v, &DMat3::IDENTITY)
                    .map(|c| if c.is_finite() { c } else { 0.0 });
                let sd = self.predicted_ray_moments(&cfg).luminance_variance().sqrt();
                (mean, if sd.is_finite() { sd } else { 0.0 })
            })
            .collect();
        TruthPrediction {
            width: w,
            height: h,
            mean: pixels.iter().map(|p| p.0).collect(),
            sd: pixels.iter().map(|p| p.1).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::Method;
    use crate::eval::test_materials::preset;
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
                    assert_eq!((pred.mean[i], pred.sd[i]), ([0.0; 3], 0.0));
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
                if pred.sd[i] == 0.0 {
                    continue;
                }
                let px = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                let (_, cov) = lifted.plane_footprint(px, w, h).unwrap();
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
        let r = correlation(&xs, &ys);
        assert!(r > 0.6, "correlation {r}");
    }

    fn correlation(a: &[f64], b: &[f64]) -> f64 {
        let n = a.len() as f64;
        let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
        let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
        let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
        let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
        cov / (va * vb).sqrt()
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
