//! Whole objects with procedural micro-relief (#19, [HN12]): a closed base shape given by its
//! signed distance ([`base_shape`]), displaced by the material's relief extended to space
//! ([`solid_noise`], [`displaced`]). What the object views' ground truth traces; the voxel octree
//! and its cone tracing [HN12 Secs. 4–5] are built from it.

pub mod base_shape;
pub mod cone_trace;
pub mod coverage_mask;
pub mod displaced;
pub mod object_truth;
pub mod octree;
pub mod shading;
pub mod solid_noise;
pub mod surface_samples;
pub mod view_error;
pub mod voxel_field;
pub mod voxel_stats;
