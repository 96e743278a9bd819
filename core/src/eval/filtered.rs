//! The filtered model: `I = V̄ · (C̄ · ρ̄_d + ρ̄_s)` [HNPN14 Eqs. 10, 13]. C̄ is the colour model over
//! the effective height distribution D_h [HNPN14 Eqs. 14–17] (exact table or fits), with the masking
//! exponent L of the height-correlated masking–shadowing G2 ([`G2`]; correlated or not, [HNPN14
//! Eq. 12]); the HN12 attribute model uses its closed form [HN12 Eq. 17]; ρ̄_d is the clamped cosine
//! averaged over the visible slope distribution D_s [HNPN14 Sec. 5.2] jointly with the slope colour
//! and environment irradiance ([`crate::eval::shading`]), and ρ̄_s the Beckmann lobe widened by the
//! unresolved slopes ([`filtered_specular`], [HN12 Sec. 5.5]). Transfer functions enter through their
//! moment tables [HNPN14 Eqs. 21–26].

use crate::eval::{Evaluator, FootprintQuery};
use crate::microfacet::brdf::filtered_specular;
use crate::microfacet::effective_height::height_moments;
use crate::microfacet::masking_shadowing::G2;
use crate::microfacet::slopes::normal_of;
use crate::scene::direction::basis;
use glam::{DMat3, DVec3};

impl Evaluator {
    /// The filtered model (see the module docs).
    pub fn filtered(&self, cfg: &FootprintQuery) -> [f64; 3] {
        self.filtered_lit(cfg, 1.0, &DMat3::IDENTITY)
    }

    /// [`Evaluator::filtered`] with the sun's visibility and the tangent frame, as
    /// [`Evaluator::naive`]'s.
    pub(super) fn filtered_lit(
        &self,
        cfg: &FootprintQuery,
        sun_visible: f64,
        frame: &DMat3,
    ) -> [f64; 3] {
        let loc = self.footprint_stats(cfg);
        let nbar = normal_of(loc.stats.slope_mean);
        let (t, b) = basis(nbar);
        let to_local = |w: DVec3| DVec3::new(w.dot(t), w.dot(b), w.dot(nbar));
        let (wo, wi) = (to_local(cfg.wo), to_local(cfg.wi));
        if wo.z <= 0.0 || cfg.wo.z <= 0.0 {
            return [0.0; 3];
        }
        let sigma = loc.stats.slope_cov;
        let f = &self.material.filtering;
        let ms = G2::from_directions(wo, wi, &sigma, f.correlation);
        let (m, s) = self.color.input_distribution(&loc, self.global_height);
        let terms = &self.material.terms;
        // The colour model over the visible and lit heights (L = Λo + Λi) for the directional
        // light, over the visible heights (L = Λo) for the unshadowed environment.
        let filtered_color = |l: f64| {
            let hm = height_moments(l, f.height_filter);
            self.color
                .of_distribution(m + s * hm.mean, s * hm.std, l, (hm.mean, hm.std), s * s)
        };
        let sun_color = terms.affine(filtered_color(ms.total));
        let env_color = if self.environment.is_some() {
            terms.affine(filtered_color(ms.lambda_o))
        } else {
            sun_color
        };
        let vbar = if wi.z > 0.0 && cfg.wi.z > 0.0 {
            ms.mean_shadowing()
        } else {
            0.0
        };
        let brdf = &self.material.brdf;
        // The footprint's slopes are N(s̄, Σ) in world slope space, exactly: average the facets there.
        let mean = loc.stats.slope_mean;
        let shading = self.visible_shading(mean, &sigma, cfg.wo, cfg.wi, frame);
        let spec = filtered_specular(brdf.specular, brdf.roughness, mean, &sigma, cfg.wo, cfg.wi);
        self.radiance(sun_color, env_color, &shading, sun_visible * vbar, spec)
    }
}
