//! A noise driver's field read from a table (issue #15: "cheaper field evaluation"): `f` and its
//! derivatives `f_x, f_y, f_xy` sampled on a square grid, interpolated by tensor-product cubic
//! Hermite polynomials (bicubic Hermite, C¹), with rigorous bounds of the interpolation error. The
//! octave march steps on it near the surface and lets a camera ray settle from it, so a ray costs
//! a few table reads instead of several sums of every wave ([`crate::scene::octave_march`]).
//!
//! **Error bound.** Each wave `a cos(ω·x + φ)` is the real part of `a e^{iφ} u(x) v(y)` with
//! `u = e^{iω_x x}`, `v = e^{iω_y y}`, and the bicubic Hermite interpolant of a product is the
//! product of the 1-D cubic Hermite interpolants `Hu·Hv`. On a cell of side c, the cubic Hermite
//! error is `e(x) = ∫ K(x, s) u⁗(s) ds` with a Peano kernel of one sign, so
//! `|u − Hu| ≤ (x−x₀)²(x−x₁)²/4! · max|u⁗| ≤ (cω_x)⁴/384 = ε_x` for complex u too; its derivative
//! `|u′ − (Hu)′| ≤ α₁ c³ ω_x⁴` per real part, with `α₁ = √3/216` (Birkhoff–Priver), taken as 1/96
//! and times √2 for real and imaginary parts: `ε′_x`. Then
//! `|uv − HuHv| ≤ |u − Hu|·|v| + |Hu|·|v − Hv| ≤ ε_x + (1 + ε_x) ε_y` and
//! `|∂_x(uv − HuHv)| ≤ ε′_x + (ω_x + ε′_x) ε_y`; summed over waves with |a| they bound the value
//! ([`FieldGrid::error`]) and the two partial derivatives ([`FieldGrid::slope_error`]) everywhere
//! in the grid. The level-of-detail surface `f̄ = Σ g_i a_i cos(…)` differs from f by at most
//! `D = Σ|a_i|(1 − g_i)` and its slope along d by `Σ|a_i|(1 − g_i)|ω_i·d|` ([`FieldView`]).
//!
//! The cell is chosen so the value bound is [`TARGET_ERROR`] of `Σ|a_i|`; the test
//! `interpolation_errors_stay_within_their_bounds` checks both bounds against the exact sum at
//! random points and that they are not vacuous.

use crate::driver::noise::SumOfSines;
use glam::DVec2;
use rayon::prelude::*;
use std::f64::consts::TAU;

/// The interpolation error aimed at, as a fraction of `Σ|a_i|` (f has unit variance, so about
/// `1e-4·√(2N)` for N waves): the cell is the largest that keeps [`FieldGrid::error`] below it.
pub const TARGET_ERROR: f64 = 1e-4;

/// GPU only: the WGSL adds this fraction of `Σ|a_i|` to the value bound for its f32 arithmetic
/// (vertices rounded to f32, a 16-term polynomial in f32), and the same for the slopes (times
/// the finest |ω|).
pub const FIELD_MARGIN_F32: f64 = 1e-5;

/// Cubic Hermite derivative error constant, `√3/216 ≈ 1/125` rounded up (module docs).
const ALPHA_1: f64 = 1.0 / 96.0;

/// A bicubic Hermite table of f around a centre.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldGrid {
    /// Lower-left vertex (texture space).
    pub origin: DVec2,
    /// Side of a cell.
    pub cell: f64,
    /// Cells per side; the table has `(n + 1)²` vertices, row-major.
    pub n: usize,
    /// Per vertex `[f, c·f_x, c·f_y, c²·f_xy]` (derivatives in cell units, c = [`FieldGrid::cell`]).
    pub vertices: Vec<[f32; 4]>,
    /// Bound of `|f − F|` over the grid (F the interpolant), f32 rounding of the vertices included.
    pub error: f64,
    /// Bounds of `|∂_x(f − F)|` and `|∂_y(f − F)|` over the grid.
    pub slope_error: DVec2,
    /// `Σ|a_i|`.
    pub amplitude_sum: f64,
}

/// The value and slope bounds of the interpolation on cells of side `cell` (module docs).
pub fn error_bounds(noise: &SumOfSines, cell: f64) -> (f64, DVec2) {
    let (mut e, mut ex, mut ey) = (0.0, 0.0, 0.0);
    for w in &noise.waves {
        let a = w.amplitude.abs();
        let (ox, oy) = ((TAU * w.k.x).abs(), (TAU * w.k.y).abs());
        let (ux, uy) = ((cell * ox).powi(4) / 384.0, (cell * oy).powi(4) / 384.0);
        let dx = 2f64.sqrt() * ALPHA_1 * cell.powi(3) * ox.powi(4);
        let dy = 2f64.sqrt() * ALPHA_1 * cell.powi(3) * oy.powi(4);
        e += a * (ux + (1.0 + ux) * uy);
        ex += a * (dx + (ox + dx) * uy);
        ey += a * (dy + (oy + dy) * ux);
    }
    (e, DVec2::new(ex, ey))
}

impl FieldGrid {
    /// `cells` × `cells` cells (at least 1, at most 2048) of the largest side whose value bound is
    /// [`TARGET_ERROR`]`·Σ|a_i|`, centred on `centre`. `None` for a noise without waves or a
    /// non-finite centre.
    pub fn around(noise: &SumOfSines, centre: DVec2, cells: usize) -> Option<Self> {
        let total: f64 = noise.waves.iter().map(|w| w.amplitude.abs()).sum();
        if noise.waves.is_empty() || !(total > 0.0) || !centre.is_finite() {
            return None;
        }
        let target = TARGET_ERROR * total;
        // The bound grows like c⁴: bisect on log c between a cell that meets it and one that fails.
        let fine = noise
            .waves
            .iter()
            .map(|w| TAU * w.k.length())
            .fold(0.0, f64::max)
            .max(1e-300);
        let (mut lo, mut hi) = (1e-6 / fine, 100.0 / fine);
        for _ in 0..60 {
            let mid = (lo * hi).sqrt();
            if error_bounds(noise, mid).0 <= target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let n = cells.clamp(1, 2048);
        Self::build(noise, centre, 0.5 * n as f64 * lo, n)
    }

    /// The table over the square of half-width `half` around `centre` with `n` cells per side.
    /// `None` for a noise without waves, `n = 0`, or a non-finite or non-positive width.
    pub fn build(noise: &SumOfSines, centre: DVec2, half: f64, n: usize) -> Option<Self> {
        if noise.waves.is_empty() || n == 0 || !(half > 0.0 && half.is_finite()) {
            return None;
        }
        if !centre.is_finite() {
            return None;
        }
        let cell = 2.0 * half / n as f64;
        let origin = centre - DVec2::splat(half);
        let v = n + 1;
        // Per wave, (sin, cos) of its phase along the columns and the rows (cos(α + β) and
        // sin(α + β) are separable), its amplitude and ω = 2πk.
        type Table = (Vec<(f64, f64)>, Vec<(f64, f64)>, f64, DVec2);
        let tables: Vec<Table> = noise
            .waves
            .iter()
            .map(|w| {
                let col = (0..v)
                    .map(|i| (TAU * w.k.x * (origin.x + cell * i as f64) + w.phase).sin_cos())
                    .collect();
                let row = (0..v)
                    .map(|j| (TAU * w.k.y * (origin.y + cell * j as f64)).sin_cos())
                    .collect();
                (col, row, w.amplitude, TAU * w.k)
            })
            .collect();
        let vertices: Vec<[f32; 4]> = (0..v * v)
            .into_par_iter()
            .map(|idx| {
                let (i, j) = (idx % v, idx / v);
                let mut s = [0.0f64; 4];
                for (col, row, a, om) in &tables {
                    let ((sa, ca), (sb, cb)) = (col[i], row[j]);
                    let c = ca * cb - sa * sb;
                    let sn = sa * cb + ca * sb;
                    s[0] += a * c;
                    s[1] -= a * om.x * sn;
                    s[2] -= a * om.y * sn;
                    s[3] -= a * om.x * om.y * c;
                }
                [
                    s[0] as f32,
                    (cell * s[1]) as f32,
                    (cell * s[2]) as f32,
                    (cell * cell * s[3]) as f32,
                ]
            })
            .collect();
        let (e, de) = error_bounds(noise, cell);
        let amplitude_sum: f64 = noise.waves.iter().map(|w| w.amplitude.abs()).sum();
        let slope_sum: f64 = noise
            .waves
            .iter()
            .map(|w| w.amplitude.abs() * TAU * w.k.length())
            .sum();
        // f32 vertices: half an ulp of each stored magnitude, times the basis weights' sum of
        // absolute values (≤ 1.2 for the value, ≤ 3.2/c for a derivative); doubled for safety.
        let round = 2.0 * f64::from(f32::EPSILON);
        let stored = amplitude_sum + cell * slope_sum * 2.0 + cell * cell * slope_sum.powi(2);
        Some(Self {
            origin,
            cell,
            n,
            vertices,
            error: e + round * 1.2 * stored,
            slope_error: de + DVec2::splat(round * 3.2 * stored / cell),
            amplitude_sum,
        })
    }

    /// The interpolant's value and gradient at `x` (texture space), or `None` outside the grid.
    pub fn sample(&self, x: DVec2) -> Option<(f64, DVec2)> {
        let u = (x - self.origin) / self.cell;
        let n = self.n as f64;
        if !(u.x >= 0.0 && u.y >= 0.0 && u.x <= n && u.y <= n) {
            return None;
        }
        let i = (u.x.floor() as usize).min(self.n - 1);
        let j = (u.y.floor() as usize).min(self.n - 1);
        let (s, t) = (u.x - i as f64, u.y - j as f64);
        let v = self.n + 1;
        let corner = |di: usize, dj: usize| self.vertices[(j + dj) * v + i + di].map(f64::from);
        let (hs, dhs) = hermite_basis(s);
        let (ht, dht) = hermite_basis(t);
        let (mut f, mut fs, mut ft) = (0.0, 0.0, 0.0);
        for dj in 0..2 {
            for di in 0..2 {
                let c = corner(di, dj);
                // Value and slope basis functions of this corner along each axis.
                let (v0, v1, d0, d1) = (hs[di], hs[2 + di], dhs[di], dhs[2 + di]);
                let (w0, w1, e0, e1) = (ht[dj], ht[2 + dj], dht[dj], dht[2 + dj]);
                f += c[0] * v0 * w0 + c[1] * v1 * w0 + c[2] * v0 * w1 + c[3] * v1 * w1;
                fs += c[0] * d0 * w0 + c[1] * d1 * w0 + c[2] * d0 * w1 + c[3] * d1 * w1;
                ft += c[0] * v0 * e0 + c[1] * v1 * e0 + c[2] * v0 * e1 + c[3] * v1 * e1;
            }
        }
        Some((f, DVec2::new(fs, ft) / self.cell))
    }
}

/// The cubic Hermite basis on [0, 1] at s and its derivative: `[h00, h01, h10, h11]` (value at
/// 0, value at 1, slope at 0, slope at 1).
pub fn hermite_basis(s: f64) -> ([f64; 4], [f64; 4]) {
    let (s2, s3) = (s * s, s * s * s);
    (
        [
            2.0 * s3 - 3.0 * s2 + 1.0,
            -2.0 * s3 + 3.0 * s2,
            s3 - 2.0 * s2 + s,
            s3 - s2,
        ],
        [
            6.0 * s2 - 6.0 * s,
            -6.0 * s2 + 6.0 * s,
            3.0 * s2 - 4.0 * s + 1.0,
            3.0 * s2 - 2.0 * s,
        ],
    )
}

/// The table as one march sees it: f itself (the explicit surface) or the level-of-detail
/// surface, which differs from f by at most `shift` and its slope along d by at most
/// `|d_x|·shift_slope.x + |d_y|·shift_slope.y` (module docs).
#[derive(Clone, Copy, Debug)]
pub struct FieldView<'a> {
    /// The table.
    pub grid: &'a FieldGrid,
    /// `D = Σ|a_i|(1 − g_i)` (0 on the explicit surface).
    pub shift: f64,
    /// `(Σ|a_i|(1 − g_i)|ω_x|, Σ|a_i|(1 − g_i)|ω_y|)`.
    pub shift_slope: DVec2,
}

/// f along a ray at a point, as the table bounds it: `f ∈ [value ± error]` and its slope along the
/// ray `∈ [slope ± slope_error]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldProbe {
    /// The interpolant.
    pub value: f64,
    /// Bound of the value's error.
    pub error: f64,
    /// The interpolant's slope along the ray.
    pub slope: f64,
    /// Bound of the slope's error.
    pub slope_error: f64,
}

impl<'a> FieldView<'a> {
    /// The explicit surface's view.
    pub fn explicit(grid: &'a FieldGrid) -> Self {
        Self {
            grid,
            shift: 0.0,
            shift_slope: DVec2::ZERO,
        }
    }

    /// The view's f at `x` with its slope along `dxy`, or `None` outside the grid.
    pub fn probe(&self, x: DVec2, dxy: DVec2) -> Option<FieldProbe> {
        let (value, grad) = self.grid.sample(x)?;
        let a = dxy.abs();
        Some(FieldProbe {
            value,
            error: self.grid.error + self.shift,
            slope: grad.dot(dxy),
            slope_error: a.dot(self.grid.slope_error + self.shift_slope),
        })
    }
}

/// A camera ray may settle where the table proves the gap within this fraction of the slab's half
/// thickness (`top`): the table's own error band is about `TARGET_ERROR·top` for the identity, so
/// the ray can always get there, and the hit is on the surface to well within shading precision.
pub const FIELD_SETTLE: f64 = 5e-4;

/// What the table says at a point of a march (`OctaveSurface::field_step`, [`crate::scene::field_step`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldStep {
    /// The true gap is within `[0, settle]`: a camera ray may stop here.
    Settle,
    /// A safe step and a lower bound of the gap.
    Clear(f64, f64),
    /// The table cannot tell (outside it, too close to the surface for its error, or below it):
    /// sum the waves.
    Unsure,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::splitmix;
    use crate::scene::bound_grid::tests::noise;

    fn uniform(state: &mut u64) -> f64 {
        splitmix(state)
    }

    #[test]
    fn the_table_interpolates_its_vertices() {
        let f = noise(3, 48);
        let g = FieldGrid::around(&f, DVec2::new(3.0, -1.0), 16).expect("grid");
        for (i, j) in [(0, 0), (5, 7), (16, 16), (16, 3)] {
            let x = g.origin + g.cell * DVec2::new(i as f64, j as f64);
            let (want, grad) = f.value_and_gradient(x);
            let (got, ggot) = g.sample(x).expect("inside");
            assert!(
                (got - want).abs() <= 1e-6 * g.amplitude_sum,
                "{got} vs {want}"
            );
            assert!((ggot - grad).length() <= 1e-5 * grad.length().max(1.0));
        }
        assert!(g.sample(g.origin - DVec2::splat(1e-9)).is_none());
        assert!(
            g.sample(g.origin + DVec2::splat(16.0 * g.cell + 1e-9))
                .is_none()
        );
        assert!(g.sample(DVec2::NAN).is_none());
    }

    /// At random points the interpolant's value and gradient stay within the bounds, on the
    /// cell `around` chooses and on cells 2× and 4× coarser (where the errors are large enough to
    /// test the constants); and the bounds are not vacuous (the worst error seen is a fair fraction
    /// of its bound).
    #[test]
    fn interpolation_errors_stay_within_their_bounds() {
        let mut rng = 11u64;
        for (octaves, components) in [(3, 48), (6, 96), (1, 8)] {
            let f = noise(octaves, components);
            let base = FieldGrid::around(&f, DVec2::ZERO, 8).expect("grid");
            for scale in [1.0, 2.0, 4.0] {
                let g = FieldGrid::build(&f, DVec2::new(0.7, 0.2), 4.0 * base.cell * scale, 8)
                    .expect("grid");
                let (mut worst, mut worst_x, mut worst_y) = (0.0f64, 0.0f64, 0.0f64);
                for _ in 0..4000 {
                    let x =
                        g.origin + DVec2::new(uniform(&mut rng), uniform(&mut rng)) * 8.0 * g.cell;
                    let (want, grad) = f.value_and_gradient(x);
                    let (got, ggot) = g.sample(x).expect("inside");
                    worst = worst.max((got - want).abs());
                    worst_x = worst_x.max((ggot.x - grad.x).abs());
                    worst_y = worst_y.max((ggot.y - grad.y).abs());
                }
                let label = format!("{octaves} octaves, {components} waves, cell ×{scale}");
                assert!(
                    worst <= g.error,
                    "{label}: value error {worst} > {}",
                    g.error
                );
                assert!(
                    worst_x <= g.slope_error.x,
                    "{label}: ∂x {worst_x} > {}",
                    g.slope_error.x
                );
                assert!(
                    worst_y <= g.slope_error.y,
                    "{label}: ∂y {worst_y} > {}",
                    g.slope_error.y
                );
                eprintln!(
                    "{label}: value {worst:.3e} of {:.3e}, ∂x {worst_x:.3e} of {:.3e}, ∂y {worst_y:.3e} of {:.3e}",
                    g.error, g.slope_error.x, g.slope_error.y
                );
                if scale > 1.0 {
                    assert!(worst >= 0.05 * g.error, "{label}: value bound vacuous");
                    assert!(
                        worst_x.max(worst_y) >= 0.02 * g.slope_error.max_element(),
                        "{label}: slope bound vacuous"
                    );
                }
            }
        }
    }

    #[test]
    fn around_meets_the_target_error() {
        for (octaves, components) in [(3, 48), (6, 96)] {
            let f = noise(octaves, components);
            let g = FieldGrid::around(&f, DVec2::ZERO, 64).expect("grid");
            let target = TARGET_ERROR * g.amplitude_sum;
            assert!(g.error <= 1.01 * target, "{} vs {target}", g.error);
            assert!(g.error >= 0.5 * target, "{} vs {target}", g.error);
            assert_eq!(g.vertices.len(), 65 * 65);
        }
        let empty = SumOfSines {
            waves: vec![],
            octaves: 1,
        };
        assert!(FieldGrid::around(&empty, DVec2::ZERO, 8).is_none());
        assert!(FieldGrid::build(&noise(1, 8), DVec2::ZERO, f64::INFINITY, 8).is_none());
        assert!(FieldGrid::build(&noise(1, 8), DVec2::ZERO, 1.0, 0).is_none());
    }
}
