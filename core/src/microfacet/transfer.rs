//! Height transfer functions `h = σ_h·g(f)` [HNPN14 Sec. 7]: curves through control points
//! (monotone cubic or linear, constant beyond the ends), named shapes, the pre-convolved moment tables
//! of g and g′ [HNPN14 Eqs. 21–28], and from them the Gaussian height and slope statistics of the
//! transformed surface [HNPN14 Eqs. 19–26].
//!
//! Tables store the moments in central form, `(ḡ, σ_g, ḡ′, σ_g′)`, which carries the same
//! information as the paper's `(ḡ, g²‾, ḡ′, g′²‾)` but keeps `Var g = g²‾ − ḡ²` from cancelling in f32.

use crate::math::piecewise::{NCOEF, PiecewisePoly};
use crate::math::preconvolved::{MARGIN_SIGMAS, PreconvolvedTable, TableSpec};
use crate::microfacet::slopes::SlopeCov;
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// Interpolation of a transfer curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum CurveInterpolation {
    /// Piecewise linear.
    Linear,
    /// Fritsch–Carlson monotone cubic Hermite: never overshoots monotone data.
    #[default]
    MonotoneCubic,
}

/// A curve `g` through control points `(f, g)`, constant beyond the first and last point.
/// Two points with the same `f` make a vertical segment (a cliff in the surface).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Curve {
    /// Control points `[f, g]`, sorted by f.
    pub points: Vec<[f64; 2]>,
    /// Interpolation between points.
    #[serde(default)]
    pub interpolation: CurveInterpolation,
}

/// A height transfer function.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
pub enum TransferFunction {
    /// `g(f) = f`: Gaussian heights. Its moments are analytic; no table is built.
    #[default]
    Identity,
    /// A curve.
    Curve(Curve),
}

/// Moments of `g(X)` and `g′(X)`, `X ~ N(m, σ²)` [HNPN14 Eqs. 21, 22, 27, 28], central form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TransferMoments {
    /// ḡ [Eq. 21].
    pub mean: f64,
    /// √(g²‾ − ḡ²) [Eqs. 21–22].
    pub std: f64,
    /// ḡ′ [Eq. 27].
    pub mean_deriv: f64,
    /// √(g′²‾ − ḡ′²) [Eqs. 27–28].
    pub std_deriv: f64,
}

/// Gaussian statistics of the transformed surface within a footprint [HNPN14 Eqs. 19–26].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceStats {
    /// Mean height h̄ (world units).
    pub height_mean: f64,
    /// Height standard deviation (world units).
    pub height_std: f64,
    /// Mean slope (∂h/∂x, ∂h/∂y) [Eq. 24].
    pub slope_mean: DVec2,
    /// Slope covariance [Eqs. 25–26].
    pub slope_cov: SlopeCov,
}

impl Curve {
    /// `Some(true)` when g never decreases, `Some(false)` when it never increases (a constant curve
    /// is non-decreasing), `None` otherwise: the control points' g in that order, which both
    /// interpolations keep (linear segments; Fritsch–Carlson never overshoots monotone data).
    pub fn monotone(&self) -> Option<bool> {
        let steps = || self.points.windows(2).map(|w| w[1][1] - w[0][1]);
        if steps().all(|d| d >= 0.0) {
            Some(true)
        } else if steps().all(|d| d <= 0.0) {
            Some(false)
        } else {
            None
        }
    }

    /// Normalise so that `g(X)`, `X ~ N(0, 1)`, has mean 0 and std 1: σ_h then keeps its meaning as
    /// the height standard deviation of the surface. Curves that are constant stay unchanged.
    pub fn normalized(mut self) -> Self {
        let m = TransferFunction::Curve(self.clone()).moments(0.0, 1.0);
        if m.std > 1e-12 {
            for p in &mut self.points {
                p[1] = (p[1] - m.mean) / m.std;
            }
        }
        self
    }

    /// Moss: a low, nearly flat floor with rounded clumps growing where the driver is high, in the
    /// spirit of [HNPN14 Fig. 11] (the figure is not in our copy). Normalised.
    pub fn moss() -> Self {
        Self {
            points: vec![
                [-3.0, 0.0],
                [-0.3, 0.02],
                [0.3, 0.35],
                [0.9, 0.85],
                [1.6, 1.0],
                [3.0, 1.05],
            ],
            interpolation: CurveInterpolation::MonotoneCubic,
        }
        .normalized()
    }

    /// Sponge: a flat top pierced by steep-walled pits where the driver is low, in the spirit of
    /// [HNPN14 Fig. 11]. Normalised.
    pub fn sponge() -> Self {
        Self {
            points: vec![
                [-3.0, -1.1],
                [-1.2, -1.0],
                [-0.6, -0.55],
                [-0.2, -0.05],
                [0.3, 0.0],
                [3.0, 0.02],
            ],
            interpolation: CurveInterpolation::MonotoneCubic,
        }
        .normalized()
    }

    /// Terraces: `steps` flat shelves joined by steep risers over f ∈ [−2.5, 2.5]. Normalised.
    pub fn terraces(steps: usize) -> Self {
        let steps = steps.clamp(2, 16);
        let mut points = vec![];
        let w = 5.0 / steps as f64;
        for s in 0..steps {
            let x0 = -2.5 + w * s as f64;
            points.push([x0 + 0.15 * w, s as f64]);
            points.push([x0 + 0.85 * w, s as f64 + 0.08]);
        }
        Self {
            points,
            interpolation: CurveInterpolation::MonotoneCubic,
        }
        .normalized()
    }

    /// Per-segment cubic coefficients in the local variable t (zero-width segments get zeros).
    fn cubics(&self) -> Vec<[f64; 4]> {
        let p = &self.points;
        let n = p.len();
        if n < 2 {
            return vec![];
        }
        let h: Vec<f64> = p.windows(2).map(|w| w[1][0] - w[0][0]).collect();
        let delta: Vec<Option<f64>> = p
            .windows(2)
            .zip(&h)
            .map(|(w, h)| (*h > 0.0).then(|| (w[1][1] - w[0][1]) / h))
            .collect();
        // Tangents (Fritsch–Carlson), treating vertical segments as breaks.
        let mut m = vec![0.0; n];
        if self.interpolation == CurveInterpolation::MonotoneCubic {
            for k in 0..n {
                let left = if k > 0 { delta[k - 1] } else { None };
                let right = if k < n - 1 { delta[k] } else { None };
                m[k] = match (left, right) {
                    (Some(a), Some(b)) if a * b > 0.0 => 0.5 * (a + b),
                    (Some(_), Some(_)) => 0.0,
                    (Some(a), None) | (None, Some(a)) => a,
                    (None, None) => 0.0,
                };
            }
            for k in 0..n - 1 {
                let Some(d) = delta[k] else { continue };
                if d == 0.0 {
                    m[k] = 0.0;
                    m[k + 1] = 0.0;
                    continue;
                }
                let (a, b) = (m[k] / d, m[k + 1] / d);
                let r = a * a + b * b;
                if r > 9.0 {
                    let tau = 3.0 / r.sqrt();
                    m[k] = tau * a * d;
                    m[k + 1] = tau * b * d;
                }
            }
        }
        (0..n - 1)
            .map(|k| {
                let (y0, y1, hk) = (p[k][1], p[k + 1][1], h[k]);
                if !(hk > 0.0) {
                    return [0.0; 4];
                }
                match self.interpolation {
                    CurveInterpolation::Linear => [y0, y1 - y0, 0.0, 0.0],
                    CurveInterpolation::MonotoneCubic => {
                        let (m0, m1) = (hk * m[k], hk * m[k + 1]);
                        [
                            y0,
                            m0,
                            3.0 * (y1 - y0) - 2.0 * m0 - m1,
                            2.0 * (y0 - y1) + m0 + m1,
                        ]
                    }
                }
            })
            .collect()
    }

    /// Four channels on the curve's knots: g, g², g′, g′² (degrees 3, 6, 2, 4).
    pub fn moment_poly(&self) -> PiecewisePoly {
        let cubics = self.cubics();
        let mut coeffs = Vec::with_capacity(4 * cubics.len());
        for (k, c) in cubics.iter().enumerate() {
            let h = self.points[k + 1][0] - self.points[k][0];
            let mut g = [0.0; NCOEF];
            g[..4].copy_from_slice(c);
            let mut d = [0.0; NCOEF];
            if h > 0.0 {
                d[0] = c[1] / h;
                d[1] = 2.0 * c[2] / h;
                d[2] = 3.0 * c[3] / h;
            }
            coeffs.push(g);
            coeffs.push(poly_square(&g));
            coeffs.push(d);
            coeffs.push(poly_square(&d));
        }
        let first = self.points.first().map_or(0.0, |p| p[1]);
        let last = self.points.last().map_or(0.0, |p| p[1]);
        PiecewisePoly {
            knots: self.points.iter().map(|p| p[0]).collect(),
            channels: 4,
            coeffs,
            left: vec![first, first * first, 0.0, 0.0],
            right: vec![last, last * last, 0.0, 0.0],
        }
    }

    /// Largest |f| of a control point (the driver has unit variance: ±1e3 is far beyond any use).
    pub const MAX_F: f64 = 1e3;
    /// Largest |g| of a control point (heights are σ_h·g).
    pub const MAX_G: f64 = 1e6;
    /// Smallest non-zero distance in f between successive points.
    pub const MIN_GAP: f64 = 1e-6;

    /// Most points a curve may have: each is a polynomial piece the pre-convolved tables integrate
    /// per texel (#16: a 400 000-point curve never finished).
    pub const MAX_POINTS: usize = 256;
}

/// Square of a polynomial of degree ≤ 3 (higher coefficients must be 0).
fn poly_square(c: &[f64; NCOEF]) -> [f64; NCOEF] {
    let mut out = [0.0; NCOEF];
    for i in 0..4 {
        for j in 0..4 {
            if i + j < NCOEF {
                out[i + j] += c[i] * c[j];
            }
        }
    }
    out
}

/// Non-Gaussianity of a surface ([`TransferFunction::shape`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceShape {
    /// Skewness of the heights.
    pub skewness: f64,
    /// Excess kurtosis of the heights.
    pub excess_kurtosis: f64,
    /// Excess kurtosis of each slope component.
    pub slope_excess_kurtosis: f64,
}

impl SurfaceShape {
    /// Whether the Gaussian approximation is likely to show (|skewness| > 0.5 or an excess
    /// kurtosis beyond ±1, the editor's warning threshold for images too).
    pub fn far_from_gaussian(&self) -> bool {
        self.skewness.abs() > 0.5
            || self.excess_kurtosis.abs() > 1.0
            || self.slope_excess_kurtosis.abs() > 1.0
    }
}

impl TransferFunction {
    /// g(f).
    pub fn eval(&self, f: f64) -> f64 {
        match self {
            Self::Identity => f,
            Self::Curve(c) => {
                let mut o = [0.0; 4];
                c.moment_poly().eval(f, &mut o);
                o[0]
            }
        }
    }

    /// g′(f) (0 beyond the ends and on vertical segments, where it is a delta).
    pub fn derivative(&self, f: f64) -> f64 {
        match self {
            Self::Identity => 1.0,
            Self::Curve(c) => {
                let mut o = [0.0; 4];
                c.moment_poly().eval(f, &mut o);
                o[2]
            }
        }
    }

    /// Largest |g′| (a Lipschitz constant of g), for ray marching.
    pub fn max_derivative(&self) -> f64 {
        match self {
            Self::Identity => 1.0,
            Self::Curve(c) => {
                let p = c.moment_poly();
                let mut best: f64 = 0.0;
                let mut o = [0.0; 4];
                for w in p.knots.windows(2) {
                    for s in 0..=64 {
                        p.eval(w[0] + (w[1] - w[0]) * f64::from(s) / 64.0, &mut o);
                        best = best.max(o[2].abs());
                    }
                }
                // Quadratic g′ sampled at 65 points: pad for the maximum between samples.
                best * 1.01
            }
        }
    }

    /// How far from Gaussian the surface is under this transfer function, for f ~ N(0, 1): the
    /// heights' skewness and excess kurtosis, and the slopes' excess kurtosis. Slopes are
    /// `σ_h g′(f) ∇f` with ∇f Gaussian and independent of f (a stationary Gaussian field), so
    /// each slope component has excess kurtosis `3(E[g′⁴]/E[g′²]² − 1)` (0 for the identity; a
    /// curve with flats and steep risers has many near-zero slopes and a heavy tail). The
    /// filtered model assumes Gaussian slopes for D_s [HNPN14 Sec. 8, Fig. 14]. Quadrature over
    /// [−8, 8] (800 panels of 8-point Gauss–Legendre: curves are piecewise polynomial). A curve
    /// whose g′ vanishes everywhere has no slopes: its slope kurtosis is reported as 0.
    pub fn shape(&self) -> SurfaceShape {
        let e = |q: &dyn Fn(f64) -> f64| {
            crate::math::quadrature::integrate(
                |f| crate::math::special::norm_pdf(f) * q(f),
                -8.0,
                8.0,
                800,
            )
        };
        let mean = e(&|f| self.eval(f));
        let var = e(&|f| (self.eval(f) - mean).powi(2));
        let (skewness, excess_kurtosis) = if var > 1e-300 {
            (
                e(&|f| (self.eval(f) - mean).powi(3)) / var.powf(1.5),
                e(&|f| (self.eval(f) - mean).powi(4)) / (var * var) - 3.0,
            )
        } else {
            (0.0, 0.0)
        };
        let d2 = e(&|f| self.derivative(f).powi(2));
        let d4 = e(&|f| self.derivative(f).powi(4));
        let slope_excess_kurtosis = if d2 > 1e-300 {
            3.0 * (d4 / (d2 * d2) - 1.0)
        } else {
            0.0
        };
        SurfaceShape {
            skewness,
            excess_kurtosis,
            slope_excess_kurtosis,
        }
    }

    /// Exact moments of g and g′ under `N(m, σ²)` [HNPN14 Eqs. 21, 22, 27, 28].
    pub fn moments(&self, m: f64, sigma: f64) -> TransferMoments {
        match self {
            Self::Identity => TransferMoments {
                mean: m,
                std: sigma.max(0.0),
                mean_deriv: 1.0,
                std_deriv: 0.0,
            },
            Self::Curve(c) => {
                let mut e = [0.0; 4];
                c.moment_poly().gaussian_expectation(m, sigma, &mut e);
                central(&e)
            }
        }
    }

    /// The pre-convolved table of `(ḡ, σ_g, ḡ′, σ_g′)` [HNPN14 Sec. 7]; `None` for the identity.
    pub fn preconvolve(&self, spec: TableSpec) -> Option<PreconvolvedTable> {
        let Self::Curve(c) = self else { return None };
        let spec = spec.sanitized();
        let (lo, hi) = (
            c.points.first().map_or(0.0, |p| p[0]),
            c.points.last().map_or(0.0, |p| p[0]),
        );
        let margin = MARGIN_SIGMAS * spec.sigma_max;
        let m = central_f32;
        Some(PreconvolvedTable::build(
            &c.moment_poly(),
            spec,
            (lo - margin, hi + margin),
            m,
        ))
    }
}

fn central(e: &[f64]) -> TransferMoments {
    TransferMoments {
        mean: e[0],
        std: (e[1] - e[0] * e[0]).max(0.0).sqrt(),
        mean_deriv: e[2],
        std_deriv: (e[3] - e[2] * e[2]).max(0.0).sqrt(),
    }
}

fn central_f32(e: &[f64]) -> [f32; 4] {
    let c = central(e);
    [
        c.mean as f32,
        c.std as f32,
        c.mean_deriv as f32,
        c.std_deriv as f32,
    ]
}

/// The transformed surface's Gaussian statistics [HNPN14 Eqs. 19–26] for `h = σ_h·g(f)`.
///
/// `moments` are g's under the footprint's driver distribution; the driver's gradient within the
/// footprint has mean `grad_mean` and covariance `grad_cov`, independent of f (a Gaussian process's
/// value and gradient are uncorrelated at a point [HNPN14 Sec. 7]). Then
/// `E[∂h] = σ_h ḡ′ E[∂f]` [Eq. 24] and
/// `Cov(∂h) = σ_h² (Var g′ · E[∂f ∂fᵀ] + ḡ′² Cov ∂f)` [Eqs. 25–26, rearranged without cancellation].
pub fn transformed_statistics(
    moments: TransferMoments,
    sigma_h: f64,
    grad_mean: DVec2,
    grad_cov: SlopeCov,
) -> SurfaceStats {
    let var_d = moments.std_deriv * moments.std_deriv;
    let md2 = moments.mean_deriv * moments.mean_deriv;
    let second = SlopeCov {
        xx: grad_cov.xx + grad_mean.x * grad_mean.x,
        yy: grad_cov.yy + grad_mean.y * grad_mean.y,
        xy: grad_cov.xy + grad_mean.x * grad_mean.y,
    };
    let cov = SlopeCov {
        xx: var_d * second.xx + md2 * grad_cov.xx,
        yy: var_d * second.yy + md2 * grad_cov.yy,
        xy: var_d * second.xy + md2 * grad_cov.xy,
    }
    .scaled(sigma_h);
    SurfaceStats {
        height_mean: sigma_h * moments.mean,
        height_std: sigma_h.abs() * moments.std,
        slope_mean: grad_mean * (sigma_h * moments.mean_deriv),
        slope_cov: cov,
    }
}

#[cfg(test)]
mod tests;
