//! Math utilities with no knowledge of materials or rendering: special functions and their f32
//! mirror, quadrature, piecewise polynomials, spherical harmonics, Gaussian helpers and the
//! reproducible random numbers of the Monte Carlo paths.

pub mod bessel;
pub mod correlation;
pub mod gaussian;
pub mod gaussian_weight;
pub mod log_linear_moments;
pub mod piecewise;
pub mod preconvolved;
pub mod quadrature;
pub mod random;
pub mod rounding;
pub mod sh;
pub mod special;
pub mod special_f32;
pub mod table_slope;
pub mod water_fill;
