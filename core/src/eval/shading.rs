//! The shading inputs every method shares: per facet, or averaged over the visible slope
//! distribution D_s [HNPN14 Sec. 5.2], and the radiance they give with the combined colour
//! [HNPN14 Sec. 6] under the directional light and the environment [HNPN14 Sec. 5.3].

use crate::eval::Evaluator;
use crate::material::color_terms::Affine;
use crate::material::measured::ChannelWeights;
use crate::microfacet::slopes::SlopeCov;
use crate::microfacet::visible_slopes::visible_slope_nodes;
use glam::{DMat3, DVec2, DVec3};
use std::f64::consts::FRAC_1_PI;

/// Shading inputs of a facet, or their average over a slope distribution: `E[(n·ωi)⁺]`,
/// `E[C_s(n)(n·ωi)⁺]`, `E[E_env(n)]` and `E[C_s(n) ⊙ E_env(n)]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SlopeShading {
    /// `E[(n·ωi)⁺]`.
    pub cos: f64,
    /// `E[C_s(n)(n·ωi)⁺]`.
    pub cs_cos: [f64; 3],
    /// `E[E_env(n)]`.
    pub env: [f64; 3],
    /// `E[C_s(n) ⊙ E_env(n)]`.
    pub cs_env: [f64; 3],
}

impl SlopeShading {
    /// Every input times `k`.
    #[must_use]
    pub fn scaled(self, k: f64) -> Self {
        Self {
            cos: self.cos * k,
            cs_cos: self.cs_cos.map(|v| v * k),
            env: self.env.map(|v| v * k),
            cs_env: self.cs_env.map(|v| v * k),
        }
    }
}

impl Evaluator {
    /// `C_s(n)` of the slope term (0 without one).
    pub(super) fn slope_color_at(&self, n: DVec3) -> [f64; 3] {
        self.slope_color.as_ref().map_or([0.0; 3], |c| c.sample(n))
    }

    /// Environment irradiance at unit normal n (0 without an environment).
    pub(super) fn environment_at(&self, n: DVec3) -> [f64; 3] {
        self.environment
            .as_ref()
            .map_or([0.0; 3], |e| e.irradiance(n))
    }

    /// [`SlopeShading`] of one facet of unit normal n (in the local tangent frame, where ωi is;
    /// `frame` takes it to the world, where the slope colour's direction and the environment are).
    pub(super) fn point_shading(&self, n: DVec3, wi: DVec3, frame: &DMat3) -> SlopeShading {
        let cos = n.dot(wi).max(0.0);
        let nw = *frame * n;
        let cs = self.slope_color_at(nw);
        let env = self.environment_at(nw);
        SlopeShading {
            cos,
            cs_cos: cs.map(|v| v * cos),
            env,
            cs_env: [0, 1, 2].map(|c| cs[c] * env[c]),
        }
    }

    /// [`SlopeShading`] averaged over the visible slope distribution D_s(ωo) of slopes N(mean, Σ)
    /// (world slope space) on the material's weighted polar nodes ([`visible_slope_nodes`], [`crate::microfacet::visible_slopes::slope_rule`]):
    /// C_s and the environment are averaged *jointly* with the clamped cosine, so no independence of
    /// colour and shading is assumed ([HNPN14 Sec. 5.2] assumes it; the joint average costs the same).
    pub(super) fn visible_shading(
        &self,
        mean: DVec2,
        sigma: &SlopeCov,
        wo: DVec3,
        wi: DVec3,
        frame: &DMat3,
    ) -> SlopeShading {
        let points = self.material.filtering.slope_points as usize;
        let (acc, den) = self.visible_shading_sums(mean, sigma, wo, wi, frame, points);
        if den > 0.0 {
            acc.scaled(1.0 / den)
        } else {
            SlopeShading::default()
        }
    }

    /// The sums [`Evaluator::visible_shading`] divides: each input weighted by the node's
    /// visible projected area, and the sum of those weights, on the rule of order `points`.
    pub(super) fn visible_shading_sums(
        &self,
        mean: DVec2,
        sigma: &SlopeCov,
        wo: DVec3,
        wi: DVec3,
        frame: &DMat3,
        points: usize,
    ) -> (SlopeShading, f64) {
        let mut acc = SlopeShading::default();
        let den = visible_slope_nodes(mean, sigma, wo, points, |n, w| {
            let p = self.point_shading(n, wi, frame);
            acc.cos += w * p.cos;
            for c in 0..3 {
                acc.cs_cos[c] += w * p.cs_cos[c];
                acc.env[c] += w * p.env[c];
                acc.cs_env[c] += w * p.cs_env[c];
            }
        });
        (acc, den)
    }

    /// Radiance from the combined colour `A + K ⊙ C_s` (`sun_color` under the directional light,
    /// `env_color` under the environment, which can differ because D_h differs), the shading inputs,
    /// the directional light's visibility `v` (shadowing) and the specular lobe `spec`:
    /// `ρ_d/π·w_d⊙(sun·v·(A⊙E[cos] + K⊙E[C_s cos]) + A⊙E[E_env] + K⊙E[C_s⊙E_env]) + sun·v·spec·w_s`,
    /// with the channel weights w_d, w_s of [`Evaluator::channel_weights`] (1 for the analytic
    /// base BRDF; a measured BRDF's fit, its lobe tinted by [`Evaluator::specular_tint`]).
    pub(super) fn radiance(
        &self,
        sun_color: Affine,
        env_color: Affine,
        s: &SlopeShading,
        v: f64,
        spec: f64,
    ) -> [f64; 3] {
        let w = self.channel_weights();
        let sun = self.material.lighting.sun * v;
        let kd = self.material.brdf.albedo * FRAC_1_PI;
        let tint = specular_tint(&w, &sun_color, s);
        [0, 1, 2].map(|c| {
            kd * w.kd[c]
                * (sun * (sun_color.a[c] * s.cos + sun_color.k[c] * s.cs_cos[c])
                    + env_color.a[c] * s.env[c]
                    + env_color.k[c] * s.cs_env[c])
                + sun * spec * tint[c]
        })
    }

    /// Radiance of one facet of unit normal n (local frame, as ωo and ωi; `frame` to the world)
    /// with colour terms `color` and light visibility v: the base BRDF at n ([`Evaluator::radiance`]
    /// with the facet's lobe), or, with a measured BRDF, its table in the facet's frame tinted by
    /// the facet's colour, `sun·v·(A + K⊙C_s)⊙ρ(ωi, ωo)(n·ωi)⁺`, plus the environment on the fit's
    /// diffuse part ([`crate::material::measured`]). Ground truth's explicit facets and the naive
    /// view's filtered normal.
    pub(super) fn facet_radiance(
        &self,
        color: Affine,
        n: DVec3,
        wo: DVec3,
        wi: DVec3,
        v: f64,
        frame: &DMat3,
    ) -> [f64; 3] {
        let s = self.point_shading(n, wi, frame);
        let Some(m) = &self.measured else {
            let spec = self
                .material
                .brdf
                .specular_with(n, wo, wi, SlopeCov::default());
            return self.radiance(color, color, &s, v, spec);
        };
        let rho = if v > 0.0 {
            m.eval_facet(n, wi, wo)
        } else {
            [0.0; 3]
        };
        let sun = self.material.lighting.sun * v;
        let kd = self.material.brdf.albedo * FRAC_1_PI;
        let w = m.channel_weights();
        [0, 1, 2].map(|c| {
            sun * (color.a[c] * s.cos + color.k[c] * s.cs_cos[c]) * rho[c]
                + kd * w.kd[c] * (color.a[c] * s.env[c] + color.k[c] * s.cs_env[c])
        })
    }
}

/// Per-channel weight of the specular lobe: the channel weight w_s, times, for a tinted lobe (a
/// measured BRDF), the mean colour of the lit facets `A + K⊙E[C_s cos]/E[cos]` (A where no facet
/// is lit: the lobe is 0 there anyway).
pub(super) fn specular_tint(w: &ChannelWeights, color: &Affine, s: &SlopeShading) -> [f64; 3] {
    [0, 1, 2].map(|c| {
        if !w.tint_specular {
            return w.f0[c];
        }
        let cs = if s.cos > 0.0 {
            s.cs_cos[c] / s.cos
        } else {
            0.0
        };
        w.f0[c] * (color.a[c] + color.k[c] * cs)
    })
}
