//! What the statistical methods are asked ([`FootprintQuery`]: a footprint seen from ωo, lit from
//! ωi) and what they share about it ([`FootprintStats`]: the driver's and the transformed surface's
//! statistics there [HNPN14 Eqs. 19–26]).

use crate::driver::footprint::{FilteredDriver, Footprint};
use crate::eval::Evaluator;
use crate::microfacet::transfer::{SurfaceStats, TransferMoments, transformed_statistics};
use glam::{DVec2, DVec3};

/// One view/light configuration over one footprint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootprintQuery {
    /// Unit direction toward the eye (tangent frame, z = macro normal).
    pub wo: DVec3,
    /// Unit direction toward the light.
    pub wi: DVec3,
    /// Footprint centre on the mean plane.
    pub x0: DVec2,
    /// Footprint covariance.
    pub footprint: Footprint,
}

impl FootprintQuery {
    /// A far, fully filtered footprint for `prepared`: isotropic with a standard deviation of 20 times
    /// the coarsest scale of the driver (longest wavelength, or the image's tile), centred away from
    /// the origin.
    pub fn far(prepared: &Evaluator, wo: DVec3, wi: DVec3) -> Self {
        let r = 20.0 * prepared.surface.driver.coarsest_scale();
        Self {
            wo,
            wi,
            x0: DVec2::new(3.0, -7.0),
            footprint: Footprint::isotropic(r),
        }
    }
}

/// Footprint-local statistics shared by the statistical methods.
#[derive(Clone, Copy, Debug)]
pub struct FootprintStats {
    /// The driver over the footprint (mean, std, resolved gradient, unresolved gradient covariance).
    pub driver: FilteredDriver,
    /// Moments of g over the driver's footprint distribution.
    pub transfer: TransferMoments,
    /// The transformed surface's heights and slopes.
    pub stats: SurfaceStats,
}

impl Evaluator {
    /// The driver's statistics over the query's footprint, the transfer function's moments over
    /// them, and the transformed surface's height and slope statistics [HNPN14 Eqs. 19–26].
    pub fn footprint_stats(&self, cfg: &FootprintQuery) -> FootprintStats {
        let driver = self.surface.driver.filtered(cfg.x0, cfg.footprint);
        let transfer = self.transfer.moments(driver.mean, driver.std);
        let stats = transformed_statistics(
            transfer,
            self.surface.sigma_h,
            driver.mean_gradient,
            driver.gradient_cov,
        );
        FootprintStats {
            driver,
            transfer,
            stats,
        }
    }
}

/// 1 when the light is above the horizon of both the macro surface and the facet n, else 0.
pub(super) fn lit(cfg: &FootprintQuery, n: DVec3) -> f64 {
    if cfg.wi.z > 0.0 && n.dot(cfg.wi) > 0.0 {
        1.0
    } else {
        0.0
    }
}
