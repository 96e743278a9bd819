//! # lodestone-core
//!
//! All of Lodestone's math and its material model, with no GPU and no UI. Every formula lives here
//! once, with the paper and equation it implements in its doc comment; the WGSL in
//! `lodestone-render` mirrors the f32 functions of this crate under the same names, in the same
//! folders. `docs/equations.md` maps each paper equation to its Rust and WGSL function.
//!
//! Modules, lowest first (each uses only those above it, except `material::features`, which names
//! the scene's [`scene::shape::Shape`]):
//! * [`math`]: special functions, quadrature, piecewise polynomials, SH, Gaussian helpers.
//! * [`microfacet`]: slopes, Smith Λ, masking–shadowing G2, D_h, D_s, base BRDF, attribute model.
//! * [`material`]: the material (preset) and its parts: colour map and pre-convolved tables,
//!   transfer functions, colour terms, slope colour, lighting, validation, feature sets.
//! * [`driver`]: the driving function (noise, image) and its footprint statistics.
//! * [`scene`]: directions, camera, shapes, the explicit surface and its march.
//! * [`eval`]: every method (naive, view-independent, filtered, ground truth) on one footprint
//!   and one pixel: the reference the GPU is tested against.
//! * [`object`]: whole objects (#19): base shapes by signed distance, the relief in space, and
//!   the displaced object's ray trace.
//!
//! Papers (plain text in `../shared/papers/`):
//! * [HN12] Heitz, Neyret. *Representing Appearance and Pre-filtering Subpixel Data in Sparse Voxel Octrees.* HPG 2012.
//! * [HNPN14] Heitz, Nowrouzezahrai, Poulin, Neyret. *Filtering Non-Linear Transfer Functions on Surfaces.* TVCG 2014.

pub mod adaptive;
pub mod driver;
pub mod eval;
#[doc(hidden)]
pub mod fixtures;
pub mod material;
pub mod math;
pub mod microfacet;
pub mod object;
pub mod scene;
