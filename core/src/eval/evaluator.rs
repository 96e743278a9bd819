//! [`Evaluator`]: a material compiled once for CPU evaluation (its explicit surface, closed-enum
//! colour model and transfer function with their tables, slope colour and environment). The methods
//! live one per file beside this one.

use crate::driver::DriverError;
use crate::driver::conditional_slopes::{ConditionalSlopes, ImageSlopes};
use crate::driver::field::DriverField;
use crate::driver::histogram::DriverHistogram;
use crate::driver::image::ImageDriver;
use crate::eval::compiled::{CompiledColor, CompiledTransfer};
use crate::eval::interception::Interception;
use crate::eval::masking::slope_masking_table::SlopeMaskingTable;
use crate::eval::masking::transfer_masking_table::TransferMaskingTable;
use crate::material::Material;
use crate::material::environment::EquirectMap;
use crate::material::measured::{ChannelWeights, MeasuredBrdf};
use crate::material::slope_color::CompiledSlopeColor;
use crate::math::sh::Sh9;
use crate::microfacet::slope_masking::SlopeMasking;
use crate::microfacet::transfer::TransferFunction;
use crate::scene::surface::Surface;
use std::sync::Arc;

/// A material with its tables built, ready to evaluate.
#[derive(Clone, Debug)]
pub struct Evaluator {
    /// The material.
    pub material: Material,
    /// Its explicit surface.
    pub surface: Surface,
    /// The colour model, compiled (a gradient owns its pre-convolved table).
    pub color: CompiledColor,
    /// The transfer function's moments, compiled (a curve owns its pre-convolved table).
    pub transfer: CompiledTransfer,
    /// Global mean and std of g(f), f ~ N(0, 1): standardizes heights for height-indexed colour.
    pub global_height: (f64, f64),
    /// The slope colour term's map, compiled (when the material has one).
    pub slope_color: Option<CompiledSlopeColor>,
    /// An image driver's value-conditioned slopes and `T⁻¹` for the mixture's bins, when the
    /// material uses them ([`Material::image_slope_mixture`]).
    pub image_slopes: Option<Arc<ImageSlopes>>,
    /// The environment's SH9 radiance with its intensity applied: built for the procedural sky,
    /// set by the application for a file ([`Evaluator::set_environment_map`]); `None` = no
    /// environment light (or a file not loaded yet).
    pub environment: Option<Sh9>,
    /// The measured base BRDF named by `material.brdf.measured`, set by the application once the
    /// file is read ([`Evaluator::set_measured`]); `None` = the analytic base BRDF (or a file not
    /// loaded yet).
    pub measured: Option<Arc<MeasuredBrdf>>,
    /// The noise's table of slope-conditioned masking, when the material asks for it
    /// (`filtering.slope_masking`, [`crate::eval::masking::slope_masking_table`]).
    pub slope_masking: Option<Arc<SlopeMaskingTable>>,
    /// The transfer mixture's masking conditioned on the driver's value and slope
    /// ([`crate::eval::masking::transfer_masking_table`]): built for a noise driver under a transfer curve
    /// when `filtering.slope_masking` is conditioned (Smith's bins otherwise).
    pub transfer_masking: Option<Arc<TransferMaskingTable>>,
    /// Whether the analytic views' camera rays can be stopped by the unresolved relief on a crest
    /// they pass before meeting h̄ ([`crate::eval::interception`]).
    pub interception: Interception,
}

impl Evaluator {
    /// Build the tables a material needs.
    pub fn new(material: &Material) -> Result<Self, DriverError> {
        Self::reusing(material, None)
    }

    /// Like [`Evaluator::new`], but takes each table from `previous` when its inputs did not change
    /// (the colour map's table depends only on the colour model and the table spec, the transfer
    /// table only on g and the spec): an edit of σ_n or of the BRDF rebuilds nothing.
    pub fn reusing(material: &Material, previous: Option<&Evaluator>) -> Result<Self, DriverError> {
        // The same image driver (path and size) keeps its loaded image.
        let image = previous
            .filter(|p| p.material.driver == material.driver)
            .and_then(|p| p.surface.driver.image())
            .map(|t| t.image.clone());
        Self::with_image(material, image, previous)
    }

    /// Like [`Evaluator::reusing`] with the decoded image of an image driver (ignored for noise).
    pub fn with_image(
        material: &Material,
        image: Option<Arc<ImageDriver>>,
        previous: Option<&Evaluator>,
    ) -> Result<Self, DriverError> {
        let surface = Surface::with_driver(material, DriverField::new(material, image)?);
        let spec = material.filtering.table;
        let same_spec = previous.is_some_and(|p| p.material.filtering.table == spec);
        // The histogram depends on the image; whether it is used, on the material.
        let histogram = material.image_histogram();
        let same_histogram = previous.is_some_and(|p| {
            p.material.image_histogram() == histogram
                && (!histogram || p.material.driver == material.driver)
        });
        // Built at most once, for the colour table and the image's slope table alike.
        let image_histogram = std::cell::OnceCell::new();
        let histogram_of = |t: &crate::driver::field::TiledImage| {
            image_histogram
                .get_or_init(|| DriverHistogram::of_image(&t.image))
                .clone()
        };
        let color = match previous {
            Some(p) if same_spec && same_histogram && p.material.color == material.color => {
                p.color.clone()
            }
            _ => {
                let h = surface
                    .driver
                    .image()
                    .filter(|_| histogram)
                    .map(histogram_of);
                CompiledColor::new(&material.color, spec, h.as_ref())
            }
        };
        let transfer = match previous {
            Some(p) if same_spec && p.material.heights.transfer == material.heights.transfer => {
                p.transfer.clone()
            }
            _ => CompiledTransfer::new(&material.heights.transfer, spec),
        };
        let image_slopes = match (material.image_slope_mixture(), surface.driver.image()) {
            (true, Some(t)) => previous
                .filter(|p| p.material.driver == material.driver)
                .and_then(|p| p.image_slopes.clone())
                .or_else(|| {
                    Some(Arc::new(ImageSlopes::new(
                        &ConditionalSlopes::of_image(&t.image),
                        &histogram_of(t),
                    )))
                }),
            _ => None,
        };
        let slope_masking = match (material.filtering.slope_masking, &surface.driver) {
            (SlopeMasking::Conditioned, DriverField::Noise(noise)) => previous
                .filter(|p| {
                    p.material.driver == material.driver && p.material.slopes == material.slopes
                })
                .and_then(|p| p.slope_masking.clone())
                .or_else(|| SlopeMaskingTable::shared(noise)),
            _ => None,
        };
        // The transfer mixture's masking conditioned on the driver's value and slope: a noise
        // driver's, under a transfer curve, with the masking conditioned.
        let transfer_masking = match (material.filtering.slope_masking, &surface.driver) {
            (SlopeMasking::Conditioned, DriverField::Noise(noise))
                if material.transfer_mixture()
                    && matches!(material.heights.transfer, TransferFunction::Curve(_)) =>
            {
                previous
                    .filter(|p| {
                        p.material.driver == material.driver
                            && p.material.heights.transfer == material.heights.transfer
                    })
                    .and_then(|p| p.transfer_masking.clone())
                    .or_else(|| TransferMaskingTable::shared(noise, &material.heights.transfer))
            }
            _ => None,
        };
        let g = material.heights.transfer.moments(0.0, 1.0);
        let environment = match previous {
            Some(p) if p.material.lighting == material.lighting => p.environment,
            _ => material.lighting.builtin_sh(),
        };
        Ok(Self {
            material: material.clone(),
            surface,
            color,
            transfer,
            global_height: (g.mean, g.std.max(1e-12)),
            slope_color: material.terms.slope.as_ref().map(|t| t.color.compiled()),
            image_slopes,
            environment,
            measured: None,
            slope_masking,
            transfer_masking,
            interception: Interception::default(),
        })
    }

    /// Use the SH9 radiance of an environment file (projected by the application with
    /// [`EquirectMap::sh`]) as the environment, scaled by the material's intensity; ignored when
    /// the material has no environment.
    pub fn set_environment_radiance(&mut self, radiance: &Sh9) {
        self.environment = self
            .material
            .lighting
            .environment
            .as_ref()
            .map(|e| radiance.scaled(e.intensity));
    }

    /// [`Evaluator::set_environment_radiance`] from an equirectangular map.
    pub fn set_environment_map(&mut self, map: &EquirectMap) {
        self.set_environment_radiance(&map.sh());
    }

    /// Use a measured base BRDF: ground truth and naive shade facets with its table, the filtered
    /// views with its fit, whose σ becomes `material.brdf`'s roughness (with albedo and F0 1, the
    /// fit's per-channel kd and F0 applied by [`Evaluator::channel_weights`]); see
    /// [`crate::material::measured`]. Ignored when the material names no measured file.
    pub fn set_measured(&mut self, measured: Arc<MeasuredBrdf>) {
        let Some(path) = self.material.brdf.measured.clone() else {
            return;
        };
        self.material.brdf = measured.fitted_base(Some(path));
        self.measured = Some(measured);
    }

    /// How the base BRDF's albedo and F0 become colours: the measured BRDF's fit, or grey and
    /// white for the analytic base BRDF.
    pub fn channel_weights(&self) -> ChannelWeights {
        self.measured
            .as_ref()
            .map_or(ChannelWeights::ANALYTIC, |m| m.channel_weights())
    }

    /// Colour of a point of the explicit surface with driver value f.
    pub fn color_at(&self, f: f64) -> [f64; 3] {
        let (gm, gs) = self.global_height;
        let t = (self.material.heights.transfer.eval(f) - gm) / gs;
        self.color.at_point(f, t)
    }
}

#[cfg(test)]
mod reuse_tests {
    use super::*;
    use crate::material::ColorModel;
    use crate::material::colormap::Gradient;
    use crate::microfacet::transfer::Curve;
    use crate::microfacet::transfer::TransferFunction;

    fn tables(p: &Evaluator) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
        (
            p.color
                .table()
                .map(|t| t.texels.clone())
                .unwrap_or_default(),
            p.transfer
                .table()
                .map(|t| t.texels.clone())
                .unwrap_or_default(),
        )
    }

    /// Reused tables equal freshly built ones; a change of an input rebuilds exactly its table.
    #[test]
    fn tables_are_reused_only_when_their_inputs_are_unchanged() {
        let mut m = Material::default();
        m.heights.transfer = TransferFunction::Curve(Curve::moss());
        let a = Evaluator::new(&m).unwrap();
        m.brdf.roughness = 0.4;
        m.slopes.sigma_nx = 0.2;
        let b = Evaluator::reusing(&m, Some(&a)).unwrap();
        assert_eq!(tables(&b), tables(&Evaluator::new(&m).unwrap()));
        assert_eq!(b.material, m);
        if let ColorModel::Gradient { map, .. } = &mut m.color {
            *map = Gradient::viridis(-2.0, 2.0);
        }
        let c = Evaluator::reusing(&m, Some(&b)).unwrap();
        assert_ne!(tables(&c).0, tables(&b).0, "colour table rebuilt");
        assert_eq!(tables(&c).1, tables(&b).1, "transfer table kept");
        assert_eq!(tables(&c), tables(&Evaluator::new(&m).unwrap()));
        m.filtering.table.size_m = 64;
        let d = Evaluator::reusing(&m, Some(&c)).unwrap();
        assert_eq!(
            tables(&d),
            tables(&Evaluator::new(&m).unwrap()),
            "new spec rebuilds both"
        );
    }
}
