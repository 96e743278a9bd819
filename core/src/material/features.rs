//! The features a material and scene actually use, so renderers build only those.
//!
//! A scene that shows colour-mapped noise on a flat plane needs neither the ray march, the masking
//! and shadowing terms, the effective-height table nor the slope quadrature; a material without a
//! transfer curve needs no transfer table; a matte material no specular lobe. [`FeatureSet::derive`]
//! finds the set from the material and the scene, and [`FeatureSet::absent`] says, for each feature
//! left out, why it is unused. `lodestone-render` compiles one view pipeline per feature set with
//! every unused term removed from the shader source and leaves the unused tables out of the
//! material buffer.
//!
//! Not features, on purpose: the view mode (the four views share one pipeline, so a side-by-side
//! frame needs one pipeline), the masking correlation and height-filter options (one-instruction
//! switches), and anisotropy: a footprint's slope covariance is a general 2×2 matrix for every
//! driver (a finite set of waves or an image is never exactly isotropic), so the general path is
//! the only path.

use crate::driver::histogram::ImageHistogram;
use crate::material::{ColorModel, ColorSource, Driver, Material};
use crate::microfacet::height_mixture::TransferSlopes;
use crate::microfacet::transfer::TransferFunction;
use crate::scene::shape::Shape;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// One feature of the material model that costs shader code or table memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Feature {
    /// The sum-of-sines noise driver (wave list, per-wave attenuation cache) [HNPN14 Sec. 4.1].
    NoiseDriver,
    /// An image driver (pyramid of value and gradient moments) [HNPN14 Sec. 4.2].
    ImageDriver,
    /// A gradient colour map indexed by the driver value (its pre-convolved table) [HNPN14 Sec. 4].
    DriverColor,
    /// A gradient colour map indexed by standardized height [HNPN14 Secs. 5.1, 7].
    HeightColor,
    /// Height-correlated attribute colour `ā + a_s·(2P(h) − 1)` [HN12 Eq. 17].
    AttributeColor,
    /// A height transfer curve g (its moment polynomial and table) [HNPN14 Sec. 7].
    TransferCurve,
    /// Slopes under a transfer curve as a mixture over the driver's value: bins of the
    /// footprint's quantiles with their own Gaussian slopes and height-dependent masking
    /// ([`crate::microfacet::height_mixture`]; needs relief and a curve).
    TransferMixture,
    /// Relief: σ_h > 0, so heights, slopes, the ray march, masking, the visible-height table D_h
    /// [HNPN14 Eqs. 14–17] and the visible-slope quadrature are needed.
    Relief,
    /// Shadow rays: the ground truth's shadow march on the explicit surface and the analytic
    /// views' on the level-of-detail surface. (The filtered model's mean shadowing [HNPN14
    /// Eq. 12] belongs to relief: it is taken in the footprint's mean-normal frame, where a light
    /// at the world normal is oblique.)
    Shadows,
    /// The specular lobe of the base BRDF and its filtered form.
    Specular,
    /// Curved geometry (the cylinder and its tangent-frame footprints).
    Curved,
    /// A slope-correlated colour term C_s(n) (its polynomial, averaged over D_s) [HNPN14 Sec. 5.2].
    SlopeColor,
    /// Environment lighting: SH9 irradiance per facet, averaged over D_s [HNPN14 Sec. 5.3].
    Environment,
    /// An image driver's histogram kept by the colour map's filtering: the table from the
    /// footprint's (f̄, σ_f) to Gaussian space and the colour table over it
    /// ([`crate::driver::histogram`]; needs an image and a gradient colour map).
    ImageHistogram,
    /// A measured base BRDF (a MERL table in the data buffer): ground truth and naive look
    /// facets up in it ([`crate::material::measured`]).
    Measured,
}

impl Feature {
    /// Every feature, in a fixed order.
    pub const ALL: [Feature; 15] = [
        Feature::NoiseDriver,
        Feature::ImageDriver,
        Feature::DriverColor,
        Feature::HeightColor,
        Feature::AttributeColor,
        Feature::TransferCurve,
        Feature::TransferMixture,
        Feature::Relief,
        Feature::Shadows,
        Feature::Specular,
        Feature::Curved,
        Feature::SlopeColor,
        Feature::Environment,
        Feature::ImageHistogram,
        Feature::Measured,
    ];

    /// The name used in shader directives (`//#if relief`), the CLI and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Feature::NoiseDriver => "noise",
            Feature::ImageDriver => "image",
            Feature::DriverColor => "driver_color",
            Feature::HeightColor => "height_color",
            Feature::AttributeColor => "attribute_color",
            Feature::TransferCurve => "transfer_curve",
            Feature::TransferMixture => "transfer_mixture",
            Feature::Relief => "relief",
            Feature::Shadows => "shadows",
            Feature::Specular => "specular",
            Feature::Curved => "curved",
            Feature::SlopeColor => "slope_color",
            Feature::Environment => "environment",
            Feature::ImageHistogram => "image_histogram",
            Feature::Measured => "measured",
        }
    }

    /// The feature with this [`Feature::name`].
    pub fn from_name(name: &str) -> Option<Feature> {
        Feature::ALL.into_iter().find(|f| f.name() == name)
    }

    fn bit(self) -> u16 {
        1 << (self as u16)
    }
}

/// A set of [`Feature`]s (a bit set: cheap to copy, hash and compare; the pipeline cache's key).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct FeatureSet(u16);

const _: () = assert!(Feature::ALL.len() <= 16, "FeatureSet is a u16");

impl FeatureSet {
    /// The empty set.
    pub const EMPTY: FeatureSet = FeatureSet(0);

    /// Every feature: the one shader that renders any material and scene.
    pub fn all() -> FeatureSet {
        Feature::ALL.into_iter().collect()
    }

    /// Whether `f` is in the set.
    pub fn contains(self, f: Feature) -> bool {
        self.0 & f.bit() != 0
    }

    /// The set with `f` added (or removed when `on` is false).
    #[must_use]
    pub fn with(self, f: Feature, on: bool) -> FeatureSet {
        if on {
            FeatureSet(self.0 | f.bit())
        } else {
            FeatureSet(self.0 & !f.bit())
        }
    }

    /// The features in the set, in [`Feature::ALL`] order.
    pub fn iter(self) -> impl Iterator<Item = Feature> {
        Feature::ALL.into_iter().filter(move |f| self.contains(*f))
    }

    /// Whether every feature of `other` is in `self` (a pipeline built for `self` renders it).
    pub fn covers(self, other: FeatureSet) -> bool {
        other.0 & !self.0 == 0
    }

    /// The set with the implications between features applied: shadows need relief (a flat
    /// plane casts none; the shadow march needs the level-of-detail surface); the transfer
    /// mixture needs relief and a transfer curve; the image histogram needs an image and a
    /// gradient colour map.
    #[must_use]
    pub fn normalized(self) -> FeatureSet {
        let relief = self.contains(Feature::Relief);
        let histogram = self.contains(Feature::ImageHistogram)
            && self.contains(Feature::ImageDriver)
            && (self.contains(Feature::DriverColor) || self.contains(Feature::HeightColor));
        let mixture = relief
            && (self.contains(Feature::TransferCurve) || histogram)
            && self.contains(Feature::TransferMixture);
        self.with(Feature::Shadows, relief && self.contains(Feature::Shadows))
            .with(Feature::TransferMixture, mixture)
            .with(Feature::ImageHistogram, histogram)
    }

    /// The features of the material alone (no scene): see [`FeatureSet::derive`].
    pub fn of_material(m: &Material) -> FeatureSet {
        let relief = m.heights.sigma_h > 0.0;
        let colour_model = m.terms.uses_height_term();
        FeatureSet::EMPTY
            .with(Feature::NoiseDriver, matches!(m.driver, Driver::Noise(_)))
            .with(
                Feature::ImageDriver,
                matches!(m.driver, Driver::Image { .. }),
            )
            .with(
                Feature::DriverColor,
                colour_model
                    && matches!(
                        m.color,
                        ColorModel::Gradient {
                            source: ColorSource::Driver,
                            ..
                        }
                    ),
            )
            .with(
                Feature::HeightColor,
                colour_model
                    && matches!(
                        m.color,
                        ColorModel::Gradient {
                            source: ColorSource::Height,
                            ..
                        }
                    ),
            )
            .with(
                Feature::AttributeColor,
                colour_model && matches!(m.color, ColorModel::Attribute { .. }),
            )
            .with(
                Feature::TransferCurve,
                matches!(m.heights.transfer, TransferFunction::Curve(_)),
            )
            .with(Feature::TransferMixture, m.transfer_mixture())
            .with(Feature::Relief, relief)
            .with(
                Feature::Specular,
                m.brdf.specular > 0.0 || m.brdf.measured.is_some(),
            )
            .with(Feature::SlopeColor, m.terms.slope.is_some())
            .with(Feature::Environment, m.lighting.environment.is_some())
            .with(Feature::ImageHistogram, colour_model && m.image_histogram())
            .with(Feature::Measured, m.brdf.measured.is_some())
    }

    /// The features a material needs in a scene with this object and light (unit direction
    /// toward the light).
    ///
    /// Shadows need relief and a light off the normal: a height field cannot occlude the vertical
    /// ray above any of its points, so with the light at the zenith no shadow ray can hit. The cylinder
    /// shadows itself at any light, so curved geometry always has them. A transfer curve with no
    /// relief still colours by height when the colour map is height-indexed, so it stays.
    pub fn derive(m: &Material, shape: Shape, light: DVec3) -> FeatureSet {
        FeatureSet::of_material(m).in_scene(shape, light)
    }

    /// A material's features ([`FeatureSet::of_material`]) completed by the scene's: curved
    /// geometry, and shadows as [`FeatureSet::derive`] describes.
    #[must_use]
    pub fn in_scene(self, shape: Shape, light: DVec3) -> FeatureSet {
        let curved = matches!(shape, Shape::Cylinder { .. });
        let oblique = light.x != 0.0 || light.y != 0.0;
        self.with(Feature::Curved, curved).with(
            Feature::Shadows,
            self.contains(Feature::Relief) && (oblique || curved),
        )
    }

    /// Each feature absent from the set with the reason it is unused (for `lodestone inspect`).
    pub fn absent(self, m: &Material) -> Vec<(Feature, &'static str)> {
        Feature::ALL
            .into_iter()
            .filter(|f| !self.contains(*f))
            .map(|f| {
                let why = match f {
                    Feature::NoiseDriver => "the driver is an image",
                    Feature::ImageDriver => "the driver is procedural noise",
                    Feature::DriverColor | Feature::HeightColor | Feature::AttributeColor
                        if !m.terms.uses_height_term() =>
                    {
                        "the colour model is not one of the colour terms"
                    }
                    Feature::DriverColor | Feature::HeightColor | Feature::AttributeColor => {
                        match m.color {
                            ColorModel::Gradient {
                                source: ColorSource::Driver,
                                ..
                            } => "the colour map is indexed by the driver value",
                            ColorModel::Gradient {
                                source: ColorSource::Height,
                                ..
                            } => "the colour map is indexed by height",
                            ColorModel::Attribute { .. } => "the colour is the attribute model",
                        }
                    }
                    Feature::TransferCurve => "the height transfer function is the identity",
                    Feature::TransferMixture => {
                        let image = matches!(m.driver, Driver::Image { .. });
                        let curve = matches!(m.heights.transfer, TransferFunction::Curve(_));
                        if m.heights.sigma_h <= 0.0 {
                            "sigma_h is 0: no slopes to mix"
                        } else if m.filtering.transfer_slopes == TransferSlopes::Gaussian {
                            "filtering.transfer_slopes is Gaussian (the papers' model)"
                        } else if image && !curve {
                            "the image's value-conditioned slopes need its histogram (filtering.image_histogram Preserving, a gradient colour map of its value)"
                        } else {
                            "the identity transfer keeps the noise's slopes one Gaussian (its value and gradient are independent)"
                        }
                    }
                    Feature::Relief => "sigma_h is 0: the surface is flat",
                    Feature::Shadows => {
                        if m.heights.sigma_h > 0.0 {
                            "the light is at the normal: a height field cannot shadow it"
                        } else {
                            "a flat plane casts no shadows"
                        }
                    }
                    Feature::Specular => "the specular weight is 0",
                    Feature::Measured => "the base BRDF is analytic (no measured file)",
                    Feature::Curved => "the scene is the plane",
                    Feature::SlopeColor => "the material has no slope colour term",
                    Feature::Environment => "the lighting has no environment",
                    Feature::ImageHistogram => {
                        if !matches!(m.driver, Driver::Image { .. }) {
                            "the noise is Gaussian at every scale"
                        } else if !m.terms.uses_height_term()
                            || matches!(m.color, ColorModel::Attribute { .. })
                        {
                            "no gradient colour map of the image's value"
                        } else if m.filtering.image_histogram == ImageHistogram::Gaussian {
                            "filtering.image_histogram is Gaussian (the papers' model)"
                        } else {
                            "the colour map is indexed by a transformed height"
                        }
                    }
                };
                (f, why)
            })
            .collect()
    }
}

impl FromIterator<Feature> for FeatureSet {
    fn from_iter<I: IntoIterator<Item = Feature>>(iter: I) -> Self {
        iter.into_iter()
            .fold(FeatureSet::EMPTY, |s, f| s.with(f, true))
    }
}

impl std::fmt::Display for FeatureSet {
    /// Feature names joined by `+` (`none` for the empty set).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<_> = self.iter().map(Feature::name).collect();
        if names.is_empty() {
            write!(f, "none")
        } else {
            write!(f, "{}", names.join("+"))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Heights;
    use crate::material::colormap::Gradient;

    #[test]
    fn names_round_trip_and_bits_are_distinct() {
        let all = FeatureSet::all();
        assert_eq!(all.iter().count(), Feature::ALL.len());
        for f in Feature::ALL {
            assert_eq!(Feature::from_name(f.name()), Some(f));
            assert!(all.contains(f));
            assert!(!FeatureSet::EMPTY.contains(f));
            assert_eq!(all.with(f, false).iter().count(), Feature::ALL.len() - 1);
        }
        assert_eq!(Feature::from_name("voxels"), None);
        assert!(all.covers(FeatureSet::derive(
            &Material::default(),
            Shape::Plane,
            DVec3::Z
        )));
    }

    #[test]
    fn default_material_under_an_oblique_light() {
        let m = Material::default();
        let s = FeatureSet::derive(&m, Shape::Plane, DVec3::new(0.5, 0.0, 0.8).normalize());
        assert!(s.contains(Feature::NoiseDriver));
        assert!(!s.contains(Feature::ImageDriver));
        assert!(s.contains(Feature::Relief) == (m.heights.sigma_h > 0.0));
        assert!(s.contains(Feature::Shadows) == s.contains(Feature::Relief));
        assert!(!s.contains(Feature::Curved));
        // Exactly one colour feature.
        let colours = [
            Feature::DriverColor,
            Feature::HeightColor,
            Feature::AttributeColor,
        ];
        assert_eq!(colours.iter().filter(|f| s.contains(**f)).count(), 1);
        // Every absent feature has a reason, every present one none.
        let absent = s.absent(&m);
        assert_eq!(absent.len() + s.iter().count(), Feature::ALL.len());
        assert!(
            absent
                .iter()
                .all(|(f, why)| !s.contains(*f) && !why.is_empty())
        );
    }

    #[test]
    fn flat_colour_mapped_noise_needs_neither_relief_nor_shadows() {
        let m = Material {
            heights: Heights {
                sigma_h: 0.0,
                transfer: TransferFunction::Identity,
            },
            color: ColorModel::Gradient {
                map: Gradient::viridis(-2.0, 2.0),
                source: ColorSource::Driver,
            },
            ..Material::default()
        };
        let oblique = DVec3::new(0.6, 0.3, 0.5).normalize();
        let s = FeatureSet::derive(&m, Shape::Plane, oblique);
        assert!(!s.contains(Feature::Relief));
        assert!(!s.contains(Feature::Shadows));
        assert!(!s.contains(Feature::TransferCurve));
        assert!(s.contains(Feature::DriverColor));
        // The cylinder shadows itself only where there is relief to march.
        let c = FeatureSet::derive(&m, Shape::Cylinder { radius: 1.0 }, oblique);
        assert!(c.contains(Feature::Curved) && !c.contains(Feature::Shadows));
    }

    #[test]
    fn a_light_at_the_normal_drops_shadows_only() {
        let m = Material::default();
        assert!(m.heights.sigma_h > 0.0);
        let zenith = FeatureSet::derive(&m, Shape::Plane, DVec3::Z);
        let oblique = FeatureSet::derive(&m, Shape::Plane, DVec3::new(1e-9, 0.0, 1.0));
        assert!(!zenith.contains(Feature::Shadows));
        assert_eq!(oblique, zenith.with(Feature::Shadows, true));
        let curved = FeatureSet::derive(&m, Shape::Cylinder { radius: 2.0 }, DVec3::Z);
        assert!(curved.contains(Feature::Shadows));
    }

    #[test]
    fn display_lists_names() {
        assert_eq!(FeatureSet::EMPTY.to_string(), "none");
        let s: FeatureSet = [Feature::Relief, Feature::NoiseDriver]
            .into_iter()
            .collect();
        assert_eq!(s.to_string(), "noise+relief");
    }
}
