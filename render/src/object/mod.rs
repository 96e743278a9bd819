//! Whole objects on the GPU (#19, [HN12]): the voxel octree uploaded ([`voxel_store`]) and cone
//! traced per pixel in WGSL ([`object_view`]), mirroring `lodestone_core::object`, whose CPU cone
//! tracer is the reference the tests hold the GPU to.

pub mod object_view;
pub mod voxel_store;
