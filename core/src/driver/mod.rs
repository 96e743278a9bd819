//! The driving function f of a material and its statistics over a pixel footprint: the
//! sum-of-sinusoids noise (analytic attenuation), an image driver (its pyramid), and the
//! [`field::DriverField`] that is either.

pub mod conditional_slopes;
pub mod field;
pub mod footprint;
pub mod histogram;
pub mod image;
pub mod mip_level;
pub mod noise;
#[cfg(test)]
pub mod test_images;

/// Errors building a material's driver.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum DriverError {
    /// An image driver was given no image (the application loads it relative to the preset).
    #[error("the material's image driver has no image loaded")]
    ImageDriver,
}
