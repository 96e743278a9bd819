//! Structs shared with WGSL, byte for byte, each written once: [`gpu_struct!`] declares the Rust
//! struct and the WGSL declaration together from one field list, and `tests/shaders.rs` checks
//! every field offset against the layout naga computes for the generated WGSL.
//!
//! The parameters are split by who changes them: [`MaterialParams`] (binding 0, `params` in WGSL)
//! is fixed when a material is uploaded and is all the material functions read (the engine bundle
//! ships exactly it); [`ViewParams`] (binding 3, `view`) is the camera, light and pass of one view
//! and is written per frame.
//!
//! Layout rules (WGSL storage, std430): a `vec3<f32>` aligns to 16 bytes and is followed by a
//! scalar; structs round up to 16 bytes. The Rust side is `#[repr(C)]` with `[f32; 3]` for vec3.

use bytemuck::{Pod, Zeroable};

/// Declare a `#[repr(C)]` struct shared with WGSL: each field is `name: RustType => "wgsl type"`
/// with its doc comment. Generates the struct, [`GpuStruct`] (its WGSL declaration and field
/// offsets) and nothing else, so the field list exists once.
macro_rules! gpu_struct {
    (
        $(#[$m:meta])*
        $name:ident as $wgsl:literal {
            $( $(#[doc = $doc:literal])* $field:ident : $rty:ty => $wty:literal ),* $(,)?
        }
    ) => {
        $(#[$m])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
        pub struct $name {
            $( $(#[doc = $doc])* pub $field: $rty ),*
        }

        impl GpuStruct for $name {
            const WGSL_NAME: &'static str = $wgsl;
            const FIELDS: &'static [(&'static str, &'static str, &'static str)] =
                &[$((stringify!($field), $wty, concat!($($doc),*))),*];

            fn offsets() -> Vec<(&'static str, usize)> {
                vec![$((stringify!($field), std::mem::offset_of!($name, $field))),*]
            }
        }
    };
}

/// A struct shared with WGSL (declared by [`gpu_struct!`]).
pub trait GpuStruct: Pod {
    /// The struct's WGSL name.
    const WGSL_NAME: &'static str;
    /// `(field, WGSL type, doc)` in declaration order.
    const FIELDS: &'static [(&'static str, &'static str, &'static str)];

    /// Field names and byte offsets on the Rust side, in declaration order (for the layout test).
    fn offsets() -> Vec<(&'static str, usize)>;

    /// The WGSL declaration, each field with its doc as a comment.
    fn wgsl() -> String {
        let mut s = format!("struct {} {{\n", Self::WGSL_NAME);
        for (name, ty, doc) in Self::FIELDS {
            s.push_str(&format!("    // {}\n    {name}: {ty},\n", doc.trim()));
        }
        s.push_str("}\n");
        s
    }
}

gpu_struct! {
    /// The camera, light and pass of one view (written per frame).
    ViewParams as "ViewParams" {
        /// Eye position, relative to the camera target (world units).
        eye: [f32; 3] => "vec3<f32>",
        /// tan of half the vertical field of view.
        tan_half_fov: f32 => "f32",
        /// Camera right axis (unit).
        right: [f32; 3] => "vec3<f32>",
        /// Width / height of the image.
        aspect: f32 => "f32",
        /// Camera up axis (unit).
        up: [f32; 3] => "vec3<f32>",
        /// Standard deviation of the Gaussian pixel filter, in pixels (`camera::PIXEL_SIGMA`).
        pixel_sigma: f32 => "f32",
        /// Camera forward axis (unit).
        forward: [f32; 3] => "vec3<f32>",
        /// Ground-truth pass index: 0 starts afresh (the pass overwrites the sums), any other
        /// value adds to them (each pixel's next ray is its own count's position in the
        /// low-discrepancy sequence); 0 for analytic modes.
        frame: u32 => "u32",
        /// Unit direction toward the directional light (world).
        light: [f32; 3] => "vec3<f32>",
        /// What the pass computes (`MODE_*`, [`crate::gpu_codes::ModeCode`]).
        mode: u32 => "u32",
        /// Image width in pixels.
        width: u32 => "u32",
        /// Image height in pixels.
        height: u32 => "u32",
        /// The object (`SHAPE_*`, [`crate::gpu_codes::ShapeCode`]).
        shape: u32 => "u32",
        /// Cylinder radius R (world units; unused for the plane).
        radius: f32 => "f32",
        /// Ground truth over a list (an adaptive plan, `Renderer::draw_planned`): how many
        /// entries (phase 0) or runs (phase 1) of the `order` buffer this pass reads; 0 traces
        /// every pixel, one ray each.
        list_len: u32 => "u32",
        /// A listed pass's phase: 0 traces the entries into `scratch`, 1 adds each run to its
        /// pixel, 2 and 3 trace again, alone in their SIMD batch, the entries (2) or this frame's
        /// pixels (3) whose loops the adapter cut.
        phase: u32 => "u32",
        /// Where the runs start in the `order` buffer (entries).
        runs_at: u32 => "u32",
        /// 1: a ray whose loops were cut is marked for phase 2 or 3 instead of kept (software
        /// adapters: `GpuContext::is_software`); 0: it is kept and counted.
        retry_cut: u32 => "u32",
    }
}

gpu_struct! {
    /// A material's constant parameters (written when the material is uploaded); offsets point into
    /// the material's data buffer (binding 1), in f32 units.
    MaterialParams as "Params" {
        /// Attribute model ā per channel [HN12 Eq. 17].
        attr_mean: [f32; 3] => "vec3<f32>",
        /// ln of the smallest L of the D_h table.
        dh_ln_min: f32 => "f32",
        /// Attribute model a_s per channel [HN12 Eq. 17].
        attr_corr: [f32; 3] => "vec3<f32>",
        /// ln of the largest L of the D_h table.
        dh_ln_max: f32 => "f32",
        /// Number of noise waves.
        wave_count: u32 => "u32",
        /// Height scale σ_h.
        sigma_h: f32 => "f32",
        /// Diffuse albedo.
        albedo: f32 => "f32",
        /// Specular F0.
        specular: f32 => "f32",
        /// Base roughness σ_n0.
        roughness: f32 => "f32",
        /// Top of the surface's slab (max height).
        h_max: f32 => "f32",
        /// max |g′| of the transfer function (Lipschitz factor of the march).
        g_lip: f32 => "f32",
        /// Smallest march step.
        min_step: f32 => "f32",
        /// Transfer function (`TRANSFER_*`).
        transfer_kind: u32 => "u32",
        /// Colour model (`COLOR_*`).
        color_kind: u32 => "u32",
        /// Masking–shadowing correlation (`CORRELATION_*`).
        correlation: u32 => "u32",
        /// D_h model (`HEIGHT_FILTER_*`).
        height_filter: u32 => "u32",
        /// Nodes of the polar slope rule (`SlopeRule::len`: radii × angles).
        slope_nodes: u32 => "u32",
        /// Mean of g(f), f ~ N(0, 1) (standardizes heights).
        g_mean: f32 => "f32",
        /// Std of g(f), f ~ N(0, 1).
        g_std: f32 => "f32",
        /// Entries of the D_h table.
        dh_size: u32 => "u32",
        /// Offset of the slope rule's nodes (z.x, z.y, weight).
        slope_rule_offset: u32 => "u32",
        /// Offset of the colour table.
        ct_offset: u32 => "u32",
        /// Colour table size along the mean.
        ct_size_m: u32 => "u32",
        /// Colour table size along σ.
        ct_size_s: u32 => "u32",
        /// Colour table's smallest mean.
        ct_m_min: f32 => "f32",
        /// Colour table's largest mean.
        ct_m_max: f32 => "f32",
        /// Colour table's largest σ.
        ct_sigma_max: f32 => "f32",
        /// Offset of the transfer table.
        tt_offset: u32 => "u32",
        /// Transfer table size along the mean.
        tt_size_m: u32 => "u32",
        /// Transfer table size along σ.
        tt_size_s: u32 => "u32",
        /// Transfer table's smallest mean.
        tt_m_min: f32 => "f32",
        /// Transfer table's largest mean.
        tt_m_max: f32 => "f32",
        /// Transfer table's largest σ.
        tt_sigma_max: f32 => "f32",
        /// Offset of the colour map's polynomial.
        cp_offset: u32 => "u32",
        /// Knots of the colour map's polynomial.
        cp_knots: u32 => "u32",
        /// Offset of the transfer function's polynomial (g, g′).
        tp_offset: u32 => "u32",
        /// Knots of the transfer function's polynomial.
        tp_knots: u32 => "u32",
        /// Offset of the waves (k.x, k.y, amplitude, phase).
        waves_offset: u32 => "u32",
        /// Offset of the D_h table (mean, std per entry).
        dh_offset: u32 => "u32",
        /// Bound of |∇h| (the cylinder's march rate).
        slope_bound: f32 => "f32",
        /// Driver (`DRIVER_*`).
        driver_kind: u32 => "u32",
        /// Offset of the image pyramid's level records.
        image_offset: u32 => "u32",
        /// Levels of the image pyramid.
        image_levels: u32 => "u32",
        /// Level-0 texels per world unit.
        image_scale: f32 => "f32",
        /// Level-0 texel coordinate of the camera target, x.
        image_u0: f32 => "f32",
        /// Level-0 texel coordinate of the camera target, y.
        image_v0: f32 => "f32",
        /// Lipschitz bound of the image along x (per texel).
        image_lip_x: f32 => "f32",
        /// Lipschitz bound of the image along y (per texel).
        image_lip_y: f32 => "f32",
        /// Constant colour term C0 (linear RGB) [HNPN14 Sec. 6].
        c0: [f32; 3] => "vec3<f32>",
        /// Weight κ0 of C0 (0 when absent).
        kappa0: f32 => "f32",
        /// Slope colour direction d (unit, world).
        sc_dir: [f32; 3] => "vec3<f32>",
        /// Weight κ2 of the slope colour C_s (0 when absent).
        kappa2: f32 => "f32",
        /// Weight κ1 of the colour model C_h.
        kappa1: f32 => "f32",
        /// Combination of the terms (`COMBINE_*`).
        combine_mode: u32 => "u32",
        /// Strength of the directional light.
        sun: f32 => "f32",
        /// Knots of the slope colour's polynomial.
        sp_knots: u32 => "u32",
        /// Offset of the slope colour's polynomial.
        sp_offset: u32 => "u32",
        /// Offset of the environment's SH9 irradiance coefficients.
        env_offset: u32 => "u32",
        /// 1 when there is an environment light.
        has_env: u32 => "u32",
        /// How marches step and refine a crossing (`MARCH_*`, core's `scene::march::March`).
        march: u32 => "u32",
        /// Nested octave levels of the fast march (core's `noise::level_ends`, at most 4).
        level_count: u32 => "u32",
        /// The first three levels' ends, eight bits each (the last level ends at `wave_count`).
        level_ends: u32 => "u32",
        /// Offset of the bound grid's pyramid (`[lo, hi]` per cell, level after level).
        grid_offset: u32 => "u32",
        /// Level-0 cells per side of the bound grid (0: no grid).
        grid_n: u32 => "u32",
        /// Levels of the bound grid's pyramid.
        grid_levels: u32 => "u32",
        /// Side of a level-0 cell of the bound grid.
        grid_cell: f32 => "f32",
        /// The bound grid's lower-left corner relative to the camera target, x.
        grid_x0: f32 => "f32",
        /// The bound grid's lower-left corner relative to the camera target, y.
        grid_y0: f32 => "f32",
        /// Σ|a_i| of the waves (the grid's tails and f32 margin are relative to it).
        grid_amp: f32 => "f32",
        /// Offset of the field table's vertices (`[f, c·f_x, c·f_y, c²·f_xy]` each; core's
        /// `scene::field_grid::FieldGrid`).
        field_offset: u32 => "u32",
        /// Cells per side of the field table (0: no table).
        field_n: u32 => "u32",
        /// Side of a cell of the field table.
        field_cell: f32 => "f32",
        /// The field table's lower-left vertex relative to the camera target, x.
        field_x0: f32 => "f32",
        /// The field table's lower-left vertex relative to the camera target, y.
        field_y0: f32 => "f32",
        /// Bound of the table's value error, with the f32 margin.
        field_error: f32 => "f32",
        /// Bound of the table's x-slope error, with the f32 margin.
        field_slope_error_x: f32 => "f32",
        /// Bound of the table's y-slope error, with the f32 margin.
        field_slope_error_y: f32 => "f32",
        /// Monotonicity of the transfer function: 1 never decreasing (the identity too), 2 never
        /// increasing, 0 neither (core's `OctaveSurface::monotone`).
        transfer_monotone: u32 => "u32",
        /// Offset of the slope rule each bin of the transfer mixture uses.
        mix_rule_offset: u32 => "u32",
        /// Nodes of that rule; 0 when the filtered view keeps one Gaussian (no mixture).
        mix_nodes: u32 => "u32",
        /// 1 when the specular lobe uses the noise's own slope density (`NoiseSlopes::Exact`),
        /// 0 for the Gaussian.
        noise_slopes: u32 => "u32",
        /// Offset of the image histogram's table H (f̄, σ_f) → (μ_G, σ_G).
        ht_offset: u32 => "u32",
        /// Table H size along the mean; 0 when the colour table is over the driver's value.
        ht_size_m: u32 => "u32",
        /// Table H size along σ.
        ht_size_s: u32 => "u32",
        /// Table H's smallest mean.
        ht_m_min: f32 => "f32",
        /// Table H's largest mean.
        ht_m_max: f32 => "f32",
        /// Table H's largest σ.
        ht_sigma_max: f32 => "f32",
        /// Offset of the transfer table's slope pyramids (core's `math::table_slope::TableSlope`).
        ts_offset: u32 => "u32",
        /// Column intervals per pyramid row, rounded up to a power of two (`TableSlope::p`).
        ts_p: u32 => "u32",
        /// Offset of an image's value-conditioned slope table (core's
        /// `driver::conditional_slopes::ImageSlopes`): IMAGE_SLOPE_BINS scales s², then
        /// IMAGE_INVERSE_SIZE values of T⁻¹.
        is_offset: u32 => "u32",
        /// 1 when the mixture's bins carry the image's value-conditioned slopes, 0 otherwise.
        is_on: u32 => "u32",
        /// 1 when a measured base BRDF's table is in the data buffer (core's
        /// `material::measured`): facets are looked up in it, the specular lobe takes their colour.
        measured: u32 => "u32",
        /// Diffuse albedo weight per channel (core's `ChannelWeights::kd`; 1 for the analytic BRDF).
        kd_rgb: [f32; 3] => "vec3<f32>",
        /// Offset of the measured table: red, green, blue channels of `MERL_ENTRIES` each.
        merl_offset: u32 => "u32",
        /// Offset of a measured BRDF's fitted lobes (core's `merl_fit::Lobe`: σ, weight RGB,
        /// Fresnel weight RGB; 7 floats each).
        lobe_offset: u32 => "u32",
        /// Number of fitted lobes (0 for the analytic BRDF).
        lobe_count: u32 => "u32",
        /// Offset of the slope-conditioned masking table (core's
        /// `eval::masking::slope_masking_table::SlopeMaskingTable`: r0, the level step, then the profiles).
        cm_offset: u32 => "u32",
        /// 1 when the filtered view conditions masking on the slope (the table is present).
        cm_on: u32 => "u32",
        /// Offset of the transfer curve's masking table conditioned on the driver's value and
        /// slope (core's `eval::masking::transfer_masking_table::TransferMaskingTable`: σ_f, the gradient
        /// covariance xx, xy, yy, then the entries).
        tm_offset: u32 => "u32",
        /// 1 when the transfer mixture's bins take that table (`tm_offset` is set).
        tm_on: u32 => "u32",
        /// Offset of the slope rule the conditioned bins shade on (x, y, weight per node).
        tm_rule_offset: u32 => "u32",
        /// Nodes of that rule (core's `conditioned_slope_rule`).
        tm_nodes: u32 => "u32",
        /// 1 when camera rays can be stopped by the unresolved relief on a crest they pass (core's
        /// `eval::interception::Interception::Crests`), 0 when they meet h̄.
        interception: u32 => "u32",
        /// The driver's unfiltered gradient covariance, xx (core's `DriverField::gradient_cov`,
        /// world units): with the footprint's unresolved part it bounds the resolved slope.
        grad_cov_xx: f32 => "f32",
        /// Its yy.
        grad_cov_yy: f32 => "f32",
        /// Its xy.
        grad_cov_xy: f32 => "f32",
    }
}

gpu_struct! {
    /// The object view's parameters (binding 4, `object` in WGSL; `render/src/object/`): the camera
    /// as an eye and the unnormalised ray direction's affine map from pixel coordinates (core's
    /// `Camera::raw_dir`), the sun, the octree's extent and hash, the compositing mode.
    ObjectParams as "ObjectParams" {
        /// The eye (world, the object's frame).
        eye: [f32; 3] => "vec3<f32>",
        /// Half the side of the octree's root cube, centred at the origin.
        half: f32 => "f32",
        /// Unnormalised ray direction at pixel coordinates (0, 0).
        dir00: [f32; 3] => "vec3<f32>",
        /// The cone's spread: the pixel's angular radius (core's `pixel_cone`).
        spread: f32 => "f32",
        /// Change of the unnormalised direction per pixel in x.
        step_x: [f32; 3] => "vec3<f32>",
        /// Image width, pixels.
        width: u32 => "u32",
        /// Change of the unnormalised direction per pixel in y.
        step_y: [f32; 3] => "vec3<f32>",
        /// Image height, pixels.
        height: u32 => "u32",
        /// Unit direction toward the sun.
        light: [f32; 3] => "vec3<f32>",
        /// The sun's strength.
        sun: f32 => "f32",
        /// The octree's finest level.
        depth: u32 => "u32",
        /// Hash table slots minus one (a power of two minus one).
        slot_mask: u32 => "u32",
        /// Compositing (`MODE_MASKS` 0, `MODE_ALPHA_BLEND` 1, `MODE_NEAREST` 2).
        mode: u32 => "u32",
        /// 1 when shadow cones are traced.
        shadows: u32 => "u32",
        /// 2 (note_budget's unfoldable count).
        two: u32 => "u32",
        /// The thin lens's radius (world units; 0: a pinhole, no depth of field).
        lens: f32 => "f32",
        /// The distance along each pixel's axis in focus.
        focus: f32 => "f32",
        /// Padding to 16 bytes.
        pad0: u32 => "u32",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The generated WGSL names every field with its type, in order.
    #[test]
    fn wgsl_declarations_list_every_field() {
        let w = MaterialParams::wgsl();
        assert!(w.starts_with("struct Params {"));
        assert_eq!(
            w.matches(": u32,").count()
                + w.matches(": f32,").count()
                + w.matches(": vec3<f32>,").count(),
            MaterialParams::FIELDS.len()
        );
        assert!(w.contains("    sigma_h: f32,"));
        assert!(ViewParams::wgsl().contains("    eye: vec3<f32>,"));
        assert_eq!(ViewParams::offsets().len(), ViewParams::FIELDS.len());
    }
}
