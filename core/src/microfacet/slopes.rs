//! Gaussian slope statistics of a microsurface: the covariance of (∂h/∂x, ∂h/∂y).
//!
//! σ_nx, σ_ny of [HN12 Sec. 3] (anisotropic when they differ), plus the cross term c_xy that height
//! transfer functions produce [HNPN14 Eq. 26].

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// Covariance of the slope vector: `xx = σ_nx²`, `yy = σ_ny²`, `xy = c_xy`.
///
/// Invariant kept by the constructors: `xx, yy ≥ 0` and `xy² ≤ xx·yy` (a valid covariance).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
pub struct SlopeCov {
    /// Variance of ∂h/∂x.
    pub xx: f64,
    /// Variance of ∂h/∂y.
    pub yy: f64,
    /// Covariance of ∂h/∂x and ∂h/∂y.
    pub xy: f64,
}

impl SlopeCov {
    /// Isotropic slopes with standard deviation `sigma` per axis.
    pub fn isotropic(sigma: f64) -> Self {
        Self::from_std(sigma, sigma)
    }

    /// Axis-aligned anisotropic slopes with standard deviations σ_nx, σ_ny [HN12 Sec. 5.5].
    /// Negative or NaN inputs are treated as 0.
    pub fn from_std(sigma_x: f64, sigma_y: f64) -> Self {
        let sx = if sigma_x.is_finite() {
            sigma_x.max(0.0)
        } else {
            0.0
        };
        let sy = if sigma_y.is_finite() {
            sigma_y.max(0.0)
        } else {
            0.0
        };
        Self {
            xx: sx * sx,
            yy: sy * sy,
            xy: 0.0,
        }
    }

    /// Scale slopes by `s` (heights scaled by s): the covariance scales by s².
    pub fn scaled(self, s: f64) -> Self {
        let s2 = s * s;
        Self {
            xx: self.xx * s2,
            yy: self.yy * s2,
            xy: self.xy * s2,
        }
    }

    /// Standard deviation of the slope projected on the horizontal unit direction (cos φ, sin φ):
    /// `σ(φ)² = cos²φ σ_x² + 2 cos φ sin φ c_xy + sin²φ σ_y²` (docs/design/filtered-model.md, "Masking–shadowing").
    /// Never negative (rounding is clamped at 0).
    pub fn projected_std(&self, cos_phi: f64, sin_phi: f64) -> f64 {
        let v = cos_phi * cos_phi * self.xx
            + 2.0 * cos_phi * sin_phi * self.xy
            + sin_phi * sin_phi * self.yy;
        v.max(0.0).sqrt()
    }

    /// The covariance as a symmetric 2×2 matrix.
    pub fn to_mat(self) -> glam::DMat2 {
        glam::DMat2::from_cols(
            glam::DVec2::new(self.xx, self.xy),
            glam::DVec2::new(self.xy, self.yy),
        )
    }

    /// From a 2×2 matrix: its diagonal and the mean of its off-diagonal entries (the symmetric part).
    pub fn from_mat(m: glam::DMat2) -> Self {
        Self {
            xx: m.x_axis.x,
            yy: m.y_axis.y,
            xy: 0.5 * (m.x_axis.y + m.y_axis.x),
        }
    }

    /// Determinant `xx·yy − xy²` (≥ 0 for a valid covariance).
    pub fn det(&self) -> f64 {
        self.xx * self.yy - self.xy * self.xy
    }
}

/// Sum of two independent slope distributions: covariances add [HN12 Sec. 5.5]
/// (the "σ_n² + σ_n0²" convolution of the NDF with the base BRDF's).
impl std::ops::Add for SlopeCov {
    type Output = Self;
    fn add(self, other: Self) -> Self {
        Self {
            xx: self.xx + other.xx,
            yy: self.yy + other.yy,
            xy: self.xy + other.xy,
        }
    }
}

/// Slope `(−n_x/n_z, −n_y/n_z)` of a unit vector with n_z > 0.
pub fn slope_of(n: DVec3) -> DVec2 {
    DVec2::new(-n.x, -n.y) / n.z.max(1e-300)
}

/// Unit normal of a facet of slope s: `(−s_x, −s_y, 1)/√(1 + |s|²)`.
pub fn normal_of(s: DVec2) -> DVec3 {
    DVec3::new(-s.x, -s.y, 1.0).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_matches_rotated_variance() {
        let c = SlopeCov {
            xx: 0.09,
            yy: 0.01,
            xy: 0.02,
        };
        for i in 0..16 {
            let phi = f64::from(i) * 0.4;
            let (s, co) = phi.sin_cos();
            // Brute force: variance of the projection of samples from the 2×2 covariance via Cholesky.
            let l11 = c.xx.sqrt();
            let l21 = c.xy / l11;
            let l22 = (c.yy - l21 * l21).sqrt();
            // Var(a·X) = aᵀ C a computed from the Cholesky factor.
            let u = co * l11 + s * l21;
            let v = s * l22;
            let want = (u * u + v * v).sqrt();
            assert!((c.projected_std(co, s) - want).abs() < 1e-15);
        }
        assert_eq!(SlopeCov::from_std(f64::NAN, -1.0), SlopeCov::default());
    }
}
