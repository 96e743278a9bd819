//! The pixel footprint: a Gaussian weight `w_P` over the mean plane (texture space), given by its
//! covariance Σ_p [HNPN14 Sec. 4.1], and the statistics of a driver over it (what every filtered
//! view reads).

use crate::microfacet::slopes::SlopeCov;
use glam::{DMat2, DVec2};

/// A Gaussian footprint in texture space, given by its covariance (symmetric 2×2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footprint {
    /// Covariance matrix Σ_p.
    pub cov: DMat2,
}

impl Footprint {
    /// An isotropic footprint of standard deviation `r` per axis.
    pub fn isotropic(r: f64) -> Self {
        Self {
            cov: DMat2::from_diagonal(DVec2::splat(r * r)),
        }
    }

    /// A point (no filtering).
    pub fn point() -> Self {
        Self::isotropic(0.0)
    }

    /// The smallest standard deviation along any direction: the square root of Σ_p's smaller
    /// eigenvalue `(a + b)/2 − √(((a − b)/2)² + c²)`; 0 for a degenerate, non-finite or
    /// non-positive covariance.
    pub fn min_std(&self) -> f64 {
        let (a, b, c) = (self.cov.x_axis.x, self.cov.y_axis.y, self.cov.x_axis.y);
        let l = 0.5 * (a + b) - (0.25 * (a - b) * (a - b) + c * c).sqrt();
        if l > 0.0 && l.is_finite() {
            l.sqrt()
        } else {
            0.0
        }
    }
}

/// Driver statistics over a footprint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilteredDriver {
    /// Footprint mean f̄.
    pub mean: f64,
    /// Phase-averaged footprint standard deviation σ_f.
    pub std: f64,
    /// Gradient of f̄ (the resolved, macro slope of the driver).
    pub mean_gradient: DVec2,
    /// Unresolved gradient covariance within the footprint.
    pub gradient_cov: SlopeCov,
}
