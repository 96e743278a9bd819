//! The effective height distribution `D_h(h) ∝ P(h)^L p(h)` of the visible and lit points
//! [HNPN14 Eqs. 14–15], its exact mean and standard deviation by quadrature, a table over ln L that
//! makes the exact moments as cheap as the paper's fits, and the fits themselves [HNPN14 Eqs. 16–17].
//!
//! Everything here is in standardized height units `t = (h − h̄)/σ_h`: multiply the mean and std by
//! σ_h (and add h̄) for a surface.
//!
//! Useful identity (docs/numerics.md): for integer L, D_h is the law of the maximum of L + 1 independent
//! standard normals (its cdf is Φ^{L+1}), so its normalising constant is exactly 1/(L + 1).

use crate::math::special::{log_norm_cdf, norm_pdf};
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

/// Which model of D_h's moments the filtered view uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum HeightFilter {
    /// Exact moments of `P^L p`, tabulated over ln L (default).
    #[default]
    Exact,
    /// The paper's fits [HNPN14 Eqs. 16–17]: off by up to 0.13·σ_h in the mean (docs/numerics.md).
    PaperFit,
}

/// Mean and standard deviation of D_h in standardized units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightMoments {
    /// μ_d/σ_h.
    pub mean: f64,
    /// σ_d/σ_h.
    pub std: f64,
}

/// Lower and upper integration bounds and panel count of the global quadrature rule. The rule
/// (composite 8-point Gauss–Legendre, panel width 0.04) resolves D_h down to its narrowest case,
/// std ≈ 0.13 at L = 1e12.
const T_LO: f64 = -11.0;
const T_HI: f64 = 15.0;
const PANELS: usize = 650;

/// Precomputed nodes with ln Φ and φ, shared by every L.
struct Rule {
    t: Vec<f64>,
    w_phi: Vec<f64>,
    log_cdf: Vec<f64>,
}

fn rule() -> &'static Rule {
    static RULE: OnceLock<Rule> = OnceLock::new();
    RULE.get_or_init(|| {
        let (x, w) = crate::math::quadrature::gl8();
        let h = (T_HI - T_LO) / PANELS as f64;
        let mut r = Rule {
            t: vec![],
            w_phi: vec![],
            log_cdf: vec![],
        };
        for p in 0..PANELS {
            let c = T_LO + (p as f64 + 0.5) * h;
            for (xi, wi) in x.iter().zip(w) {
                let t = c + 0.5 * h * xi;
                r.t.push(t);
                r.w_phi.push(0.5 * h * wi * norm_pdf(t));
                r.log_cdf.push(log_norm_cdf(t));
            }
        }
        r
    })
}

/// Exact mean and std of `D_h ∝ Φ(t)^L φ(t)` by quadrature [HNPN14 Eqs. 16–17, left-hand sides].
/// Accurate to ~1e-12 for L ∈ [0, 1e12]; negative or NaN L is treated as 0; L = ∞ is clamped to 1e12.
pub fn exact_moments(l: f64) -> HeightMoments {
    let l = if l.is_nan() { 0.0 } else { l.clamp(0.0, 1e12) };
    let r = rule();
    let (mut z, mut m1) = (0.0, 0.0);
    let weights: Vec<f64> = r
        .log_cdf
        .iter()
        .zip(&r.w_phi)
        .map(|(lc, w)| w * (l * lc).exp())
        .collect();
    for (w, t) in weights.iter().zip(&r.t) {
        z += w;
        m1 += w * t;
    }
    let mean = m1 / z;
    let var: f64 = weights
        .iter()
        .zip(&r.t)
        .map(|(w, t)| w * (t - mean) * (t - mean))
        .sum::<f64>()
        / z;
    HeightMoments {
        mean,
        std: var.sqrt(),
    }
}

/// α_μ of the paper's fit of the mean of D_h, `μ_d = α_μ ln(β_μ L + 1)` [HNPN14 Eq. 16].
pub const FIT_ALPHA_MU: f64 = 0.39;
/// β_μ of [`FIT_ALPHA_MU`]'s fit [HNPN14 Eq. 16].
pub const FIT_BETA_MU: f64 = 4.75;
/// α_σ of the paper's fit of the std of D_h, `σ_d = 1/(1 + α_σ ln(β_σ L + 1))` [HNPN14 Eq. 17].
pub const FIT_ALPHA_SIGMA: f64 = 0.26;
/// β_σ of [`FIT_ALPHA_SIGMA`]'s fit [HNPN14 Eq. 17].
pub const FIT_BETA_SIGMA: f64 = 1.13;

/// The paper's fits [HNPN14 Eqs. 16–17]: `μ_d = 0.39 ln(4.75 L + 1)`,
/// `σ_d = 1/(1 + 0.26 ln(1.13 L + 1))` (standardized). L is clamped to [0, 1e30]: always finite.
pub fn paper_fit_moments(l: f64) -> HeightMoments {
    let l = if l.is_nan() { 0.0 } else { l.clamp(0.0, 1e30) };
    HeightMoments {
        mean: FIT_ALPHA_MU * (FIT_BETA_MU * l).ln_1p(),
        std: 1.0 / (1.0 + FIT_ALPHA_SIGMA * (FIT_BETA_SIGMA * l).ln_1p()),
    }
}

/// Exact D_h moments tabulated over ln L with linear interpolation (the GPU samples the same table
/// with a linear filter). Below `l_min` it interpolates linearly in L toward the exact value at
/// L = 0 (mean 0, std 1); above `l_max` it clamps.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectiveHeightTable {
    /// ln of the first tabulated L.
    pub ln_l_min: f64,
    /// ln of the last tabulated L.
    pub ln_l_max: f64,
    /// Standardized means, one per entry.
    pub mean: Vec<f64>,
    /// Standardized standard deviations, one per entry.
    pub std: Vec<f64>,
}

impl EffectiveHeightTable {
    /// Default range: L from 1e-6 to 1e12 (the table must cover 1e-6 … 1e6; the extra decades keep
    /// grazing angles exact); 1024 entries give interpolation error below 1e-4·σ_h (tested).
    pub const DEFAULT_SIZE: usize = 1024;

    /// Build a table of `n ≥ 2` entries over L ∈ [l_min, l_max] (both > 0).
    pub fn new(l_min: f64, l_max: f64, n: usize) -> Self {
        let n = n.max(2);
        let (a, b) = (l_min.max(1e-300).ln(), l_max.max(l_min * 1.0001).ln());
        let mut mean = Vec::with_capacity(n);
        let mut std = Vec::with_capacity(n);
        for i in 0..n {
            let ln_l = a + (b - a) * i as f64 / (n - 1) as f64;
            let m = exact_moments(ln_l.exp());
            mean.push(m.mean);
            std.push(m.std);
        }
        Self {
            ln_l_min: a,
            ln_l_max: b,
            mean,
            std,
        }
    }

    /// The shared default table (built once, ~20 ms).
    pub fn shared() -> &'static Self {
        static TABLE: OnceLock<EffectiveHeightTable> = OnceLock::new();
        TABLE.get_or_init(|| Self::new(1e-6, 1e12, Self::DEFAULT_SIZE))
    }

    /// Interpolated moments at L (L ≥ 0; NaN → 0).
    pub fn lookup(&self, l: f64) -> HeightMoments {
        let l = if l.is_nan() { 0.0 } else { l.max(0.0) };
        let n = self.mean.len();
        let l_min = self.ln_l_min.exp();
        if l < l_min {
            let s = l / l_min;
            return HeightMoments {
                mean: s * self.mean[0],
                std: 1.0 + s * (self.std[0] - 1.0),
            };
        }
        let u = ((l.ln() - self.ln_l_min) / (self.ln_l_max - self.ln_l_min) * (n - 1) as f64)
            .clamp(0.0, (n - 1) as f64);
        let i = (u.floor() as usize).min(n - 2);
        let f = u - i as f64;
        HeightMoments {
            mean: self.mean[i] + f * (self.mean[i + 1] - self.mean[i]),
            std: self.std[i] + f * (self.std[i + 1] - self.std[i]),
        }
    }
}

/// D_h moments under the chosen model.
pub fn height_moments(l: f64, model: HeightFilter) -> HeightMoments {
    match model {
        HeightFilter::Exact => EffectiveHeightTable::shared().lookup(l),
        HeightFilter::PaperFit => paper_fit_moments(l),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn integer_l_is_the_max_of_l_plus_one_normals() {
        let sqrt_pi = PI.sqrt();
        // (L, mean, variance) of the max of L+1 standard normals (closed forms and Tippett's values).
        let cases = [
            (1.0, 1.0 / sqrt_pi, 1.0 - 1.0 / PI),
            (
                2.0,
                1.5 / sqrt_pi,
                1.0 + 3f64.sqrt() / (2.0 * PI) - 9.0 / (4.0 * PI),
            ),
        ];
        for (l, mean, var) in cases {
            let m = exact_moments(l);
            assert!(
                (m.mean - mean).abs() < 1e-12,
                "L={l}: mean {} vs {mean}",
                m.mean
            );
            assert!(
                (m.std * m.std - var).abs() < 1e-12,
                "L={l}: var {} vs {var}",
                m.std * m.std
            );
        }
        assert!((exact_moments(3.0).mean - 1.029_375_373_0).abs() < 1e-9);
        assert!((exact_moments(4.0).mean - 1.162_964_473_6).abs() < 1e-9);
        assert!((exact_moments(9.0).mean - 1.538_752_731_4).abs() < 1e-9);
        let m0 = exact_moments(0.0);
        assert!(m0.mean.abs() < 1e-14 && (m0.std - 1.0).abs() < 1e-13);
    }

    #[test]
    fn normalisation_is_one_over_l_plus_one() {
        let r = rule();
        for l in [0.5, 7.0, 1e3, 1e6, 1e12] {
            let z: f64 = r
                .log_cdf
                .iter()
                .zip(&r.w_phi)
                .map(|(lc, w)| w * (l * lc).exp())
                .sum();
            assert!(
                ((z * (l + 1.0)) - 1.0).abs() < 1e-11,
                "L={l}: {}",
                z * (l + 1.0)
            );
        }
    }

    #[test]
    fn table_interpolation_error_below_1e_4() {
        let table = EffectiveHeightTable::shared();
        let mut worst: f64 = 0.0;
        // Midpoints between entries are where linear interpolation is worst; sample densely.
        for k in 0..2000 {
            let ln_l =
                (1e-6f64).ln() + ((1e6f64).ln() - (1e-6f64).ln()) * (k as f64 + 0.37) / 2000.0;
            let l = ln_l.exp();
            let e = exact_moments(l);
            let t = table.lookup(l);
            worst = worst
                .max((e.mean - t.mean).abs())
                .max((e.std - t.std).abs());
        }
        for l in [0.0, 1e-9, 1e-7, 5e-7] {
            let e = exact_moments(l);
            let t = table.lookup(l);
            worst = worst
                .max((e.mean - t.mean).abs())
                .max((e.std - t.std).abs());
        }
        assert!(worst <= 1e-4, "table interpolation error {worst}");
        eprintln!("D_h table worst interpolation error {worst:e} σ_h");
    }

    #[test]
    fn paper_fits_are_off_as_numerics_md_says() {
        // Not a correctness check of the fit (it is what it is) but of our claim about it.
        let mut worst = (0.0_f64, 0.0);
        for k in 0..400 {
            let l = 10f64.powf(-3.0 + 7.0 * k as f64 / 399.0);
            let d = (paper_fit_moments(l).mean - exact_moments(l).mean).abs();
            if d > worst.0 {
                worst = (d, l);
            }
        }
        assert!(worst.0 > 0.1 && worst.0 < 0.5, "fit error {worst:?}");
        // Small-L slope: exact ≈ 0.903 L, the fit 1.85 L.
        let slope = exact_moments(1e-5).mean / 1e-5;
        assert!((slope - 0.903).abs() < 2e-3, "slope {slope}");
    }

    #[test]
    fn extreme_l_is_finite() {
        for l in [
            0.0,
            1e-300,
            1e-6,
            1.0,
            1e6,
            1e12,
            1e20,
            f64::INFINITY,
            f64::NAN,
            -1.0,
        ] {
            for m in [
                exact_moments(l),
                paper_fit_moments(l),
                EffectiveHeightTable::shared().lookup(l),
            ] {
                assert!(
                    m.mean.is_finite() && m.std.is_finite() && m.std > 0.0,
                    "L={l}: {m:?}"
                );
            }
        }
    }
}
