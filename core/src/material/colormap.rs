//! Colour maps: gradients of linear-RGB stops, their sampling, and their pre-convolved table
//! `T[m, σ] = (C ∗ N(0, σ²))(m)` [HNPN14 Eq. 9, Sec. 4.2].
//!
//! A gradient maps a scalar (the driver value f, or a standardized height) to linear RGB. Outside its
//! first and last stop it is constant (the end colours). Interpolation between stops is
//! [`Interpolation::Linear`], [`Interpolation::Smooth`] (smoothstep, C¹ at the stops) or
//! [`Interpolation::Constant`] (each stop's colour holds until the next stop: a step map).

use crate::material::validation::Problems;
use crate::math::piecewise::{NCOEF, PiecewisePoly};
use crate::math::preconvolved::{MARGIN_SIGMAS, PreconvolvedTable, TableSpec};
use serde::{Deserialize, Serialize};

/// Rec. 709 luminance weights of linear RGB: `Y = Σ LUMINANCE[c]·rgb[c]` (the error maps' and
/// the truth's noise estimates; `view.wgsl` accumulates `Y²` with the same weights).
pub const LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// How colours are interpolated between stops.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum Interpolation {
    /// Piecewise linear.
    #[default]
    Linear,
    /// Smoothstep `3t² − 2t³` between stops (zero slope at each stop).
    Smooth,
    /// Piecewise constant: a stop's colour holds until the next stop.
    Constant,
}

/// One gradient stop.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColorStop {
    /// Position along the mapped scalar.
    pub position: f64,
    /// Linear RGB (not sRGB); components usually in [0, 1].
    pub color: [f64; 3],
}

/// A colour gradient.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gradient {
    /// Stops sorted by position (equal positions make a hard edge).
    pub stops: Vec<ColorStop>,
    /// Interpolation between stops.
    #[serde(default)]
    pub interpolation: Interpolation,
}

/// sRGB transfer → linear (IEC 61966-2-1).
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear → sRGB transfer (IEC 61966-2-1); input clamped to [0, 1].
pub fn linear_to_srgb(c: f64) -> f64 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

impl Gradient {
    /// A gradient from sRGB bytes at evenly spaced positions over `[lo, hi]`.
    pub fn from_srgb8(colors: &[[u8; 3]], lo: f64, hi: f64, interpolation: Interpolation) -> Self {
        let n = colors.len().max(2) - 1;
        let stops = colors
            .iter()
            .enumerate()
            .map(|(i, c)| ColorStop {
                position: lo + (hi - lo) * i as f64 / n as f64,
                color: c.map(|v| srgb_to_linear(f64::from(v) / 255.0)),
            })
            .collect();
        Self {
            stops,
            interpolation,
        }
    }

    /// Two-stop linear gradient.
    pub fn two(lo: f64, c0: [f64; 3], hi: f64, c1: [f64; 3]) -> Self {
        Self {
            stops: vec![
                ColorStop {
                    position: lo,
                    color: c0,
                },
                ColorStop {
                    position: hi,
                    color: c1,
                },
            ],
            interpolation: Interpolation::Linear,
        }
    }

    /// Viridis (matplotlib), 10 stops over [lo, hi].
    pub fn viridis(lo: f64, hi: f64) -> Self {
        Self::from_srgb8(
            &[
                [0x44, 0x01, 0x54],
                [0x48, 0x28, 0x78],
                [0x3e, 0x49, 0x89],
                [0x31, 0x68, 0x8e],
                [0x26, 0x82, 0x8e],
                [0x1f, 0x9e, 0x89],
                [0x35, 0xb7, 0x79],
                [0x6e, 0xce, 0x58],
                [0xb5, 0xde, 0x2b],
                [0xfd, 0xe7, 0x25],
            ],
            lo,
            hi,
            Interpolation::Linear,
        )
    }

    /// A terrain map: deep water, shore, grass, rock, snow, over [lo, hi].
    pub fn terrain(lo: f64, hi: f64) -> Self {
        Self::from_srgb8(
            &[
                [0x1d, 0x3c, 0x6e],
                [0x3f, 0x86, 0xc2],
                [0xd9, 0xc8, 0x8c],
                [0x4f, 0x8a, 0x3b],
                [0x7a, 0x6a, 0x55],
                [0xf4, 0xf4, 0xf6],
            ],
            lo,
            hi,
            Interpolation::Smooth,
        )
    }

    /// Rust in the crevices: dark orange-brown low, bare grey metal high, over [lo, hi].
    pub fn rust(lo: f64, hi: f64) -> Self {
        Self::from_srgb8(
            &[
                [0x5a, 0x22, 0x0b],
                [0xa3, 0x4a, 0x17],
                [0x8c, 0x80, 0x76],
                [0xb4, 0xb6, 0xb8],
            ],
            lo,
            hi,
            Interpolation::Smooth,
        )
    }

    /// Colour at x (constant beyond the end stops). An empty gradient is black.
    pub fn sample(&self, x: f64) -> [f64; 3] {
        if self.stops.is_empty() {
            return [0.0; 3];
        }
        let p = self.to_piecewise();
        let mut out = [0.0; 3];
        p.eval(x, &mut out);
        out
    }

    /// The gradient as a 3-channel piecewise polynomial (degree ≤ 3) on its stop positions.
    pub fn to_piecewise(&self) -> PiecewisePoly {
        let n = self.stops.len();
        let mut coeffs = Vec::with_capacity(3 * n.saturating_sub(1));
        for w in self.stops.windows(2) {
            for ch in 0..3 {
                let (c0, c1) = (w[0].color[ch], w[1].color[ch]);
                let d = c1 - c0;
                let mut c = [0.0; NCOEF];
                c[0] = c0;
                match self.interpolation {
                    Interpolation::Linear => c[1] = d,
                    Interpolation::Smooth => {
                        c[2] = 3.0 * d;
                        c[3] = -2.0 * d;
                    }
                    Interpolation::Constant => {}
                }
                coeffs.push(c);
            }
        }
        let first = self.stops.first().map_or([0.0; 3], |s| s.color);
        let last = self.stops.last().map_or([0.0; 3], |s| s.color);
        PiecewisePoly {
            knots: self.stops.iter().map(|s| s.position).collect(),
            channels: 3,
            coeffs,
            left: first.to_vec(),
            right: last.to_vec(),
        }
    }

    /// The mean colour `⟨C, N(m, σ²)⟩ = (C ∗ N(0, σ²))(m)` [HNPN14 Eq. 9], exactly.
    pub fn convolved(&self, m: f64, sigma: f64) -> [f64; 3] {
        let mut out = [0.0; 3];
        self.to_piecewise().gaussian_expectation(m, sigma, &mut out);
        out
    }

    /// The pre-convolved table [HNPN14 Sec. 4.2] over the stops' range widened by 4σ_max
    /// (see [`crate::math::preconvolved`] for layout and border behaviour). Channel 3 holds 1.
    pub fn preconvolve(&self, spec: TableSpec) -> PreconvolvedTable {
        let spec = spec.sanitized();
        let (lo, hi) = self.range();
        let margin = MARGIN_SIGMAS * spec.sigma_max;
        let poly = self.to_piecewise();
        PreconvolvedTable::build(&poly, spec, (lo - margin, hi + margin), |e| {
            [e[0] as f32, e[1] as f32, e[2] as f32, 1.0]
        })
    }

    /// First and last stop positions ((0, 0) when empty).
    pub fn range(&self) -> (f64, f64) {
        match (self.stops.first(), self.stops.last()) {
            (Some(a), Some(b)) => (a.position, b.position),
            _ => (0.0, 0.0),
        }
    }

    /// Reverse the gradient (positions mirrored within its range).
    pub fn flipped(&self) -> Self {
        let (lo, hi) = self.range();
        let stops = self
            .stops
            .iter()
            .rev()
            .map(|s| ColorStop {
                position: lo + hi - s.position,
                color: s.color,
            })
            .collect();
        Self {
            stops,
            interpolation: self.interpolation,
        }
    }

    /// Spread the stops evenly over the current range, keeping their order and colours.
    pub fn distributed(&self) -> Self {
        let (lo, hi) = self.range();
        let n = self.stops.len().max(2) - 1;
        let stops = self
            .stops
            .iter()
            .enumerate()
            .map(|(i, s)| ColorStop {
                position: lo + (hi - lo) * i as f64 / n as f64,
                color: s.color,
            })
            .collect();
        Self {
            stops,
            interpolation: self.interpolation,
        }
    }

    /// Largest stop position magnitude accepted (the driver has unit variance).
    pub const MAX_POSITION: f64 = 1e6;
    /// Largest linear colour component accepted (HDR headroom; reflectances are ≤ 1).
    pub const MAX_COLOR: f64 = 1e3;

    /// Most stops a gradient may have: each costs the pre-convolved table a Gaussian integral per
    /// texel (#16: 8 000 stops took `eval` 61 s, 600 000 never finished).
    pub const MAX_STOPS: usize = 256;

    /// Record every problem: no stops or more than [`Self::MAX_STOPS`], positions beyond ±[`Self::MAX_POSITION`], non-finite,
    /// negative or above [`Self::MAX_COLOR`] colour components, unsorted positions.
    pub fn validate(&self, field: &str, problems: &mut Problems) {
        if self.stops.is_empty() {
            problems.push(
                format!("{field}.stops"),
                "a gradient needs at least one stop",
            );
        }
        if self.stops.len() > Self::MAX_STOPS {
            problems.push(
                format!("{field}.stops"),
                format!(
                    "a gradient has at most {} stops, got {}",
                    Self::MAX_STOPS,
                    self.stops.len()
                ),
            );
            return;
        }
        for (i, s) in self.stops.iter().enumerate() {
            problems.in_range(
                &format!("{field}.stops[{i}].position"),
                s.position,
                -Self::MAX_POSITION,
                Self::MAX_POSITION,
            );
            for (c, v) in s.color.iter().enumerate() {
                let f = format!("{field}.stops[{i}].color[{c}]");
                if !v.is_finite() {
                    problems.push(f, format!("must be a finite number, got {v}"));
                } else if *v < 0.0 {
                    problems.push(f, format!("colour components cannot be negative, got {v}"));
                } else if *v > Self::MAX_COLOR {
                    problems.push(
                        f,
                        format!("colour components are at most {}, got {v}", Self::MAX_COLOR),
                    );
                }
            }
        }
        for (i, w) in self.stops.windows(2).enumerate() {
            if w[1].position < w[0].position {
                problems.push(
                    format!("{field}.stops[{}].position", i + 1),
                    format!(
                        "stops must be sorted by position: {} comes after {}",
                        w[1].position, w[0].position
                    ),
                );
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::math::special::norm_cdf;

    /// A small deterministic generator for Monte Carlo tests (SplitMix64 + Box–Muller).
    pub(crate) struct Rng(pub u64);
    impl Rng {
        pub fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        pub fn uniform(&mut self) -> f64 {
            (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
        }
        pub fn normal(&mut self) -> f64 {
            let u1 = self.uniform().max(1e-300);
            let u2 = self.uniform();
            (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
        }
    }

    #[test]
    fn step_map_is_a_normal_cdf() {
        let g = Gradient {
            stops: vec![
                ColorStop {
                    position: -0.5,
                    color: [0.2, 0.0, 1.0],
                },
                ColorStop {
                    position: 0.4,
                    color: [0.9, 0.5, 0.0],
                },
            ],
            interpolation: Interpolation::Constant,
        };
        for &(m, s) in &[(0.0, 0.3), (0.4, 0.01), (1.2, 0.5), (-2.0, 1.0)] {
            let got = g.convolved(m, s);
            let w = norm_cdf((m - 0.4) / s);
            for ch in 0..3 {
                let want = g.stops[0].color[ch] * (1.0 - w) + g.stops[1].color[ch] * w;
                assert!((got[ch] - want).abs() < 1e-14, "m={m} σ={s}");
            }
        }
    }

    #[test]
    fn linear_map_is_unchanged_inside_its_range() {
        // A linear ramp convolved with a Gaussian that stays inside it is the ramp itself.
        let g = Gradient::two(-10.0, [0.0, 1.0, 0.5], 10.0, [1.0, 0.0, 0.5]);
        let got = g.convolved(0.7, 0.8);
        let want = g.sample(0.7);
        for ch in 0..3 {
            assert!((got[ch] - want[ch]).abs() < 1e-12);
        }
    }

    #[test]
    fn table_matches_monte_carlo() {
        let g = Gradient::terrain(-2.0, 2.0);
        let t = g.preconvolve(TableSpec::default());
        let mut rng = Rng(7);
        for &(m, s) in &[(0.0, 1.0), (-1.3, 0.25), (0.8, 0.6)] {
            let n = 200_000;
            let mut acc = [0.0; 3];
            let mut acc2 = [0.0; 3];
            for _ in 0..n {
                let c = g.sample(m + s * rng.normal());
                for ch in 0..3 {
                    acc[ch] += c[ch];
                    acc2[ch] += c[ch] * c[ch];
                }
            }
            let got = t.sample(m, s);
            for ch in 0..3 {
                let mean = acc[ch] / n as f64;
                let se = ((acc2[ch] / n as f64 - mean * mean) / n as f64).sqrt();
                assert!(
                    (got[ch] - mean).abs() < 4.0 * se + 5e-4,
                    "m={m} σ={s} ch={ch}: {} vs {mean} ± {se}",
                    got[ch]
                );
            }
        }
    }

    #[test]
    fn table_interpolation_error_is_small() {
        // Bilinear interpolation between exact texels: measure against the exact convolution.
        let g = Gradient::viridis(-2.0, 2.0);
        let spec = TableSpec::default();
        let t = g.preconvolve(spec);
        // Worst error per σ band: near σ = 0 the table is as sharp as the map's kinks allow.
        let bands = [(0.0, 0.05, 1e-2), (0.05, 0.2, 2e-3), (0.2, 1.0, 5e-4)];
        for (lo, hi, bound) in bands {
            let mut worst: f64 = 0.0;
            for i in 0..157 {
                for j in 0..23 {
                    let m = -3.5 + 7.0 * (i as f64 + 0.31) / 157.0;
                    let s = lo + (hi - lo) * (j as f64 + 0.47) / 23.0;
                    let e = g.convolved(m, s);
                    let got = t.sample(m, s);
                    for ch in 0..3 {
                        worst = worst.max((got[ch] - e[ch]).abs());
                    }
                }
            }
            assert!(
                worst < bound,
                "σ ∈ [{lo}, {hi}]: bilinear interpolation error {worst}"
            );
            eprintln!("viridis 256×256 table, σ ∈ [{lo}, {hi}]: worst bilinear error {worst:.2e}");
        }
        let _ = spec;
    }

    #[test]
    fn validation_reports_every_problem() {
        let g = Gradient {
            stops: vec![
                ColorStop {
                    position: 0.5,
                    color: [f64::NAN, 0.0, -1.0],
                },
                ColorStop {
                    position: 0.1,
                    color: [0.0; 3],
                },
                ColorStop {
                    position: f64::INFINITY,
                    color: [0.0; 3],
                },
            ],
            interpolation: Interpolation::Linear,
        };
        let mut p = Problems::default();
        g.validate("color", &mut p);
        let fields: Vec<_> = p.0.iter().map(|p| p.field.as_str()).collect();
        assert!(fields.contains(&"color.stops[0].color[0]"));
        assert!(fields.contains(&"color.stops[0].color[2]"));
        assert!(fields.contains(&"color.stops[1].position"));
        assert!(fields.contains(&"color.stops[2].position"));
        let mut p = Problems::default();
        Gradient {
            stops: vec![],
            interpolation: Interpolation::Smooth,
        }
        .validate("c", &mut p);
        assert_eq!(p.0.len(), 1);
    }

    #[test]
    fn flip_and_distribute() {
        let g = Gradient::viridis(-1.0, 3.0);
        let f = g.flipped().flipped();
        for (a, b) in f.stops.iter().zip(&g.stops) {
            assert!((a.position - b.position).abs() < 1e-12 && a.color == b.color);
        }
        assert_eq!(g.flipped().sample(-1.0), g.sample(3.0));
        let d = Gradient::two(0.0, [0.0; 3], 4.0, [1.0; 3]).distributed();
        assert_eq!(d.range(), (0.0, 4.0));
    }
}
