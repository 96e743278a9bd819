//! The parts of a [`Material`](crate::material::Material) that evaluation needs, compiled once into
//! closed enums that own what their variant needs: a gradient colour model owns its pre-convolved
//! table, a transfer curve owns its moment table. No "table is missing" state exists.

use crate::driver::histogram::{DriverHistogram, MU_RANGE, SIGMA_G_MAX};
use crate::eval::query::FootprintStats;
use crate::material::colormap::Gradient;
use crate::material::{ColorModel, ColorSource};
use crate::math::preconvolved::{PreconvolvedTable, TableSpec};
use crate::math::special::erf;
use crate::math::table_slope::TableSlope;
use crate::microfacet::attribute::{attribute_shape, mean_attribute_shape};
use crate::microfacet::transfer::{TransferFunction, TransferMoments};

/// The colour model, compiled.
#[derive(Clone, Debug, PartialEq)]
pub enum CompiledColor {
    /// A gradient colour map of the driver or the standardized height, with its pre-convolved
    /// table `⟨C, N(m, σ²)⟩` [HNPN14 Eq. 9, Sec. 7].
    Gradient {
        /// The map (point lookups on the explicit surface).
        map: Gradient,
        /// What indexes it.
        source: ColorSource,
        /// Its pre-convolved table (filtered lookups): over the driver's value, or over the
        /// Gaussian space of an image's histogram when `gaussianize` is present.
        table: PreconvolvedTable,
        /// For an image driver whose histogram is kept ([`crate::driver::histogram`]): the table
        /// `H(f̄, σ_f) = (μ_G, σ_G)`; `table` is then `C∘T⁻¹` pre-convolved over G.
        gaussianize: Option<PreconvolvedTable>,
    },
    /// The attribute model `a(h) = ā + a_s·s(h)` [HN12 Eq. 17].
    Attribute {
        /// ā per channel.
        mean: [f64; 3],
        /// a_s per channel.
        correlation: [f64; 3],
    },
}

impl CompiledColor {
    /// Compile a colour model, building a gradient's table at `spec`; with an image's
    /// `histogram`, over the histogram's Gaussian space (μ_G ∈ ±[`MU_RANGE`], σ_G ≤
    /// [`SIGMA_G_MAX`], `spec`'s sizes).
    pub fn new(model: &ColorModel, spec: TableSpec, histogram: Option<&DriverHistogram>) -> Self {
        match model {
            ColorModel::Gradient { map, source } => match histogram {
                None => Self::Gradient {
                    map: map.clone(),
                    source: *source,
                    table: map.preconvolve(spec),
                    gaussianize: None,
                },
                Some(h) => {
                    let composed = h.compose(&map.to_piecewise());
                    let g_spec = TableSpec {
                        sigma_max: SIGMA_G_MAX,
                        ..spec
                    };
                    let table =
                        PreconvolvedTable::build(&composed, g_spec, (-MU_RANGE, MU_RANGE), |e| {
                            [e[0] as f32, e[1] as f32, e[2] as f32, 1.0]
                        });
                    Self::Gradient {
                        map: map.clone(),
                        source: *source,
                        table,
                        gaussianize: Some(h.gaussianize_table()),
                    }
                }
            },
            ColorModel::Attribute { mean, correlation } => Self::Attribute {
                mean: *mean,
                correlation: *correlation,
            },
        }
    }

    /// The pre-convolved table (gradients only).
    pub fn table(&self) -> Option<&PreconvolvedTable> {
        match self {
            Self::Gradient { table, .. } => Some(table),
            Self::Attribute { .. } => None,
        }
    }

    /// The table from the footprint's (f̄, σ_f) to the histogram's Gaussian space (gradients of
    /// an image driver whose histogram is kept).
    pub fn gaussianize_table(&self) -> Option<&PreconvolvedTable> {
        match self {
            Self::Gradient { gaussianize, .. } => gaussianize.as_ref(),
            Self::Attribute { .. } => None,
        }
    }

    /// Whether the driver value f, rather than the standardized height, indexes the colour.
    fn indexed_by_driver(&self) -> bool {
        matches!(
            self,
            Self::Gradient {
                source: ColorSource::Driver,
                ..
            }
        )
    }

    /// Colour of a point of the explicit surface with driver value `f` and standardized height `t`.
    pub fn at_point(&self, f: f64, t: f64) -> [f64; 3] {
        match self {
            Self::Gradient { map, .. } => map.sample(if self.indexed_by_driver() { f } else { t }),
            Self::Attribute { mean, correlation } => {
                let s = attribute_shape(t);
                [0, 1, 2].map(|c| (mean[c] + correlation[c] * s).max(0.0))
            }
        }
    }

    /// The colour input's distribution within the footprint before masking, (mean, std): the
    /// driver's, or the transformed height's standardized by `global_height` (mean, std of g(f),
    /// f ~ N(0, 1)); with an image's histogram, mapped to its Gaussian space by the table H
    /// (`(μ_G, σ_G)`, what the colour table is indexed by then).
    pub fn input_distribution(&self, loc: &FootprintStats, (gm, gs): (f64, f64)) -> (f64, f64) {
        let (m, s) = if self.indexed_by_driver() {
            (loc.driver.mean, loc.driver.std)
        } else {
            ((loc.transfer.mean - gm) / gs, loc.transfer.std / gs)
        };
        match self.gaussianize_table() {
            Some(h) => {
                let v = h.sample(m, s);
                (v[0], v[1].max(0.0))
            }
            None => (m, s),
        }
    }

    /// Mean colour of an input distributed N(mean, std²), `l` the masking exponent (0 = none):
    /// the pre-convolved table [HNPN14 Eq. 9], or for the attribute model `E[s]` in closed form
    /// `erf(μ/√(2(1+s²)))` corrected by the exact far-field [HN12 Eq. 17] in proportion to the
    /// unresolved variance `w` (exact at both ends of the zoom, smooth in between).
    pub fn of_distribution(
        &self,
        mean: f64,
        std: f64,
        l: f64,
        far: (f64, f64),
        w: f64,
    ) -> [f64; 3] {
        match self {
            Self::Gradient { table, .. } => {
                let v = table.sample(mean, std);
                [v[0], v[1], v[2]]
            }
            Self::Attribute {
                mean: abar,
                correlation,
            } => {
                let gauss = |m: f64, s: f64| erf(m / (2.0 * (1.0 + s * s)).sqrt());
                let s = gauss(mean, std)
                    + w.clamp(0.0, 1.0) * (mean_attribute_shape(l) - gauss(far.0, far.1));
                [0, 1, 2].map(|c| (abar[c] + correlation[c] * s).max(0.0))
            }
        }
    }
}

/// The transfer function's footprint moments, compiled.
#[derive(Clone, Debug, PartialEq)]
pub enum CompiledTransfer {
    /// `g(f) = f`: moments in closed form.
    Identity,
    /// A curve, through its pre-convolved table of `(ḡ, σ_g, ḡ′, σ_g′)` [HNPN14 Sec. 7].
    Curve {
        /// The table.
        table: PreconvolvedTable,
        /// Its mean channel's slope bounds, for the level-of-detail march.
        slopes: TableSlope,
    },
}

impl CompiledTransfer {
    /// Compile a transfer function, building a curve's table at `spec`.
    pub fn new(transfer: &TransferFunction, spec: TableSpec) -> Self {
        match transfer.preconvolve(spec) {
            Some(table) => Self::Curve {
                slopes: TableSlope::new(&table),
                table,
            },
            None => Self::Identity,
        }
    }

    /// The pre-convolved table (curves only).
    pub fn table(&self) -> Option<&PreconvolvedTable> {
        match self {
            Self::Curve { table, .. } => Some(table),
            Self::Identity => None,
        }
    }

    /// Moments of g over `N(m, s²)` [HNPN14 Eqs. 21, 22, 27, 28]: exact for the identity, the
    /// table's bilinear lookup for a curve.
    pub fn moments(&self, m: f64, s: f64) -> TransferMoments {
        match self {
            Self::Curve { table, .. } => {
                let v = table.sample(m, s);
                TransferMoments {
                    mean: v[0],
                    std: v[1].max(0.0),
                    mean_deriv: v[2],
                    std_deriv: v[3].max(0.0),
                }
            }
            Self::Identity => TransferFunction::Identity.moments(m, s),
        }
    }
}
