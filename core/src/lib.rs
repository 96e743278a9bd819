//! # lodestone-core
//!
//! All of Lodestone's math and its material model, with no GPU and no UI. Every formula lives here
//! once, with the paper and equation it implements in its doc comment; the WGSL in
//! `lodestone-render` mirrors the f32 functions of this crate under the same names.
//!
//! Papers (plain text in `../shared/papers/`):
//! * [HN12] Heitz, Neyret. *Representing Appearance and Pre-filtering Subpixel Data in Sparse Voxel Octrees.* HPG 2012.
//! * [HNPN14] Heitz, Nowrouzezahrai, Poulin, Neyret. *Filtering Non-Linear Transfer Functions on Surfaces.* TVCG 2014.

pub mod attribute;
pub mod brdf;
pub mod camera;
pub mod cielab;
pub mod color_terms;
pub mod colormap;
pub mod cylinder;
pub mod driver_field;
pub mod effective_height;
pub mod environment;
pub mod features;
pub mod footprint;
pub mod image_driver;
pub mod material;
pub mod noise;
pub mod piecewise;
pub mod preconvolved;
pub mod quadrature;
pub mod sh;
pub mod shadowing;
pub mod slope_color;
pub mod slopes;
pub mod smith;
pub mod special;
pub mod special_f32;
pub mod stability;
pub mod surface;
pub mod transfer;
pub mod validation;
pub mod visible_slopes;
