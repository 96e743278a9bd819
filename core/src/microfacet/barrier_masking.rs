//! Masking under a transfer curve, conditioned on the start's driver value and slope (#17;
//! docs/design/transfer-curves.md, "Masking that knows the driver's slope").
//!
//! The surface is `h = σ_h·g(f)` over a Gaussian driver f. Along a horizontal direction d the
//! driver is a stationary Gaussian process; in units where it has unit variance and unit slope
//! variance ([`crate::microfacet::slope_masking::LineProcess`]: x = f/σ_f, τ the distance over
//! `σ_f/σ_t`, σ_t the driver's slope deviation along d) the ray `h₀ + μs` meets the surface where
//! x crosses the **barrier**
//! `b(τ) = G⁻¹(G(x₀) + ντ)`, with `G(x) = g(σ_f x)/σ_f` and `ν = μ/(σ_h σ_t)` (the ν of
//! [`crate::microfacet::slope_masking`]: under the identity transfer the barrier is the ray
//! `x₀ + ντ` and everything here is that module's `G1`). The barrier's slope is `ν/G′(b)`:
//! steep where g is flat (a tread: the ray climbs past its height in no x at all), shallow on a
//! riser.
//!
//! Rice's crossing rate with Smith's "below the barrier so far",
//! `E[(x′ − b′)⁺ | x = b]·p(x = b)/P(x < b)`, with (x, x′) at τ conditioned on the start
//! `(x₀, t)` (t the driver's slope along d in σ_t) through the process's autocovariance, gives
//! `G1(x₀, t) = exp(−∫ rate dτ)`. Past the process's memory the rate is Smith's, unconditioned,
//! integrated on to the top of g. Why it matters: over a tread the shading does not see the
//! driver's slope, but the masking does (f rising toward the eye meets the next riser up), and
//! toward a light opposite the eye the same slope points the other way, so being seen and being
//! lit are anti-correlated among a tread's points (terraces at 60°, light 60° opposite: the views'
//! height-only visibility left the filtered view 7% too bright).

use crate::math::special::{norm_cdf, norm_pdf};
use crate::microfacet::slope_masking::{ProcessGrid, conditioned_rate};
use crate::microfacet::transfer::TransferFunction;

/// `G(x) = g(σ_f x)/σ_f` tabulated for its inverse ([`TransferBarrier::inverse`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TransferBarrier {
    values: Vec<f64>,
    slopes: Vec<f64>,
}

/// The barrier is tabulated on x in [−X_RANGE, X_RANGE] (the driver's standardized value).
const X_RANGE: f64 = 8.0;
/// Samples of the barrier's table (step 0.002 in x).
const X_SAMPLES: usize = 8001;
/// Steepest barrier slope followed: `ν/G′` over a flat run is infinite; its rate is 0 anyway.
const MAX_BARRIER_SLOPE: f64 = 1e6;
/// Most steps of the unconditioned tail.
const MAX_TAIL_STEPS: usize = 20_000;
/// `G1 < e^−700` counts as 0.
const MAX_LOG: f64 = 700.0;

impl TransferBarrier {
    /// The barrier of `transfer` for a driver of standard deviation `sigma_f` (> 0). A curve that
    /// decreases somewhere is taken as its running maximum (heights ordered like f, as the
    /// transfer mixture's masking takes them).
    pub fn new(transfer: &TransferFunction, sigma_f: f64) -> Self {
        let sf = if sigma_f > 0.0 && sigma_f.is_finite() {
            sigma_f
        } else {
            1.0
        };
        // g and g′ at f: a curve's polynomial built once (`eval` and `derivative` build it per
        // call), channels 0 and 2 of its moment polynomial.
        let poly = match transfer {
            TransferFunction::Curve(c) => Some(c.moment_poly()),
            TransferFunction::Identity => None,
        };
        let g_and_slope = |f: f64| match &poly {
            Some(p) => {
                let mut o = [0.0; 4];
                p.eval(f, &mut o);
                (o[0], o[2])
            }
            None => (f, 1.0),
        };
        let mut values = Vec::with_capacity(X_SAMPLES);
        let mut slopes = Vec::with_capacity(X_SAMPLES);
        let mut top = f64::NEG_INFINITY;
        for k in 0..X_SAMPLES {
            let x = Self::x_of(k);
            let (g, d) = g_and_slope(sf * x);
            let v = g / sf;
            top = top.max(if v.is_finite() { v } else { top });
            values.push(if top.is_finite() { top } else { 0.0 });
            slopes.push(if d.is_finite() { d.max(0.0) } else { 0.0 });
        }
        Self { values, slopes }
    }

    fn x_of(k: usize) -> f64 {
        -X_RANGE + 2.0 * X_RANGE * k as f64 / (X_SAMPLES - 1) as f64
    }

    /// G(x) (linear between samples, clamped to the ends).
    pub fn value(&self, x: f64) -> f64 {
        let (k, w) = Self::cell(x);
        self.values[k] * (1.0 - w) + self.values[k + 1] * w
    }

    /// G′(x) = g′(σ_f x) (≥ 0; linear between samples, clamped).
    pub fn slope(&self, x: f64) -> f64 {
        let (k, w) = Self::cell(x);
        self.slopes[k] * (1.0 - w) + self.slopes[k + 1] * w
    }

    fn cell(x: f64) -> (usize, f64) {
        let x = if x.is_nan() { 0.0 } else { x };
        let u = ((x + X_RANGE) / (2.0 * X_RANGE) * (X_SAMPLES - 1) as f64)
            .clamp(0.0, (X_SAMPLES - 1) as f64);
        let k = (u as usize).min(X_SAMPLES - 2);
        (k, u - k as f64)
    }

    /// The top of the surface, `G(X_RANGE)`: a ray above it is crossed no more.
    pub fn top(&self) -> f64 {
        self.values[X_SAMPLES - 1]
    }

    /// The least x with `G(x) ≥ y` (linear between samples); `None` above the top.
    pub fn inverse(&self, y: f64) -> Option<f64> {
        if !(y <= self.top()) {
            return None;
        }
        let k = self.values.partition_point(|v| *v < y);
        if k == 0 {
            return Some(-X_RANGE);
        }
        let (a, b) = (self.values[k - 1], self.values[k]);
        let w = if b > a { (y - a) / (b - a) } else { 1.0 };
        Some(Self::x_of(k - 1) + w * (Self::x_of(k) - Self::x_of(k - 1)))
    }

    /// Whether a start at `x0` with driver slope `t` (σ_t units) faces away from a ray of slope
    /// `nu`: its surface slope `G′(x₀)·t` is at least the ray's.
    pub fn back_face(&self, x0: f64, t: f64, nu: f64) -> bool {
        self.slope(x0) * t >= nu
    }
}

/// `ln G1(x₀, t)` of a ray of slope `nu` over `barrier` (module docs), on `grid` (the driver's
/// normalized process along the ray's azimuth, built for rays at most as grazing). `−∞` where the
/// start is certainly masked; a back face ([`TransferBarrier::back_face`]) or `nu ≤ 0`/NaN gives
/// `−∞`. Never NaN.
pub fn barrier_log_g1(
    grid: &ProcessGrid,
    barrier: &TransferBarrier,
    x0: f64,
    t: f64,
    nu: f64,
) -> f64 {
    if !(nu > 0.0) || x0.is_nan() || t.is_nan() || barrier.back_face(x0, t, nu) {
        return f64::NEG_INFINITY;
    }
    let dt = grid.step();
    let start = barrier.value(x0);
    let mut integral = 0.0f64;
    let mut tau = 0.0;
    let barrier_at = |tau: f64| -> Option<(f64, f64)> {
        let b = barrier.inverse(start + nu * tau)?;
        let slope = barrier.slope(b);
        let bd = if slope > nu / MAX_BARRIER_SLOPE {
            nu / slope
        } else {
            MAX_BARRIER_SLOPE
        };
        Some((b, bd))
    };
    for (i, &(r, r1, r2)) in grid.remembered().iter().enumerate() {
        tau = (i as f64 + 0.5) * dt;
        let Some((b, bd)) = barrier_at(tau) else {
            return -integral;
        };
        let Some(rate) = conditioned_rate((r, r1, r2), (x0, t), (b, bd)) else {
            return f64::NEG_INFINITY;
        };
        integral += rate * dt;
        if integral > MAX_LOG {
            return f64::NEG_INFINITY;
        }
    }
    // The process has forgotten the start: Smith's rate, unconditioned, to the top.
    for _ in 0..MAX_TAIL_STEPS {
        tau += dt;
        let Some((b, bd)) = barrier_at(tau) else {
            break;
        };
        let up = (norm_pdf(bd) - bd * norm_cdf(-bd)).max(0.0);
        integral += up * norm_pdf(b) / norm_cdf(b).max(1e-300) * dt;
        if integral > MAX_LOG {
            return f64::NEG_INFINITY;
        }
    }
    -integral
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::microfacet::slope_masking::{LineProcess, conditioned_masking};
    use crate::microfacet::transfer::{Curve, CurveInterpolation};

    fn process() -> LineProcess {
        LineProcess::new((0..48).map(|i| {
            let w = 1.0 + 3.0 * (i as f64 / 47.0);
            (1.0 / w.powi(3), w * (1.0 + 0.37 * (i as f64).sin()))
        }))
        .expect("a process")
    }

    /// Under the identity the barrier is the ray: the height-averaged G1 matches
    /// `conditioned_masking` (the Gaussian module's own integration, with its closed tail) at
    /// every front slope node.
    #[test]
    fn the_identity_barrier_is_the_ray() {
        let p = process();
        let barrier = TransferBarrier::new(&TransferFunction::Identity, 1.0);
        for nu in [0.3, 1.0, 2.5] {
            let grid = ProcessGrid::new(&p, nu);
            let reference = conditioned_masking(&p, nu);
            let hs: Vec<f64> = (0..10).map(|i| -4.5 + i as f64).collect();
            let w: Vec<f64> = hs
                .iter()
                .enumerate()
                .map(|(i, h)| if i == 0 || i == 9 { 0.5 } else { 1.0 } * norm_pdf(*h))
                .collect();
            for j in 0..9 {
                let t = -4.0 + j as f64;
                if t >= nu {
                    continue;
                }
                let mean: f64 = hs
                    .iter()
                    .zip(&w)
                    .map(|(h, w)| w * barrier_log_g1(&grid, &barrier, *h, t, nu).exp())
                    .sum::<f64>()
                    / w.iter().sum::<f64>();
                let r = reference.slopes[j];
                assert!(
                    (mean - r).abs() < 2e-3 + 1e-2 * r,
                    "ν {nu} t {t}: {mean} vs {r}"
                );
            }
        }
    }

    /// A terrace: a start on a tread is masked more where the driver rises toward the eye (it meets
    /// the riser up) than where it falls, though the tread is flat either way; a start above the
    /// whole curve is never masked; a back face and ν ≤ 0 are −∞; nothing is NaN.
    #[test]
    fn a_tread_is_masked_by_the_driver_slope_it_hides() {
        let curve = TransferFunction::Curve(Curve {
            points: vec![[-3.0, -1.0], [-0.2, -0.9], [0.2, 0.9], [3.0, 1.0]],
            interpolation: CurveInterpolation::MonotoneCubic,
        });
        let barrier = TransferBarrier::new(&curve, 1.0);
        let p = process();
        let grid = ProcessGrid::new(&p, 0.5);
        let on_tread = |t: f64| barrier_log_g1(&grid, &barrier, -1.0, t, 1.0);
        assert!(
            on_tread(1.5) < on_tread(-1.5) - 0.05,
            "{} {}",
            on_tread(1.5),
            on_tread(-1.5)
        );
        assert!(on_tread(0.0) < 0.0);
        assert_eq!(barrier_log_g1(&grid, &barrier, 7.9, 0.0, 1.0), 0.0);
        // On the riser (G′ ≈ 4.4 at 0) a slope of 1σ is steeper than a ray of slope 1.
        assert_eq!(
            barrier_log_g1(&grid, &barrier, 0.0, 1.0, 1.0),
            f64::NEG_INFINITY
        );
        assert_eq!(
            barrier_log_g1(&grid, &barrier, 0.0, 0.0, 0.0),
            f64::NEG_INFINITY
        );
        for x in [-9.0, -4.0, -0.1, 0.0, 0.3, 4.0, 9.0, f64::NAN] {
            for t in [-4.0, -0.5, 0.0, 0.2, 4.0] {
                for nu in [1e-3, 0.08, 1.0, 7.0, 1e3] {
                    assert!(!barrier_log_g1(&grid, &barrier, x, t, nu).is_nan());
                }
            }
        }
    }
}
