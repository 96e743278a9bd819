//! A material's geometry as the views trace it: its driver field (the noise, or an image the
//! application decoded) and its explicit surface `h = σ_h·g(f)`. The material is above the driver
//! and the scene, so the constructors that read a whole [`Material`] live here.

use crate::driver::DriverError;
use crate::driver::field::DriverField;
use crate::driver::image::ImageDriver;
use crate::material::{Driver, Material};
use crate::scene::surface::Surface;
use std::sync::Arc;

impl DriverField {
    /// The driver of `material`; an image driver needs its decoded `image` (the application loads
    /// it relative to the preset), otherwise [`DriverError::ImageDriver`].
    pub fn new(material: &Material, image: Option<Arc<ImageDriver>>) -> Result<Self, DriverError> {
        match (&material.driver, image) {
            (Driver::Noise(_), _) => Ok(Self::Noise(
                material.noise().expect("a noise driver has noise"),
            )),
            (Driver::Image { size, .. }, Some(image)) => Ok(Self::tiled(image, *size)),
            (Driver::Image { .. }, None) => Err(DriverError::ImageDriver),
        }
    }
}

impl Surface {
    /// The surface of a noise-driven material (`None` for an image driver, which needs its image:
    /// [`Surface::with_driver`]).
    pub fn new(material: &Material) -> Option<Self> {
        Some(Self::with_driver(
            material,
            DriverField::Noise(material.noise()?),
        ))
    }

    /// The surface of `material` driven by `driver`.
    pub fn with_driver(material: &Material, driver: DriverField) -> Self {
        Self::from_parts(
            material.heights.sigma_h,
            material.heights.transfer.clone(),
            driver,
        )
    }
}
