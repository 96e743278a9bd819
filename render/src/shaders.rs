//! WGSL sources. Every file is listed in [`ALL`] so one test validates them all with naga.
//!
//! The sources carry `//#if feature` directives (see [`crate::specialize`]): use them through
//! [`crate::specialize::specialize`] (with [`FeatureSet::all`](lodestone_core::features::FeatureSet::all)
//! for the all-features shader), never raw.

/// f32 special functions, mirroring `lodestone_core::special_f32`.
pub const SPECIAL: &str = include_str!("shaders/special.wgsl");

/// The material model (mirrors of core's noise, transfer, tables, Smith, BRDF and footprint code).
pub const MATERIAL: &str = include_str!("shaders/material.wgsl");

/// The image driver (mirrors `lodestone_core::image_driver` and the image half of `driver_field`).
pub const IMAGE_DRIVER: &str = include_str!("shaders/image_driver.wgsl");

/// The curved object (mirrors `lodestone_core::cylinder`).
pub const CYLINDER: &str = include_str!("shaders/cylinder.wgsl");

/// The view pass (camera rays, footprints, modes, progressive ground truth).
pub const VIEW: &str = include_str!("shaders/view.wgsl");

/// Every WGSL source with its file name; each is validated together with the files it needs.
pub const ALL: &[(&str, &str)] = &[
    ("special.wgsl", SPECIAL),
    ("material.wgsl", MATERIAL),
    ("image_driver.wgsl", IMAGE_DRIVER),
    ("cylinder.wgsl", CYLINDER),
    ("view.wgsl", VIEW),
];

/// The sources a file needs before it (WGSL has no includes; files are concatenated in this order).
pub fn prelude_for(name: &str) -> Vec<&'static str> {
    match name {
        // material.wgsl and image_driver.wgsl call each other (module scope is order-free in WGSL).
        "material.wgsl" => vec![SPECIAL, IMAGE_DRIVER],
        "image_driver.wgsl" => vec![SPECIAL, MATERIAL],
        "cylinder.wgsl" => vec![SPECIAL, MATERIAL, IMAGE_DRIVER],
        "view.wgsl" => vec![SPECIAL, MATERIAL, IMAGE_DRIVER, CYLINDER],
        _ => vec![],
    }
}

/// Names of the functions `special.wgsl` mirrors from `lodestone_core::special_f32` (same names).
pub const SPECIAL_MIRRORED: &[&str] = &[
    "erf",
    "erfc",
    "erfcx",
    "norm_pdf",
    "norm_cdf",
    "log_norm_cdf",
    "smith_lambda",
    "erf_series_sum",
    "cf_tail",
];
