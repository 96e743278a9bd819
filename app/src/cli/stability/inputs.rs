//! Inputs the stability cases share: a step colour map and its ramp, and terraces with vertical
//! risers.

use lodestone_core::material::colormap::{ColorStop, Gradient, Interpolation};
use lodestone_core::microfacet::transfer::Curve;

/// A red/blue step colour map (Constant interpolation) with steps at ±0.5.
pub fn step_map() -> Gradient {
    Gradient {
        stops: vec![
            ColorStop {
                position: -0.5,
                color: [0.9, 0.1, 0.1],
            },
            ColorStop {
                position: 0.5,
                color: [0.1, 0.1, 0.9],
            },
        ],
        interpolation: Interpolation::Constant,
    }
}

/// `map` (Constant interpolation) as a Linear map: each step becomes a ramp 1e-7 wide ending at
/// the step.
pub fn ramp(map: &Gradient) -> Gradient {
    let mut stops = vec![];
    for (i, s) in map.stops.iter().enumerate() {
        if i > 0 {
            stops.push(ColorStop {
                position: s.position - 1e-7,
                color: map.stops[i - 1].color,
            });
        }
        stops.push(*s);
    }
    Gradient {
        stops,
        interpolation: Interpolation::Linear,
    }
}

/// Terraces with exactly vertical risers (equal f at both ends of each riser).
pub fn vertical_curve() -> Curve {
    Curve {
        points: vec![
            [-2.0, -1.0],
            [-0.5, -1.0],
            [-0.5, 0.0],
            [0.5, 0.0],
            [0.5, 1.0],
            [2.0, 1.0],
        ],
        interpolation: lodestone_core::microfacet::transfer::CurveInterpolation::Linear,
    }
}
