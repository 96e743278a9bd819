//! The material-level cases of `lodestone stability`: extreme σ's, anisotropy, attributes beyond
//! their mean, step colour maps, vertical transfer risers, slope colours under the sky and a
//! constant image, each run through every CPU output ([`material_outputs`]: must be finite and
//! ≥ 0) and checked against a [`Reference`]: an exact identity of the model or a limit, computed
//! through other materials or other outputs.

use crate::cli::stability::inputs::{ramp, step_map, vertical_curve};
use crate::cli::stability::row::{Path, Row, deviation};
use glam::DVec3;
use lodestone_core::driver::footprint::Footprint;
use lodestone_core::driver::image::ImageDriver;
use lodestone_core::eval::{Evaluator, FootprintQuery, Method};
use lodestone_core::material::color_terms::{ColorTerms, CombineMode, ConstantTerm, SlopeTerm};
use lodestone_core::material::colormap::{ColorStop, Gradient, Interpolation};
use lodestone_core::material::environment::{Environment, EnvironmentSource, Lighting, Sky};
use lodestone_core::material::slope_color::SlopeColor;
use lodestone_core::material::{ColorModel, ColorSource, Heights, Material, Slopes};
use lodestone_core::microfacet::slope_masking::SlopeMasking;
use lodestone_core::microfacet::transfer::TransferFunction;
use lodestone_core::scene::direction::direction;
use std::f64::consts::FRAC_PI_2;
use std::sync::Arc;

/// View angles from the normal: 0, 1e-7 rad, 89.9°, 89.999°, 90° and 100° (below the horizon).
pub fn angles() -> [f64; 6] {
    [
        0.0,
        1e-7,
        89.9f64.to_radians(),
        89.999f64.to_radians(),
        90f64.to_radians(),
        100f64.to_radians(),
    ]
}

fn base() -> Material {
    Material {
        heights: Heights {
            sigma_h: 0.05,
            transfer: TransferFunction::Identity,
        },
        ..Material::default()
    }
}

fn with_sigmas(sh: f64, sx: f64, sy: f64) -> Material {
    Material {
        heights: Heights {
            sigma_h: sh,
            transfer: TransferFunction::Identity,
        },
        slopes: Slopes {
            sigma_nx: sx,
            sigma_ny: sy,
        },
        ..base()
    }
}

/// What a material case's far-footprint statistics (naive, view-independent and filtered colour at
/// the angles below 90°) are checked against. Each is an exact identity of the model or a limit it
/// must reach, computed through a different material or different outputs, never the case itself.
#[derive(Debug)]
pub enum Reference {
    /// Another (procedural) material gives the same statistics within `bound` (relative, floor
    /// 1e-3), seen from the same azimuths or, `mirrored`, from azimuths mirrored across x = y.
    Same {
        /// The reference material.
        material: Box<Material>,
        /// Seen from π/2 − φ instead of φ (view and light).
        mirrored: bool,
        /// Bound on the relative deviation.
        bound: f64,
        /// Why it must be the same.
        what: &'static str,
    },
    /// Without micro-slopes (σ_n = 0, or g′ = 0 but for vertical risers) nothing is masked or
    /// shadowed: filtered equals view-independent within `bound` (relative, floor 1e-3): exact
    /// (1e-9) for one Gaussian; a transfer curve's mixture averages the colour per bin on
    /// quadrature nodes instead of the pre-convolved table (measured 4.2e-4; bound 1e-3).
    FilteredIsViewIndependent {
        /// Bound on the relative deviation.
        bound: f64,
    },
    /// [HN12 Eq. 17] clamped at 0, per channel `D·max(0, ā + a_s·s̄) + S`, with the diffuse factor
    /// D, the rest S and the mean shape s̄ measured on three attribute materials that stay positive
    /// (ā, a_s) = (0, 0), (1, 0), (1, 1).
    ClampedAttribute {
        /// ā.
        mean: [f64; 3],
        /// a_s.
        correlation: [f64; 3],
    },
}

impl Reference {
    fn bound(&self) -> f64 {
        match self {
            Self::Same { bound, .. } => *bound,
            Self::FilteredIsViewIndependent { bound } => *bound,
            Self::ClampedAttribute { .. } => 1e-9,
        }
    }

    fn describe(&self) -> String {
        match self {
            Self::Same { what, .. } => format!("{what} (relative, floor 1e-3)"),
            Self::FilteredIsViewIndependent { .. } => {
                "no micro-slopes, nothing masked: filtered = view-independent (relative, floor 1e-3)"
                    .into()
            }
            Self::ClampedAttribute { .. } => {
                "HN12 Eq. 17 clamped at 0, from three positive attribute materials (relative, floor 1e-3)"
                    .into()
            }
        }
    }
}

/// A material case: its name, the material, its image (image drivers), and its [`Reference`].
#[derive(Debug)]
pub struct MaterialCase {
    /// What it stresses.
    pub name: String,
    /// The material.
    pub material: Material,
    /// The image of an image driver.
    pub image: Option<Arc<ImageDriver>>,
    /// What its statistics must equal.
    pub reference: Reference,
}

fn same(material: Material, bound: f64, what: &'static str) -> Reference {
    Reference::Same {
        material: Box::new(material),
        mirrored: false,
        bound,
        what,
    }
}

/// The material-level cases of `lodestone stability`.
pub fn material_cases() -> Vec<MaterialCase> {
    let mut out = Vec::new();
    let flat = with_sigmas(0.0, 0.0, 0.0);
    out.push(MaterialCase {
        name: "σ_h = σ_n = 1e-9".into(),
        material: with_sigmas(1e-9, 1e-9, 1e-9),
        image: None,
        reference: same(flat.clone(), 1e-6, "the flat material (σ = 0)"),
    });
    out.push(MaterialCase {
        name: "σ_h = σ_n = 0".into(),
        material: flat,
        image: None,
        reference: Reference::FilteredIsViewIndependent { bound: 1e-9 },
    });
    // With the identity transfer the far statistics are free of σ_h's scale (heights enter
    // through Λ and the standardized height distribution only); σ_n → ∞ has a limit.
    const SCALE_FREE: &str = "σ_h = 0.05: the far statistics do not depend on σ_h's scale";
    for (sh, sn, reference) in [
        (
            1e6,
            0.35,
            same(with_sigmas(0.05, 0.35, 0.35), 1e-9, SCALE_FREE),
        ),
        (
            0.05,
            1e6,
            same(
                with_sigmas(0.05, 1e5, 1e5),
                2e-3,
                "the σ_n → ∞ limit, reached at σ_n = 1e5",
            ),
        ),
        (
            1e6,
            1e6,
            same(with_sigmas(0.05, 1e6, 1e6), 1e-9, SCALE_FREE),
        ),
    ] {
        out.push(MaterialCase {
            name: format!("σ_h = {sh:e}, σ_n = {sn:e}"),
            material: with_sigmas(sh, sn, sn),
            image: None,
            reference,
        });
    }
    for r in [1e-6f64, 1e6] {
        out.push(MaterialCase {
            name: format!("anisotropy σ_nx/σ_ny = {r:e}"),
            material: with_sigmas(0.05, 0.35 * r.sqrt(), 0.35 / r.sqrt()),
            image: None,
            reference: Reference::Same {
                material: Box::new(with_sigmas(0.05, 0.35 / r.sqrt(), 0.35 * r.sqrt())),
                mirrored: true,
                // The specular lobe's exact slope density and the slope-conditioned masking's
                // table depend on the realised waves, which are isotropic in distribution but not
                // mirror-symmetric: 5e-8 measured with Smith's masking, 2.1e-6 with the joint.
                bound: 1e-5,
                what: "the transposed anisotropy seen mirrored across x = y (the noise is isotropic)",
            },
        });
    }
    let attr = |corr: f64| Material {
        color: ColorModel::Attribute {
            mean: [0.2, 0.3, 0.1],
            correlation: [corr, -corr, 0.0],
        },
        ..base()
    };
    out.push(MaterialCase {
        name: "a_s = ±2.5·ā (attribute beyond its mean)".into(),
        material: attr(0.5),
        image: None,
        reference: Reference::ClampedAttribute {
            mean: [0.2, 0.3, 0.1],
            correlation: [0.5, -0.5, 0.0],
        },
    });
    let single = Material {
        color: ColorModel::Gradient {
            map: Gradient {
                stops: vec![ColorStop {
                    position: 0.3,
                    color: [0.4, 0.3, 0.2],
                }],
                interpolation: Interpolation::Linear,
            },
            source: ColorSource::Driver,
        },
        ..base()
    };
    let constant = Material {
        color: ColorModel::Attribute {
            mean: [0.4, 0.3, 0.2],
            correlation: [0.0; 3],
        },
        ..base()
    };
    out.push(MaterialCase {
        name: "colour map with a single stop".into(),
        material: single,
        image: None,
        reference: same(constant, 1e-6, "the same constant colour as an attribute"),
    });
    out.push(MaterialCase {
        name: "step colour map (Constant interpolation)".into(),
        material: Material {
            color: ColorModel::Gradient {
                map: step_map(),
                source: ColorSource::Driver,
            },
            ..base()
        },
        image: None,
        reference: same(
            Material {
                color: ColorModel::Gradient {
                    map: ramp(&step_map()),
                    source: ColorSource::Driver,
                },
                ..base()
            },
            1e-6,
            "the same steps as a Linear map with 1e-7 ramps",
        ),
    });
    out.push(MaterialCase {
        name: "transfer function with vertical segments".into(),
        material: {
            let mut m = Material {
                heights: Heights {
                    sigma_h: 0.05,
                    transfer: TransferFunction::Curve(vertical_curve()),
                },
                ..base()
            };
            m.filtering.slope_masking = SlopeMasking::Smith;
            m
        },
        image: None,
        // g′ = 0 off the risers, whose slopes are deltas the statistics leave out (a riser of
        // width ε adds slopes of variance ∝ 1/ε: there is no limit to compare with), so the
        // transformed surface has no micro-slopes to mask with under Smith's height-only
        // masking. (The masking conditioned on the driver's slope sees the risers block rays,
        // as the explicit staircase does: 2% off this reference.) Its mixture's colour is a
        // quadrature over the bins (8 equal ones and the knots, 4 nodes each).
        reference: Reference::FilteredIsViewIndependent { bound: 1e-3 },
    });
    // Slope colour and environment: a constant slope map is the constant term exactly;
    // a step slope map under the sky at extreme slope spreads stays finite.
    let sky = Some(Environment {
        source: EnvironmentSource::Sky(Sky::default()),
        intensity: 1.0,
    });
    let slope_term = |map: Gradient, weight: f64| {
        Some(SlopeTerm {
            color: SlopeColor {
                map,
                elevation_deg: 60.0,
                azimuth_deg: 30.0,
            },
            weight,
        })
    };
    let single_stop = Gradient {
        stops: vec![ColorStop {
            position: 0.1,
            color: [0.4, 0.3, 0.2],
        }],
        interpolation: Interpolation::Linear,
    };
    let lit = |m: Material| Material {
        lighting: Lighting {
            sun: 1.0,
            environment: sky.clone(),
        },
        ..m
    };
    out.push(MaterialCase {
        name: "constant slope colour under the sky".into(),
        material: lit(Material {
            terms: ColorTerms {
                height: None,
                slope: slope_term(single_stop, 1.0),
                ..ColorTerms::default()
            },
            ..base()
        }),
        image: None,
        reference: same(
            lit(Material {
                terms: ColorTerms {
                    height: None,
                    constant: Some(ConstantTerm {
                        color: [0.4, 0.3, 0.2],
                        weight: 1.0,
                    }),
                    ..ColorTerms::default()
                },
                ..base()
            }),
            1e-6,
            "the same colour as a constant term",
        ),
    });
    for (sh, sn, mode, weight) in [
        (1e-9, 1e-9, CombineMode::Multiplicative, 1.0),
        (0.05, 1e6, CombineMode::Multiplicative, 1.0),
        (1e6, 1e6, CombineMode::Linear, 1e3),
    ] {
        out.push(MaterialCase {
            name: format!(
                "step slope colour with the colour map ({mode:?}, κ = {weight:e}) under the sky, σ_h = {sh:e}, σ_n = {sn:e}"
            ),
            material: lit(Material {
                terms: ColorTerms {
                    mode,
                    slope: slope_term(step_map(), weight),
                    ..ColorTerms::default()
                },
                ..with_sigmas(sh, sn, sn)
            }),
            image: None,
            reference: same(
                lit(Material {
                    terms: ColorTerms {
                        mode,
                        slope: slope_term(ramp(&step_map()), weight),
                        ..ColorTerms::default()
                    },
                    ..with_sigmas(sh, sn, sn)
                }),
                1e-6,
                "the same steps as a Linear slope map with 1e-7 ramps",
            ),
        });
    }
    let image = Arc::new(ImageDriver::new(4, 4, &[0.7; 16]).expect("a constant image"));
    out.push(MaterialCase {
        name: "image driver of constant value".into(),
        material: Material {
            driver: lodestone_core::material::Driver::Image {
                path: "constant.png".into(),
                size: 1.0,
            },
            ..base()
        },
        image: Some(image),
        reference: same(
            Material {
                color: ColorModel::Attribute {
                    mean: base_map().sample(0.0),
                    correlation: [0.0; 3],
                },
                ..with_sigmas(0.0, 0.0, 0.0)
            },
            1e-6,
            "the flat material in the colour map's colour at 0 (a constant image standardizes to 0)",
        ),
    });
    out
}

/// The colour map of [`base`].
fn base_map() -> Gradient {
    match base().color {
        ColorModel::Gradient { map, .. } => map,
        _ => unreachable!("the default material has a colour map"),
    }
}

/// Whether a case's explicit surface is checked by ground truth: slope bound below 10 and relief
/// below 10 units. Beyond that the march needs up to 1e6 steps per ray on the CPU (1e-4 of a
/// wavelength of 1e-6 units), and on the GPU its f32 positions cannot resolve the surface (a 50-unit
/// camera has a coordinate ulp of 4e-6).
pub fn truth_traceable(p: &Evaluator) -> bool {
    p.surface.slope_bound() < 10.0 && p.surface.h_max < 10.0
}

/// View and light azimuths of [`material_outputs`], and the same mirrored across x = y.
const AZIMUTHS: (f64, f64) = (0.3, 2.0);
const MIRRORED: (f64, f64) = (FRAC_PI_2 - 0.3, FRAC_PI_2 - 2.0);

/// The far footprint and the three analytic methods, a near level-of-detail pixel and a short ground
/// truth at every angle of [`angles`] (light at 40°): the values a material case produces on the CPU.
pub fn material_outputs(p: &Evaluator) -> Vec<f64> {
    let mut v = Vec::new();
    let (view_az, light_az) = AZIMUTHS;
    for theta in angles() {
        let cfg = FootprintQuery::far(p, direction(theta, view_az), direction(0.7, light_az));
        v.extend(far_statistics(p, &cfg));
        // A near footprint through the level-of-detail surface too.
        let o = DVec3::new(0.2, 0.1, 2.0);
        let d = -direction(theta.min(89.999f64.to_radians()), view_az);
        v.extend(p.pixel(
            Method::Filtered,
            o,
            d,
            direction(0.7, light_az),
            Footprint::isotropic(1e-3),
        ));
        // Ground truth only where the explicit surface is traceable in reasonable time: its march
        // takes steps down to 1e-4 of the finest wavelength (σ_n = 1e6 puts that at 1e-11) and
        // crosses the slab over h_max/cos θ.
        if truth_traceable(p) && theta <= 89.9f64.to_radians() {
            v.extend(p.ground_truth(&cfg, 8, 3).mean);
        } else {
            v.extend([0.0; 3]);
        }
    }
    v
}

/// Naive, view-independent and filtered colour of a far footprint (9 values).
fn far_statistics(p: &Evaluator, cfg: &FootprintQuery) -> Vec<f64> {
    let mut v = Vec::with_capacity(9);
    v.extend(p.naive(cfg));
    v.extend(p.view_independent(cfg));
    v.extend(p.filtered(cfg));
    v
}

/// The far statistics of [`material_outputs`] at the angles below 90° (9 per angle), from the
/// given azimuths. Exactly at the horizon σ → 0 and θ → 90° do not commute (any roughness there
/// masks all but the tops, Λ ≈ 1/ν → ∞), so references stop short of it.
fn compared_statistics(p: &Evaluator, (view_az, light_az): (f64, f64)) -> Vec<f64> {
    angles()
        .into_iter()
        .filter(|t| *t < FRAC_PI_2 - 1e-9)
        .flat_map(|theta| {
            let cfg = FootprintQuery::far(p, direction(theta, view_az), direction(0.7, light_az));
            far_statistics(p, &cfg)
        })
        .collect()
}

fn procedural(m: &Material) -> Evaluator {
    Evaluator::new(m).expect("reference materials are procedural and valid")
}

/// What the case's compared statistics should be, by its [`Reference`].
fn expected(case: &MaterialCase, p: &Evaluator) -> Vec<f64> {
    match &case.reference {
        Reference::Same {
            material, mirrored, ..
        } => compared_statistics(
            &procedural(material),
            if *mirrored { MIRRORED } else { AZIMUTHS },
        ),
        Reference::FilteredIsViewIndependent { .. } => {
            // Each angle's filtered colour (values 6..9) should be its view-independent one (3..6).
            let mut s = compared_statistics(p, AZIMUTHS);
            for a in s.chunks_mut(9) {
                let vi = [a[3], a[4], a[5]];
                a[6..9].copy_from_slice(&vi);
            }
            s
        }
        Reference::ClampedAttribute { mean, correlation } => {
            let with = |m: [f64; 3], c: [f64; 3]| {
                compared_statistics(
                    &procedural(&Material {
                        color: ColorModel::Attribute {
                            mean: m,
                            correlation: c,
                        },
                        ..case.material.clone()
                    }),
                    AZIMUTHS,
                )
            };
            let (rest, flat, shaped) = (
                with([0.0; 3], [0.0; 3]),
                with([1.0; 3], [0.0; 3]),
                with([1.0; 3], [1.0; 3]),
            );
            (0..rest.len())
                .map(|i| {
                    let k = i % 3;
                    let diffuse = flat[i] - rest[i];
                    let shape = if diffuse != 0.0 {
                        (shaped[i] - flat[i]) / diffuse
                    } else {
                        0.0
                    };
                    diffuse * (mean[k] + correlation[k] * shape).max(0.0) + rest[i]
                })
                .collect()
        }
    }
}

/// Rows for the material cases on the CPU: every output finite and ≥ 0, and the far statistics
/// within the bound of their [`Reference`].
pub fn material_rows() -> Vec<Row> {
    let mut rows = Vec::new();
    for case in material_cases() {
        let row = match Evaluator::with_image(&case.material, case.image.clone(), None) {
            Err(e) => Row {
                case: format!("{}: {e}", case.name),
                path: Path::CoreF64,
                outputs: 0,
                max_deviation: f64::INFINITY,
                bound: 0.0,
                non_finite: 1,
                reference: String::new(),
            },
            Ok(p) => {
                let out = material_outputs(&p);
                let bad = out.iter().filter(|v| !v.is_finite() || **v < 0.0).count();
                let got = compared_statistics(&p, AZIMUTHS);
                let want = expected(&case, &p);
                let dev = got
                    .iter()
                    .zip(&want)
                    .map(|(a, b)| deviation(*a, *b, 1e-3))
                    .fold(0.0, f64::max);
                Row {
                    case: case.name.clone(),
                    path: Path::CoreF64,
                    outputs: out.len(),
                    max_deviation: dev,
                    bound: case.reference.bound(),
                    non_finite: bad,
                    reference: case.reference.describe(),
                }
            }
        };
        rows.push(row);
    }
    rows
}

#[cfg(test)]
mod tests;
