//! Rigorous bounds of a noise driver `f` over boxes of the plane, so the octave march can skip the
//! empty part of the slab in a few lookups instead of many Lipschitz steps (issue #15: a min–max
//! pyramid, as in maximum mipmaps for relief mapping).
//!
//! `f` is sampled on a square grid of vertices around a centre. Over a cell of side c, `f` differs
//! from the bilinear interpolant of its corners by at most `E = c²/8 · (max|f_xx| + max|f_yy|)`
//! (linear interpolation error along each axis), and `max|f_xx| + max|f_yy| ≤ M = Σ|a_i|(2π|k_i|)²`, so
//! the cell's range lies within `[min corners − E, max corners + E]`. Level 0 of the pyramid holds
//! those ranges, each level above the min and max of four cells below, so the range over any
//! axis-aligned box inside the grid costs at most four lookups (the level at which the box spans at
//! most two cells per axis). Ranges are stored as f32 rounded outward, so the GPU reads the same
//! bounds.
//!
//! The level-of-detail surface is `f̄ = f ∗ N(0, Σ_p)` (each wave's attenuation is the footprint
//! Gaussian's Fourier transform), so over a box it lies within the range of `f` over the box
//! dilated by 6σ per axis, up to the Gaussian's mass beyond (≤ 4e-9, times `Σ|a_i|`), and within
//! the undilated box's range widened by `Σ|a_i|(1 − g_i)` (what the attenuations took away):
//! [`GridView::level_of_detail`] takes the tighter.

use crate::driver::footprint::Footprint;
use crate::driver::noise::SumOfSines;
use crate::math::rounding::{f32_down, f32_up};
use glam::DVec2;
use rayon::prelude::*;
use std::f64::consts::TAU;

/// The most cells per side at level 0.
pub const MAX_CELLS: usize = 1024;

/// Bilinear slack aimed at, in units of f (which has unit variance): the cell size is chosen for it
/// unless [`MAX_CELLS`] over the requested width forces larger cells.
pub const TARGET_SLACK: f64 = 0.05;

/// GPU only: the WGSL widens every range by this fraction of Σ|a_i| for its f32 sums (phases near
/// the camera target are accurate to about 1e-5 rad, so f to about 1e-5·Σ|a_i|).
pub const GRID_MARGIN_F32: f64 = 1e-4;

/// A min–max pyramid of the ranges of f over the cells of a square grid.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundGrid {
    /// Lower-left corner (texture space).
    pub origin: DVec2,
    /// Side of a level-0 cell.
    pub cell: f64,
    /// Cells per side at level 0 (a power of two).
    pub n: usize,
    /// Level k has `(n >> k)²` cells of side `cell·2^k`, row-major, each `[lo, hi]`.
    pub levels: Vec<Vec<[f32; 2]>>,
}

/// A wave's `(sin, cos)` of its phase along the grid's columns and rows, and its amplitude.
type WaveTable = (Vec<(f64, f64)>, Vec<(f64, f64)>, f64);

/// `M = Σ|a_i|(2π|k_i|)²`, a bound of `|f_xx| + |f_yy|` (module docs).
fn curvature_bound(noise: &SumOfSines) -> f64 {
    noise
        .waves
        .iter()
        .map(|w| w.amplitude.abs() * (TAU * w.k.length()).powi(2))
        .sum()
}

impl BoundGrid {
    /// `cells` × `cells` cells (a power of two, at most [`MAX_CELLS`]) of the size [`TARGET_SLACK`]
    /// asks for, centred on `centre`: the region scales with the noise's finest wavelength.
    pub fn around(noise: &SumOfSines, centre: DVec2, cells: usize) -> Option<Self> {
        let cells = cells.clamp(1, MAX_CELLS).next_power_of_two();
        let m = curvature_bound(noise);
        let cell = if m > 0.0 {
            (8.0 * TARGET_SLACK / m).sqrt()
        } else {
            1.0
        };
        // A hair under the exact width, so rounding cannot round the cell count up.
        Self::build(noise, centre, 0.5 * cells as f64 * cell * (1.0 - 1e-12))
    }

    /// The grid over the square of half-width `half` around `centre`, with cells no larger than
    /// the [`TARGET_SLACK`] needs (and at most [`MAX_CELLS`] per side). `None` for a noise without
    /// waves or a non-finite or non-positive width.
    pub fn build(noise: &SumOfSines, centre: DVec2, half: f64) -> Option<Self> {
        if noise.waves.is_empty() || !(half > 0.0 && half.is_finite()) || !centre.is_finite() {
            return None;
        }
        let m = curvature_bound(noise);
        let wanted = if m > 0.0 {
            (8.0 * TARGET_SLACK / m).sqrt()
        } else {
            2.0 * half
        };
        let n = ((2.0 * half / wanted).ceil() as usize)
            .clamp(1, MAX_CELLS)
            .next_power_of_two();
        let cell = 2.0 * half / n as f64;
        let origin = centre - DVec2::splat(half);
        let slack = cell * cell / 8.0 * m;
        // f at the (n+1)² vertices: cos(α_i + β_j) = cos α_i cos β_j − sin α_i sin β_j per wave,
        // separable in the grid's rows and columns.
        let v = n + 1;
        let tables: Vec<WaveTable> = noise
            .waves
            .iter()
            .map(|w| {
                let col = (0..v)
                    .map(|i| (TAU * w.k.x * (origin.x + cell * i as f64) + w.phase).sin_cos())
                    .collect();
                let row = (0..v)
                    .map(|j| (TAU * w.k.y * (origin.y + cell * j as f64)).sin_cos())
                    .collect();
                (col, row, w.amplitude)
            })
            .collect();
        let vertices: Vec<f64> = (0..v * v)
            .into_par_iter()
            .map(|idx| {
                let (i, j) = (idx % v, idx / v);
                tables
                    .iter()
                    .map(|(col, row, a)| a * (col[i].1 * row[j].1 - col[i].0 * row[j].0))
                    .sum()
            })
            .collect();
        let level: Vec<[f32; 2]> = (0..n * n)
            .map(|idx| {
                let (i, j) = (idx % n, idx / n);
                let c = [
                    vertices[j * v + i],
                    vertices[j * v + i + 1],
                    vertices[(j + 1) * v + i],
                    vertices[(j + 1) * v + i + 1],
                ];
                let lo = c.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = c.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                // Rounding of the sums: a few ulps of Σ|a_i|.
                let eps = 1e-12 * (1.0 + hi.abs().max(lo.abs()));
                [f32_down(lo - slack - eps), f32_up(hi + slack + eps)]
            })
            .collect();
        // Coarser levels: the min and max of 2×2 cells of the level below.
        let mut levels = vec![level];
        let mut size = n;
        while size > 1 {
            let below = levels.last().expect("a level");
            let half_size = size / 2;
            let next = (0..half_size * half_size)
                .map(|idx| {
                    let (i, j) = (2 * (idx % half_size), 2 * (idx / half_size));
                    let at = |i: usize, j: usize| below[j * size + i];
                    let c = [at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)];
                    [
                        c.iter().map(|r| r[0]).fold(f32::INFINITY, f32::min),
                        c.iter().map(|r| r[1]).fold(f32::NEG_INFINITY, f32::max),
                    ]
                })
                .collect();
            levels.push(next);
            size = half_size;
        }
        Some(Self {
            origin,
            cell,
            n,
            levels,
        })
    }

    /// The range of f over the box `[lo, hi]` (texture space), or `None` where the box is not
    /// inside the grid (or not finite).
    pub fn range(&self, lo: DVec2, hi: DVec2) -> Option<(f64, f64)> {
        let n = self.n as f64;
        let u0 = (lo - self.origin) / self.cell;
        let u1 = (hi - self.origin) / self.cell;
        if !(u0.x >= 0.0 && u0.y >= 0.0 && u1.x <= n && u1.y <= n && u0.x <= u1.x && u0.y <= u1.y) {
            return None;
        }
        // The cells of level k that the box touches: (i0, i1, j0, j1).
        let cells = |k: usize| {
            let scale = (1usize << k) as f64;
            let size = self.n >> k;
            let c = |x: f64| (x / scale).floor().clamp(0.0, size as f64 - 1.0) as usize;
            (c(u0.x), c(u1.x), c(u0.y), c(u1.y))
        };
        // The finest level at which the box spans at most two cells per axis.
        let span = (u1 - u0).max_element().max(1.0);
        let mut k = (span.log2().ceil() as usize).min(self.levels.len() - 1);
        let (mut i0, mut i1, mut j0, mut j1) = cells(k);
        if i1 > i0 + 1 || j1 > j0 + 1 {
            // log2 rounding: one level up always covers it.
            k = (k + 1).min(self.levels.len() - 1);
            (i0, i1, j0, j1) = cells(k);
        }
        let size = self.n >> k;
        let level = &self.levels[k];
        let (mut a, mut b) = (f32::INFINITY, f32::NEG_INFINITY);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let r = level[j * size + i];
                a = a.min(r[0]);
                b = b.max(r[1]);
            }
        }
        Some((f64::from(a), f64::from(b)))
    }
}

/// The grid as one march sees it: boxes are dilated by `dilate` per axis and the range widened
/// by `tail` (both zero on the explicit surface).
#[derive(Clone, Copy, Debug)]
pub struct GridView<'a> {
    /// The grid.
    pub grid: &'a BoundGrid,
    /// Half-widths added to every box.
    pub dilate: DVec2,
    /// Added to both ends of every range.
    pub tail: f64,
    /// On the level-of-detail surface, `D = Σ|a_i|(1 − g_i)` (g_i the footprint attenuations):
    /// `|f̄ − f| ≤ D` everywhere, so f̄ also lies within the undilated box's range widened by D;
    /// the view returns the tighter of the two ranges. Infinite on the explicit surface (unused).
    /// CPU only: the WGSL skips this second lookup, which cost llvmpipe more than it saved.
    pub shift: f64,
}

impl<'a> GridView<'a> {
    /// The explicit surface's view: f itself.
    pub fn explicit(grid: &'a BoundGrid) -> Self {
        Self {
            grid,
            dilate: DVec2::ZERO,
            tail: 0.0,
            shift: f64::INFINITY,
        }
    }

    /// The level-of-detail surface's view for footprint `fp`: boxes dilated by 6σ per axis, the
    /// Gaussian's mass beyond (≤ 4e-9) times `Σ|a_i|` (`amplitude_sum`) as tail (module docs), and
    /// `shift` = `Σ|a_i|(1 − g_i)`.
    pub fn level_of_detail(
        grid: &'a BoundGrid,
        fp: Footprint,
        amplitude_sum: f64,
        shift: f64,
    ) -> Self {
        let sx = fp.cov.x_axis.x.max(0.0).sqrt();
        let sy = fp.cov.y_axis.y.max(0.0).sqrt();
        Self {
            grid,
            dilate: 6.0 * DVec2::new(sx, sy),
            tail: 8e-9 * amplitude_sum,
            shift,
        }
    }

    /// The range of the view's f over the segment from `a` to `b` (texture space): over the box
    /// dilated by `dilate`, widened by `tail`, intersected with the undilated box's range widened
    /// by `shift + tail` where that box is inside the grid.
    pub fn range(&self, a: DVec2, b: DVec2) -> Option<(f64, f64)> {
        let (lo, hi) = (a.min(b), a.max(b));
        let (mut l, mut h) = self.grid.range(lo - self.dilate, hi + self.dilate)?;
        if self.shift.is_finite()
            && let Some((l2, h2)) = self.grid.range(lo, hi)
        {
            l = l.max(l2 - self.shift);
            h = h.min(h2 + self.shift);
        }
        Some((l - self.tail, h + self.tail))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::driver::noise::NoiseParams;
    use crate::material::{Driver, Material};
    use crate::math::random::splitmix;

    /// The default material's noise with `octaves` and `components` (also the field table's tests).
    pub(crate) fn noise(octaves: u32, components: u32) -> SumOfSines {
        Material {
            driver: Driver::Noise(NoiseParams {
                octaves,
                components,
                ..NoiseParams::default()
            }),
            ..Material::default()
        }
        .noise()
        .expect("a noise driver")
    }

    /// Every range holds the field's values at random points of random boxes (dense checks), and
    /// is not loose: within 2·slack + the box's own variation of the sampled extremes.
    #[test]
    fn ranges_contain_the_field_over_random_boxes() {
        for (octaves, components) in [(3, 48), (6, 60)] {
            let f = noise(octaves, components);
            let g = BoundGrid::build(&f, DVec2::new(0.3, -1.7), 2.0).expect("grid");
            assert!(g.n.is_power_of_two() && g.n <= MAX_CELLS);
            let mut rng = 11u64;
            for _ in 0..300 {
                let c = DVec2::new(
                    -1.7 + 4.0 * splitmix(&mut rng),
                    -3.7 + 4.0 * splitmix(&mut rng),
                );
                let size = 0.6 * splitmix(&mut rng).powi(2);
                let (lo, hi) = (c, c + DVec2::new(size, 0.7 * size));
                let Some((a, b)) = g.range(lo, hi) else {
                    continue;
                };
                let (mut smin, mut smax) = (f64::INFINITY, f64::NEG_INFINITY);
                for _ in 0..400 {
                    let p = lo + (hi - lo) * DVec2::new(splitmix(&mut rng), splitmix(&mut rng));
                    let v = f.value(p);
                    assert!(v >= a && v <= b, "f({p}) = {v} outside [{a}, {b}]");
                    smin = smin.min(v);
                    smax = smax.max(v);
                }
                // Loose only by what the cells covering the box add (at most two cells per axis
                // at the chosen level): a sanity bound, not a tight one.
                assert!(
                    b - a < (smax - smin) + 6.0,
                    "[{a}, {b}] vs sampled [{smin}, {smax}]"
                );
            }
            assert!(
                g.range(DVec2::new(-10.0, 0.0), DVec2::new(-9.0, 1.0))
                    .is_none()
            );
            assert!(g.range(DVec2::NAN, DVec2::ZERO).is_none());
        }
    }

    /// The level-of-detail view bounds f̄ = f ∗ N(0, Σ_p) (the attenuated waves).
    #[test]
    fn level_of_detail_ranges_contain_the_filtered_field() {
        let f = noise(3, 48);
        let g = BoundGrid::build(&f, DVec2::ZERO, 3.0).expect("grid");
        let total: f64 = f.waves.iter().map(|w| w.amplitude.abs()).sum();
        let mut rng = 5u64;
        for r in [0.002, 0.02, 0.08] {
            let fp = Footprint::isotropic(r);
            let shift = f
                .waves
                .iter()
                .map(|w| w.amplitude.abs() * (1.0 - f.attenuation(w, fp)))
                .sum();
            let view = GridView::level_of_detail(&g, fp, total, shift);
            for _ in 0..200 {
                let a = DVec2::new(
                    -2.0 + 4.0 * splitmix(&mut rng),
                    -2.0 + 4.0 * splitmix(&mut rng),
                );
                let b = a + DVec2::new(0.3 * splitmix(&mut rng), 0.3 * splitmix(&mut rng));
                let Some((lo, hi)) = view.range(a, b) else {
                    continue;
                };
                for s in 0..50 {
                    let p = a + (b - a) * (f64::from(s) / 49.0);
                    let v: f64 = f
                        .waves
                        .iter()
                        .map(|w| {
                            w.amplitude * f.attenuation(w, fp) * (TAU * w.k.dot(p) + w.phase).cos()
                        })
                        .sum();
                    assert!(
                        v >= lo && v <= hi,
                        "f̄({p}) = {v} outside [{lo}, {hi}] at r = {r}"
                    );
                }
            }
        }
    }
}
