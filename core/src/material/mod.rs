//! The material model: one serde type holding the driver, colour model, height transfer function,
//! microsurface statistics (σ_h, σ_nx, σ_ny), base BRDF and filtering options, with validation that
//! reports every invalid field at once.
//!
//! Conventions. The driver f has zero mean and unit variance. Heights are `h = σ_h·g(f)`; for the
//! identity transfer function the surface has height std σ_h and slope std σ_nx, σ_ny exactly (the
//! noise's frequencies are set from σ_n/σ_h, see [`crate::driver::noise`]). With a curve g, σ_h and σ_n set
//! the scale of the driver before g, and the surface's statistics follow from [HNPN14 Eqs. 19–26].
//!
//! The parts, one module each: the colour map and its pre-convolved tables ([`colormap`],
//! [`preconvolved`]), transfer functions ([`transfer`]), the colour terms and slope colour of
//! [HNPN14 Sec. 6] ([`color_terms`], [`slope_color`]), the preview lighting ([`environment`]),
//! validation messages ([`validation`]) and the feature set a material needs in a scene
//! ([`features`]).

pub mod color_terms;
pub mod colormap;
pub mod environment;
pub mod features;
pub mod geometry;
pub mod measured;
pub mod merl;
pub mod merl_fit;
pub mod slope_color;
pub mod validation;

use crate::driver::histogram::ImageHistogram;
use crate::driver::noise::{NoiseParams, SumOfSines};
use crate::material::color_terms::ColorTerms;
use crate::material::colormap::Gradient;
use crate::material::environment::Lighting;
use crate::material::validation::{Problem, Problems};
use crate::math::preconvolved::TableSpec;
use crate::microfacet::brdf::BaseBrdf;
use crate::microfacet::effective_height::HeightFilter;
use crate::microfacet::height_mixture::TransferSlopes;
use crate::microfacet::masking_shadowing::Correlation;
use crate::microfacet::slope_density::NoiseSlopes;
use crate::microfacet::slope_masking::SlopeMasking;
use crate::microfacet::slope_rule::SlopeRule;
use crate::microfacet::slopes::SlopeCov;
use crate::microfacet::transfer::TransferFunction;
use serde::{Deserialize, Serialize};

/// Current preset format version.
pub const MATERIAL_VERSION: u32 = 1;

/// Upper bound of σ_h and roughness accepted from a preset.
pub const MAX_SIGMA: f64 = 1e6;

/// Upper bound of σ_nx and σ_ny accepted from a preset: a slope standard deviation of 10 (84°; the
/// editor's sliders end at 2). The noise's wave numbers scale with σ_n/σ_h, so a ray's march steps
/// scale with σ_n: at 1e6 `eval` marched for minutes and returned a ground truth of 0 (#16). The
/// formulas themselves stay finite far beyond (`lodestone stability` runs σ_n = 1e6 directly).
pub const MAX_SLOPE_SIGMA: f64 = 10.0;

/// The driving function f.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Driver {
    /// Sum-of-sinusoids noise with analytic footprint statistics.
    Noise(NoiseParams),
    /// A grayscale image, tiled over `size` world units; loaded by the application.
    Image {
        /// Path of the image, relative to the preset file.
        path: String,
        /// World size of one tile of the image.
        size: f64,
    },
}

/// What a gradient colour map is indexed by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum ColorSource {
    /// The driver value f ([HNPN14 Sec. 4]; height-correlated when σ_h > 0 and g is the identity).
    #[default]
    Driver,
    /// The standardized height `(h − h̄)/std(h)` of the surface [HNPN14 Secs. 5.1, 7].
    Height,
}

/// How the surface is coloured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ColorModel {
    /// A gradient colour map [HNPN14 Secs. 4, 5.1].
    Gradient {
        /// The map.
        map: Gradient,
        /// Its input.
        #[serde(default)]
        source: ColorSource,
    },
    /// The HN12 attribute model per channel: `a(h) = ā + a_s·(2P(h) − 1)` [HN12 Eq. 17].
    Attribute {
        /// ā per linear-RGB channel.
        mean: [f64; 3],
        /// a_s per channel (correlation with height; may exceed ±ā, the result is then clamped at 0).
        correlation: [f64; 3],
    },
}

/// Height statistics and transfer function.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Heights {
    /// σ_h: height standard deviation (world units), ≥ 0.
    pub sigma_h: f64,
    /// The height transfer function g [HNPN14 Sec. 7].
    #[serde(default)]
    pub transfer: TransferFunction,
}

/// Slope statistics σ_nx, σ_ny [HN12 Sec. 3].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Slopes {
    /// Slope standard deviation along x, ≥ 0.
    pub sigma_nx: f64,
    /// Slope standard deviation along y, ≥ 0.
    pub sigma_ny: f64,
}

/// Filtering options of the filtered view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Filtering {
    /// Masking–shadowing combination (correlated by default).
    pub correlation: Correlation,
    /// Effective height moments: exact table (default) or the paper's fits.
    pub height_filter: HeightFilter,
    /// Size and σ range of the pre-convolved tables.
    pub table: TableSpec,
    /// n of the polar rule ([`crate::microfacet::visible_slopes::slope_rule`]: n radii × n angles) for averages over
    /// the visible slope distribution D_s
    /// (the GPU evaluates n² points per pixel).
    pub slope_points: u32,
    /// Slopes under a transfer curve: a mixture over the driver's value (default) or one Gaussian.
    pub transfer_slopes: TransferSlopes,
    /// The noise's slope density under the specular lobe: its own (default) or the Gaussian.
    pub noise_slopes: NoiseSlopes,
    /// An image driver's footprint values: its own histogram (default) or the Gaussian.
    pub image_histogram: ImageHistogram,
    /// Masking and shadowing of the visible slopes: Smith's, or conditioned on the facet's slope
    /// along the ray (#17; noise drivers).
    pub slope_masking: SlopeMasking,
}

impl Default for Filtering {
    fn default() -> Self {
        Self {
            correlation: Correlation::default(),
            height_filter: HeightFilter::default(),
            table: TableSpec::default(),
            slope_points: Self::DEFAULT_SLOPE_POINTS,
            transfer_slopes: TransferSlopes::default(),
            noise_slopes: NoiseSlopes::default(),
            image_histogram: ImageHistogram::default(),
            slope_masking: SlopeMasking::default(),
        }
    }
}

impl Filtering {
    /// Default n (64 nodes).
    pub const DEFAULT_SLOPE_POINTS: u32 = 8;
    /// Largest accepted order.
    pub const MAX_SLOPE_POINTS: u32 = 32;
}

/// A material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Preset format version ([`MATERIAL_VERSION`]).
    pub version: u32,
    /// Display name.
    pub name: String,
    /// The driving function.
    pub driver: Driver,
    /// Heights.
    pub heights: Heights,
    /// Slopes.
    pub slopes: Slopes,
    /// Colour: the height- or driver-correlated colour model C_h.
    pub color: ColorModel,
    /// Which colour terms (constant C0, the colour model C_h, slope colour C_s) combine, and how
    /// [HNPN14 Sec. 6]. Default: the colour model alone.
    #[serde(default)]
    pub terms: ColorTerms,
    /// Base BRDF.
    #[serde(default)]
    pub brdf: BaseBrdf,
    /// Filtering options.
    #[serde(default)]
    pub filtering: Filtering,
    /// The preview lighting saved with the material: directional light scale and environment.
    #[serde(default)]
    pub lighting: Lighting,
}

/// Errors reading a material.
#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    /// The text is not valid RON for a material.
    #[error("line {line}, column {column}: {message}")]
    Parse {
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What the parser says.
        message: String,
    },
    /// The preset was written by a newer Lodestone.
    #[error(
        "preset version {found} is newer than this Lodestone understands ({supported}); update Lodestone"
    )]
    TooNew {
        /// Version in the file.
        found: u32,
        /// Newest supported.
        supported: u32,
    },
    /// Values parse but are invalid; every problem is listed.
    #[error("invalid material:\n{}", .0.iter().map(|p| format!("  - {p}")).collect::<Vec<_>>().join("\n"))]
    Invalid(Vec<Problem>),
}

impl Default for Material {
    /// The default preset: colour-mapped Gaussian heights, rust in the crevices.
    fn default() -> Self {
        Self {
            version: MATERIAL_VERSION,
            name: "Rusty bumps".into(),
            driver: Driver::Noise(NoiseParams::default()),
            heights: Heights {
                sigma_h: 0.05,
                transfer: TransferFunction::Identity,
            },
            slopes: Slopes {
                sigma_nx: 0.35,
                sigma_ny: 0.35,
            },
            color: ColorModel::Gradient {
                map: Gradient::rust(-2.0, 2.0),
                source: ColorSource::Driver,
            },
            brdf: BaseBrdf {
                albedo: 1.0,
                specular: 0.04,
                roughness: 0.15,
                measured: None,
            },
            filtering: Filtering::default(),
            terms: ColorTerms::default(),
            lighting: Lighting::default(),
        }
    }
}

impl Material {
    /// Whether the filtered view models the slopes as a mixture over the driver's value
    /// ([`crate::microfacet::height_mixture`]), with [`TransferSlopes::Mixture`] on relief: under a
    /// transfer curve (g′ depends on the value), or for an image driver whose slopes depend on its
    /// value ([`Material::image_slope_mixture`]). A noise driver under the identity keeps one
    /// Gaussian: its value and gradient are independent, and the mixture would be that Gaussian.
    pub fn transfer_mixture(&self) -> bool {
        self.heights.sigma_h > 0.0
            && self.filtering.transfer_slopes == TransferSlopes::Mixture
            && (matches!(self.heights.transfer, TransferFunction::Curve(_))
                || self.image_slope_mixture())
    }

    /// Whether the mixture's bins carry an image's value-conditioned slopes
    /// ([`crate::driver::conditional_slopes`]): an image driver that keeps its histogram (the
    /// bins live in its Gaussian space), under the identity transfer, on relief, with
    /// [`TransferSlopes::Mixture`].
    pub fn image_slope_mixture(&self) -> bool {
        self.heights.sigma_h > 0.0
            && self.filtering.transfer_slopes == TransferSlopes::Mixture
            && matches!(self.heights.transfer, TransferFunction::Identity)
            && self.image_histogram()
    }

    /// Whether the filtered view keeps an image driver's histogram
    /// ([`crate::driver::histogram`]): an image driver under a gradient colour map indexed by the
    /// driver value (or by height under the identity transfer, the same standardized value), with
    /// [`ImageHistogram::Preserving`].
    pub fn image_histogram(&self) -> bool {
        matches!(self.driver, Driver::Image { .. })
            && self.filtering.image_histogram == ImageHistogram::Preserving
            && match &self.color {
                ColorModel::Gradient { source, .. } => {
                    *source == ColorSource::Driver
                        || matches!(self.heights.transfer, TransferFunction::Identity)
                }
                ColorModel::Attribute { .. } => false,
            }
    }

    /// Parse RON, then validate. Errors carry line and column where the parser has them.
    pub fn from_ron(text: &str) -> Result<Self, MaterialError> {
        let options = ron::Options::default();
        let m: Self = options.from_str(text).map_err(|e| MaterialError::Parse {
            line: e.position.line,
            column: e.position.col,
            message: e.code.to_string(),
        })?;
        if m.version > MATERIAL_VERSION {
            return Err(MaterialError::TooNew {
                found: m.version,
                supported: MATERIAL_VERSION,
            });
        }
        m.validate().map_err(MaterialError::Invalid)?;
        Ok(m)
    }

    /// Pretty RON.
    pub fn to_ron(&self) -> String {
        let cfg = ron::ser::PrettyConfig::new()
            .depth_limit(6)
            .struct_names(true);
        ron::ser::to_string_pretty(self, cfg)
            .unwrap_or_else(|e| format!("// serialisation failed: {e}"))
    }

    /// Every invalid field at once (empty = valid).
    pub fn validate(&self) -> Result<(), Vec<Problem>> {
        let mut p = Problems::default();
        if self.version == 0 {
            p.push("version", "must be at least 1");
        }
        match &self.driver {
            Driver::Noise(n) => {
                if n.components == 0 || n.components > NoiseParams::MAX_COMPONENTS {
                    p.push(
                        "driver.components",
                        format!(
                            "must be in 1..={}, got {}",
                            NoiseParams::MAX_COMPONENTS,
                            n.components
                        ),
                    );
                }
                if n.octaves == 0 || n.octaves > 12 {
                    p.push(
                        "driver.octaves",
                        format!("must be in 1..=12, got {}", n.octaves),
                    );
                }
                p.in_range("driver.gain", n.gain, 0.0, 4.0);
                p.in_range("driver.bandwidth", n.bandwidth, 0.0, 1.5);
                p.in_range("driver.frequency", n.frequency, 1e-6, 1e6);
            }
            Driver::Image { path, size } => {
                if path.trim().is_empty() {
                    p.push("driver.path", "an image driver needs a file path");
                }
                p.in_range("driver.size", *size, 1e-6, 1e6);
            }
        }
        p.in_range("heights.sigma_h", self.heights.sigma_h, 0.0, MAX_SIGMA);
        if let TransferFunction::Curve(c) = &self.heights.transfer {
            c.validate("heights.transfer", &mut p);
        }
        p.in_range(
            "slopes.sigma_nx",
            self.slopes.sigma_nx,
            0.0,
            MAX_SLOPE_SIGMA,
        );
        p.in_range(
            "slopes.sigma_ny",
            self.slopes.sigma_ny,
            0.0,
            MAX_SLOPE_SIGMA,
        );
        match &self.color {
            ColorModel::Gradient { map, .. } => map.validate("color.map", &mut p),
            ColorModel::Attribute { mean, correlation } => {
                for c in 0..3 {
                    p.in_range(&format!("color.mean[{c}]"), mean[c], 0.0, 1e3);
                    p.in_range(
                        &format!("color.correlation[{c}]"),
                        correlation[c],
                        -1e3,
                        1e3,
                    );
                }
            }
        }
        self.terms.validate(&mut p);
        self.lighting.validate(&mut p);
        p.in_range("brdf.albedo", self.brdf.albedo, 0.0, 1.0);
        p.in_range("brdf.specular", self.brdf.specular, 0.0, 1.0);
        p.in_range("brdf.roughness", self.brdf.roughness, 0.0, MAX_SIGMA);
        let t = self.filtering.table;
        for (name, v) in [("size_m", t.size_m), ("size_sigma", t.size_sigma)] {
            if !(2..=TableSpec::MAX_SIZE).contains(&v) {
                p.push(
                    format!("filtering.table.{name}"),
                    format!("must be in 2..={}, got {v}", TableSpec::MAX_SIZE),
                );
            }
        }
        p.in_range("filtering.table.sigma_max", t.sigma_max, 1e-3, 100.0);
        let sp = self.filtering.slope_points;
        if !(1..=Filtering::MAX_SLOPE_POINTS).contains(&sp) {
            p.push(
                "filtering.slope_points",
                format!("must be in 1..={}, got {sp}", Filtering::MAX_SLOPE_POINTS),
            );
        }
        if p.0.is_empty() { Ok(()) } else { Err(p.0) }
    }

    /// The polar rule of the filtered views' averages over a footprint's slopes:
    /// `filtering.slope_points` radii, twice as many angles with a slope colour term whose map
    /// changes colour ([`SlopeRule::for_material`]; a constant C_s has nothing to resolve, and
    /// keeps the rule, so it equals the constant term exactly).
    pub fn slope_rule(&self) -> SlopeRule {
        let turns = self.terms.slope.as_ref().is_some_and(|t| {
            let stops = &t.color.map.stops;
            stops.iter().any(|s| s.color != stops[0].color)
        });
        SlopeRule::for_material(self.filtering.slope_points, turns)
    }

    /// Slope covariance σ_nx², σ_ny² of the (pre-transfer) surface.
    pub fn slope_cov(&self) -> SlopeCov {
        SlopeCov::from_std(self.slopes.sigma_nx, self.slopes.sigma_ny)
    }

    /// The noise realisation whose `h = σ_h·f` has this material's σ_h and σ_n; `None` for an image driver.
    pub fn noise(&self) -> Option<SumOfSines> {
        let Driver::Noise(params) = &self.driver else {
            return None;
        };
        let sh = self.heights.sigma_h;
        let target = if sh > 0.0 {
            self.slope_cov().scaled(1.0 / sh.max(1e-12))
        } else {
            SlopeCov::default()
        };
        Some(SumOfSines::new(params, target))
    }
}

#[cfg(test)]
mod tests;
