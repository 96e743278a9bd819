//! View-independent texture filtering: the exact footprint average of the colour,
//! `⟨C, N(f̄, σ_f²)⟩` [HNPN14 Eq. 9], shaded like naive: what a perfectly mip-mapped colour texture
//! gives.

use crate::eval::query::lit;
use crate::eval::{Evaluator, FootprintQuery};
use crate::microfacet::slopes::normal_of;
use crate::microfacet::visible_slopes::slope_mean;
use glam::DMat3;

impl Evaluator {
    /// View-independent texture filtering: the exact footprint mean colour, shaded like naive. A
    /// slope colour is averaged over the footprint's slopes without the projected-area weight (what
    /// a mip-mapped slope-colour texture holds).
    pub fn view_independent(&self, cfg: &FootprintQuery) -> [f64; 3] {
        self.view_independent_lit(cfg, 1.0, &DMat3::IDENTITY)
    }

    /// [`Evaluator::view_independent`] with the sun's visibility and the tangent frame, as
    /// [`Evaluator::naive`]'s.
    pub(super) fn view_independent_lit(
        &self,
        cfg: &FootprintQuery,
        sun_visible: f64,
        frame: &DMat3,
    ) -> [f64; 3] {
        let loc = self.footprint_stats(cfg);
        let (m, s) = self.color.input_distribution(&loc, self.global_height);
        let c = self.color.of_distribution(m, s, 0.0, (0.0, 1.0), s * s);
        let n = normal_of(loc.stats.slope_mean);
        let aff = self.material.terms.affine(c);
        let mut sh = self.point_shading(n, cfg.wi, frame);
        if let Some(sc) = &self.slope_color {
            let cs = slope_mean(
                loc.stats.slope_mean,
                &loc.stats.slope_cov,
                self.material.slope_rule(),
                |n| sc.sample(*frame * n),
            );
            sh.cs_cos = cs.map(|v| v * sh.cos);
            sh.cs_env = [0, 1, 2].map(|k| cs[k] * sh.env[k]);
        }
        let spec = self.facet_specular(n, cfg.wo, cfg.wi);
        let v = sun_visible * lit(cfg, n);
        self.radiance(aff, aff, &sh, v, spec)
    }
}
