//! Naive MIP [HNPN14 Sec. 4, Sec. 9]: the colour map of the footprint-filtered driver `C(f̄)`,
//! shaded by the base BRDF (or a measured one's table) at the filtered (mean-slope) normal; no
//! masking, no shadowing. What a mip-mapped pipeline does.

use crate::eval::query::lit;
use crate::eval::{Evaluator, FootprintQuery};
use crate::microfacet::slopes::normal_of;
use glam::DMat3;

impl Evaluator {
    /// Naive MIP: `C(f̄)` shaded at the filtered normal with the base roughness; no masking. The
    /// slope colour and the environment irradiance are taken at the filtered normal too.
    pub fn naive(&self, cfg: &FootprintQuery) -> [f64; 3] {
        self.naive_lit(cfg, 1.0, &DMat3::IDENTITY)
    }

    /// [`Evaluator::naive`] with the directional light's visibility `sun_visible` (the pixel's
    /// shadow ray) and the tangent frame `frame` (world axes, for slope colour and environment).
    pub(super) fn naive_lit(
        &self,
        cfg: &FootprintQuery,
        sun_visible: f64,
        frame: &DMat3,
    ) -> [f64; 3] {
        let loc = self.footprint_stats(cfg);
        let n = normal_of(loc.stats.slope_mean);
        let aff = self.material.terms.affine(self.color_at(loc.driver.mean));
        let v = sun_visible * lit(cfg, n);
        self.facet_radiance(aff, n, cfg.wo, cfg.wi, v, frame)
    }
}
