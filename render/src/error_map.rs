//! The error view: per-pixel |mode − ground truth| as a heat map with a legend bar, plus RMSE and max.

use crate::image::LinearImage;
use lodestone_core::material::colormap::Gradient;

/// Error statistics of one image against a reference (linear RGB).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorStats {
    /// Root mean square error over pixels and channels.
    pub rmse: f64,
    /// Largest per-pixel error (max over channels).
    pub max: f64,
    /// Mean absolute error.
    pub mean_abs: f64,
}

/// Error statistics of `image` against `reference` (same size).
pub fn error_stats(image: &LinearImage, reference: &LinearImage) -> ErrorStats {
    assert_eq!(
        (image.width, image.height),
        (reference.width, reference.height),
        "image sizes differ"
    );
    let (mut sq, mut abs, mut max) = (0.0f64, 0.0f64, 0.0f64);
    let n = f64::from(image.width * image.height);
    for y in 0..image.height {
        for x in 0..image.width {
            let (a, b) = (image.rgb(x, y), reference.rgb(x, y));
            let mut px = 0.0f64;
            for k in 0..3 {
                let d = f64::from(a[k] - b[k]).abs();
                sq += d * d / 3.0;
                abs += d / 3.0;
                px = px.max(d);
            }
            max = max.max(px);
        }
    }
    ErrorStats {
        rmse: (sq / n).sqrt(),
        max,
        mean_abs: abs / n,
    }
}

/// The heat map's colours (magma-like, dark = no error), as linear RGB.
pub fn heat_gradient() -> Gradient {
    Gradient::from_srgb8(
        &[
            [0x00, 0x00, 0x04],
            [0x3b, 0x0f, 0x70],
            [0x8c, 0x29, 0x81],
            [0xde, 0x49, 0x68],
            [0xfe, 0x9f, 0x6d],
            [0xfc, 0xfd, 0xbf],
        ],
        0.0,
        1.0,
        lodestone_core::material::colormap::Interpolation::Linear,
    )
}

/// Per-channel absolute difference |image − reference| (linear RGB, weight 1), for EXR export.
pub fn abs_difference(image: &LinearImage, reference: &LinearImage) -> LinearImage {
    let (w, h) = (image.width, image.height);
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (image.rgb(x, y), reference.rgb(x, y));
            pixels.push([
                (a[0] - b[0]).abs(),
                (a[1] - b[1]).abs(),
                (a[2] - b[2]).abs(),
                1.0,
            ]);
        }
    }
    LinearImage {
        width: w,
        height: h,
        pixels,
    }
}

/// Heat map of the per-pixel error (max over channels), `scale` mapping to the top of the scale
/// (errors above it saturate). Same size as the inputs, no legend (the editor draws its own).
pub fn error_heat(image: &LinearImage, reference: &LinearImage, scale: f64) -> LinearImage {
    let g = heat_gradient();
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let (w, h) = (image.width, image.height);
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (image.rgb(x, y), reference.rgb(x, y));
            let e = (0..3)
                .map(|k| f64::from(a[k] - b[k]).abs())
                .fold(0.0, f64::max);
            let c = g.sample((e / scale).min(1.0));
            pixels.push([c[0] as f32, c[1] as f32, c[2] as f32, 1.0]);
        }
    }
    LinearImage {
        width: w,
        height: h,
        pixels,
    }
}

/// [`error_heat`] with a legend bar along the bottom (left 0, right `scale`).
pub fn heat_map(image: &LinearImage, reference: &LinearImage, scale: f64) -> LinearImage {
    with_legend(error_heat(image, reference, scale))
}

/// `heat` (a map in [`heat_gradient`]'s colours) with the gradient as a legend bar along the
/// bottom, 1/16 of its height (at least 2 rows): left 0, right the map's top.
pub fn with_legend(mut heat: LinearImage) -> LinearImage {
    let g = heat_gradient();
    let (w, h) = (heat.width, heat.height);
    let bar = (h / 16).max(2);
    for _ in 0..bar {
        for x in 0..w {
            let c = g.sample(f64::from(x) / f64::from(w.max(2) - 1));
            heat.pixels
                .push([c[0] as f32, c[1] as f32, c[2] as f32, 1.0]);
        }
    }
    heat.height = h + bar;
    heat
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(v: f32) -> LinearImage {
        LinearImage {
            width: 4,
            height: 2,
            pixels: vec![[v, v, v, 1.0]; 8],
        }
    }

    #[test]
    fn stats_of_a_constant_offset() {
        let s = error_stats(&img(0.5), &img(0.25));
        assert!(
            (s.rmse - 0.25).abs() < 1e-7
                && (s.max - 0.25).abs() < 1e-7
                && (s.mean_abs - 0.25).abs() < 1e-7
        );
        assert_eq!(error_stats(&img(0.3), &img(0.3)).max, 0.0);
    }

    #[test]
    fn abs_difference_is_per_channel() {
        let a = img(0.5);
        let mut b = img(0.25);
        b.pixels[3] = [1.0, 0.5, 0.0, 2.0];
        let d = abs_difference(&a, &b);
        assert_eq!(d.rgb(0, 0), [0.25; 3]);
        // Pixel 3 of b has weight 2: (0.5, 0.25, 0) after division.
        assert_eq!(d.rgb(3, 0), [0.0, 0.25, 0.5]);
    }

    #[test]
    fn heat_map_has_a_legend_and_saturates() {
        let h = heat_map(&img(2.0), &img(0.0), 0.5);
        assert_eq!((h.width, h.height), (4, 4));
        let top = heat_gradient().sample(1.0);
        assert!(
            (f64::from(h.rgb(0, 0)[0]) - top[0]).abs() < 1e-6,
            "saturated"
        );
        assert!(
            h.rgb(0, 3)[0] < h.rgb(3, 3)[0],
            "legend runs dark to bright"
        );
    }
}
