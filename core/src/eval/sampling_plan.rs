//! Where an adaptive ground truth spends its rays over an image [BSSBH13 Secs. 2.4, 3] (#18 §1):
//! which pixels are shaded at all, how many rays each gets, and how the others are filled in.
//!
//! BSSBH13 shade a sparse set of pixels where the image's predicted bandwidth is low and up-sample
//! the rest [Sec. 3.2], and give each shaded pixel rays in proportion to its integrand's predicted
//! variance [Sec. 2.4]. Lodestone predicts both from the statistical model: the filtered view is the
//! truth's expected image (its local variation is the image-space bandwidth, measured directly
//! instead of propagated through the transport operators), and
//! [`Evaluator::predicted_ray_moments`](crate::eval::Evaluator::predicted_ray_moments) is one
//! ray's variance.
//!
//! The plan, for a `step`-pixel lattice (every pixel with both coordinates a multiple of `step`,
//! plus the last row and column, is always shaded):
//! 1. a pixel off the lattice is interpolated (bilinearly from its cell's four lattice corners)
//!    when the predicted image's interpolation error there, `b = |Σ w_k F_k − F|`, is below the
//!    noise the pixel would have if shaded with the budget's average ray count, `b² ≤ σ̂²/n̄`;
//!    otherwise it is shaded;
//! 2. the rays go to the shaded pixels in proportion to σ̂ (the allocation that minimises
//!    `Σ σ²/n` for a fixed total), at least one each.
//!
//! Uniform sampling is the plan with `step = 1` and equal σ̂.

/// Which pixels a ground truth shades, with how many rays, and how the rest are reconstructed.
#[derive(Clone, Debug, PartialEq)]
pub struct SamplingPlan {
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Lattice step (pixels).
    pub step: usize,
    /// Rays per pixel, row-major; 0 for a pixel filled by interpolation.
    pub rays: Vec<u32>,
}

/// `v` where it is finite and positive, else 0 (a deviation, a ray count).
fn positive(v: f64) -> f64 {
    if v.is_finite() && v > 0.0 { v } else { 0.0 }
}

/// `s[p]` where it exists and is finite, else 0.
fn value(s: &[f64], p: usize) -> f64 {
    s.get(p).copied().filter(|v| v.is_finite()).unwrap_or(0.0)
}

/// Rays for the `shaded` pixels: `rays_per_pixel` a pixel over the whole image (at least one a
/// pixel), in proportion to `sd` (equal shares where every `sd` is 0), at least one each and at
/// least `floor[p]` where given; 0 for the others.
fn allocate(shaded: &[bool], sd: &[f64], rays_per_pixel: f64, floor: &[u32]) -> Vec<u32> {
    let n = shaded.len();
    let budget = (positive(rays_per_pixel) * n as f64).max(n as f64);
    let count = shaded.iter().filter(|s| **s).count().max(1);
    let total_sd: f64 = (0..n)
        .filter(|p| shaded[*p])
        .map(|p| positive(value(sd, p)))
        .sum();
    (0..n)
        .map(|p| {
            if !shaded[p] {
                return 0;
            }
            let share = if total_sd > 0.0 {
                positive(value(sd, p)) / total_sd
            } else {
                1.0 / count as f64
            };
            let r = (budget * share).round().clamp(1.0, u32::MAX as f64) as u32;
            r.max(floor.get(p).copied().unwrap_or(0))
        })
        .collect()
}

/// The lattice coordinates bracketing `i` on a `step` lattice of `n` pixels, and `i`'s weight on
/// the upper one: the last pixel is a lattice point too.
fn bracket(i: usize, step: usize, n: usize) -> (usize, usize, f64) {
    let lo = (i / step) * step;
    let hi = (lo + step).min(n - 1);
    if hi <= lo {
        return (lo, lo, 0.0);
    }
    (lo, hi, (i - lo) as f64 / (hi - lo) as f64)
}

impl SamplingPlan {
    /// The plan for a `width × height` image with predicted mean `mean` and predicted per-ray
    /// standard deviation `sd` (row-major, one value per pixel, e.g. luminance; missing values count as 0), `rays_per_pixel`
    /// rays on average and lattice `step` (1: every pixel shaded). Non-finite predictions (and
    /// negative deviations) count as 0; empty images give an empty plan.
    pub fn new(
        width: usize,
        height: usize,
        mean: &[f64],
        sd: &[f64],
        rays_per_pixel: f64,
        step: usize,
    ) -> Self {
        let n = width * height;
        let step = step.max(1);
        let mean_at = |p: usize| value(mean, p);
        let mut shaded = vec![false; n];
        for y in 0..height {
            for x in 0..width {
                let on_lattice =
                    (x % step == 0 || x == width - 1) && (y % step == 0 || y == height - 1);
                let p = y * width + x;
                if on_lattice {
                    shaded[p] = true;
                    continue;
                }
                let interp = Self::interpolate_at(width, height, step, x, y, mean_at);
                let b = interp - mean_at(p);
                let noise = positive(value(sd, p)).powi(2) / positive(rays_per_pixel).max(1.0);
                shaded[p] = b * b > noise;
            }
        }
        let rays = allocate(&shaded, sd, rays_per_pixel, &[]);
        Self {
            width,
            height,
            step,
            rays,
        }
    }

    /// The a posteriori refinement [BSSBH13 Sec. 3.2, hierarchically]: after this plan's rays gave
    /// `estimates` (read where `rays > 0`), every lattice cell whose four corners' residuals from
    /// the prediction, `r_k = estimates_k − guide_k`, spread by more than their own noise
    /// (`Var_k(r) − mean_k(sd_k²/n_k)`) and more than the noise a pixel would have at the final
    /// budget (`σ̂²/rays_per_pixel`, σ̂ the cell's largest `sd`) has all its pixels shaded: the
    /// truth departs there from its prediction in a way the lattice cannot interpolate (the
    /// micro-geometry's own realisation on near views). The rays of the refined plan total
    /// `rays_per_pixel` a pixel over the image, in proportion to `sd`, and no shaded pixel gets
    /// fewer than it already has.
    pub fn refine(
        &self,
        estimates: &[f64],
        sd: &[f64],
        guide: &[f64],
        rays_per_pixel: f64,
    ) -> Self {
        let (w, h, step) = (self.width, self.height, self.step);
        let n = w * h;
        let mut shaded: Vec<bool> = self.rays.iter().map(|r| *r > 0).collect();
        let lattice = |len: usize| {
            let mut v: Vec<usize> = (0..len).step_by(step).collect();
            if v.last() != Some(&(len - 1)) {
                v.push(len - 1);
            }
            v
        };
        if n > 0 {
            let (xs, ys) = (lattice(w), lattice(h));
            for cy in ys.windows(2) {
                for cx in xs.windows(2) {
                    let corners = [
                        (cx[0], cy[0]),
                        (cx[1], cy[0]),
                        (cx[0], cy[1]),
                        (cx[1], cy[1]),
                    ];
                    let idx = corners.map(|(x, y)| y * w + x);
                    if idx.iter().any(|p| self.rays[*p] == 0) {
                        continue;
                    }
                    let r = idx.map(|p| value(estimates, p) - value(guide, p));
                    let mean = r.iter().sum::<f64>() / 4.0;
                    let spread = r.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 3.0;
                    let noise = idx
                        .iter()
                        .map(|p| positive(value(sd, *p)).powi(2) / f64::from(self.rays[*p]))
                        .sum::<f64>()
                        / 4.0;
                    let sigma = idx
                        .iter()
                        .map(|p| positive(value(sd, *p)))
                        .fold(0.0, f64::max);
                    let target = sigma * sigma / positive(rays_per_pixel).max(1.0);
                    if spread - noise > target {
                        for y in cy[0]..=cy[1] {
                            for x in cx[0]..=cx[1] {
                                shaded[y * w + x] = true;
                            }
                        }
                    }
                }
            }
        }
        let rays = allocate(&shaded, sd, rays_per_pixel, &self.rays);
        Self {
            width: w,
            height: h,
            step,
            rays,
        }
    }

    /// Bilinear interpolation at (x, y) of `value` at its cell's four lattice corners.
    fn interpolate_at(
        width: usize,
        height: usize,
        step: usize,
        x: usize,
        y: usize,
        value: impl Fn(usize) -> f64,
    ) -> f64 {
        let (x0, x1, tx) = bracket(x, step, width);
        let (y0, y1, ty) = bracket(y, step, height);
        let v = |xx: usize, yy: usize| value(yy * width + xx);
        (1.0 - ty) * ((1.0 - tx) * v(x0, y0) + tx * v(x1, y0))
            + ty * ((1.0 - tx) * v(x0, y1) + tx * v(x1, y1))
    }

    /// The interpolation weights of pixel (x, y) on lattice pixels (index, weight): itself with
    /// weight 1 when it is shaded.
    pub fn weights(&self, x: usize, y: usize) -> Vec<(usize, f64)> {
        let p = y * self.width + x;
        if self.rays[p] > 0 {
            return vec![(p, 1.0)];
        }
        let (x0, x1, tx) = bracket(x, self.step, self.width);
        let (y0, y1, ty) = bracket(y, self.step, self.height);
        [
            (x0, y0, (1.0 - tx) * (1.0 - ty)),
            (x1, y0, tx * (1.0 - ty)),
            (x0, y1, (1.0 - tx) * ty),
            (x1, y1, tx * ty),
        ]
        .into_iter()
        .filter(|c| c.2 > 0.0)
        .map(|(xx, yy, w)| (yy * self.width + xx, w))
        .collect()
    }

    /// The image from the shaded pixels' estimates (`shaded[p]` read only where `rays[p] > 0`).
    /// With a `guide` (the filtered image: the truth's prediction), an interpolated pixel is the
    /// guide there plus the interpolated residual `Σ w_k (x_k − guide_k)`, so what the prediction
    /// already knows is not blurred; without, the plain bilinear interpolation.
    pub fn reconstruct(&self, shaded: &[f64], guide: Option<&[f64]>) -> Vec<f64> {
        let g = |q: usize| guide.and_then(|g| g.get(q).copied()).unwrap_or(0.0);
        let mut out = vec![0.0; self.width * self.height];
        for y in 0..self.height {
            for x in 0..self.width {
                let p = y * self.width + x;
                out[p] = g(p)
                    + self
                        .weights(x, y)
                        .into_iter()
                        .map(|(q, w)| w * (shaded[q] - g(q)))
                        .sum::<f64>();
            }
        }
        out
    }

    /// Expected mean squared error of [`Self::reconstruct`] (with the same `guide`) against the
    /// true image `mean`, when each shaded pixel averages its rays of per-ray standard deviation
    /// `sd`: per pixel the interpolation bias squared plus `Σ w_k² sd_k²/n_k`.
    pub fn expected_mse(&self, mean: &[f64], sd: &[f64], guide: Option<&[f64]>) -> f64 {
        let g = |q: usize| guide.and_then(|g| g.get(q).copied()).unwrap_or(0.0);
        let mut total = 0.0;
        for y in 0..self.height {
            for x in 0..self.width {
                let p = y * self.width + x;
                let mut est = g(p);
                let mut var = 0.0;
                for (q, w) in self.weights(x, y) {
                    est += w * (mean[q] - g(q));
                    var += w * w * sd[q] * sd[q] / f64::from(self.rays[q].max(1));
                }
                total += (est - mean[p]).powi(2) + var;
            }
        }
        total / (self.width * self.height).max(1) as f64
    }

    /// Rays the plan traces.
    pub fn total_rays(&self) -> u64 {
        self.rays.iter().map(|r| u64::from(*r)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth image is interpolated between lattice points and costs only their rays; a
    /// reconstruction of exact lattice values is exact for a bilinear image.
    #[test]
    fn a_bilinear_image_is_reconstructed_exactly_from_its_lattice() {
        let (w, h) = (9, 7);
        let f = |x: usize, y: usize| 1.0 + 0.3 * x as f64 - 0.2 * y as f64 + 0.01 * (x * y) as f64;
        let mean: Vec<f64> = (0..w * h).map(|p| f(p % w, p / w)).collect();
        let sd = vec![0.5; w * h];
        let plan = SamplingPlan::new(w, h, &mean, &sd, 16.0, 4);
        // Lattice: x ∈ {0, 4, 8}, y ∈ {0, 4, 6}: nine pixels, nothing else shaded.
        assert_eq!(plan.rays.iter().filter(|r| **r > 0).count(), 9);
        let rec = plan.reconstruct(&mean, None);
        for p in 0..w * h {
            assert!((rec[p] - mean[p]).abs() < 1e-12, "pixel {p}");
        }
        // The whole budget on the nine: 16·63/9 = 112 rays each.
        assert_eq!(plan.total_rays(), 9 * 112);
        // No bias; the variance of each shaded pixel shrinks by its 112 rays.
        let mse = plan.expected_mse(&mean, &sd, None);
        assert!(mse < 0.25 / 112.0 + 1e-15 && mse > 0.0);
    }

    /// An edge the lattice cannot interpolate is shaded; equal σ̂ with step 1 is uniform sampling.
    #[test]
    fn edges_are_shaded_and_step_one_is_uniform() {
        let (w, h) = (9, 9);
        let mean: Vec<f64> = (0..w * h)
            .map(|p| if p % w < 5 { 0.0 } else { 1.0 })
            .collect();
        let sd = vec![0.1; w * h];
        let plan = SamplingPlan::new(w, h, &mean, &sd, 4.0, 4);
        for y in 0..h {
            // Pixel x = 5 lies between lattice columns 4 (0) and 8 (1): interpolated 0.25, off by 0.75.
            assert!(plan.rays[y * w + 5] > 0);
            // x = 1 lies between 0 and 4, both 0: interpolated exactly.
            assert_eq!(plan.rays[y * w + 1], 0);
        }
        let uniform = SamplingPlan::new(w, h, &mean, &sd, 4.0, 1);
        assert!(uniform.rays.iter().all(|r| *r == 4));
        assert!((uniform.expected_mse(&mean, &sd, None) - 0.01 / 4.0).abs() < 1e-15);
    }

    /// Rays follow σ̂: a pixel predicted three times as noisy gets three times the rays.
    #[test]
    fn rays_are_in_proportion_to_the_predicted_deviation() {
        let mean = vec![0.0; 4];
        let sd = [1.0, 3.0, 1.0, 3.0];
        let plan = SamplingPlan::new(2, 2, &mean, &sd, 8.0, 1);
        assert_eq!(plan.rays, vec![4, 12, 4, 12]);
    }

    /// Garbage predictions and empty images give a plan, not a panic.
    #[test]
    fn hostile_predictions_give_a_plan() {
        let mean = [f64::NAN, f64::INFINITY, -1.0, 0.0];
        let sd = [f64::NAN, -2.0, f64::INFINITY, 0.0];
        let plan = SamplingPlan::new(2, 2, &mean, &sd, f64::NAN, 0);
        assert!(plan.rays.iter().all(|r| *r >= 1));
        let empty = SamplingPlan::new(0, 0, &[], &[], 4.0, 2);
        assert_eq!(empty.total_rays(), 0);
        assert_eq!(empty.expected_mse(&[], &[], None), 0.0);
    }

    /// With the true image as the guide, interpolation has no bias whatever the image: an edge
    /// the lattice misses is reconstructed exactly from exact lattice values.
    #[test]
    fn a_guide_carries_what_the_lattice_misses() {
        let (w, h) = (9, 9);
        let mean: Vec<f64> = (0..w * h)
            .map(|p| if p % w < 5 { 0.2 } else { 1.0 } + 0.05 * (p / w) as f64)
            .collect();
        let sd = vec![0.0; w * h];
        // Zero deviations: the rule interpolates wherever the plain bilinear error is 0 only.
        let plan = SamplingPlan::new(w, h, &mean, &sd, 4.0, 4);
        let guide: Vec<f64> = mean.iter().map(|m| m + 0.3).collect();
        let rec = plan.reconstruct(&mean, Some(&guide));
        for p in 0..w * h {
            assert!((rec[p] - mean[p]).abs() < 1e-12, "pixel {p}");
        }
        // Only the lattice shaded (a flat prediction): 8·81/9 = 72 rays on each of its nine.
        let sd = vec![0.2; w * h];
        let coarse = SamplingPlan::new(w, h, &vec![0.0; w * h], &sd, 8.0, 4);
        assert_eq!(coarse.rays.iter().filter(|r| **r > 0).count(), 9);
        // Unguided, the edge is blurred; guided, only the lattice's noise is left.
        let blurred = coarse.expected_mse(&mean, &sd, None);
        let guided = coarse.expected_mse(&mean, &sd, Some(&guide));
        assert!(guided <= 0.04 / 72.0 + 1e-15, "{guided}");
        assert!(blurred > 10.0 * guided, "{blurred} {guided}");
    }

    /// A residual the prediction misses inside one cell gets that cell shaded; a residual the
    /// noise explains does not.
    #[test]
    fn refinement_shades_cells_whose_residual_is_not_smooth() {
        let (w, h) = (9, 9);
        let guide = vec![0.5; w * h];
        let sd = vec![0.1; w * h];
        let first = SamplingPlan::new(w, h, &guide, &sd, 2.0, 4);
        assert_eq!(first.rays.iter().filter(|r| **r > 0).count(), 9);
        // The truth's residual from the guide: 0 except +0.4 at corner (4, 4), which the four
        // cells around it share.
        let mut est = guide.clone();
        est[4 * w + 4] += 0.4;
        let refined = first.refine(&est, &sd, &guide, 16.0);
        assert!(
            refined.rays.iter().all(|r| *r > 0),
            "all four cells touch (4, 4)"
        );
        // The same bump at noise level (0.1/√18 a corner) leaves the lattice alone.
        let mut quiet = guide.clone();
        quiet[4 * w + 4] += 0.01;
        let kept = first.refine(&quiet, &sd, &guide, 16.0);
        assert_eq!(kept.rays.iter().filter(|r| **r > 0).count(), 9);
        assert!(kept.rays.iter().zip(&first.rays).all(|(a, b)| a >= b));
        assert!(kept.total_rays() >= 16 * 81 - 9 && kept.total_rays() <= 16 * 81 + 9);
    }
}
