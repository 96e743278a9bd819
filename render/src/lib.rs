//! # lodestone-render
//!
//! Lodestone's renderer on wgpu, with no UI: headless device setup, the WGSL mirrors of
//! `lodestone-core`'s f32 functions (and the harness that checks them on the adapter), one
//! accumulation target per view (naive MIP, view-independent, filtered, ground truth) with readback
//! to linear f32 and 8-bit sRGB, and error heat maps (against the truth with its own noise taken
//! out: `truth_noise`).

pub mod adaptive_truth;
pub mod compute;
pub mod error;
pub mod error_map;
pub mod export;
pub mod gpu;
pub mod gpu_codes;
pub mod gpu_material;
pub mod gpu_types;
pub mod image;
pub mod material_data;
pub mod object;
pub mod pipelines;
pub mod renderer;
pub mod shaders;
pub mod specialize;
pub mod truth_noise;
pub mod view;
pub mod view_target;

pub use error::RenderError;
pub use gpu::{GpuContext, GpuError};
pub use gpu_material::GpuMaterial;
pub use image::LinearImage;
pub use renderer::Renderer;
pub use view::{Scene, ViewMode};
pub use view_target::ViewTarget;
