//! A measured base BRDF (#18 §2): a MERL table ([`MerlBrdf`]) that replaces the analytic base
//! BRDF of the micro-facets, with its fit to the analytic model ([`MerlFit`]).
//!
//! # What each view does with it
//! - **Ground truth and naive** shade each facet (the explicit micro-normal, or the naive view's
//!   filtered normal) with the table itself, in the facet's own frame: ωi and ωo are expressed in a
//!   tangent frame around the facet normal ([`crate::scene::direction::basis`]); the table is
//!   isotropic, so which tangent is chosen changes nothing.
//! - **The filtered views** average the base BRDF over a footprint's slopes in closed form, which a
//!   table does not allow; they use the fit (Lambert `kd/π` plus the base lobe with weight F0 and
//!   slope deviation σ, per channel), and its [`MerlFit::relative_error`] says how far that is from
//!   the table.
//!
//! # Colour
//! The material's colour C (colour map and terms, [HNPN14 Sec. 6]) tints the whole measured BRDF:
//! a facet reflects `C ⊙ ρ_table(ωi, ωo)·(n·ωi)⁺` under the directional light, so a white colour
//! shows the measurement as it is. (The analytic base BRDF tints only its diffuse part; a
//! measurement has no such split.) The filtered views tint the fit's specular lobe with the mean
//! colour of the lit visible facets (`(A·E[cos] + K ⊙ E[C_s cos]) / E[cos]`).
//!
//! # Environment
//! As for the analytic base BRDF, the environment lights the diffuse part only: `kd/π ⊙ C ⊙ E_env(n)`
//! with the fit's kd, in every view (the table's own directional albedo is not integrated against
//! the environment).

use crate::material::merl::MerlBrdf;
use crate::material::merl_fit::MerlFit;
use crate::microfacet::brdf::BaseBrdf;
use crate::scene::direction::basis;
use glam::DVec3;

/// A measured base BRDF and its fit to the analytic model.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredBrdf {
    /// The table.
    pub table: MerlBrdf,
    /// The analytic model closest to it (what the filtered views use).
    pub fit: MerlFit,
}

impl MeasuredBrdf {
    /// Fit `table` (a few tens of milliseconds) and keep both.
    pub fn new(table: MerlBrdf) -> Self {
        let fit = MerlFit::of(&table);
        Self { table, fit }
    }

    /// ρ per channel (per steradian, not times the cosine) of a facet of unit normal n, with ωi
    /// and ωo unit vectors in the same frame as n. 0 when either direction is at or below the
    /// facet (or n is not finite).
    pub fn eval_facet(&self, n: DVec3, wi: DVec3, wo: DVec3) -> [f64; 3] {
        if !n.is_finite() {
            return [0.0; 3];
        }
        let (t, b) = basis(n);
        let local = |w: DVec3| DVec3::new(w.dot(t), w.dot(b), w.dot(n));
        self.table.eval(local(wi), local(wo))
    }

    /// The analytic base BRDF the filtered views start from: albedo 1 (the fit's per-channel kd
    /// is applied as a weight, [`MeasuredBrdf::channel_weights`]), F0 1 when the fit has a lobe
    /// (its lobes replace the base lobe, [`crate::eval::Evaluator`]'s `specular_lobes`), and the
    /// narrowest lobe's σ as base roughness. The measured file stays named.
    pub fn fitted_base(&self, measured: Option<String>) -> BaseBrdf {
        BaseBrdf {
            albedo: 1.0,
            specular: if self.fit.lobes.is_empty() { 0.0 } else { 1.0 },
            roughness: self.fit.lobes.first().map_or(0.2, |l| l.sigma),
            measured,
        }
    }

    /// Per-channel weights of the diffuse albedo under [`MeasuredBrdf::fitted_base`] (the fit's
    /// kd), with the specular lobes tinted by the facets' colour.
    pub fn channel_weights(&self) -> ChannelWeights {
        ChannelWeights {
            kd: self.fit.kd,
            tint_specular: true,
        }
    }
}

/// How the base BRDF's scalar albedo becomes a colour, and whether the specular lobe takes the
/// facets' colour (a measured BRDF) or stays white (the analytic one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChannelWeights {
    /// Weight of the diffuse albedo per channel.
    pub kd: [f64; 3],
    /// Whether the specular lobe is tinted by the facets' colour.
    pub tint_specular: bool,
}

impl ChannelWeights {
    /// The analytic base BRDF: grey weights, white specular.
    pub const ANALYTIC: ChannelWeights = ChannelWeights {
        kd: [1.0; 3],
        tint_specular: false,
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::direction::direction;
    use std::f64::consts::PI;

    /// A Lambertian-plus-lobe table (red diffuse, blue lobe) for the tests.
    fn measured() -> &'static MeasuredBrdf {
        static M: std::sync::OnceLock<MeasuredBrdf> = std::sync::OnceLock::new();
        M.get_or_init(|| {
            MeasuredBrdf::new(MerlBrdf::tabulate(|wi, wo| {
                if wi.z <= 0.0 || wo.z <= 0.0 {
                    return [0.0; 3];
                }
                let h = (wi + wo).normalize();
                let a2: f64 = 0.3 * 0.3;
                let c2 = h.z * h.z;
                let d = (-(1.0 - c2) / (c2 * a2)).exp() / (PI * a2 * c2 * c2);
                [0.6 / PI, 0.2 / PI, 0.5 * d / (4.0 * wi.z * wo.z)]
            }))
        })
    }

    /// At the macro normal the facet lookup is the table's; on a tilted facet it is the table at
    /// the directions rotated with the facet (any rotation, so any tangent frame, gives the same).
    #[test]
    fn a_facet_sees_the_table_in_its_own_frame() {
        let m = measured();
        for (ti, pi, to, po) in [
            (0.3, 0.2, 0.7, 2.0),
            (1.0, -1.0, 0.2, 0.5),
            (0.1, 0.0, 1.3, 3.0),
        ] {
            let (wi, wo) = (direction(ti, pi), direction(to, po));
            assert_eq!(m.eval_facet(DVec3::Z, wi, wo), m.table.eval(wi, wo));
            // Tilt everything by a rotation R: the facet R·z sees R·ωi, R·ωo as z sees ωi, ωo.
            for r in [
                glam::DMat3::from_rotation_x(0.4),
                glam::DMat3::from_rotation_y(-0.7) * glam::DMat3::from_rotation_z(1.1),
            ] {
                let got = m.eval_facet(r * DVec3::Z, r * wi, r * wo);
                let want = m.table.eval(wi, wo);
                for c in 0..3 {
                    // Bins are nearest-neighbour: a rounding at a bin edge may pick the neighbour.
                    assert!(
                        (got[c] - want[c]).abs() <= 0.02 * want[c].max(1e-3),
                        "{got:?} {want:?}"
                    );
                }
            }
        }
        // Below the facet: nothing; a non-finite normal: nothing.
        let n = direction(0.5, 0.0);
        assert_eq!(m.eval_facet(n, -n, DVec3::Z), [0.0; 3]);
        assert_eq!(m.eval_facet(DVec3::NAN, DVec3::Z, DVec3::Z), [0.0; 3]);
    }

    #[test]
    fn the_fitted_base_carries_the_fit() {
        let m = measured();
        let b = m.fitted_base(Some("x.binary".into()));
        assert_eq!((b.albedo, b.specular), (1.0, 1.0));
        assert_eq!(b.roughness, m.fit.lobes[0].sigma);
        assert_eq!(b.measured.as_deref(), Some("x.binary"));
        let w = m.channel_weights();
        assert!(w.tint_specular);
        // Red and green diffuse only, blue the lobe only.
        assert!(
            (w.kd[0] - 0.6).abs() < 0.02 && (w.kd[1] - 0.2).abs() < 0.01,
            "{w:?}"
        );
        let lobe = |c: usize| {
            m.fit
                .lobes
                .iter()
                .map(|l| l.weight[c] + l.fresnel[c])
                .sum::<f64>()
        };
        assert!(lobe(0) < 0.01 && lobe(2) > 0.3, "{:?}", m.fit);
    }

    /// A MERL table of an analytic base BRDF, read as the measured base BRDF, renders like that
    /// BRDF in every view: exactly for a Lambertian one (any colour, with the environment), and
    /// within the table's resolution and the frames' difference for a lobe (the analytic lobe is
    /// written in the macro frame's slope space, the table is looked up in each facet's frame);
    /// its filtered view follows its own truth.
    #[test]
    fn a_table_of_the_base_brdf_renders_like_it() {
        use crate::eval::Evaluator;
        use crate::fixtures::{far_patch, gaussian_material};
        use crate::material::ColorModel;
        use crate::material::environment::{Environment, EnvironmentSource, Sky};

        let with_table = |m: &crate::material::Material, table: MerlBrdf| {
            let mut analytic = m.clone();
            analytic.brdf.measured = None;
            let analytic = Evaluator::new(&analytic).expect("evaluator");
            let mut e = Evaluator::new(m).expect("evaluator");
            e.set_measured(std::sync::Arc::new(MeasuredBrdf::new(table)));
            assert!(e.measured.is_some());
            (analytic, e)
        };
        let configs = [
            (direction(0.5, 0.0), direction(0.4, 2.5)),
            (direction(1.05, 0.0), direction(0.35, 0.0)),
            (direction(0.9, 1.0), direction(0.7, -2.0)),
        ];
        let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-3);

        // Lambertian, albedo 0.8, under the sun and the sky, with the colour map.
        let mut m = gaussian_material();
        m.brdf.albedo = 0.8;
        m.brdf.measured = Some("lambert.binary".into());
        m.lighting.environment = Some(Environment {
            source: EnvironmentSource::Sky(Sky::default()),
            intensity: 0.5,
        });
        let (analytic, measured) = with_table(&m, MerlBrdf::tabulate(|_, _| [0.8 / PI; 3]));
        for (wo, wi) in configs {
            let q = far_patch(wo, wi);
            let pairs = [
                (analytic.filtered(&q), measured.filtered(&q)),
                (analytic.naive(&q), measured.naive(&q)),
                (analytic.view_independent(&q), measured.view_independent(&q)),
                (
                    analytic.ground_truth(&q, 600, 7).mean,
                    measured.ground_truth(&q, 600, 7).mean,
                ),
            ];
            for (a, b) in pairs {
                for c in 0..3 {
                    assert!(rel(b[c], a[c]) < 1e-5, "{wo} {wi}: {b:?} for {a:?}");
                }
            }
        }

        // Diffuse plus the base lobe (σ0 = 0.32, a rung of the fit's ladder), white, on slopes of
        // σ_n = 0.08.
        let mut m = gaussian_material();
        m.color = ColorModel::Attribute {
            mean: [1.0; 3],
            correlation: [0.0; 3],
        };
        m.slopes.sigma_nx = 0.08;
        m.slopes.sigma_ny = 0.08;
        m.brdf = BaseBrdf {
            albedo: 0.5,
            specular: 0.3,
            roughness: 0.32,
            measured: Some("lobe.binary".into()),
        };
        let base = m.brdf.clone();
        let table = MerlBrdf::tabulate(|wi, wo| {
            let spec = base.specular_with(DVec3::Z, wo, wi, Default::default()) / wi.z.max(1e-12);
            [0.5 / PI + spec; 3]
        });
        let (analytic, measured) = with_table(&m, table);
        for (wo, wi) in configs {
            let q = far_patch(wo, wi);
            let (a, b) = (analytic.filtered(&q), measured.filtered(&q));
            let (ta, tb) = (
                analytic.ground_truth(&q, 4000, 3),
                measured.ground_truth(&q, 4000, 3),
            );
            eprintln!(
                "{wo} {wi}: filtered {b:?} for {a:?}, truth {:?} for {:?}",
                tb.mean, ta.mean
            );
            for c in 0..3 {
                // The measured lobe is looked up in the facet's frame (truth) and corrected to it
                // in the filtered view (`facet_frame_factor`); the analytic lobe lives in the
                // macro frame's slope space. Measured: 0.1–1.9% from the measured truth.
                assert!(
                    rel(b[c], tb.mean[c]) < 0.025,
                    "{wo} {wi}: filtered {b:?} for the truth {:?}",
                    tb.mean
                );
                assert!(
                    rel(b[c], a[c]) < 0.03,
                    "{wo} {wi}: filtered {b:?} for {a:?}"
                );
                assert!(
                    rel(tb.mean[c], ta.mean[c]) < 0.015,
                    "{wo} {wi}: truth {:?} for {:?}",
                    tb.mean,
                    ta.mean
                );
            }
        }
    }
}
