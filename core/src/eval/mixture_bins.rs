//! The filtered model under a transfer curve, or for an image whose slopes depend on its value
//! ([`crate::driver::conditional_slopes`]): the footprint's slopes as a mixture of Gaussians over
//! bins of the driver's value, each with its colour, its visible-slope shading and
//! height-dependent masking ([`crate::microfacet::height_mixture`]).
//!
//! Per bin b (quantiles [lo, hi] of the footprint's driver N(f̄, σ_f²), [`mixture_edges`]): the
//! mean ḡ′_b and root mean square of g′ and the mean colour C_b of the points in it (on
//! [`BIN_SAMPLES`] midpoints in u, [`Evaluator::bin_moments`]); its slopes
//! `N(σ_h ḡ′_b·∇f̄, σ_h² E_b[g′²]·Σ_∇f)`, their Λ(ωo), Λ(ωi) and joint exponent L_b ([`G2`]); the
//! visible-slope sums on n² nodes ([`bin_slope_points`]). With `W1_b` the bin's weight times its
//! mean visibility along ωo and `W2_b` the same for the joint masking–shadowing ([`bin_masking`],
//! chained from the top bin down), and `So_b` the bin's visible projected area,
//!
//! `I = Σ_b [W2_b·E_sun·(ρ/π·(A_b⊙S_b + K_b⊙S^C_b) + So_b·ρ_s,b) + W1_b·ρ/π·(A_b⊙S^env_b +
//! K_b⊙S^Cenv_b)] / Σ_b W1_b·So_b`
//!
//! (`A_b + K_b ⊙ C_s` the colour terms of C_b, S the visible-slope sums of [`SlopeShading`],
//! ρ_s,b the bin's widened specular lobe per unit visible area, [`filtered_specular`]). With the
//! identity transfer every bin has the same slopes and this is the filtered model with D_h
//! integrated exactly (tested). Against the 241-node mixture ([`Evaluator::filtered_mixture`]) on
//! the moss, sponge and terraces presets: within 0.1%, 0.8% and 3.0% (terraces at 75°; a riser
//! whose g′ runs from 0 to its peak inside one bin is still one Gaussian).
//!
//! **Conditioned on the driver's slope (#17).** With [`Evaluator::transfer_masking`] set (a
//! noise driver under a transfer curve with conditioned masking), each bin is also summed over
//! its [`BIN_SAMPLES`] sub-values, each with its own g′ and its own visibility (a riser and a tread
//! in one bin are two slope scales, not their root mean square). Its conditioned G1 along ωo and
//! joint masking–shadowing over the driver's slopes
//! ([`crate::eval::masking::transfer_masking_table::TransferRays::visibility_weights`]: each ray's from its
//! 1-D moments in the table, their joint term in closed form) are Gaussian functions of the slopes: each
//! reweights the slopes' Gaussian into another ([`GaussianWeight::tilted`]), which the bin shades
//! as it shades any Gaussian of slopes (within 0.9% of summing shading and visibility node by
//! node on #17's grid). Each sub-value's specular lobe is widened by its own slopes and takes the
//! joint term's mean over its half-vector posterior, in closed form
//! ([`Evaluator::lobe_visibility`]). The two are blended by the
//! footprint's far weight (docs/design/transfer-curves.md, "Masking that knows the driver's
//! slope"). On #17's grid terraces' worst excess is 2.69% (0–60°) and 1.32% (75–85°), where
//! Smith's bins have 5.06% and 14.46%; sponge 0.24% and 4.52% (Smith's 2.10% and 13.43%).

use crate::driver::conditional_slopes::ImageSlopes;
use crate::eval::masking::transfer_masking_table::TransferRays;
use crate::eval::query::FootprintStats;
use crate::eval::shading::{SlopeShading, specular_tint};
use crate::eval::{Evaluator, FootprintQuery};
use crate::math::gaussian::cholesky;
use crate::math::gaussian_weight::GaussianWeight;
use crate::math::special::norm_quantile;
use crate::microfacet::brdf::half_vector_posterior;
use crate::microfacet::height_mixture::{
    BIN_SAMPLES, bin_exponent, bin_masking, bin_slope_points, mixture_edges,
};
use crate::microfacet::masking_shadowing::G2;
use crate::microfacet::slope_rule::SlopeRule;
use crate::microfacet::slopes::SlopeCov;
use crate::microfacet::transfer::TransferFunction;
use crate::microfacet::visible_slopes::expected_positive_part;
use glam::{DMat2, DMat3, DVec2, DVec3};

use std::f64::consts::FRAC_1_PI;

/// n of the polar rule (n² nodes) over a sub-value's slopes when its masking is conditioned on
/// the driver's slope ([`crate::eval::masking::transfer_masking_table`]), at least: the bins' own 4 × 4.
/// On #17's grid 6 × 6 gave terraces 2.66% / 1.19%, sponge 0.00% / 4.39% and moss 0 / 0, and 4 × 4
/// gives 2.69% / 1.32%, 0.24% / 4.52% and 0.05% / 0.21%, at 1868 instead of 2260 ms a frame on
/// llvmpipe (terraces, 256 × 192; in one run with a Smith copy, 1872 against Smith's bins' 810).
pub const CONDITIONED_SLOPE_POINTS: usize = 4;

/// The rule of the shading under each sub-value's tilted Gaussians: the bins' own rule, with at
/// least [`CONDITIONED_SLOPE_POINTS`] radii.
pub fn conditioned_slope_rule(bins: SlopeRule) -> SlopeRule {
    if bins.radii >= CONDITIONED_SLOPE_POINTS {
        bins
    } else {
        SlopeRule::square(CONDITIONED_SLOPE_POINTS)
    }
}

/// What a bin of the driver's value contributes: its mean g′, the root mean square of g′ and the
/// mean point colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinMoments {
    /// Mean of g′ over the bin.
    pub mean_deriv: f64,
    /// √E[g′²] over the bin.
    pub rms_deriv: f64,
    /// Mean colour of its points ([`Evaluator::color_at`]).
    pub color: [f64; 3],
}

impl Evaluator {
    /// [`BinMoments`] of the quantiles [lo, hi] of N(mean, std²), on [`BIN_SAMPLES`] midpoints in u.
    /// For an image's value-conditioned slopes ([`Evaluator::image_slopes`]) N(mean, std²) is the
    /// footprint in the image's Gaussian space: a point at G has the value `T⁻¹(G)`, `g′ = 1` and
    /// `E[g′²]` its slope scale `s²` (normalized over the footprint by [`Evaluator::filtered_bins`]).
    pub fn bin_moments(&self, mean: f64, std: f64, lo: f64, hi: f64) -> BinMoments {
        let g = &self.material.heights.transfer;
        let (mut d1, mut d2, mut color) = (0.0, 0.0, [0.0; 3]);
        let k = 1.0 / BIN_SAMPLES as f64;
        for q in 0..BIN_SAMPLES {
            let u = lo + (hi - lo) * (q as f64 + 0.5) * k;
            let x = mean + std * norm_quantile(u);
            let (f, gd, gd2) = match &self.image_slopes {
                Some(t) => (t.value_at_gauss(x), 1.0, t.scale_at_gauss(x)),
                None => {
                    let gd = g.derivative(x);
                    (x, gd, gd * gd)
                }
            };
            d1 += gd * k;
            d2 += gd2 * k;
            let c = self.color_at(f);
            for ch in 0..3 {
                color[ch] += c[ch] * k;
            }
        }
        BinMoments {
            mean_deriv: d1,
            rms_deriv: d2.max(0.0).sqrt(),
            color,
        }
    }

    /// `E_b[s²]` of an image's value-conditioned slopes ([`ImageSlopes`]) over the quantiles
    /// [lo, hi] of N(mean, std²) in its Gaussian space, on the [`BIN_SAMPLES`] midpoints of
    /// [`Evaluator::bin_moments`]: what the footprint's normalization needs, without the colour.
    pub fn bin_slope_scale(t: &ImageSlopes, mean: f64, std: f64, lo: f64, hi: f64) -> f64 {
        let k = 1.0 / BIN_SAMPLES as f64;
        (0..BIN_SAMPLES)
            .map(|q| {
                let u = lo + (hi - lo) * (q as f64 + 0.5) * k;
                t.scale_at_gauss(mean + std * norm_quantile(u)) * k
            })
            .sum()
    }

    /// The filtered model with the footprint's slopes as the binned mixture (module docs), `wo`
    /// and `wi` in the frame of the footprint's mean normal (for Λ), `cfg`'s in the macro frame
    /// (for the slope averages, which live in world slope space), `sun_visible` the shadow ray's
    /// verdict and `frame` the tangent frame, as [`Evaluator::filtered`] takes them.
    pub(super) fn filtered_bins(
        &self,
        loc: &FootprintStats,
        cfg: &FootprintQuery,
        (wo, wi): (DVec3, DVec3),
        sun_visible: f64,
        frame: &DMat3,
    ) -> [f64; 3] {
        let m = &self.material;
        let d = loc.driver;
        let knots: Vec<f64> = match &m.heights.transfer {
            TransferFunction::Curve(c) => c.points.iter().map(|p| p[0]).collect(),
            TransferFunction::Identity => Vec::new(),
        };
        // An image's bins live in its Gaussian space (the colour's input distribution there).
        let (mean, std) = if self.image_slopes.is_some() {
            self.color.input_distribution(loc, self.global_height)
        } else {
            (d.mean, d.std)
        };
        let edges = mixture_edges(&knots, mean, std);
        let mut bins: Vec<(f64, f64, BinMoments)> = edges
            .windows(2)
            .filter(|e| e[1] > e[0])
            .map(|e| (e[0], e[1], self.bin_moments(mean, std, e[0], e[1])))
            .collect();
        if let Some(t) = &self.image_slopes {
            // The image's slope scale splits the footprint's slope covariance among its values:
            // normalized so that their mean is 1 (the pyramid's total stays).
            let total: f64 = bins
                .iter()
                .map(|(lo, hi, _)| (hi - lo) * Self::bin_slope_scale(t, mean, std, *lo, *hi))
                .sum();
            if total > 0.0 {
                let k = total.sqrt().recip();
                for (_, _, b) in &mut bins {
                    b.rms_deriv *= k;
                }
            }
        }
        let sigma_h = self.surface.sigma_h;
        let sun_lit = wi.z > 0.0 && cfg.wi.z > 0.0;
        let b = &m.brdf;
        let kd = b.albedo * FRAC_1_PI;
        let weights = self.channel_weights();
        let sun = m.lighting.sun * sun_visible;
        let points = bin_slope_points(m.slope_rule(), m.terms.slope.is_some());
        let conditioned = self
            .transfer_masking
            .as_ref()
            .map(|t| TransferRays::new(t, d, (wo, wi), sun_lit, sigma_h, m.filtering.correlation));
        let conditioned_points = conditioned_slope_rule(points);
        let (mut above_o, mut above) = (0.0, 0.0);
        let (mut num, mut den) = ([0.0f64; 3], 0.0f64);
        for &(lo, hi, bin) in bins.iter().rev() {
            let mean = d.mean_gradient * (sigma_h * bin.mean_deriv);
            let cov = d.gradient_cov.scaled(sigma_h * bin.rms_deriv);
            let ms = G2::from_directions(wo, wi, &cov, m.filtering.correlation);
            let w1 = bin_masking(lo, hi, ms.lambda_o, above_o);
            let w2 = bin_masking(lo, hi, ms.total, above);
            above_o += bin_exponent(lo, hi, ms.lambda_o);
            above += bin_exponent(lo, hi, ms.total);
            // Smith's bin: its visible-slope sums, projected area and lobe (computed only where
            // they are used: the conditioned path of a far footprint has no Smith share).
            let smith = || {
                let (s, s_o) = self.visible_shading_sums(mean, &cov, cfg.wo, cfg.wi, frame, points);
                let spec = sun_lit.then(|| self.specular_lobes(mean, &cov, cfg.wo, cfg.wi));
                (s, s_o, spec.map_or([0.0; 3], |l| l.map(|l| l * s_o)))
            };
            let c = m.terms.affine(bin.color);
            // One part of the bin, weighted by `share`: masses w1 (seen) and w2 (seen and lit),
            // the shading sums weighted by the masking (environment) and by the joint term
            // (sun), and the lobe's visible mass.
            let mut add = |share: f64,
                           (w1, w2): (f64, f64),
                           s1: &SlopeShading,
                           s1o: f64,
                           s2: &SlopeShading,
                           spec: [f64; 3]| {
                den += share * w1 * s1o;
                let v = if sun_lit { share * w2 * sun } else { 0.0 };
                let tint = specular_tint(&weights, &c, s2);
                for ch in 0..3 {
                    let kd = kd * weights.kd[ch];
                    num[ch] += v
                        * (kd * (c.a[ch] * s2.cos + c.k[ch] * s2.cs_cos[ch]) + spec[ch] * tint[ch])
                        + share * w1 * kd * (c.a[ch] * s1.env[ch] + c.k[ch] * s1.cs_env[ch]);
                }
            };
            let Some(rays) = &conditioned else {
                let (s, s_o, spec) = smith();
                add(1.0, (w1, w2), &s, s_o, &s, spec);
                continue;
            };
            // Smith's bin blended with the conditioned one by the footprint's far weight.
            if rays.far() < 1.0 {
                let (s, s_o, spec) = smith();
                add(1.0 - rays.far(), (w1, w2), &s, s_o, &s, spec);
            }
            let (mut s1, mut s1o, mut s2) = (SlopeShading::default(), 0.0, SlopeShading::default());
            // Each of the bin's sub-values with its own g′ (a riser and a tread in one bin are
            // two slope scales, not their root mean square) and its own visibility.
            let ks = 1.0 / BIN_SAMPLES as f64;
            let mut spec = [0.0f64; 3];
            for q in 0..BIN_SAMPLES {
                let xq = rays.value_at(lo + (hi - lo) * (q as f64 + 0.5) * ks);
                let gd = m.heights.transfer.derivative(rays.driver_value(xq));
                let mean_q = d.mean_gradient * (sigma_h * gd);
                // The conditioned visibility as a reweighting of the driver slopes' Gaussian,
                // shaded as the bins shade any Gaussian of slopes.
                let lz = rays.gradient_factor() * (sigma_h * gd);
                let [vo, v2] = rays.visibility_weights(xq);
                let shade_under = |v: Option<GaussianWeight>| {
                    let (m0, mu, c) = v?.tilted()?;
                    let cov = SlopeCov::from_mat(lz * c * lz.transpose());
                    let (sh, so) = self.visible_shading_sums(
                        mean_q + lz * mu,
                        &cov,
                        cfg.wo,
                        cfg.wi,
                        frame,
                        conditioned_points,
                    );
                    Some((m0, sh, so))
                };
                if let Some((m0, sh, so)) = shade_under(vo) {
                    s1.add(&sh, ks * m0);
                    s1o += ks * m0 * so;
                }
                let mut s2o_q = 0.0;
                if let Some((m0, sh, so)) = shade_under(v2) {
                    s2.add(&sh, ks * m0);
                    s2o_q = m0 * so;
                }
                if let (true, Some(v2)) = (sun_lit, v2) {
                    let cov_q = d.gradient_cov.scaled(sigma_h * gd);
                    // Its visible projected area, in closed form (the rule's sum of weights).
                    let so_q = expected_positive_part(
                        cfg.wo.z,
                        DVec2::new(cfg.wo.x, cfg.wo.y),
                        mean_q,
                        &cov_q,
                    );
                    let lobe = self.specular_lobes(mean_q, &cov_q, cfg.wo, cfg.wi);
                    let mass = self
                        .lobe_visibility(rays, &v2, sigma_h * gd, (mean_q, &cov_q), cfg)
                        .map_or(s2o_q, |v| v * so_q);
                    for ch in 0..3 {
                        spec[ch] += ks * lobe[ch] * mass;
                    }
                }
            }
            let width = hi - lo;
            add(rays.far(), (width, width), &s1, s1o, &s2, spec);
        }
        if !(den > 0.0) {
            return [0.0; 3];
        }
        num.map(|v| v / den)
    }

    /// The joint visibility of the facets under the specular lobe of a sub-value whose surface
    /// slopes are `scale·(∇f̄ + t)` with `t` the footprint's driver slopes (`(mean, cov)` in
    /// surface slope space): the joint term `v2` (a Gaussian function of the whitened driver
    /// slopes, [`TransferRays::visibility_weights`]) averaged over the lobe's half-vector
    /// posterior (the facets near the half vector), in closed form
    /// ([`GaussianWeight::expect_under`]). On #17's grid this took terraces' grazing lobe along
    /// the view (85°/60°) from −4.7% to −0.6% against the 64-node polar rule, and sponge's from
    /// −21% to −17%. `None` where there is no slope to select the facets by (then the average
    /// facet's).
    fn lobe_visibility(
        &self,
        rays: &TransferRays,
        v2: &GaussianWeight,
        scale: f64,
        (mean, cov): (DVec2, &SlopeCov),
        cfg: &FootprintQuery,
    ) -> Option<f64> {
        if !(scale.abs() > 1e-12) {
            return None;
        }
        let (pm, pc) =
            half_vector_posterior(mean, cov, cfg.wo, cfg.wi, self.material.brdf.roughness)?;
        // The posterior in whitened driver slopes: z = L⁻¹ (s − mean)/scale.
        let w = rays.whitening()? * (1.0 / scale);
        let (a11, a21, a22) = cholesky(pc.xx, pc.xy, pc.yy);
        let root = DMat2::from_cols(DVec2::new(a11, a21), DVec2::new(0.0, a22));
        v2.expect_under(w * (pm - mean), w * root)
    }
}
