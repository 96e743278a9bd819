//! What a view draws: its mode and its scene (camera, light, object).

use crate::gpu_codes::ModeCode;
use glam::DVec3;
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::shape::Shape;

/// What a view shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ViewMode {
    /// Colour map of the filtered driver, filtered normal, no masking [HNPN14 Sec. 9].
    Naive,
    /// Exact footprint average of the colour, no masking.
    ViewIndependent,
    /// The papers' filtering.
    Filtered,
    /// Ray-traced explicit micro-geometry.
    Truth,
}

impl ViewMode {
    pub(crate) fn code(self) -> u32 {
        match self {
            Self::Naive => ModeCode::Naive,
            Self::ViewIndependent => ModeCode::ViewIndependent,
            Self::Filtered => ModeCode::Filtered,
            Self::Truth => ModeCode::Truth,
        }
        .code()
    }
}

/// Camera, light and object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// Unit direction toward the light.
    pub light: DVec3,
    /// The object: the plane, or a cylinder.
    pub shape: Shape,
}
