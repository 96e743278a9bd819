//! Stiff and extreme inputs run through core's f64 functions and their f32 mirrors, each against a
//! reference computed independently (quadrature, an exact limit or identity), for
//! `lodestone stability` ([`crate::cli::stability`] adds the WGSL path, which needs a GPU adapter).
//!
//! A [`Row`] passes when no output is non-finite (or negative where the quantity cannot be) and the
//! largest deviation stays within the row's documented bound. Deviations are relative with an absolute
//! floor, `|got − ref| / max(|ref|, floor)`, so values that underflow (erfc(30) ≈ 2e-393) compare as 0.

use crate::cli::stability::inputs::{step_map, vertical_curve};
use crate::cli::stability::materials::angles;
use crate::cli::stability::row::{Path, Row, deviation};
use lodestone_core::math::preconvolved::TableSpec;
use lodestone_core::math::quadrature::integrate;
use lodestone_core::math::{special, special_f32};
use lodestone_core::microfacet::effective_height::{EffectiveHeightTable, exact_moments};
use lodestone_core::microfacet::transfer::TransferFunction;
use lodestone_core::scene::direction::direction;
use std::f64::consts::{FRAC_PI_2, PI};

/// The special functions mirrored in f32 and WGSL (closed set; [`SpecialFunction::name`] is the
/// function's name in core, its f32 mirror and the WGSL alike).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpecialFunction {
    /// [`special::erf`].
    Erf,
    /// [`special::erfc`].
    Erfc,
    /// [`special::erfcx`].
    Erfcx,
    /// [`special::norm_cdf`].
    NormCdf,
    /// [`special::log_norm_cdf`].
    LogNormCdf,
    /// [`special::smith_lambda`].
    SmithLambda,
}

impl SpecialFunction {
    /// Every function, in table order.
    pub const ALL: [Self; 6] = [
        Self::Erf,
        Self::Erfc,
        Self::Erfcx,
        Self::NormCdf,
        Self::LogNormCdf,
        Self::SmithLambda,
    ];

    /// The function's name in core, the f32 mirror and the WGSL.
    pub fn name(self) -> &'static str {
        match self {
            Self::Erf => "erf",
            Self::Erfc => "erfc",
            Self::Erfcx => "erfcx",
            Self::NormCdf => "norm_cdf",
            Self::LogNormCdf => "log_norm_cdf",
            Self::SmithLambda => "smith_lambda",
        }
    }

    /// Extreme arguments (all finite f32 values too): 0, ±1e-30, ±1e-7, the branch points, the
    /// underflow edges and up to ±1e30 (erfcx only down to −26, where e^{x²} overflows f64;
    /// smith_lambda only ν ≥ 0, below which it is clamped).
    pub fn inputs(self) -> Vec<f64> {
        let pos = [
            0.0, 1e-30, 1e-7, 0.3, 0.5, 1.0, 1.9999, 2.0, 2.5, 3.0, 5.0, 9.0, 10.0, 10.5, 15.0,
            26.0, 27.2, 27.5, 40.0, 1e3, 1e6, 1e12, 1e30,
        ];
        let mut v: Vec<f64> = pos.to_vec();
        match self {
            Self::SmithLambda => {}
            Self::Erfcx => v.extend(pos.iter().filter(|x| **x > 0.0 && **x <= 26.0).map(|x| -x)),
            _ => v.extend(pos.iter().filter(|x| **x > 0.0).map(|x| -x)),
        }
        v
    }

    /// core's f64 function at x.
    pub fn f64(self, x: f64) -> f64 {
        match self {
            Self::Erf => special::erf(x),
            Self::Erfc => special::erfc(x),
            Self::Erfcx => special::erfcx(x),
            Self::NormCdf => special::norm_cdf(x),
            Self::LogNormCdf => special::log_norm_cdf(x),
            Self::SmithLambda => special::smith_lambda(x),
        }
    }

    /// core's f32 mirror at x.
    pub fn f32(self, x: f32) -> f32 {
        match self {
            Self::Erf => special_f32::erf(x),
            Self::Erfc => special_f32::erfc(x),
            Self::Erfcx => special_f32::erfcx(x),
            Self::NormCdf => special_f32::norm_cdf(x),
            Self::LogNormCdf => special_f32::log_norm_cdf(x),
            Self::SmithLambda => special_f32::smith_lambda(x),
        }
    }
}

/// erfcx(x) for x ≥ 0 by quadrature of `(2/√π)∫₀^∞ e^{−t² − 2xt} dt` (well conditioned for every x:
/// the integrand is in [0, 1] and decays over t ≈ min(1, 1/x)).
fn erfcx_quadrature(x: f64) -> f64 {
    let t_max = if x > 1.0 { 40.0 / x } else { 12.0 };
    let f = |t: f64| (-t * t - 2.0 * x * t).exp();
    2.0 / PI.sqrt()
        * (integrate(f, 0.0, t_max * 0.05, 200) + integrate(f, t_max * 0.05, t_max, 400))
}

/// An independent reference for `function` at x (quadrature and exact identities, f64).
pub fn special_reference(function: SpecialFunction, x: f64) -> f64 {
    let erfc_ref = |x: f64| {
        if x >= 0.0 {
            (-x * x).exp() * erfcx_quadrature(x)
        } else {
            2.0 - (-x * x).exp() * erfcx_quadrature(-x)
        }
    };
    match function {
        SpecialFunction::Erfc => erfc_ref(x),
        SpecialFunction::Erf => {
            if x.abs() < 0.5 {
                2.0 / PI.sqrt() * integrate(|t| (-t * t).exp(), 0.0, x, 8)
            } else {
                x.signum() * (1.0 - erfc_ref(x.abs()))
            }
        }
        SpecialFunction::Erfcx => {
            if x >= 0.0 {
                erfcx_quadrature(x)
            } else {
                2.0 * (x * x).exp() - erfcx_quadrature(-x)
            }
        }
        SpecialFunction::NormCdf => 0.5 * erfc_ref(-x / 2f64.sqrt()),
        SpecialFunction::LogNormCdf => {
            let y = -x / 2f64.sqrt();
            if y > 0.0 {
                0.5f64.ln() + erfcx_quadrature(y).ln() - y * y
            } else {
                (-0.5 * erfc_ref(-y)).ln_1p()
            }
        }
        SpecialFunction::SmithLambda => {
            // Λ = (1/a)·φ(a)·∫₀^∞ t e^{−at − t²/2} dt with a = √2·ν (ν clamped like core's).
            let nu = x.max(special::NU_MIN);
            let a = 2f64.sqrt() * nu;
            let t_max = if a > 1.0 { 60.0 / a } else { 40.0 };
            let i = integrate(|t| t * (-a * t - 0.5 * t * t).exp(), 0.0, t_max, 2000);
            (-0.5 * a * a).exp() / (2.0 * PI).sqrt() * i / a
        }
    }
}

/// The relative condition number `|x·f′(x)/f(x)|` of `function` at x, from core's f64 function by a
/// central difference (0 where f is 0 or not finite, as past an underflow). A float evaluation of f
/// carries a relative error of about ε·(1 + κ): e^{−x²} with x² rounded is off by 2x²·ε, and κ of
/// erfc at large x is 2x²; where f saturates (erf → ±1, erfcx → 1/(x√π)) κ is at most 1 and the
/// allowance does not grow with x.
pub fn condition(function: SpecialFunction, x: f64) -> f64 {
    let f = function.f64(x);
    if x == 0.0 || f == 0.0 || !f.is_finite() {
        return 0.0;
    }
    let d = 1e-6;
    let (hi, lo) = (function.f64(x * (1.0 + d)), function.f64(x * (1.0 - d)));
    let k = ((hi - lo) / (2.0 * d * f)).abs();
    if k.is_finite() { k } else { 0.0 }
}

/// The deviation of an f32 (or WGSL) value `got` of `function` at the f32 argument `x32`, scaled by
/// the function's conditioning: `deviation(got, ref(x32), 1e-30) / (1 + κ(x32))`, with the
/// reference at the rounded argument and clamped to f32's range (values beyond it saturate at
/// ±f32::MAX: erfcx below −9.4).
pub fn f32_deviation(function: SpecialFunction, x32: f32, got: f64) -> f64 {
    let x = f64::from(x32);
    let r = special_reference(function, x).clamp(-f64::from(f32::MAX), f64::from(f32::MAX));
    deviation(got, r, 1e-30) / (1.0 + condition(function, x))
}

/// Rows for the special functions: f64 against the references (bound 1e-9 relative, floor 1e-300),
/// f32 against the references at the rounded argument (bound 2e-6 relative per unit of
/// conditioning, [`f32_deviation`]).
pub fn special_rows() -> Vec<Row> {
    let mut rows = Vec::new();
    for function in SpecialFunction::ALL {
        let name = function.name();
        let xs = function.inputs();
        let refs: Vec<f64> = xs.iter().map(|x| special_reference(function, *x)).collect();
        let (mut d64, mut d32, mut bad64, mut bad32) = (0.0f64, 0.0f64, 0, 0);
        for (x, r) in xs.iter().zip(&refs) {
            let g = function.f64(*x);
            if !g.is_finite() {
                bad64 += 1;
            }
            d64 = d64.max(deviation(g, *r, 1e-300));
            let g32 = f64::from(function.f32(*x as f32));
            if !g32.is_finite() {
                bad32 += 1;
            }
            d32 = d32.max(f32_deviation(function, *x as f32, g32));
        }
        rows.push(Row {
            case: format!("{name} at {} extreme arguments", xs.len()),
            path: Path::CoreF64,
            outputs: xs.len(),
            max_deviation: d64,
            bound: 1e-9,
            non_finite: bad64,
            reference: "quadrature of the defining integrals (relative)".into(),
        });
        rows.push(Row {
            case: format!("{name} at {} extreme arguments", xs.len()),
            path: Path::CoreF32,
            outputs: xs.len(),
            max_deviation: d32,
            bound: 2e-6,
            non_finite: bad32,
            reference: "quadrature at the f32 argument (relative / (1 + condition number))".into(),
        });
    }
    rows
}

/// Smith's Λ for the direction (θ, φ) over slopes with independent Gaussian components of std
/// (σx, σy), by definition: `(1/μ)·E[max(0, s − μ)]`, μ = cot θ, s = σx·u·cos φ + σy·v·sin φ
/// with u, v ~ N(0, 1), integrated over u and v (the inner integral split at the kink), without the
/// projected-σ identity the code uses.
pub fn smith_lambda_quadrature(theta: f64, phi: f64, sx: f64, sy: f64) -> f64 {
    let mu = theta.cos() / theta.sin();
    let (a, b) = (sx * phi.cos(), sy * phi.sin());
    if mu <= 0.0 || (a == 0.0 && b == 0.0) {
        return 0.0;
    }
    // Inner: E_v[max(0, a·u + b·v − μ)], integrand in v from the kink (or −12) to 12.
    let inner = |u: f64| {
        let c = a * u - mu;
        if b == 0.0 {
            return c.max(0.0);
        }
        let kink = -c / b;
        let f = |v: f64| (c + b * v).max(0.0) * special::norm_pdf(v);
        let (lo, hi) = if b > 0.0 {
            (kink.max(-12.0), 12.0)
        } else {
            (-12.0, kink.min(12.0))
        };
        if lo >= hi {
            0.0
        } else {
            integrate(f, lo, hi, 400)
        }
    };
    // Outer over u, split where the kink leaves [−12, 12] for fewer wasted nodes.
    integrate(|u| inner(u) * special::norm_pdf(u), -12.0, 12.0, 1200) / mu
}

/// Rows for the lookup tables: D_h moments for L up to 1e12 and beyond against exact quadrature,
/// the colour table at and beyond σ_max against the exact convolution (clamped at σ_max), transfer
/// moments with vertical segments against quadrature, and the attribute's mean shape at huge L.
pub fn table_rows() -> Vec<Row> {
    let mut rows = Vec::new();
    // D_h: table against exact moments.
    let t = EffectiveHeightTable::shared();
    let ls = [
        0.0,
        1e-12,
        1e-7,
        1e-3,
        0.5,
        1.0,
        7.0,
        1e3,
        1e6,
        1e9,
        1e12,
        1e13,
        1e30,
        f64::MAX,
    ];
    let (mut dev, mut bad) = (0.0f64, 0);
    for l in ls {
        let got = t.lookup(l);
        let want = exact_moments(l.min(1e12));
        if !(got.mean.is_finite() && got.std.is_finite() && got.std >= 0.0) {
            bad += 1;
        }
        dev = dev
            .max((got.mean - want.mean).abs())
            .max((got.std - want.std).abs());
    }
    rows.push(Row {
        case: format!(
            "D_h moments, L from 0 to 1e12 and beyond ({} values)",
            ls.len()
        ),
        path: Path::CoreF64,
        outputs: 2 * ls.len(),
        max_deviation: dev,
        bound: 1e-4,
        non_finite: bad,
        reference: "exact quadrature, L clamped at the table's 1e12 (absolute, σ_h units)".into(),
    });
    let (mut dev, mut bad) = (0.0f64, 0);
    for l in ls {
        let s = lodestone_core::microfacet::attribute::mean_attribute_shape(l);
        if !s.is_finite() {
            bad += 1;
        }
        dev = dev.max((s - (1.0 - 2.0 / (l + 2.0))).abs());
    }
    rows.push(Row {
        case: "attribute mean shape 1 − 2/(L+2), L up to f64::MAX".into(),
        path: Path::CoreF64,
        outputs: ls.len(),
        max_deviation: dev,
        bound: 1e-15,
        non_finite: bad,
        reference: "the closed form [HN12 Eq. 17] (absolute)".into(),
    });
    // Colour table at and beyond σ_max, with a step map.
    let map = step_map();
    let spec = TableSpec::default();
    let table = map.preconvolve(spec);
    let (mut dev, mut bad, mut n) = (0.0f64, 0, 0);
    // Within a few texels of a step at σ ≈ 0 the bilinear table blends both sides (resolution, not
    // stability): those points are checked for finiteness only.
    let texel_m = (table.m_max - table.m_min) / (table.size_m - 1) as f64;
    let texel_s = table.sigma_max / (table.size_sigma - 1) as f64;
    for sigma in [0.0, 1e-9, 0.5, 1.0, 1.0 + 1e-9, 2.0, 1e6, f64::INFINITY] {
        for i in 0..41 {
            let m = -10.0 + 0.5 * i as f64 + 0.01;
            let got = table.sample(m, sigma);
            let blurred = sigma < 3.0 * texel_s
                && map
                    .stops
                    .iter()
                    .any(|s| (s.position - m).abs() < 3.0 * texel_m);
            let want = map.convolved(m, sigma.min(spec.sigma_max));
            for k in 0..3 {
                n += 1;
                if !got[k].is_finite() {
                    bad += 1;
                }
                if !blurred {
                    dev = dev.max((got[k] - want[k]).abs());
                }
            }
        }
    }
    rows.push(Row {
        case: "colour table (step map) at and beyond σ_max".into(),
        path: Path::CoreF64,
        outputs: n,
        max_deviation: dev,
        bound: 0.02,
        non_finite: bad,
        reference:
            "exact convolution at min(σ, σ_max) (absolute; bilinear interpolation of a 256² table)"
                .into(),
    });
    // Transfer moments with vertical segments.
    let g = TransferFunction::Curve(vertical_curve());
    let (mut dev, mut bad, mut n) = (0.0f64, 0, 0);
    for sigma in [0.0, 1e-9, 0.1, 1.0, 10.0] {
        for m in [-0.5, -0.3, 0.0, 0.5, 3.0] {
            let got = g.moments(m, sigma);
            let want_mean = if sigma == 0.0 || sigma == 1e-9 {
                g.eval(m)
            } else {
                integrate(
                    |z| g.eval(m + sigma * z) * special::norm_pdf(z),
                    -12.0,
                    12.0,
                    4800,
                )
            };
            n += 1;
            if !(got.mean.is_finite() && got.std.is_finite() && got.std >= 0.0) {
                bad += 1;
            }
            // At a riser with σ = 0 the value is either side's: compare only off the risers there.
            if sigma > 1e-6 || (m.abs() - 0.5).abs() > 1e-9 {
                dev = dev.max((got.mean - want_mean).abs());
            }
        }
    }
    rows.push(Row {
        case: "transfer moments, vertical segments".into(),
        path: Path::CoreF64,
        outputs: n,
        max_deviation: dev,
        bound: 1e-4,
        non_finite: bad,
        reference: "quadrature of g over N(m, σ²) (absolute)".into(),
    });
    // Smith Λ from directions at the listed angles and σ's, against 2-D quadrature over the
    // anisotropic slope distribution.
    let (mut bad, mut n, mut dev) = (0, 0, 0.0f64);
    for theta in angles() {
        for s in [0.0, 1e-9, 0.35, 1e6] {
            for r in [1e-6f64, 1.0, 1e6] {
                let (sx, sy) = (s * r.sqrt(), s / r.sqrt());
                let sl = lodestone_core::microfacet::slopes::SlopeCov::from_std(sx, sy);
                let l = lodestone_core::microfacet::smith::lambda(direction(theta, 0.7), &sl);
                n += 1;
                if !(l.is_finite() && l >= 0.0) {
                    bad += 1;
                }
                // At and below the horizon Λ is a convention (clamped): finite and ≥ 0 only.
                if theta < FRAC_PI_2 - 1e-9 {
                    // Floor 1e-12: below it Λ changes G = 1/(1 + Λ) by less than an f64 ulp.
                    dev = dev.max(deviation(
                        l,
                        smith_lambda_quadrature(theta, 0.7, sx, sy),
                        1e-12,
                    ));
                }
            }
        }
    }
    rows.push(Row {
        case: "Smith Λ(ω) at every angle, σ_n 0…1e6, anisotropy 1e-6…1e6".into(),
        path: Path::CoreF64,
        outputs: n,
        max_deviation: dev,
        bound: 1e-6,
        non_finite: bad,
        reference:
            "2-D quadrature of (1/μ)·E[max(0, slope along ω − μ)] over the slope Gaussian (relative, \
             floor 1e-12; finite and ≥ 0 only at and below the horizon)"
                .into(),
    });
    rows
}

/// Every CPU row.
pub fn cpu_rows() -> Vec<Row> {
    let mut rows = special_rows();
    rows.extend(table_rows());
    rows.extend(crate::cli::stability::materials::material_rows());
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_cpu_case_is_finite_and_within_its_bound() {
        let rows = cpu_rows();
        assert!(rows.len() > 20);
        for r in &rows {
            eprintln!(
                "{:<60} {:<9} {:>6} {:>11.3e} {:>9.1e} {:>4}",
                r.case,
                r.path.name(),
                r.outputs,
                r.max_deviation,
                r.bound,
                r.non_finite
            );
        }
        let failed: Vec<_> = rows.iter().filter(|r| !r.passed()).collect();
        assert!(failed.is_empty(), "{failed:#?}");
    }

    #[test]
    fn the_references_are_independent_and_accurate() {
        // Spot values (mpmath at 30 digits).
        assert!(
            (special_reference(SpecialFunction::Erf, 0.3) - 0.328_626_759_459_127_4).abs() < 1e-15
        );
        assert!(
            (special_reference(SpecialFunction::Erfc, 5.0) / 1.537_459_794_428_035e-12 - 1.0).abs()
                < 1e-12
        );
        assert!(
            (special_reference(SpecialFunction::Erfcx, 1e6) / 5.641_895_835_474_742e-7 - 1.0).abs()
                < 1e-10
        );
        assert!(
            (special_reference(SpecialFunction::LogNormCdf, -40.0) / -804.608_442_013_753_8 - 1.0)
                .abs()
                < 1e-12
        );
        // A bug in a function shows as a deviation: a 1e-6 relative error fails the f64 bound.
        let r = special_reference(SpecialFunction::Erf, 0.3);
        assert!(deviation(r * (1.0 + 1e-6), r, 1e-300) > 1e-9);
        // The f32 allowance follows the conditioning, not the argument: a 200% error at x = 1000
        // (where erf is flat) fails, as does 1% on erfc at 5 (κ ≈ 50) and on Λ at 3.5.
        assert!(f32_deviation(SpecialFunction::Erf, 1000.0, 3.0) > 2e-6);
        assert!(f32_deviation(SpecialFunction::Erf, -1e6, 1.0) > 2e-6);
        let e5 = special_reference(SpecialFunction::Erfc, 5.0);
        assert!(f32_deviation(SpecialFunction::Erfc, 5.0, e5 * 1.01) > 2e-6);
        let l = special_reference(SpecialFunction::SmithLambda, 3.5);
        assert!(f32_deviation(SpecialFunction::SmithLambda, 3.5, l * 1.01) > 2e-6);
        // And κ itself: erfc's is 2x² in the tail, erf's vanishes there.
        assert!((condition(SpecialFunction::Erfc, 5.0) / 50.0 - 1.0).abs() < 0.05);
        assert!(condition(SpecialFunction::Erf, 10.0) < 1e-30);
    }
}
