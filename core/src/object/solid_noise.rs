//! The material's noise extended to space, for the relief of a whole object (#19):
//! `f(p) = Σ a_i cos(2π k_i·p + φ_i)` with the plane noise's amplitudes and phases
//! ([`crate::driver::noise::SumOfSines`]) and wave vectors of the same lengths, scaled by √(3/2),
//! pointing in directions spread over the sphere.
//!
//! Why this form: an object has no global parametrisation (a sphere's poles, a mesh without UVs),
//! but a function of space restricted to any surface is smooth and seamless. On a surface with
//! unit normal m, the tangential gradient is `P∇f`, `P = I − m mᵀ`, and a wave of length |k|
//! contributes `|Pk|²`, whose mean over directions is `⅔|k|²`; the √(3/2) makes the mean tangential
//! gradient covariance's trace the plane noise's, so the relief's slope variance σ_n² is the
//! material's on average (isotropically: an anisotropic material's σ_nx ≠ σ_ny has no direction to
//! follow on an object, and its trace is what is kept). Heights keep unit variance (`Σ a_i²/2 = 1`).
//! The waves of each octave get their own set of directions (a Fibonacci lattice on the
//! hemisphere, turned by a rotation drawn from the seed), so no octave leans toward an axis.

use crate::driver::noise::SumOfSines;
use crate::math::random::standard_normal;
use glam::{DQuat, DVec3};
use std::f64::consts::TAU;

/// One sinusoid `a cos(2π k·p + φ)` in space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolidWave {
    /// Wave vector, cycles per unit length.
    pub k: DVec3,
    /// Amplitude.
    pub amplitude: f64,
    /// Phase, radians.
    pub phase: f64,
}

/// The noise of space (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct SolidNoise {
    /// The waves, coarse octave first (as the plane noise's).
    pub waves: Vec<SolidWave>,
}

impl SolidNoise {
    /// The plane noise `plane` extended to space (module docs); `seed` turns each octave's
    /// directions.
    pub fn from_plane(plane: &SumOfSines, seed: u64) -> Self {
        let n = plane.waves.len();
        let octaves = plane.octaves.max(1);
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let mut rng = seed ^ 0x005E_ED0B_1EC7_u64;
        let mut waves = Vec::with_capacity(n);
        let mut start = 0;
        for o in 0..octaves {
            // Waves i with i·octaves/n == o, as SumOfSines lays them out.
            let end = (start..n).find(|&i| i * octaves / n > o).unwrap_or(n);
            let m = end - start;
            let turn = random_rotation(&mut rng);
            for (j, w) in plane.waves[start..end].iter().enumerate() {
                let z = (j as f64 + 0.5) / m as f64;
                let s = (1.0 - z * z).max(0.0).sqrt();
                let phi = golden * j as f64;
                let dir = turn * DVec3::new(s * phi.cos(), s * phi.sin(), z);
                waves.push(SolidWave {
                    k: dir * (w.k.length() * 1.5f64.sqrt()),
                    amplitude: w.amplitude,
                    phase: w.phase,
                });
            }
            start = end;
        }
        Self { waves }
    }

    /// f(p).
    pub fn value(&self, p: DVec3) -> f64 {
        self.waves
            .iter()
            .map(|w| w.amplitude * (TAU * w.k.dot(p) + w.phase).cos())
            .sum()
    }

    /// f(p) and ∇f(p).
    pub fn value_and_gradient(&self, p: DVec3) -> (f64, DVec3) {
        let (mut f, mut g) = (0.0, DVec3::ZERO);
        for w in &self.waves {
            let (s, c) = (TAU * w.k.dot(p) + w.phase).sin_cos();
            f += w.amplitude * c;
            g -= w.k * (w.amplitude * TAU * s);
        }
        (f, g)
    }

    /// A bound of |∇f| everywhere: `Σ |a_i| 2π |k_i|`.
    pub fn gradient_bound(&self) -> f64 {
        self.waves
            .iter()
            .map(|w| w.amplitude.abs() * TAU * w.k.length())
            .sum()
    }

    /// A bound of |f|: `Σ |a_i|`.
    pub fn amplitude_bound(&self) -> f64 {
        self.waves.iter().map(|w| w.amplitude.abs()).sum()
    }

    /// The shortest wavelength (1/max|k|; infinite without waves).
    pub fn finest_wavelength(&self) -> f64 {
        1.0 / self.waves.iter().map(|w| w.k.length()).fold(0.0, f64::max)
    }

    /// The gradient covariance `Σ a_i²/2 (2π)² k_i k_iᵀ` (its tangential part on a surface of
    /// normal m is `P Σ P`).
    pub fn gradient_cov(&self) -> glam::DMat3 {
        let mut c = glam::DMat3::ZERO;
        for w in &self.waves {
            let s = 0.5 * w.amplitude * w.amplitude * TAU * TAU;
            c += glam::DMat3::from_cols(w.k * (s * w.k.x), w.k * (s * w.k.y), w.k * (s * w.k.z));
        }
        c
    }
}

/// A rotation drawn uniformly (a normalised 4-D Gaussian quaternion).
fn random_rotation(rng: &mut u64) -> DQuat {
    let mut q = [0.0; 4];
    for x in &mut q {
        *x = standard_normal(rng);
    }
    let len = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    if len > 1e-12 {
        DQuat::from_xyzw(q[0] / len, q[1] / len, q[2] / len, q[3] / len)
    } else {
        DQuat::IDENTITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::math::random::splitmix;

    fn noise() -> (SumOfSines, SolidNoise) {
        let plane = Material::default().noise().unwrap();
        let solid = SolidNoise::from_plane(&plane, 1);
        (plane, solid)
    }

    #[test]
    fn gradient_is_the_derivative_and_within_its_bound() {
        let (_, s) = noise();
        let mut rng = 3u64;
        let bound = s.gradient_bound();
        for _ in 0..300 {
            let p = DVec3::new(splitmix(&mut rng), splitmix(&mut rng), splitmix(&mut rng)) * 7.0;
            let (f, g) = s.value_and_gradient(p);
            assert!((f - s.value(p)).abs() < 1e-12);
            let e = 1e-6;
            let fd = crate::object::central_gradient(|q| s.value(q), p, e);
            assert!((g - fd).length() < 1e-5 * (1.0 + g.length()), "{g} {fd}");
            assert!(g.length() <= bound && f.abs() <= s.amplitude_bound());
        }
    }

    /// Unit variance, and on planes of every orientation the tangential gradient covariance's
    /// trace is the plane noise's on average (module docs): its exact value `tr(PΣP)` over 2000
    /// random normals has the plane's trace as its mean within 2%, and no orientation is off by
    /// more than the finite wave count allows (±35%).
    #[test]
    fn heights_and_tangential_slopes_keep_the_materials_statistics() {
        let (plane, s) = noise();
        let var: f64 = s
            .waves
            .iter()
            .map(|w| 0.5 * w.amplitude * w.amplitude)
            .sum();
        assert!((var - 1.0).abs() < 1e-9, "{var}");
        let pc = plane.gradient_cov();
        let plane_trace = pc.xx + pc.yy;
        let c = s.gradient_cov();
        let mut rng = 11u64;
        let (mut sum, count) = (0.0, 2000);
        for _ in 0..count {
            let m = DVec3::new(
                standard_normal(&mut rng),
                standard_normal(&mut rng),
                standard_normal(&mut rng),
            )
            .normalize();
            let t = c.x_axis.x + c.y_axis.y + c.z_axis.z - m.dot(c * m);
            assert!(
                (t / plane_trace - 1.0).abs() < 0.35,
                "{t} against {plane_trace}"
            );
            sum += t;
        }
        let mean = sum / count as f64;
        assert!(
            (mean / plane_trace - 1.0).abs() < 0.02,
            "{mean} against {plane_trace}"
        );
    }
}
