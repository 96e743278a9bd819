//! The ground truth's noise as heat maps (#18 §1): the standard error of each pixel's mean, the
//! predicted deviation of one ray that adaptive sampling plans with, the rays each pixel has, and
//! the truth reconstructed over windows flat within its noise, with those windows' radii.

use super::view_state::TruthDisplay;
use super::worker::Frame;
use lodestone_core::adaptive::image_bandwidth::NYQUIST;
use lodestone_core::adaptive::windows::{WindowOptions, WindowReconstruction};
use lodestone_render::LinearImage;
use lodestone_render::adaptive_truth::reconstruct_truth;
use lodestone_render::error_map::heat_gradient;
use lodestone_render::truth_noise::TruthEstimate;

/// A heat map of the truth frame, with the value at the top of its scale.
pub(super) struct TruthHeat {
    /// Linear RGB, the frame's size; pixels with no value are dark grey.
    pub image: LinearImage,
    /// The largest value shown (the top of the scale).
    pub max: f64,
}

/// Dark grey: a pixel whose value is unknown (one ray, or none).
const UNKNOWN: [f32; 4] = [0.02, 0.02, 0.02, 1.0];

/// `frame` (a ground truth) reconstructed over windows ([`reconstruct_truth`]); the prediction
/// pools each pixel's measured variance where the frame has one (adaptive truth). `None` without
/// moments.
fn reconstruction(frame: &Frame) -> Option<(LinearImage, WindowReconstruction)> {
    let predicted: Vec<f64> = frame
        .predicted_sd
        .as_deref()
        .map(|sd| sd.iter().map(|v| f64::from(*v)).collect())
        .unwrap_or_default();
    Some(reconstruct_truth(
        &frame.image,
        frame.moments.as_deref()?,
        &predicted,
        None,
        WindowOptions::default(),
    ))
}

/// What the truth viewport shows instead of its image: a heat map of [`truth_values`], or the
/// reconstructed image (with a scale of 0). `None` for the image, or where the frame lacks what
/// `display` needs.
pub(super) fn truth_map(frame: &Frame, display: TruthDisplay) -> Option<TruthHeat> {
    if display == TruthDisplay::Reconstructed {
        return reconstruction(frame).map(|(image, _)| TruthHeat { image, max: 0.0 });
    }
    let values = truth_values(frame, display)?;
    let (w, h) = (frame.image.width, frame.image.height);
    Some(if display == TruthDisplay::PredictedBandwidth {
        // On Nyquist's fixed scale, so that maps of different views compare.
        truth_heat_to(&values, w, h, NYQUIST)
    } else {
        truth_heat(&values, w, h)
    })
}

/// Per pixel of `frame` (a ground truth), the value `display` shows; `None` for the images, or
/// where the frame lacks it (no moments, or no prediction for a uniform truth's deviation).
pub(super) fn truth_values(frame: &Frame, display: TruthDisplay) -> Option<Vec<Option<f64>>> {
    let (w, h) = (frame.image.width, frame.image.height);
    let n = (w * h) as usize;
    match display {
        TruthDisplay::Image | TruthDisplay::Reconstructed => None,
        TruthDisplay::WindowRadius => {
            let (_, r) = reconstruction(frame)?;
            Some(r.radius.iter().map(|v| Some(f64::from(*v))).collect())
        }
        TruthDisplay::StandardError => {
            let est = TruthEstimate::new(&frame.image, frame.moments.as_deref()?)?;
            Some(
                (0..n as u32)
                    .map(|i| {
                        let v = est.pixel(i % w, i / w).var_mean_y;
                        v.is_finite().then(|| v.max(0.0).sqrt())
                    })
                    .collect(),
            )
        }
        TruthDisplay::PredictedDeviation => {
            let sd = frame.predicted_sd.as_deref()?;
            (sd.len() == n).then(|| sd.iter().map(|v| Some(f64::from(*v))).collect())
        }
        TruthDisplay::PredictedBandwidth => {
            let b = frame.predicted_bandwidth.as_deref()?;
            (b.len() == n).then(|| b.iter().map(|v| Some(f64::from(*v))).collect())
        }
        TruthDisplay::Cost => {
            let c = frame.cost.as_deref()?;
            (c.len() == n).then(|| c.iter().map(|v| Some(f64::from(*v))).collect())
        }
        TruthDisplay::Rays => Some(match frame.rays.as_deref() {
            Some(r) if r.len() == n => r.iter().map(|v| Some(f64::from(*v))).collect(),
            // Uniform truth: every pixel has the frame's rays (its weight).
            _ => frame
                .image
                .pixels
                .iter()
                .map(|p| Some(f64::from(p[3])))
                .collect(),
        }),
    }
}

/// `values` (row-major, `w × h`) as a heat map scaled to their largest finite value; `None`
/// entries dark grey. An all-zero map is black with a scale of 0.
pub(super) fn truth_heat(values: &[Option<f64>], w: u32, h: u32) -> TruthHeat {
    let max = values
        .iter()
        .flatten()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0_f64, f64::max);
    truth_heat_to(values, w, h, max)
}

/// [`truth_heat`] on the scale [0, `max`] (values above it at the top).
fn truth_heat_to(values: &[Option<f64>], w: u32, h: u32, max: f64) -> TruthHeat {
    let g = heat_gradient();
    let pixels = values
        .iter()
        .map(|v| match v {
            Some(v) if v.is_finite() => {
                let t = if max > 0.0 {
                    (v / max).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let c = g.sample(t);
                [c[0] as f32, c[1] as f32, c[2] as f32, 1.0]
            }
            _ => UNKNOWN,
        })
        .collect();
    TruthHeat {
        image: LinearImage {
            width: w,
            height: h,
            pixels,
        },
        max,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lodestone_render::ViewMode;
    use lodestone_render::truth_noise::SampleMoments;
    use std::sync::Arc;
    use std::time::Duration;

    fn frame(pixels: Vec<[f32; 4]>, sum_sq: Vec<[f32; 4]>, rays: Option<Vec<u32>>) -> Frame {
        let n = pixels.len() as u32;
        Frame {
            generation: 1,
            mode: ViewMode::Truth,
            image: Arc::new(LinearImage {
                width: n,
                height: 1,
                pixels,
            }),
            samples: 2,
            rays: rays.map(Arc::new),
            predicted_sd: Some(Arc::new(vec![0.5; n as usize])),
            predicted_bandwidth: Some(Arc::new(vec![0.25; n as usize])),
            cost: Some(Arc::new(vec![2.0; n as usize])),
            moments: Some(Arc::new(SampleMoments {
                width: n,
                height: 1,
                sum_sq,
            })),
            pass_time: Duration::ZERO,
            cut_rays: 0,
            scale: 1.0,
        }
    }

    #[test]
    fn maps_carry_the_truths_own_numbers() {
        // Pixel 0: rays 0 and 1 in grey (Y 0 and 1): s² = 0.5, standard error √(0.5/2) = 0.5.
        // Pixel 1: four equal rays: standard error 0. Pixel 2: one ray: unknown.
        let f = frame(
            vec![
                [1.0, 1.0, 1.0, 2.0],
                [2.0, 2.0, 2.0, 4.0],
                [1.0, 1.0, 1.0, 1.0],
            ],
            vec![
                [1.0, 1.0, 1.0, 1.0],
                [1.0, 1.0, 1.0, 1.0],
                [1.0, 1.0, 1.0, 1.0],
            ],
            Some(vec![2, 4, 1]),
        );
        let se = truth_values(&f, TruthDisplay::StandardError).unwrap();
        assert!((se[0].unwrap() - 0.5).abs() < 1e-6, "{se:?}");
        assert!(se[1].unwrap().abs() < 1e-6);
        assert_eq!(se[2], None);
        let rays = truth_values(&f, TruthDisplay::Rays).unwrap();
        assert_eq!(rays, vec![Some(2.0), Some(4.0), Some(1.0)]);
        assert!(truth_values(&f, TruthDisplay::Image).is_none());
        // The predicted bandwidth on Nyquist's fixed scale: 0.25 cycles per pixel is mid-scale.
        let bw = truth_map(&f, TruthDisplay::PredictedBandwidth).unwrap();
        assert_eq!(bw.max, NYQUIST);
        let mid = heat_gradient().sample(0.5);
        assert!((bw.image.pixels[0][0] - mid[0] as f32).abs() < 1e-6);
        assert_eq!(
            truth_values(&f, TruthDisplay::Cost).unwrap(),
            vec![Some(2.0); 3]
        );
        // A uniform truth's rays are its weights.
        let u = frame(vec![[0.0, 0.0, 0.0, 3.0]; 2], vec![[0.0; 4]; 2], None);
        assert_eq!(
            truth_values(&u, TruthDisplay::Rays).unwrap(),
            vec![Some(3.0); 2]
        );
        let heat = truth_heat(&rays, 3, 1);
        assert_eq!(heat.max, 4.0);
        // The top of the scale is the gradient's last colour, unknown pixels dark grey.
        let top = heat_gradient().sample(1.0);
        assert!((heat.image.pixels[1][0] - top[0] as f32).abs() < 1e-6);
        let unknown = truth_heat(&[None, Some(f64::NAN)], 2, 1);
        assert_eq!(unknown.image.pixels, vec![UNKNOWN; 2]);
        assert_eq!(unknown.max, 0.0);
    }

    #[test]
    fn the_reconstruction_pools_flat_pixels_and_keeps_an_outlier() {
        // Five grey pixels of 4 rays (s² = 1/15 each): four at 0.5, the last at 5. The flat four
        // pool over the widest window that leaves out the outlier (radius 3 from pixel 0); the
        // outlier keeps its own rays.
        let mut pixels = vec![[2.0, 2.0, 2.0, 4.0]; 4];
        pixels.push([20.0, 20.0, 20.0, 4.0]);
        let mut sum_sq = vec![[1.2; 4]; 4];
        sum_sq.push([100.2; 4]);
        let f = frame(pixels, sum_sq, Some(vec![4; 5]));
        let radius = truth_values(&f, TruthDisplay::WindowRadius).unwrap();
        assert_eq!(radius[0], Some(3.0), "{radius:?}");
        assert_eq!(radius[4], Some(0.0), "{radius:?}");
        let img = truth_map(&f, TruthDisplay::Reconstructed).unwrap().image;
        for p in 0..4 {
            assert!((img.pixels[p][0] - 0.5).abs() < 1e-5, "{:?}", img.pixels);
        }
        assert!((img.pixels[4][0] - 5.0).abs() < 1e-5, "{:?}", img.pixels);
        assert!(truth_values(&f, TruthDisplay::Reconstructed).is_none());
    }
}
