//! Irradiance environment maps as nine spherical-harmonic coefficients per channel
//! [Ramamoorthi and Hanrahan 2001, "An efficient representation for irradiance environment maps"],
//! used as a slope colour map [HNPN14 Sec. 5.3].
//!
//! Real SH basis up to l = 2 in the tangent frame (z = macro normal, directions unit):
//! `Y00 = 0.282095`, `Y1,-1 = 0.488603 y`, `Y10 = 0.488603 z`, `Y11 = 0.488603 x`,
//! `Y2,-2 = 1.092548 xy`, `Y2,-1 = 1.092548 yz`, `Y20 = 0.315392 (3z² − 1)`, `Y21 = 1.092548 xz`,
//! `Y22 = 0.546274 (x² − y²)`. Radiance projects to `L_lm = ∫ L(ω) Y_lm(ω) dω`; the irradiance at a
//! normal n is `E(n) = Σ Â_l L_lm Y_lm(n)` with the clamped-cosine kernel's `Â_0 = π`, `Â_1 = 2π/3`,
//! `Â_2 = π/4` [RH01 Eqs. 7–8]. The truncation is exact for radiance of degree ≤ 2 in ω and within a
//! few percent of the true irradiance for any environment (the kernel's l > 2 terms are ≤ 0.4% of
//! Â_0 each, [RH01 Sec. 3]); ground truth and the filtered model use the same E, so comparisons
//! measure the filtering, not the truncation.
//!
//! Edge cases: `E` is finite for every input (a non-unit n is used as given; callers pass unit
//! normals); the irradiance of a physically valid environment can still come out slightly negative
//! at normals facing away from a very bright, small source (SH ringing): [`Sh9::irradiance`]
//! clamps at 0.

use glam::DVec3;
use std::f64::consts::PI;

/// Basis constants in the order of [`sh_basis`].
const K: [f64; 5] = [0.282095, 0.488603, 1.092548, 0.315392, 0.546274];

/// The clamped-cosine kernel's coefficients per band [RH01 Eq. 8].
pub const A_HAT: [f64; 3] = [PI, 2.0 * PI / 3.0, PI / 4.0];

/// The nine real SH basis functions at unit direction `d`, in the order
/// (0,0), (1,-1), (1,0), (1,1), (2,-2), (2,-1), (2,0), (2,1), (2,2).
pub fn sh_basis(d: DVec3) -> [f64; 9] {
    let (x, y, z) = (d.x, d.y, d.z);
    [
        K[0],
        K[1] * y,
        K[1] * z,
        K[1] * x,
        K[2] * x * y,
        K[2] * y * z,
        K[3] * (3.0 * z * z - 1.0),
        K[2] * x * z,
        K[4] * (x * x - y * y),
    ]
}

/// Visit the cells of a `rows × cols` grid in (θ from the zenith, φ from +x toward +y), the layout
/// of an equirectangular image: `visit(row, col, centre direction, exact solid angle of the cell)`.
/// The solid angles sum to 4π exactly.
pub fn sphere_grid(rows: usize, cols: usize, mut visit: impl FnMut(usize, usize, DVec3, f64)) {
    for i in 0..rows {
        let (t0, t1) = (
            PI * i as f64 / rows as f64,
            PI * (i + 1) as f64 / rows as f64,
        );
        let theta = 0.5 * (t0 + t1);
        let d_omega = (t0.cos() - t1.cos()) * (2.0 * PI / cols as f64);
        for j in 0..cols {
            let phi = 2.0 * PI * (j as f64 + 0.5) / cols as f64;
            let d = DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            visit(i, j, d, d_omega);
        }
    }
}

/// Band of each coefficient in [`sh_basis`] order.
const BAND: [usize; 9] = [0, 1, 1, 1, 2, 2, 2, 2, 2];

/// Radiance of an environment projected onto SH up to l = 2, per linear-RGB channel.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Sh9 {
    /// `L_lm` per coefficient (in [`sh_basis`] order), per channel.
    pub coeffs: [[f64; 3]; 9],
}

impl Sh9 {
    /// Project radiance `l(ω)` by midpoint quadrature on a `rows × 2·rows` grid in (θ, φ) with exact
    /// per-row solid angles (`rows` ≥ 2). A grid of 256 rows resolves features down to about 1°.
    pub fn project(rows: usize, l: impl Fn(DVec3) -> [f64; 3]) -> Self {
        let rows = rows.max(2);
        let mut sh = Self::default();
        sphere_grid(rows, 2 * rows, |_, _, d, d_omega| sh.add(l(d), d, d_omega));
        sh
    }

    /// Add radiance `l` arriving from direction `d` over solid angle `d_omega` to the projection.
    pub fn add(&mut self, l: [f64; 3], d: DVec3, d_omega: f64) {
        let y = sh_basis(d);
        for k in 0..9 {
            for ch in 0..3 {
                self.coeffs[k][ch] += l[ch] * y[k] * d_omega;
            }
        }
    }

    /// Every coefficient multiplied by `s`.
    #[must_use]
    pub fn scaled(&self, s: f64) -> Self {
        Self {
            coeffs: self.coeffs.map(|c| c.map(|v| v * s)),
        }
    }

    /// Irradiance `E(n) = Σ Â_l L_lm Y_lm(n)` [RH01 Eq. 7] at unit normal n, clamped at 0.
    pub fn irradiance(&self, n: DVec3) -> [f64; 3] {
        let y = sh_basis(n);
        let mut e = [0.0; 3];
        for k in 0..9 {
            let a = A_HAT[BAND[k]] * y[k];
            for ch in 0..3 {
                e[ch] += a * self.coeffs[k][ch];
            }
        }
        e.map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 })
    }

    /// The 27 coefficients pre-multiplied by `Â_l`, coefficient-major (what the GPU stores).
    pub fn irradiance_coefficients(&self) -> [[f64; 3]; 9] {
        let mut out = self.coeffs;
        for k in 0..9 {
            out[k] = out[k].map(|v| v * A_HAT[BAND[k]]);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫ l(ω) (n·ω)⁺ dω` by brute force on a fine (θ, φ) grid.
    fn brute_irradiance(n: DVec3, l: impl Fn(DVec3) -> f64) -> f64 {
        let mut e = 0.0;
        sphere_grid(600, 1200, |_, _, d, dw| e += l(d) * n.dot(d).max(0.0) * dw);
        e
    }

    #[test]
    fn basis_is_orthonormal() {
        // ∫ Y_i Y_j dω = δ_ij, by the same quadrature the projection uses.
        for i in 0..9 {
            let sh = Sh9::project(128, |d| [sh_basis(d)[i], 0.0, 0.0]);
            for j in 0..9 {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!(
                    (sh.coeffs[j][0] - want).abs() < 2e-4,
                    "<Y{i}, Y{j}> = {}",
                    sh.coeffs[j][0]
                );
            }
        }
    }

    #[test]
    fn constant_environment_gives_pi() {
        let sh = Sh9::project(64, |_| [1.0, 0.5, 2.0]);
        for n in [DVec3::Z, DVec3::X, DVec3::new(0.3, -0.4, 0.866).normalize()] {
            let e = sh.irradiance(n);
            for (ch, s) in [1.0, 0.5, 2.0].into_iter().enumerate() {
                assert!((e[ch] - PI * s).abs() < 1e-3, "{e:?}");
            }
        }
    }

    /// Radiance of degree ≤ 2 in ω is represented exactly, so SH9 irradiance equals brute force.
    #[test]
    fn quadratic_radiance_irradiance_matches_brute_force() {
        let l = |d: DVec3| 1.0 + 0.5 * d.z - 0.3 * d.x + 0.8 * d.x * d.y + 0.4 * d.z * d.z;
        let sh = Sh9::project(256, |d| [l(d); 3]);
        for n in [
            DVec3::Z,
            DVec3::new(0.6, 0.0, 0.8),
            DVec3::new(-0.2, 0.7, 0.3).normalize(),
            DVec3::new(0.0, 0.0, -1.0),
        ] {
            let want = brute_irradiance(n, l);
            let got = sh.irradiance(n)[0];
            assert!(
                (got - want).abs() < 1e-3 * want.abs().max(1.0),
                "n {n:?}: {got} vs {want}"
            );
        }
    }

    /// For a general sky (a bright upper hemisphere), SH9 irradiance is within a few percent of the
    /// exact irradiance where it is not near 0 [RH01 Sec. 3].
    #[test]
    fn hemisphere_light_is_within_a_few_percent() {
        let l = |d: DVec3| if d.z > 0.0 { 1.0 } else { 0.1 };
        let sh = Sh9::project(256, |d| [l(d); 3]);
        for deg in [0.0_f64, 30.0, 60.0, 90.0] {
            let t = deg.to_radians();
            let n = DVec3::new(t.sin(), 0.0, t.cos());
            let want = brute_irradiance(n, l);
            let got = sh.irradiance(n)[0];
            assert!((got - want).abs() < 0.05 * want, "{deg}°: {got} vs {want}");
        }
    }

    #[test]
    fn irradiance_is_finite_and_non_negative() {
        // A tiny, very bright source rings in SH9; E is clamped at 0.
        let sun = DVec3::new(0.0, 0.6, 0.8);
        let sh = Sh9::project(128, |d| [if d.dot(sun) > 0.999 { 1e6 } else { 0.0 }; 3]);
        for k in 0..200 {
            let t = k as f64 * 0.1;
            let n = DVec3::new(
                t.cos() * (0.3 * t).sin(),
                t.sin() * (0.3 * t).sin(),
                (0.3 * t).cos(),
            );
            let e = sh.irradiance(n);
            assert!(e.iter().all(|v| v.is_finite() && *v >= 0.0), "{e:?}");
        }
        assert_eq!(Sh9::default().irradiance(DVec3::Z), [0.0; 3]);
    }
}
