//! The filtered model: `I = V̄ · (C̄ · ρ̄_d + ρ̄_s)` [HNPN14 Eqs. 10, 13]. C̄ is the colour model over
//! the effective height distribution D_h [HNPN14 Eqs. 14–17] (exact table or fits), with the masking
//! exponent L of the height-correlated masking–shadowing G2 ([`G2`]; correlated or not, [HNPN14
//! Eq. 12]); the HN12 attribute model uses its closed form [HN12 Eq. 17]; ρ̄_d is the clamped cosine
//! averaged over the visible slope distribution D_s [HNPN14 Sec. 5.2] jointly with the slope colour
//! and environment irradiance ([`crate::eval::shading`]), and ρ̄_s the Beckmann lobe widened by the
//! unresolved slopes ([`filtered_specular`], [HN12 Sec. 5.5]). Transfer functions enter through their
//! moment tables [HNPN14 Eqs. 21–26]; under a transfer curve, and for an image driver whose slopes
//! depend on its value ([`crate::driver::conditional_slopes`]), the slopes are by default a mixture
//! over the driver's value instead of one Gaussian ([`crate::eval::mixture_bins`]).

use crate::driver::field::DriverField;
use crate::eval::masking::slope_weights::joint_inputs;
use crate::eval::{Evaluator, FootprintQuery};
use crate::material::color_terms::Affine;
use crate::microfacet::effective_height::{HeightMoments, height_moments};
use crate::microfacet::masking_shadowing::G2;
use crate::microfacet::slope_density::{NoiseSlopes, sinusoid_density_ratio};
use crate::microfacet::slope_masking::SLOPE_NODES;
use crate::microfacet::slopes::{normal_of, slope_of};
use crate::microfacet::transfer::TransferFunction;
use crate::scene::direction::basis;
use glam::{DMat3, DVec2, DVec3};

impl Evaluator {
    /// The filtered model (see the module docs).
    pub fn filtered(&self, cfg: &FootprintQuery) -> [f64; 3] {
        self.filtered_lit(cfg, 1.0, &DMat3::IDENTITY)
    }

    /// [`Evaluator::filtered`] with the slopes as the binned mixture over the driver's value
    /// whatever the material says ([`crate::eval::mixture_bins`]; under the identity transfer it
    /// is one Gaussian with D_h integrated exactly): for tests and `lodestone diagnose`.
    pub fn filtered_as_mixture(&self, cfg: &FootprintQuery) -> [f64; 3] {
        self.filtered_with(cfg, 1.0, &DMat3::IDENTITY, true)
    }

    /// [`Evaluator::filtered`] with the sun's visibility and the tangent frame, as
    /// [`Evaluator::naive`]'s.
    pub(crate) fn filtered_lit(
        &self,
        cfg: &FootprintQuery,
        sun_visible: f64,
        frame: &DMat3,
    ) -> [f64; 3] {
        let mixture = self.material.transfer_mixture();
        self.filtered_with(cfg, sun_visible, frame, mixture)
    }

    /// [`Evaluator::filtered_lit`], the slopes one Gaussian or (`mixture`) the binned mixture.
    fn filtered_with(
        &self,
        cfg: &FootprintQuery,
        sun_visible: f64,
        frame: &DMat3,
        mixture: bool,
    ) -> [f64; 3] {
        if cfg.wo.z <= 0.0 {
            return [0.0; 3];
        }
        let (loc, wo, wi) = self.footprint_frame(cfg);
        if mixture {
            return self.filtered_bins(&loc, cfg, (wo, wi), sun_visible, frame);
        }
        let sigma = loc.stats.slope_cov;
        let f = &self.material.filtering;
        let ms = G2::from_directions(wo, wi, &sigma, f.correlation);
        let (m, s) = self.color.input_distribution(&loc, self.global_height);
        let terms = &self.material.terms;
        // The colour model over the visible and lit heights (L = Λo + Λi) for the directional
        // light, over the visible heights (L = Λo) for the unshadowed environment; at heights of
        // moments (mean, std) within D_h(L) of moments `hm`.
        let color_of = |l: f64, hm: HeightMoments, (mean, std): (f64, f64)| {
            self.color
                .of_distribution(m + s * mean, s * std, l, (hm.mean, hm.std), s * s)
        };
        let hm_sun = height_moments(ms.total, f.height_filter);
        let hm_env = if self.environment.is_some() {
            height_moments(ms.lambda_o, f.height_filter)
        } else {
            hm_sun
        };
        let vbar = if wi.z > 0.0 && cfg.wi.z > 0.0 {
            ms.mean_shadowing()
        } else {
            0.0
        };
        // The footprint's slopes are N(s̄, Σ) in world slope space, exactly: average the facets there.
        let mean = loc.stats.slope_mean;
        let lit = sun_visible * vbar;
        let mut spec = self.specular_lobes(mean, &sigma, cfg.wo, cfg.wi);
        let points = self.material.slope_rule();
        let (sun_color, env_color, shading) =
            match self.slope_weights(cfg.footprint, mean, &sigma, cfg.wo, [hm_sun, hm_env]) {
                None => {
                    let sun = terms.affine(color_of(ms.total, hm_sun, (hm_sun.mean, hm_sun.std)));
                    let env = if self.environment.is_some() {
                        terms.affine(color_of(ms.lambda_o, hm_env, (hm_env.mean, hm_env.std)))
                    } else {
                        sun
                    };
                    let shading = self.visible_shading(mean, &sigma, cfg.wo, cfg.wi, frame);
                    (sun, env, shading)
                }
                Some(w) => {
                    // Masking conditioned on height and slope jointly (#17): each slope node sees
                    // its own heights, so colour and shading are summed together.
                    let per_node = |l: f64, hm: HeightMoments| {
                        let heights = w.heights(hm);
                        let colors: [Affine; SLOPE_NODES] = std::array::from_fn(|j| {
                            terms.affine(color_of(l, hm, (heights[j].mean, heights[j].std)))
                        });
                        (heights.map(|h| h.mass), colors)
                    };
                    let sun = per_node(ms.total, hm_sun);
                    let env = if self.environment.is_some() {
                        per_node(ms.lambda_o, hm_env)
                    } else {
                        sun
                    };
                    let buckets = self
                        .visible_shading_buckets(mean, &sigma, cfg.wo, cfg.wi, frame, points, &w);
                    let joint = joint_inputs(&buckets, (&sun.0, &sun.1), (&env.0, &env.1));
                    let k = w.lobe_factor(
                        &sun.0,
                        mean,
                        &sigma,
                        cfg.wo,
                        cfg.wi,
                        self.material.brdf.roughness,
                        &buckets.map(|b| b.1),
                    );
                    spec = spec.map(|v| v * k);
                    (joint.sun, joint.env, joint.shading)
                }
            };
        // The density ratio scales only the sun's specular term: where the sun does not reach the
        // pixel (shadowed, behind the mean plane, or no sun) or the lobe is 0, it changes nothing,
        // and its saddle point is the costliest part of the pixel (issue #15).
        if spec.iter().any(|v| *v > 0.0) && lit > 0.0 && self.material.lighting.sun != 0.0 {
            let r = self.lobe_density_ratio(cfg, mean);
            spec = spec.map(|v| v * r);
        }
        self.radiance(sun_color, env_color, &shading, lit, spec)
    }
}

impl Evaluator {
    /// The footprint's statistics and ωo, ωi in the frame of its mean normal n̄ (tangent frame
    /// [`basis`]). The footprint's resolved slope can tilt its mean plane away from a grazing view
    /// the ray still meets (image drivers at the horizon): the view then grazes the mean plane,
    /// kept just above its horizon so that the result is continuous across the tilt instead of
    /// black ([`above_horizon`]).
    pub(crate) fn footprint_frame(
        &self,
        cfg: &FootprintQuery,
    ) -> (crate::eval::query::FootprintStats, DVec3, DVec3) {
        let loc = self.footprint_stats(cfg);
        let nbar = normal_of(loc.stats.slope_mean);
        let (t, b) = basis(nbar);
        let to_local = |w: DVec3| DVec3::new(w.dot(t), w.dot(b), w.dot(nbar));
        (loc, above_horizon(to_local(cfg.wo)), to_local(cfg.wi))
    }

    /// The noise's exact unresolved slope density over the Gaussian the lobe assumes, at the half
    /// vector's slope relative to the footprint's mean ([`sinusoid_density_ratio`], with the base
    /// roughness as the added Gaussian): 1 for image drivers, transfer curves (their slopes are
    /// not the waves' alone), without specular, with `filtering.noise_slopes: Gaussian`, and for a
    /// measured BRDF (its fitted lobes keep the Gaussian).
    pub fn lobe_density_ratio(&self, cfg: &FootprintQuery, mean: DVec2) -> f64 {
        let m = &self.material;
        let DriverField::Noise(noise) = &self.surface.driver else {
            return 1.0;
        };
        if m.brdf.specular <= 0.0
            || self.measured.is_some()
            || m.filtering.noise_slopes == NoiseSlopes::Gaussian
            || !matches!(m.heights.transfer, TransferFunction::Identity)
            || cfg.wo.z <= 0.0
            || cfg.wi.z <= 0.0
        {
            return 1.0;
        }
        let h = (cfg.wo + cfg.wi).normalize();
        if !(h.z > 1e-9) {
            return 1.0;
        }
        let sigma_h = self.surface.sigma_h;
        let v: Vec<DVec2> = noise
            .unresolved_gradient_terms(cfg.footprint)
            .into_iter()
            .map(|t| t * sigma_h)
            .collect();
        sinusoid_density_ratio(&v, m.brdf.roughness, slope_of(h) - mean)
    }
}

/// Lowest cosine a view keeps to the footprint's mean plane: `ω` with `ω_z` raised to it and
/// its horizontal part shortened to stay unit (unchanged above it).
pub const MIN_VIEW_COS: f64 = 1e-3;

/// `ω` (unit, tangent frame) kept at least [`MIN_VIEW_COS`] above the horizon.
pub fn above_horizon(w: DVec3) -> DVec3 {
    if w.z >= MIN_VIEW_COS {
        return w;
    }
    let h = DVec2::new(w.x, w.y);
    let len = h.length();
    let scale = (1.0 - MIN_VIEW_COS * MIN_VIEW_COS).sqrt();
    let h = if len > 0.0 {
        h * (scale / len)
    } else {
        DVec2::new(scale, 0.0)
    };
    DVec3::new(h.x, h.y, MIN_VIEW_COS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::driver::footprint::Footprint;
    use crate::eval::{Evaluator, FootprintQuery};
    use crate::material::{Material, Slopes};
    use crate::scene::direction::direction;
    use glam::DVec2;

    /// A small footprint on steep relief seen at 89°: where its mean plane faces away from the
    /// view, the filtered model used to return black while the naive view (and the ray) saw
    /// the surface; now it is finite, positive, and close to its value just before the flip.
    #[test]
    fn a_mean_plane_tilted_away_from_the_view_is_not_black() {
        let m = Material {
            slopes: Slopes {
                sigma_nx: 1.5,
                sigma_ny: 1.5,
            },
            ..Material::default()
        };
        let p = Evaluator::new(&m).expect("valid");
        let (mut flipped, mut rng) = (0, 7u64);
        for _ in 0..400 {
            let x0 = DVec2::new(
                20.0 * crate::math::random::splitmix(&mut rng),
                20.0 * crate::math::random::splitmix(&mut rng),
            );
            let az = std::f64::consts::TAU * crate::math::random::splitmix(&mut rng);
            let cfg = FootprintQuery {
                wo: direction(89f64.to_radians(), az),
                wi: direction(0.5, 1.0),
                x0,
                footprint: Footprint::isotropic(0.02),
            };
            let loc = p.footprint_stats(&cfg);
            let nbar = normal_of(loc.stats.slope_mean);
            if cfg.wo.dot(nbar) <= 0.0 {
                flipped += 1;
                let (fi, na) = (p.filtered(&cfg), p.naive(&cfg));
                assert!(fi.iter().all(|v| v.is_finite() && *v >= 0.0), "{fi:?}");
                assert!(
                    na.iter().sum::<f64>() <= 0.0 || fi.iter().sum::<f64>() > 0.0,
                    "black where naive is {na:?}"
                );
            }
        }
        assert!(flipped > 10, "the test needs tilted footprints: {flipped}");
        // Continuity: just below and just above the horizon of a unit frame agree.
        let a = above_horizon(DVec3::new(1.0, 0.0, -1e-6).normalize());
        let b = above_horizon(DVec3::new(1.0, 0.0, 1e-6).normalize());
        assert!((a - b).length() < 1e-9 && (a.length() - 1.0).abs() < 1e-12);
    }
}
