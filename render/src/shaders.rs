//! WGSL sources. Every file is listed in [`ALL`] so one test validates them all with naga.

/// f32 special functions, mirroring `lodestone_core::special_f32`.
pub const SPECIAL: &str = include_str!("shaders/special.wgsl");

/// Every WGSL source with its file name.
pub const ALL: &[(&str, &str)] = &[("special.wgsl", SPECIAL)];

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
