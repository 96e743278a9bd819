//! How an image driver's slopes depend on its value (#17, cobblestones): `s²(f) = E[|∇f|² | f] /
//! E[|∇f|²]` over the explicit (bilinear) surface, in bins of equal probability.
//!
//! A Gaussian field's value and gradient at a point are independent, so for the noise driver
//! `s² ≡ 1` and a footprint's slopes are one Gaussian given any value. An image need not be: the
//! cobblestones image has flat stone tops (its top sixteenth of values: s² = 0.13) and steep
//! flanks and mortar (its second to fourth sixteenths: s² = 2.2–2.9). A model that draws every
//! value's slopes from the footprint's one slope covariance then gives the bright tops the slopes
//! of the flanks, and the colour–shading correlation is lost.
//!
//! **Use** (the prototype [`crate::eval::Evaluator::filtered_mixture`]): a footprint's points of
//! value f get the slope covariance `Σ_∇f · s²(f) / E_fp[s²]`, where `E_fp` averages over the
//! footprint's own value distribution. The footprint's total slope covariance stays what the
//! pyramid says; only its split among values follows the image's global conditional. A footprint
//! that sees one value (a texel on a flank) is unchanged (its s² ratio is 1 everywhere), so the
//! near field keeps the pyramid's local statistics.

use crate::driver::histogram::{DriverHistogram, G_END};
use crate::driver::image::ImageDriver;
use crate::math::special::norm_cdf;

/// Bins of equal probability of the value.
pub const BINS: usize = 32;

/// `s²(f)` of an image driver (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct ConditionalSlopes {
    /// The bins' value edges, increasing (`BINS + 1` of them; equal edges where the image has a
    /// plateau).
    pub edges: Vec<f64>,
    /// `E[|∇f|² | bin] / E[|∇f|²]` per bin (1 everywhere for a flat image).
    pub scale: Vec<f64>,
}

impl ConditionalSlopes {
    /// The conditional of an image's explicit surface, sampled on a regular sub-grid of each cell
    /// (as [`crate::driver::histogram::DriverHistogram::of_image`] samples its values).
    pub fn of_image(image: &ImageDriver) -> Self {
        let mut samples = Vec::new();
        image.for_each_surface_sample(|f, g| samples.push((f, g.length_squared())));
        Self::from_samples(samples)
    }

    /// The conditional of equally weighted `(f, |∇f|²)` samples (non-finite ones dropped).
    pub fn from_samples(mut samples: Vec<(f64, f64)>) -> Self {
        samples.retain(|(f, g)| f.is_finite() && g.is_finite());
        if samples.is_empty() {
            return Self {
                edges: vec![0.0; BINS + 1],
                scale: vec![1.0; BINS],
            };
        }
        samples.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let n = samples.len();
        let total = samples.iter().map(|s| s.1).sum::<f64>() / n as f64;
        let mut edges = Vec::with_capacity(BINS + 1);
        let mut scale = Vec::with_capacity(BINS);
        edges.push(samples[0].0);
        for b in 0..BINS {
            let (lo, hi) = (
                b * n / BINS,
                ((b + 1) * n / BINS).max(b * n / BINS + 1).min(n),
            );
            let part = &samples[lo..hi];
            let mean = part.iter().map(|s| s.1).sum::<f64>() / part.len() as f64;
            scale.push(if total > 0.0 { mean / total } else { 1.0 });
            edges.push(part[part.len() - 1].0);
        }
        Self { edges, scale }
    }

    /// `s²(f)`: the scale of the bin holding f (the end bins beyond the range).
    pub fn scale_at(&self, f: f64) -> f64 {
        let k = self.edges[1..BINS].partition_point(|&e| e < f);
        self.scale[k.min(BINS - 1)]
    }
}

/// Entries of [`ImageSlopes::inverse`], uniform in Gaussian space over `[−G_END, G_END]`.
pub const INVERSE_SIZE: usize = 256;

/// What the views' binned mixture reads for an image driver (the GPU's table, core's mirror):
/// `s²` over the image's global rank and `T⁻¹` over Gaussian space, both interpolated linearly.
/// In Gaussian space the rank of value `T⁻¹(G)` is `Φ(G)`, so bin k of [`ConditionalSlopes`]
/// holds `G ∈ [Φ⁻¹(k/BINS), Φ⁻¹((k+1)/BINS)]`.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageSlopes {
    /// `s²` per rank bin ([`ConditionalSlopes::scale`]).
    pub scale: Vec<f64>,
    /// `T⁻¹` at `INVERSE_SIZE` points uniform over `[−G_END, G_END]`.
    pub inverse: Vec<f64>,
}

impl ImageSlopes {
    /// The table of an image's conditional and histogram.
    pub fn new(c: &ConditionalSlopes, h: &DriverHistogram) -> Self {
        let step = 2.0 * G_END / (INVERSE_SIZE - 1) as f64;
        Self {
            scale: c.scale.clone(),
            inverse: (0..INVERSE_SIZE)
                .map(|i| h.inverse(-G_END + step * i as f64))
                .collect(),
        }
    }

    /// `s²` at Gaussian-space value g: linear between the rank bins' centres (constant beyond
    /// the first and last), so the views' bins see no jump at a bin edge.
    pub fn scale_at_gauss(&self, g: f64) -> f64 {
        lerp_table(&self.scale, norm_cdf(g) * BINS as f64 - 0.5)
    }

    /// `T⁻¹(g)` from the uniform table (constant beyond ±G_END).
    pub fn value_at_gauss(&self, g: f64) -> f64 {
        let x = (g + G_END) / (2.0 * G_END) * (INVERSE_SIZE - 1) as f64;
        lerp_table(&self.inverse, x)
    }
}

/// `t` read at fractional index x, linear between entries, clamped to the ends (NaN: the first).
fn lerp_table(t: &[f64], x: f64) -> f64 {
    let last = t.len() - 1;
    if !(x > 0.0) {
        return t[0];
    }
    if x >= last as f64 {
        return t[last];
    }
    let i = x.floor() as usize;
    let a = x - i as f64;
    t[i] + a * (t[i + 1] - t[i])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A surface whose slopes are twice as large (s² four times) above the median as below: the
    /// bins say so, and their mean is 1 (s² is normalized by the overall mean).
    #[test]
    fn the_conditional_follows_the_samples_and_averages_to_one() {
        let samples: Vec<(f64, f64)> = (0..10_000)
            .map(|i| {
                let f = i as f64 / 10_000.0;
                (f, if f < 0.5 { 1.0 } else { 4.0 })
            })
            .collect();
        let c = ConditionalSlopes::from_samples(samples);
        assert!((c.scale_at(0.1) - 0.4).abs() < 1e-9, "{}", c.scale_at(0.1));
        assert!((c.scale_at(0.9) - 1.6).abs() < 1e-9, "{}", c.scale_at(0.9));
        assert!((c.scale_at(-5.0) - 0.4).abs() < 1e-9);
        assert!((c.scale_at(5.0) - 1.6).abs() < 1e-9);
        let mean = c.scale.iter().sum::<f64>() / BINS as f64;
        assert!((mean - 1.0).abs() < 1e-12, "{mean}");
    }

    /// A constant image (no slopes anywhere) gives 1 in every bin, not NaN.
    #[test]
    fn a_flat_image_has_unit_scale() {
        let c = ConditionalSlopes::from_samples(vec![(0.3, 0.0); 100]);
        assert!(c.scale.iter().all(|&s| s == 1.0));
        assert_eq!(c.scale_at(0.3), 1.0);
        assert_eq!(ConditionalSlopes::from_samples(vec![]).scale_at(1.0), 1.0);
    }

    /// The views' table reads back the conditional and the histogram: at a bin's centre rank the
    /// bin's s², and T⁻¹ within the histogram's own interpolation at the table's points.
    #[test]
    fn the_views_table_reads_back_its_sources() {
        let image = ImageDriver::new(
            crate::driver::test_images::SIDE,
            crate::driver::test_images::SIDE,
            &crate::driver::test_images::bricks(),
        )
        .unwrap();
        let c = ConditionalSlopes::of_image(&image);
        let h = DriverHistogram::of_image(&image);
        let t = ImageSlopes::new(&c, &h);
        for k in 0..BINS {
            let g = crate::math::special::norm_quantile((k as f64 + 0.5) / BINS as f64);
            assert!((t.scale_at_gauss(g) - c.scale[k]).abs() < 1e-9, "bin {k}");
        }
        for i in [0, 1, 100, 128, 200, INVERSE_SIZE - 1] {
            let g = -G_END + 2.0 * G_END * i as f64 / (INVERSE_SIZE - 1) as f64;
            assert!((t.value_at_gauss(g) - h.inverse(g)).abs() < 1e-12, "{i}");
        }
        assert_eq!(t.value_at_gauss(f64::NAN), t.inverse[0]);
        assert_eq!(t.scale_at_gauss(40.0), c.scale[BINS - 1]);
        // The bricks' flat tops carry less slope than their mortar edges.
        assert!(
            t.scale_at_gauss(2.0) < 0.8 && t.scale_at_gauss(-1.0) > 1.2,
            "{:?}",
            c.scale
        );
    }
}
