//! Prototype (#17): the filtered model (diffuse and specular, sun) as a mixture over the driver's
//! value.
//!
//! For a Gaussian driver f ~ N(f̄, σ_f²) over the footprint, the value and the gradient of f at a
//! point are independent, so the transformed surface h = σ_h·g(f) has, given f, Gaussian slopes
//! N(σ_h g′(f)·∇f̄, σ_h² g′(f)²·Σ_∇f): a scale mixture of Gaussians, not one Gaussian, whenever g
//! is not linear. The colour C(f) (or C of the standardized height g(f)) rides on the same f, so
//! colour and slope correlate through g′(f). Smith's masking with slopes that depend on height
//! (Smith 1967; Bourlier et al. 2002): a point at standardized driver value z (heights ordered
//! like z for a non-decreasing g) is visible along ω with probability
//! `G1(z) = exp(−∫_z^∞ Λ(ω; z′) φ(z′)/Φ(z′) dz′)`, Λ(ω; z′) the Gaussian Λ of the slopes at z′
//! (with slopes independent of height this is Φ(z)^Λ, the usual form). View and light combine per
//! z′ as in [`G2::new`]. The diffuse radiance per visible projected area is then
//!
//! `I = Σ_j w_j [G2(z_j)·E_sun((ρ/π)·C_j S_j + So_j ρ_s,j) + G1o(z_j)(ρ/π)·C_j S_env,j] / Σ_j w_j G1o(z_j) So_j`
//!
//! with `S_j = E[⟨ωo·m⟩⁺/m_z·⟨ωi·m⟩⁺]` and `So_j = E[⟨ωo·m⟩⁺/m_z]` over node j's slopes, and
//! ρ_s,j the widened specular lobe of node j's slopes per unit of their visible area
//! ([`filtered_specular`], [`visible_slope_nodes`]). The colour terms (constant, slope colour)
//! and the environment enter per node as in the model: `C_j` is the point colour's `A + K ⊙ C_s`,
//! the environment is weighted by G1 (unshadowed), the sun by G2. Far field, plane; the colour
//! map (driver or height source) or the HN12 attribute at the point's standardized height
//! (clamped at 0). CPU only: compared with the ground truth by `lodestone diagnose` before the
//! model adopts it.
//!
//! **Image drivers.** An image's value and gradient are not independent: the nodes carry the
//! image's values `T⁻¹(μ_G + σ_G z)` where it keeps its histogram
//! ([`crate::driver::histogram`]), and node z gets the slope covariance
//! `Σ_∇f · s²(f_z) / E_z[s²]` with `s²` the image's conditional slope scale
//! ([`ConditionalSlopes`], normalized over the footprint's nodes so the total stays the
//! pyramid's). Cobblestones' far patch against the truth (`tests/tests/image_slopes.rs`): one
//! Gaussian −2.2% at 0°, −2.2% at 60° (light 30° opposite), +7.8% and +17.4% at 85°; value-
//! conditioned +0.5%, 0.0%, +0.1%, +2.2%. Without `s²` the mixture is the model (within 0.1%).

use crate::driver::conditional_slopes::ConditionalSlopes;
use crate::driver::histogram::DriverHistogram;
use crate::eval::shading::{SlopeShading, specular_tint};
use crate::eval::{Evaluator, FootprintQuery};
use crate::material::color_terms::Affine;
use crate::material::{ColorModel, ColorSource};
use crate::math::special::{norm_cdf, norm_pdf};
use crate::microfacet::attribute::attribute;
use crate::microfacet::masking_shadowing::{G2, azimuth_difference};
use crate::microfacet::smith::lambda;
use crate::microfacet::visible_slopes::visible_slope_nodes;
use glam::DMat3;
use std::f64::consts::FRAC_1_PI;

/// Nodes of the driver's standardized value: z in [−Z_MAX, Z_MAX], step 2·Z_MAX/(NODES − 1).
const NODES: usize = 241;
const Z_MAX: f64 = 6.0;

impl Evaluator {
    /// The filtered model as a mixture over the driver's value (module docs). `Some` always (an
    /// `Option` so that a variant it cannot represent can say so).
    pub fn filtered_mixture(&self, cfg: &FootprintQuery) -> Option<[f64; 3]> {
        let m = &self.material;
        let (wo, wi) = (cfg.wo, cfg.wi);
        if wo.z <= 0.0 {
            return Some([0.0; 3]);
        }
        // The colour of a point with driver value f (t its standardized height), as the ground
        // truth colours it ([`Evaluator::color_at`]), then the colour terms' A + K ⊙ C_s(n).
        let color_of = |f: f64| -> [f64; 3] {
            let (gm, gs) = self.global_height;
            let t = (m.heights.transfer.eval(f) - gm) / gs;
            match &m.color {
                ColorModel::Gradient { map, source } => map.sample(match source {
                    ColorSource::Driver => f,
                    ColorSource::Height => t,
                }),
                ColorModel::Attribute { mean, correlation } => {
                    [0, 1, 2].map(|k| attribute(mean[k], correlation[k], t).max(0.0))
                }
            }
        };
        let loc = self.footprint_stats(cfg);
        let d = loc.driver;
        let sigma_h = self.surface.sigma_h;
        let dz = 2.0 * Z_MAX / (NODES - 1) as f64;
        let zs: Vec<f64> = (0..NODES).map(|j| -Z_MAX + dz * j as f64).collect();
        let total: f64 = zs.iter().map(|&z| norm_pdf(z)).sum();
        let points = m.slope_rule();
        let dphi = azimuth_difference(wo, wi);
        let sun_up = wi.z > 0.0;
        struct Node {
            w: f64,
            color: Affine,
            l_o: f64,
            l_total: f64,
            // Unnormalized visible-slope sums: the shading inputs weighted by ⟨ωo·m⟩⁺/m_z.
            shading: SlopeShading,
            s_o: f64,
            spec: [f64; 3],
        }
        // An image driver: its values T⁻¹(μ_G + σ_G z) where it keeps its histogram, and its
        // slopes' dependence on the value ([`ConditionalSlopes`]), normalized over the footprint.
        let image = self.surface.driver.image().map(|t| {
            let hist = m
                .image_histogram()
                .then(|| DriverHistogram::of_image(&t.image));
            (hist, ConditionalSlopes::of_image(&t.image))
        });
        let values: Vec<f64> = match &image {
            Some((Some(h), _)) => {
                let (mu, sg) = h.gaussianize(d.mean, d.std);
                zs.iter().map(|&z| h.inverse(mu + sg * z)).collect()
            }
            _ => zs.iter().map(|&z| d.mean + d.std * z).collect(),
        };
        let slope_scale: Vec<f64> = match &image {
            Some((_, c)) => {
                let raw: Vec<f64> = values.iter().map(|&f| c.scale_at(f)).collect();
                let mean = raw
                    .iter()
                    .zip(&zs)
                    .map(|(s, &z)| s * norm_pdf(z))
                    .sum::<f64>()
                    / total;
                raw.iter()
                    .map(|s| if mean > 0.0 { (s / mean).sqrt() } else { 1.0 })
                    .collect()
            }
            _ => vec![1.0; NODES],
        };
        let nodes: Vec<Node> = zs
            .iter()
            .zip(values.iter().zip(&slope_scale))
            .map(|(&z, (&f, &scale))| {
                let gd = m.heights.transfer.derivative(f) * scale;
                let mean = d.mean_gradient * (sigma_h * gd);
                let cov = d.gradient_cov.scaled(sigma_h * gd);
                let ms = G2::new(
                    lambda(wo, &cov),
                    lambda(wi, &cov),
                    dphi,
                    m.filtering.correlation,
                );
                let mut acc = SlopeShading::default();
                let mut s_o = 0.0;
                visible_slope_nodes(mean, &cov, wo, points, |n, w| {
                    s_o += w;
                    let p = self.point_shading(n, wi, &DMat3::IDENTITY);
                    if sun_up {
                        acc.cos += w * p.cos;
                    }
                    for c in 0..3 {
                        if sun_up {
                            acc.cs_cos[c] += w * p.cs_cos[c];
                        }
                        acc.env[c] += w * p.env[c];
                        acc.cs_env[c] += w * p.cs_env[c];
                    }
                });
                Node {
                    w: norm_pdf(z) / total,
                    color: m.terms.affine(color_of(f)),
                    l_o: ms.lambda_o,
                    l_total: ms.total,
                    shading: acc,
                    s_o,
                    spec: self.specular_lobes(mean, &cov, wo, wi),
                }
            })
            .collect();
        // G(z_j) = exp(−Σ_{i>j} Λ_i w_i/Φ(z_i) − ½Λ_j w_j/Φ(z_j)): the integral from the top down.
        let kd = m.brdf.albedo * FRAC_1_PI;
        let w = self.channel_weights();
        let sun = m.lighting.sun;
        let (mut acc_o, mut acc) = (0.0, 0.0);
        let (mut num, mut den) = ([0.0f64; 3], 0.0f64);
        for (j, node) in nodes.iter().enumerate().rev() {
            let phi = norm_cdf(zs[j]).max(1e-300);
            let (half_o, half) = (
                0.5 * node.l_o * node.w / phi,
                0.5 * node.l_total * node.w / phi,
            );
            // Visible (G1) for the unshadowed environment, visible and lit (G2) for the sun.
            let (g1, g2) = ((-(acc_o + half_o)).exp(), (-(acc + half)).exp());
            acc_o += 2.0 * half_o;
            acc += 2.0 * half;
            den += node.w * g1 * node.s_o;
            let (a, k, sh) = (node.color.a, node.color.k, &node.shading);
            let tint = specular_tint(&w, &node.color, sh);
            for c in 0..3 {
                let sun_part = sun * (a[c] * sh.cos + k[c] * sh.cs_cos[c]);
                let env_part = a[c] * sh.env[c] + k[c] * sh.cs_env[c];
                // The node's lobe per unit of its visible area (filtered_specular divides by So).
                let spec = if sun_up {
                    sun * node.s_o * node.spec[c]
                } else {
                    0.0
                };
                num[c] += node.w
                    * (g2 * (kd * w.kd[c] * sun_part + spec * tint[c])
                        + g1 * kd * w.kd[c] * env_part);
            }
        }
        if !(den > 0.0) {
            return Some([0.0; 3]);
        }
        Some(num.map(|v| v / den))
    }
}

#[cfg(test)]
mod tests {
    use crate::eval::{Evaluator, FootprintQuery};
    use crate::fixtures::gaussian_material;
    use crate::material::{ColorModel, ColorSource};
    use crate::microfacet::height_mixture::TransferSlopes;
    use crate::microfacet::transfer::{Curve, TransferFunction};
    use crate::scene::direction::direction;
    use glam::DVec3;

    fn far(deg: f64, wi: DVec3) -> FootprintQuery {
        crate::fixtures::far_patch(direction(deg.to_radians(), 0.3), wi)
    }

    /// With the identity transfer the slopes do not depend on f: the mixture is one Gaussian and
    /// reproduces the filtered model (to its quadrature): colour map, HN12 attribute, and specular
    /// with the sky and a slope colour. So does the binned form the views run.
    #[test]
    fn with_the_identity_transfer_it_is_the_filtered_model() {
        let mut attribute = gaussian_material();
        attribute.color = ColorModel::Attribute {
            mean: [0.4, 0.25, 0.1],
            correlation: [0.2, 0.1, -0.05],
        };
        // Specular, the sky and a slope colour multiplying the height colour.
        let mut lit = gaussian_material();
        lit.brdf.specular = 0.04;
        lit.brdf.roughness = 0.15;
        // The mixture's lobes are Gaussian: compare with the model's Gaussian lobe (the noise's
        // own slope density is checked in microfacet::slope_density).
        lit.filtering.noise_slopes = crate::microfacet::slope_density::NoiseSlopes::Gaussian;
        lit.lighting.environment = Some(crate::material::environment::Environment {
            source: crate::material::environment::EnvironmentSource::Sky(
                crate::material::environment::Sky::default(),
            ),
            intensity: 0.7,
        });
        lit.terms.mode = crate::material::color_terms::CombineMode::Multiplicative;
        lit.terms.slope = Some(crate::material::color_terms::SlopeTerm {
            color: crate::material::slope_color::SlopeColor::snow(),
            weight: 0.8,
        });
        for mut m in [gaussian_material(), attribute, lit] {
            // The mixture's bins carry Smith's masking (the joint one is for noise drivers
            // under the identity, where the mixture is not used).
            m.filtering.slope_masking = crate::microfacet::slope_masking::SlopeMasking::Smith;
            let p = Evaluator::new(&m).expect("valid");
            for (deg, wi) in [
                (0.0, DVec3::Z),
                (45.0, direction(0.8, 3.4)),
                (75.0, direction(0.5, 0.3)),
            ] {
                let cfg = far(deg, wi);
                let (a, b) = (p.filtered(&cfg), p.filtered_mixture(&cfg).expect("applies"));
                let bins = p.filtered_as_mixture(&cfg);
                // The model's height filter fits D_h's moments; the mixture integrates
                // Φ(z)^L exactly: 0.25% apart at 75°.
                for k in 0..3 {
                    assert!((a[k] - b[k]).abs() < 4e-3 * a[k], "{deg}°: {a:?} vs {b:?}");
                    assert!(
                        (a[k] - bins[k]).abs() < 8e-3 * a[k],
                        "{deg}°: {a:?} vs {bins:?}"
                    );
                }
            }
        }
    }

    /// A transfer curve (moss) makes the slopes a scale mixture correlated with the colour: one
    /// Gaussian (the papers' model, `transfer_slopes: Gaussian`) is 6–34% off the ray-traced
    /// truth up to 60° (core/src/eval/independent_tests.rs), the mixture within 3% up to 30%
    /// (measured: 2.7% at most) with the colour by driver or by height, and so is the binned
    /// mixture the views run; over these configurations the worst errors of either sum to under
    /// a third of the Gaussian's. Far patch, 20k rays.
    #[test]
    fn on_a_transfer_curve_it_closes_most_of_the_gap() {
        let mut m = gaussian_material();
        m.heights.transfer = TransferFunction::Curve(Curve::moss());
        let mut by_height = m.clone();
        if let ColorModel::Gradient { source, .. } = &mut by_height.color {
            *source = ColorSource::Height;
        }
        let (mut sum_filtered, mut sum_mixture, mut sum_bins) = (0.0, 0.0, 0.0);
        for m in [m, by_height] {
            let p = Evaluator::new(&m).expect("valid");
            let mut gaussian = m.clone();
            gaussian.filtering.transfer_slopes = TransferSlopes::Gaussian;
            let pg = Evaluator::new(&gaussian).expect("valid");
            for (deg, wi) in [
                (0.0, DVec3::Z),
                (30.0, direction(0.8, 0.3)),
                (30.0, DVec3::Z),
            ] {
                let cfg = far(deg, wi);
                let gt = p.ground_truth(&cfg, 20_000, 29);
                let (fi, mx) = (
                    pg.filtered(&cfg),
                    p.filtered_mixture(&cfg).expect("applies"),
                );
                let bins = p.filtered(&cfg);
                let rel = |v: [f64; 3], k: usize| (v[k] - gt.mean[k]).abs() / gt.mean[k];
                let se = |k: usize| gt.std_error[k] / gt.mean[k];
                sum_filtered += (0..3).map(|k| rel(fi, k)).fold(0.0, f64::max);
                sum_mixture += (0..3).map(|k| rel(mx, k)).fold(0.0, f64::max);
                sum_bins += (0..3).map(|k| rel(bins, k)).fold(0.0, f64::max);
                for k in 0..3 {
                    for (v, what) in [(mx, "mixture"), (bins, "binned")] {
                        assert!(
                            rel(v, k) < 0.03 + 3.0 * se(k),
                            "{deg}°, channel {k}: {what} {v:?} vs truth {:?} ± {:?}",
                            gt.mean,
                            gt.std_error
                        );
                    }
                }
            }
        }
        assert!(
            sum_mixture.max(sum_bins) < sum_filtered / 3.0,
            "mixture {sum_mixture}, binned {sum_bins} vs Gaussian {sum_filtered}"
        );
    }
}

#[cfg(test)]
mod binning {
    use crate::eval::{Evaluator, FootprintQuery};
    use crate::fixtures::preset;
    use crate::microfacet::height_mixture::TransferSlopes;
    use crate::scene::direction::direction;
    use glam::DVec3;

    /// Signed relative error of `v` against `fine`, the channel farthest off, in %.
    fn worst(v: [f64; 3], fine: [f64; 3]) -> f64 {
        (0..3)
            .map(|k| 100.0 * (v[k] - fine[k]) / fine[k])
            .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a })
    }

    const CONFIGS: [(f64, f64, f64); 4] = [
        (0.0, 0.0, 0.0),
        (45.0, 30.0, 180.0),
        (75.0, 30.0, 0.0),
        (75.0, 0.0, 0.0),
    ];

    /// The filtered view's binned mixture with Smith's masking (8 equal bins and the curve's knots, 4 samples and
    /// 4×4 slope nodes per bin) against the 241-node mixture on the library's transfer-curve
    /// presets, where one Gaussian is 4–51% off it. Measured: moss ≤ 0.11%, sponge ≤ 0.8%,
    /// terraces ≤ 1.7% at 0°, 2.5% at 45°, 5.1% at 75°.
    #[test]
    fn the_binned_mixture_follows_the_fine_one() {
        for (name, bounds) in [
            ("moss", [0.3, 0.3, 0.3]),
            ("sponge", [1.0, 1.2, 1.2]),
            ("terraces", [2.2, 3.2, 6.5]),
        ] {
            // Smith's bins: the fine mixture's masking is Smith's (the conditioned bins are
            // measured against the truth, core/tests/measurements/transfer_masking.rs).
            let mut p = Evaluator::new(&preset(name)).expect("prepared");
            p.transfer_masking = None;
            for (deg, light, az) in CONFIGS {
                let cfg = FootprintQuery::far(
                    &p,
                    direction(deg.to_radians(), 0.0),
                    direction(light.to_radians(), az.to_radians()),
                );
                let fine = p.filtered_mixture(&cfg).expect("applies");
                let e = worst(p.filtered(&cfg), fine);
                let bound = bounds[if deg < 30.0 {
                    0
                } else if deg < 60.0 {
                    1
                } else {
                    2
                }];
                assert!(e.abs() < bound, "{name} {deg}°: {e:+.2}% (bound {bound}%)");
            }
        }
    }

    /// The binned mixture against the fine one, and the one Gaussian (`transfer_slopes:
    /// Gaussian`) for comparison (measurement; `cargo test -- --ignored`).
    #[test]
    #[ignore = "a measurement for the closing note, prints a table"]
    fn binned_against_fine() {
        for name in ["moss", "terraces", "sponge"] {
            let m = preset(name);
            let p = Evaluator::new(&m).expect("prepared");
            let mut g = m.clone();
            g.filtering.transfer_slopes = TransferSlopes::Gaussian;
            let pg = Evaluator::new(&g).expect("prepared");
            for (deg, light, az) in CONFIGS {
                let wi = if light == 0.0 {
                    DVec3::Z
                } else {
                    direction(light.to_radians(), az.to_radians())
                };
                let cfg = FootprintQuery::far(&p, direction(deg.to_radians(), 0.0), wi);
                let fine = p.filtered_mixture(&cfg).expect("applies");
                eprintln!(
                    "{name:9} {deg:3}° light {light}/{az}: gaussian {:+6.2}%  bins {:+6.2}%",
                    worst(pg.filtered(&cfg), fine),
                    worst(p.filtered(&cfg), fine)
                );
            }
        }
    }
}

#[cfg(test)]
mod image_tests {
    use crate::driver::image::ImageDriver;
    use crate::driver::test_images;
    use crate::eval::{Evaluator, FootprintQuery};
    use crate::microfacet::height_mixture::TransferSlopes;
    use crate::scene::direction::direction;
    use std::sync::Arc;

    /// The far patch of the cobblestones material with each generated test image as its driver:
    /// (image, whether it is far from Gaussian, view, light azimuth, the one-Gaussian model's
    /// relative error (`TransferSlopes::Gaussian`), the views' value-conditioned bins', the
    /// truth's relative standard error), worst channel; the 241-node prototype is printed.
    fn errors(
        views: &[f64],
        azimuths: &[f64],
    ) -> Vec<(&'static str, bool, f64, f64, f64, f64, f64)> {
        let base = crate::fixtures::preset("cobblestones");
        let mut gaussian = base.clone();
        gaussian.filtering.transfer_slopes = TransferSlopes::Gaussian;
        let mut rows = vec![];
        for (name, img, skewed) in test_images::all() {
            let image =
                Arc::new(ImageDriver::new(test_images::SIDE, test_images::SIDE, &img).unwrap());
            let p = Evaluator::with_image(&base, Some(image.clone()), None).unwrap();
            let pg = Evaluator::with_image(&gaussian, Some(image), None).unwrap();
            for &view in views {
                for &azimuth in azimuths {
                    let cfg = FootprintQuery::far(
                        &p,
                        direction(view.to_radians(), 0.0),
                        direction(30f64.to_radians(), azimuth.to_radians()),
                    );
                    let t = p.ground_truth(&cfg, 20_000, 1);
                    let err = |v: [f64; 3]| {
                        (0..3)
                            .map(|k| (v[k] - t.mean[k]) / t.mean[k])
                            .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a })
                    };
                    let model = err(pg.filtered(&cfg));
                    let mixture = err(p.filtered(&cfg));
                    let prototype = err(p.filtered_mixture(&cfg).unwrap());
                    let se = (0..3)
                        .map(|k| t.std_error[k] / t.mean[k])
                        .fold(0.0, f64::max);
                    eprintln!(
                        "{name:<18} view {view:>2}° light 30°/{azimuth:>3}°: one Gaussian \
                         {:+.2}%, conditioned bins {:+.2}% (prototype {:+.2}%; s.e. {:.2}%)",
                        100.0 * model,
                        100.0 * mixture,
                        100.0 * prototype,
                        100.0 * se
                    );
                    rows.push((name, skewed, view, azimuth, model, mixture, se));
                }
            }
        }
        rows
    }

    /// Issue #17 item 6, at the normal view (no masking: what the slopes' split among values
    /// does alone). On the generated non-Gaussian images the one-Gaussian model is 10–22% off
    /// (the slopes of flat tops and steep edges pooled); the value-conditioned slopes are within
    /// 2.5%, at least three times closer; the Gaussian-like control is unchanged.
    #[test]
    fn value_conditioned_slopes_fix_the_test_images_at_the_normal_view() {
        for (name, skewed, _, _, model, mixture, se) in errors(&[0.0], &[180.0]) {
            if skewed && model.abs() > 0.03 {
                assert!(
                    mixture.abs() * 3.0 <= model.abs(),
                    "{name}: {mixture} against {model}"
                );
                assert!(mixture.abs() <= 0.025 + 3.0 * se, "{name}: {mixture}");
            } else {
                assert!(
                    (mixture - model).abs() <= 0.002,
                    "{name}: {mixture} against {model}"
                );
            }
        }
    }

    /// The whole grid (views 0°, 60°, 85° × light 30° on the view's side and opposite), printed:
    /// `cargo test --release -p lodestone-core -- --ignored image_tests --nocapture`.
    /// Measured 2026-12-03: at 0° and 60° (light opposite) the conditioned slopes are 3–17×
    /// closer on every skewed image; at 60° with the light on the view's side bricks gets worse
    /// (−4.8% → −7.4%) and cracked mud changes sign (+3.9% → −3.8%); at 85° both are far off on
    /// bricks, gravel, cracked mud and tiles (to −59%/+130%: masking on plateaus and grooves).
    #[test]
    #[ignore = "measurement: prints the grid"]
    fn value_conditioned_slopes_on_the_test_images_grid() {
        let rows = errors(&[0.0, 60.0, 85.0], &[0.0, 180.0]);
        assert_eq!(rows.len(), 36);
    }
}
