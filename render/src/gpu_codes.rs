//! Enum codes and constants shared with WGSL, defined once here and written into a WGSL prelude
//! ([`wgsl_prelude`], which also declares the material's `Params` struct from
//! [`MaterialParams`]) that the material unit starts with: the shaders compare `params.shape` with
//! `SHAPE_CYLINDER`, never with a bare `1u`, and the D_h fit constants, the azimuthal correlation
//! factor and the march's over-relaxation come from `lodestone-core`, so each has one definition.

use crate::gpu_types::{GpuStruct, MaterialParams};
use lodestone_core::driver::conditional_slopes;
use lodestone_core::driver::histogram::G_END;
use lodestone_core::eval::interception;
use lodestone_core::eval::lod_surface::LOD_SETTLE;
use lodestone_core::eval::masking::{
    slope_masking_table, transfer_masking_table, transfer_moments,
};
use lodestone_core::math::gaussian_weight;
use lodestone_core::microfacet::effective_height::{
    FIT_ALPHA_MU, FIT_ALPHA_SIGMA, FIT_BETA_MU, FIT_BETA_SIGMA,
};
use lodestone_core::microfacet::height_mixture::{MAX_KNOT_EDGES, MIXTURE_BINS};
use lodestone_core::microfacet::masking_shadowing::AZIMUTH_CORRELATION;
use lodestone_core::microfacet::slope_masking;
use lodestone_core::scene::bound_grid::GRID_MARGIN_F32;
use lodestone_core::scene::field_grid::FIELD_SETTLE;
use lodestone_core::scene::march::FAST_WIDTH_F32;
use lodestone_core::scene::march::RELAXATION;
use lodestone_core::scene::octave_march::{GRID_TRIES, HIT_GAP_F32};
use std::fmt::Write;
use std::sync::LazyLock;

/// A closed set of codes: a `#[repr(u32)]` enum and the WGSL constants naming its values.
macro_rules! gpu_enum {
    ($(#[$m:meta])* $name:ident { $($(#[$vm:meta])* $v:ident = $val:literal => $wgsl:literal),* $(,)? }) => {
        $(#[$m])*
        #[repr(u32)]
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum $name {
            $($(#[$vm])* $v = $val),*
        }

        impl $name {
            /// The WGSL constant of each value.
            pub const WGSL: &'static [(&'static str, u32)] = &[$(($wgsl, $val)),*];

            /// The code as the GPU sees it.
            pub fn code(self) -> u32 {
                self as u32
            }
        }
    };
}

gpu_enum! {
    /// `params.mode`: what a view computes (the first three are analytic methods, the order of
    /// `lodestone_core::eval::Method`).
    ModeCode {
        /// Naive MIP.
        Naive = 0 => "MODE_NAIVE",
        /// View-independent texture filtering.
        ViewIndependent = 1 => "MODE_VIEW_INDEPENDENT",
        /// The filtered model.
        Filtered = 2 => "MODE_FILTERED",
        /// Ground truth (progressive).
        Truth = 3 => "MODE_TRUTH",
    }
}

gpu_enum! {
    /// `params.shape`: `lodestone_core::scene::shape::Shape`.
    ShapeCode {
        /// The plane z = 0.
        Plane = 0 => "SHAPE_PLANE",
        /// The cylinder of `params.radius`.
        Cylinder = 1 => "SHAPE_CYLINDER",
    }
}

gpu_enum! {
    /// `params.driver_kind`: `lodestone_core::material::Driver`.
    DriverCode {
        /// Sum of sinusoids.
        Noise = 0 => "DRIVER_NOISE",
        /// Image pyramid.
        Image = 1 => "DRIVER_IMAGE",
    }
}

gpu_enum! {
    /// `params.color_kind`: `lodestone_core::eval::CompiledColor` and its source.
    ColorCode {
        /// Gradient of the driver value.
        Driver = 0 => "COLOR_DRIVER",
        /// Gradient of the standardized height.
        Height = 1 => "COLOR_HEIGHT",
        /// The attribute model ā + a_s·s(h).
        Attribute = 2 => "COLOR_ATTRIBUTE",
    }
}

gpu_enum! {
    /// `params.transfer_kind`: `lodestone_core::eval::CompiledTransfer`.
    TransferCode {
        /// g(f) = f.
        Identity = 0 => "TRANSFER_IDENTITY",
        /// A curve with its moment table.
        Curve = 1 => "TRANSFER_CURVE",
    }
}

gpu_enum! {
    /// `params.combine_mode`: `lodestone_core::material::color_terms::CombineMode`.
    CombineCode {
        /// κ0C0 + κ1C_h + κ2C_s.
        Linear = 0 => "COMBINE_LINEAR",
        /// Π(1 − κ + κC).
        Multiplicative = 1 => "COMBINE_MULTIPLICATIVE",
    }
}

gpu_enum! {
    /// `params.correlation`: `lodestone_core::microfacet::masking_shadowing::Correlation`.
    CorrelationCode {
        /// L = Λo + Λi.
        Uncorrelated = 0 => "CORRELATION_UNCORRELATED",
        /// Height–direction correlated.
        HeightDirection = 1 => "CORRELATION_HEIGHT_DIRECTION",
    }
}

gpu_enum! {
    /// `params.height_filter`: `lodestone_core::microfacet::effective_height::HeightFilter`.
    HeightFilterCode {
        /// The exact D_h table.
        Exact = 0 => "HEIGHT_FILTER_EXACT",
        /// The paper's fits [HNPN14 Eqs. 16–17].
        PaperFit = 1 => "HEIGHT_FILTER_PAPER_FIT",
    }
}

gpu_enum! {
    /// `params.march`: `lodestone_core::scene::march::March`.
    MarchCode {
        /// Global Lipschitz steps, bisection (24 halvings in f32).
        Reference = 0 => "MARCH_REFERENCE",
        /// The octave march for a noise driver; the Illinois method to the same bracket width.
        Fast = 1 => "MARCH_FAST",
    }
}

/// The WGSL prelude: every code above and core's named constants, as WGSL `const` declarations
/// (f32 constants written in Rust's shortest round-trip form, so WGSL reads the same f32).
pub fn wgsl_prelude() -> &'static str {
    static PRELUDE: LazyLock<String> = LazyLock::new(|| {
        let mut s = String::from(
            "// Generated by lodestone-render's gpu_codes.rs from Rust: do not edit.\n",
        );
        let sets: [&[(&str, u32)]; 9] = [
            ModeCode::WGSL,
            ShapeCode::WGSL,
            DriverCode::WGSL,
            ColorCode::WGSL,
            TransferCode::WGSL,
            CombineCode::WGSL,
            CorrelationCode::WGSL,
            HeightFilterCode::WGSL,
            MarchCode::WGSL,
        ];
        let counts: &[(&str, u32)] = &[
            ("GRID_TRIES", GRID_TRIES as u32),
            ("MIXTURE_BINS", MIXTURE_BINS as u32),
            ("MAX_KNOT_EDGES", MAX_KNOT_EDGES as u32),
            ("IMAGE_SLOPE_BINS", conditional_slopes::BINS as u32),
            (
                "IMAGE_INVERSE_SIZE",
                conditional_slopes::INVERSE_SIZE as u32,
            ),
            ("SLOPE_NODES", slope_masking::SLOPE_NODES as u32),
            ("HEIGHT_NODES", slope_masking::HEIGHT_NODES as u32),
            ("TABLE_ENTRY", slope_masking_table::ENTRY as u32),
            ("TABLE_AZIMUTHS", slope_masking_table::TABLE_AZIMUTHS as u32),
            ("TABLE_LEVELS", slope_masking_table::TABLE_LEVELS as u32),
            ("TABLE_NUS", slope_masking_table::TABLE_NUS as u32),
            (
                "TRANSFER_VALUE_NODES",
                transfer_masking_table::VALUE_NODES as u32,
            ),
            (
                "TRANSFER_LENGTH_NODES",
                transfer_moments::LENGTH_NODES as u32,
            ),
            (
                "TRANSFER_MOMENT_ENTRY",
                transfer_masking_table::MOMENT_ENTRY as u32,
            ),
            ("DATA_ROW", DATA_ROW),
            ("INTERCEPTION_MAX_STEPS", interception::MAX_STEPS as u32),
        ];
        for (name, v) in sets.into_iter().flatten().chain(counts) {
            let _ = writeln!(s, "const {name}: u32 = {v}u;");
        }
        let floats = [
            ("DH_FIT_ALPHA_MU", FIT_ALPHA_MU),
            ("DH_FIT_BETA_MU", FIT_BETA_MU),
            ("DH_FIT_ALPHA_SIGMA", FIT_ALPHA_SIGMA),
            ("DH_FIT_BETA_SIGMA", FIT_BETA_SIGMA),
            ("AZIMUTH_CORRELATION", AZIMUTH_CORRELATION),
            ("RELAXATION", RELAXATION),
            ("HIT_GAP", HIT_GAP_F32),
            ("FAST_WIDTH", FAST_WIDTH_F32),
            ("GRID_MARGIN", GRID_MARGIN_F32),
            ("FIELD_SETTLE", FIELD_SETTLE),
            ("LOD_SETTLE", LOD_SETTLE),
            ("INTERCEPTION_LEVEL_STEP", interception::LEVEL_STEP),
            ("INTERCEPTION_REACH", interception::REACH),
            ("INTERCEPTION_MIN_WEIGHT", interception::MIN_WEIGHT),
            ("INTERCEPTION_SLOPE_REACH", interception::SLOPE_REACH),
            ("HISTOGRAM_G_END", G_END),
            ("TABLE_NU_MIN", slope_masking_table::NU_MIN),
            ("TABLE_NU_RATIO", slope_masking_table::NU_RATIO),
            ("HEIGHT_NODE_DEPTH", -slope_masking::height_node(0)),
            (
                "TRANSFER_VALUE_DEPTH",
                -transfer_masking_table::value_node(0),
            ),
            ("TRANSFER_VALUE_STEP", transfer_masking_table::VALUE_STEP),
            (
                "GAUSSIAN_WEIGHT_MIN_VARIANCE",
                gaussian_weight::MIN_VARIANCE,
            ),
        ];
        for (name, v) in floats {
            let _ = writeln!(s, "const {name}: f32 = {:?};", v as f32);
        }
        s.push_str(&MaterialParams::wgsl());
        s
    });
    &PRELUDE
}

/// Words of the material's data per row of its texture (a power of two; `DATA_ROW` in WGSL).
pub const DATA_ROW: u32 = 4096;

const _: () = assert!(DATA_ROW.is_power_of_two());

#[cfg(test)]
mod tests {
    use super::*;

    /// The WGSL packs a slope-masking profile in a 3 × 3 matrix and the joint masking in an
    /// array of 90 (`microfacet/slope_masking.wgsl`: literal sizes, which the GLSL export
    /// round-trips).
    #[test]
    fn a_slope_masking_profile_fills_a_three_by_three_matrix() {
        assert_eq!(slope_masking::SLOPE_NODES, 9);
        assert_eq!(slope_masking::HEIGHT_NODES * slope_masking::SLOPE_NODES, 90);
        assert_eq!(slope_masking_table::ENTRY, 90);
    }

    /// Every constant is declared once, and the f32 literals read back as the same f32.
    #[test]
    fn prelude_declares_each_constant_once() {
        let p = wgsl_prelude();
        let names: Vec<&str> = p
            .lines()
            .filter_map(|l| l.strip_prefix("const "))
            .map(|l| l.split(':').next().unwrap_or(""))
            .collect();
        let mut sorted = names.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), names.len(), "duplicate constant in {p}");
        assert!(p.contains("const SHAPE_CYLINDER: u32 = 1u;"));
        assert!(p.contains(&format!("const AZIMUTH_CORRELATION: f32 = {:?};", 4.41f32)));
        for l in p.lines().filter(|l| l.contains(": f32 = ")) {
            let v: f32 = l
                .split("= ")
                .nth(1)
                .unwrap()
                .trim_end_matches(';')
                .parse()
                .unwrap();
            assert!(v.is_finite() && v > 0.0, "{l}");
        }
    }
}
