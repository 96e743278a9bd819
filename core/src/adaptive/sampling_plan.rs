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

use crate::math::water_fill::water_fill;

/// How many rows of cells above and below a lattice cell [`SamplingPlan::refine`] pools the
/// realisation over, across the whole width: the footprint, and so the realisation, changes down
/// a view (with distance, and with the cylinder's curvature), hardly across it. Five rows of a
/// 64-pixel-wide image at step 4 are 80 cells; a 5 × 5 window's 25 left the estimate's standard
/// error at 0.57 of itself where the corners' noise equals the realisation, too loose to decide on.
pub const POOL_ROWS: usize = 2;
/// How many standard errors below its estimate [`SamplingPlan::refine`] takes the pooled
/// realisation where shading takes rays from other pixels: about a 96% one-sided bound. At about
/// half that, a noise-limited first pass shaded cells for nothing in two of eight trials, costing
/// up to 47%.
const LOWER_SE: f64 = 1.75;

/// The pooled spreads' standard error over what independent cells would give, for cells that
/// share corners (√3; 1.73 simulated for independent corner residuals over 5 × 5 cells).
const SHARED_CORNERS: f64 = 1.732_050_807_568_877_2;

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
/// least `floor[p]` where given, at most `max_rays` (unless the floor is higher; what the caps
/// leave goes to the others, and what none can take is not spent); 0 for the others.
fn allocate(
    shaded: &[bool],
    sd: &[f64],
    rays_per_pixel: f64,
    floor: &[u32],
    max_rays: u32,
) -> Vec<u32> {
    let n = shaded.len();
    let budget = (positive(rays_per_pixel) * n as f64).max(n as f64);
    let any_sd = (0..n).any(|p| shaded[p] && positive(value(sd, p)) > 0.0);
    let weight: Vec<f64> = (0..n)
        .map(|p| match (shaded[p], any_sd) {
            (false, _) => 0.0,
            (true, true) => positive(value(sd, p)),
            (true, false) => 1.0,
        })
        .collect();
    let low: Vec<f64> = (0..n)
        .map(|p| {
            if shaded[p] {
                f64::from(floor.get(p).copied().unwrap_or(0).max(1))
            } else {
                0.0
            }
        })
        .collect();
    let cap: Vec<f64> = (0..n)
        .map(|p| {
            if shaded[p] {
                f64::from(max_rays.max(1))
            } else {
                0.0
            }
        })
        .collect();
    water_fill(&weight, &low, &cap, budget)
}

/// A lattice cell of [`SamplingPlan::refine`]: its pixel ranges (lattice corners included) and,
/// where its four corners are shaded, their residuals' spread.
#[derive(Clone, Copy)]
struct Cell {
    xs: (usize, usize),
    ys: (usize, usize),
    spread: Option<Spread>,
}

/// The corners' residuals' sample variance beyond their mean noise (`excess`), and that noise.
#[derive(Clone, Copy)]
struct Spread {
    excess: f64,
    noise: f64,
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
    /// rays on average, at most `max_rays` a pixel (what the caps leave goes to the other shaded
    /// pixels), and lattice `step` (1: every pixel shaded). Non-finite predictions (and negative
    /// deviations) count as 0; empty images give an empty plan.
    pub fn new(
        width: usize,
        height: usize,
        mean: &[f64],
        sd: &[f64],
        rays_per_pixel: f64,
        step: usize,
        max_rays: u32,
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
        let rays = allocate(&shaded, sd, rays_per_pixel, &[], max_rays);
        Self {
            width,
            height,
            step,
            rays,
        }
    }

    /// The a posteriori refinement [BSSBH13 Sec. 3.2, hierarchically]. After this plan's rays gave
    /// `estimates` (read where `rays > 0`), each lattice cell's four corners' residuals from the
    /// prediction, `r_k = estimates_k − guide_k`, say how far the truth departs from its
    /// prediction in a way the lattice cannot interpolate (the micro-geometry's own realisation,
    /// an edge the prediction misplaced). Their spread beyond their own noise,
    /// `e = Var_k(r) − mean_k(sd_k²/n_k)`, is what a cell holds; two rules shade whole cells:
    ///
    /// 1. **Local**: `e` exceeds the noise a pixel would have at the final budget
    ///    (`σ̂²/rays_per_pixel`, σ̂ the cell's largest `sd`) and four times the corners' own noise.
    ///    Robust against the first pass's noise (four corners are three degrees of freedom), so
    ///    it catches what stands out: an edge, a glint the prediction missed.
    /// 2. **Pooled**: the realisation is a property of the surface and the footprint, not of one
    ///    cell, so its variance `ρ = Σe/m` is pooled over the m cells of the rows within
    ///    [`POOL_ROWS`] of each. Where shading takes rays from other pixels it is taken at the lower end of its
    ///    interval (`(Σe − LOWER_SE·SE)/m`, at least 0): only a realisation the first pass
    ///    resolved from its noise shades anything, and a marginal one little (a window that just
    ///    passed a significance test is biased high, and shaded noise-limited images for
    ///    nothing). Where the caps leave rays unspent, shading costs only the pixel's own noise
    ///    at the cap, and the point estimate decides (where it stands two standard errors out): a
    ///    capped first pass rarely resolves the realisation it is deciding on. It is pooled as a
    ///    variance, not relative to one ray's: where the relief is resolved the realisation is
    ///    the relief itself, far above the rays' spread inside a pixel. With residuals
    ///    independent from pixel to pixel, an interpolated pixel misses by
    ///    `E[(r_p − Σ w_k r_k)²] = ρ (1 + Σ w_k²)`, plus the corners' noise `Σ w_k² sd_k²/n_k`.
    ///    A cell is worth shading when that loss, summed over its unshaded pixels, exceeds what shading them costs at equal
    ///    total rays: each pixel's own noise `sd_p²/n_p` with Neyman's `n_p = sd_p/Λ`
    ///    (`Λ = Σ_shaded sd / budget`) plus what its rays take from the others, `sd_p Λ`; when the
    ///    shaded pixels are all at `max_rays` and cannot spend the budget, only the own noise
    ///    `sd_p²/max_rays`. Cells are taken greedily, most loss per unit of `Σ sd` first.
    ///
    /// So the lattice falls back to shading every pixel as the budget grows past what the
    /// realisation allows (`ρ ≳ sd²/n̄`), and spends rays the caps would leave unspent on more
    /// pixels. The refined plan's rays total `rays_per_pixel` a pixel over the image (less only
    /// where every shaded pixel is at `max_rays`), in proportion to `sd`, and no shaded pixel gets
    /// fewer than it already has (nor more than `max_rays` unless it had them).
    pub fn refine(
        &self,
        estimates: &[f64],
        sd: &[f64],
        guide: &[f64],
        rays_per_pixel: f64,
        max_rays: u32,
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
        let sd_at = |p: usize| positive(value(sd, p));
        let budget = (positive(rays_per_pixel) * n as f64).max(n as f64);
        let cap = f64::from(max_rays.max(1));
        if n > 0 {
            let (xs, ys) = (lattice(w), lattice(h));
            let (cw, ch) = (xs.len().saturating_sub(1), ys.len().saturating_sub(1));
            let mut cells: Vec<Cell> = Vec::new();
            for cy in ys.windows(2) {
                for cx in xs.windows(2) {
                    let idx = [
                        (cx[0], cy[0]),
                        (cx[1], cy[0]),
                        (cx[0], cy[1]),
                        (cx[1], cy[1]),
                    ]
                    .map(|(x, y)| y * w + x);
                    let stat = idx.iter().all(|p| self.rays[*p] > 0).then(|| {
                        let r = idx.map(|p| value(estimates, p) - value(guide, p));
                        let mean = r.iter().sum::<f64>() / 4.0;
                        let spread = r.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 3.0;
                        let noise = idx
                            .iter()
                            .map(|p| sd_at(*p).powi(2) / f64::from(self.rays[*p]))
                            .sum::<f64>()
                            / 4.0;
                        Spread {
                            excess: spread - noise,
                            noise,
                        }
                    });
                    cells.push(Cell {
                        xs: (cx[0], cx[1]),
                        ys: (cy[0], cy[1]),
                        spread: stat,
                    });
                }
            }
            let fill = |shaded: &mut [bool], (x0, x1): (usize, usize), (y0, y1): (usize, usize)| {
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        shaded[y * w + x] = true;
                    }
                }
            };
            // Rule 1, local.
            for &Cell {
                xs: xr,
                ys: yr,
                spread,
            } in &cells
            {
                let Some(Spread { excess: e, noise }) = spread else {
                    continue;
                };
                let sigma = [(xr.0, yr.0), (xr.1, yr.0), (xr.0, yr.1), (xr.1, yr.1)]
                    .iter()
                    .map(|(x, y)| sd_at(y * w + x))
                    .fold(0.0, f64::max);
                // At least four times the corners' noise too: where a capped first pass left the
                // corners noisier than the final budget's pixels, the spread of pure noise passes
                // `σ̂²/n̄` often (χ²₃/3 > 5 has probability 0.2%).
                if e > (sigma * sigma / positive(rays_per_pixel).max(1.0)).max(4.0 * noise) {
                    fill(&mut shaded, xr, yr);
                }
            }
            // Rule 2, pooled: the realisation's variance, (lower bound, point estimate), once per
            // row of cells from the rows around it (every cell of a row shares it).
            let pooled: Vec<(f64, f64)> = (0..ch)
                .map(|j| {
                    let mut es = Vec::new();
                    for jj in j.saturating_sub(POOL_ROWS)..(j + POOL_ROWS + 1).min(ch) {
                        for ii in 0..cw {
                            if let Some(spread) = cells[jj * cw + ii].spread {
                                es.push(spread.excess);
                            }
                        }
                    }
                    let m = es.len() as f64;
                    let total: f64 = es.iter().sum();
                    if es.len() < 4 || !(total > 0.0) {
                        return (0.0, 0.0);
                    }
                    let mean = total / m;
                    let var = es.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (m - 1.0);
                    // Neighbouring cells share corners (each corner enters up to four spreads):
                    // for independent corners the sum's deviation is √3 times what independent
                    // cells would give (1.73, simulated over 5 × 5 cells).
                    let se = SHARED_CORNERS * (m * var).sqrt();
                    let lower = (total - LOWER_SE * se).max(0.0) / m;
                    let point = if total > 2.0 * se { mean } else { 0.0 };
                    (lower, point)
                })
                .collect();
            let realised: Vec<(f64, f64)> = (0..cells.len())
                .map(|c| pooled.get(c / cw.max(1)).copied().unwrap_or((0.0, 0.0)))
                .collect();
            // What interpolating a cell's unshaded pixels loses: the realisation's bias and the
            // corners' noise carried through the weights, the corners at the rays the final
            // allocation gives them (Neyman's `sd/Λ`, at most the cap).
            let rays_for = |s: f64, lambda: f64| {
                if lambda > 0.0 {
                    (s / lambda).clamp(1.0, cap)
                } else {
                    cap
                }
            };
            let open = |shaded: &[bool], c: usize, lambda: f64, free: bool| -> (f64, Vec<usize>) {
                let rho = if free { realised[c].1 } else { realised[c].0 };
                let Cell {
                    xs: (x0, x1),
                    ys: (y0, y1),
                    ..
                } = cells[c];
                let mut loss = 0.0;
                let mut pixels = Vec::new();
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        let p = y * w + x;
                        if shaded[p] {
                            continue;
                        }
                        let (xa, xb, tx) = bracket(x, step, w);
                        let (ya, yb, ty) = bracket(y, step, h);
                        let corners = [
                            (xa, ya, (1.0 - tx) * (1.0 - ty)),
                            (xb, ya, tx * (1.0 - ty)),
                            (xa, yb, (1.0 - tx) * ty),
                            (xb, yb, tx * ty),
                        ];
                        let sum_w2: f64 = corners.iter().map(|k| k.2 * k.2).sum();
                        let noise: f64 = corners
                            .iter()
                            .map(|&(kx, ky, wk)| {
                                let sk = sd_at(ky * w + kx);
                                wk * wk * sk * sk / rays_for(sk, lambda)
                            })
                            .sum();
                        loss += rho * (1.0 + sum_w2) + noise;
                        pixels.push(p);
                    }
                }
                (loss, pixels)
            };
            let mut sum_sd: f64 = (0..n).filter(|p| shaded[*p]).map(sd_at).sum();
            let mut count = shaded.iter().filter(|s| **s).count() as f64;
            let mut order: Vec<(usize, f64)> = (0..cells.len())
                .filter(|c| realised[*c].1 > 0.0)
                .map(|c| {
                    let (loss, pixels) = open(&shaded, c, 0.0, true);
                    let cost: f64 = pixels.iter().map(|p| sd_at(*p)).sum();
                    (c, loss / cost.max(f64::MIN_POSITIVE))
                })
                .filter(|(_, r)| *r > 0.0)
                .collect();
            order.sort_by(|a, b| b.1.total_cmp(&a.1));
            for (c, _) in order {
                let lambda = sum_sd / budget;
                let free = count * cap < budget;
                let (loss, pixels) = open(&shaded, c, if free { 0.0 } else { lambda }, free);
                // Shading a pixel costs its own noise, and (unless the caps leave rays unspent)
                // the noise its rays add to the others.
                let cost: f64 = pixels
                    .iter()
                    .map(|p| {
                        let s = sd_at(*p);
                        if free {
                            s * s / cap
                        } else {
                            s * s / rays_for(s, lambda) + s * lambda
                        }
                    })
                    .sum();
                if loss > cost {
                    for p in &pixels {
                        shaded[*p] = true;
                        sum_sd += sd_at(*p);
                    }
                    count += pixels.len() as f64;
                }
            }
        }
        let rays = allocate(&shaded, sd, rays_per_pixel, &self.rays, max_rays);
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
mod tests;
