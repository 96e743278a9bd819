//! The closed set of objects the views show.

use serde::{Deserialize, Serialize};

/// Which object the views show.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub enum Shape {
    /// The unbounded plane z = 0.
    #[default]
    Plane,
    /// A cylinder of this radius around an axis parallel to x through (·, 0, −R).
    Cylinder {
        /// Radius R (world units, > 0).
        radius: f64,
    },
}
