//! # lodestone-render
//!
//! Lodestone's renderer on wgpu, with no UI. It grows into one render target per view (naive MIP,
//! ground truth, filtered) with offscreen readback; today it holds device setup, the WGSL mirrors of
//! `lodestone-core`'s f32 functions and the harness that checks them on the adapter.

pub mod compute;
pub mod error_map;
pub mod gpu;
pub mod gpu_types;
pub mod renderer;
pub mod shaders;

pub use gpu::{GpuContext, GpuError};
pub use renderer::{GpuMaterial, LinearImage, RenderError, Renderer, Scene, ViewMode, ViewTarget};
