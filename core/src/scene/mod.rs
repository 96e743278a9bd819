//! What the views look at and from where: directions and tangent frames, the orbit camera and its
//! pixel footprints, the closed set of shapes (plane, cylinder) and the explicit micro-geometry
//! ([`surface::Surface`]) with its rigorous ray march.

pub mod bound_grid;
pub mod camera;
pub mod crossing;
pub mod cylinder;
pub mod direction;
pub mod field_grid;
pub mod field_step;
pub mod grid_skip;
pub mod local_slope;
pub mod march;
pub mod octave_march;
pub mod shape;
pub mod surface;
