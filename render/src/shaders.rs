//! WGSL sources, one file per core module in the same folders (`shaders/microfacet/smith.wgsl`
//! mirrors `core/src/microfacet/smith.rs`), plus the GPU-only files (`bindings.wgsl`, `view.wgsl`).
//!
//! WGSL has no includes: a shader is a concatenation of *units*. [`material`] is the generated
//! constants prelude ([`crate::gpu_codes::wgsl_prelude`]) followed by every file of
//! [`MATERIAL_FILES`]; [`SPECIAL`], [`IMAGE_DRIVER`], [`CYLINDER`] and [`VIEW`] are single files.
//! [`all`] lists every unit so one test validates them all with naga, and
//! `render/tests/shaders.rs` checks a table of (Rust function, WGSL function) pairs over every file.
//!
//! The sources carry `//#if feature` directives (see [`crate::specialize`]): use them through
//! [`crate::specialize::specialize`] (with [`FeatureSet::all`](lodestone_core::material::features::FeatureSet::all)
//! for the all-features shader), never raw.

use std::sync::LazyLock;

/// `(path under shaders/, source)` for each listed file.
macro_rules! wgsl_files {
    ($($path:literal),* $(,)?) => {
        &[$(($path, include_str!(concat!("shaders/", $path)))),*]
    };
}

/// f32 special functions, mirroring `lodestone_core::math::special_f32`.
pub const SPECIAL: &str = include_str!("shaders/math/special.wgsl");

/// The material model, one file per core module (order is free in WGSL; this is core's order).
pub const MATERIAL_FILES: &[(&str, &str)] = wgsl_files![
    "bindings.wgsl",
    "math/gaussian.wgsl",
    "math/bessel.wgsl",
    "math/piecewise.wgsl",
    "math/gaussian_weight.wgsl",
    "microfacet/slopes.wgsl",
    "microfacet/smith.wgsl",
    "microfacet/masking_shadowing.wgsl",
    "microfacet/effective_height.wgsl",
    "microfacet/height_mixture.wgsl",
    "microfacet/visible_slopes.wgsl",
    "microfacet/slope_density.wgsl",
    "microfacet/slope_masking.wgsl",
    "microfacet/brdf.wgsl",
    "microfacet/attribute.wgsl",
    "math/preconvolved.wgsl",
    "math/table_slope.wgsl",
    "microfacet/transfer.wgsl",
    "material/color_terms.wgsl",
    "material/merl.wgsl",
    "material/merl_fit.wgsl",
    "material/measured.wgsl",
    "driver/footprint.wgsl",
    "driver/noise.wgsl",
    "driver/field.wgsl",
    "driver/conditional_slopes.wgsl",
    "scene/direction.wgsl",
    "scene/bound_grid.wgsl",
    "scene/grid_skip.wgsl",
    "scene/field_grid.wgsl",
    "scene/field_step.wgsl",
    "scene/local_slope.wgsl",
    "scene/march.wgsl",
    "scene/octave_march.wgsl",
    "scene/surface.wgsl",
    "eval/compiled.wgsl",
    "eval/query.wgsl",
    "eval/shading.wgsl",
    "eval/masking/slope_masking_table.wgsl",
    "eval/masking/transfer_masking_table.wgsl",
    "eval/masking/slope_weights.wgsl",
    "eval/naive.wgsl",
    "eval/view_independent.wgsl",
    "eval/filtered.wgsl",
    "eval/mixture_bins.wgsl",
    "eval/ground_truth.wgsl",
    "eval/lod_surface.wgsl",
    "eval/interception.wgsl",
    "eval/pixel.wgsl",
];

/// The image driver (mirrors `lodestone_core::driver::image` and the image half of `driver::field`).
pub const IMAGE_DRIVER: &str = include_str!("shaders/driver/image.wgsl");

/// The curved object: its geometry (mirrors `lodestone_core::scene::cylinder`) and its pixels
/// (mirrors `lodestone_core::eval::cylinder`).
pub const CYLINDER: &str = concat!(
    include_str!("shaders/scene/cylinder.wgsl"),
    "\n",
    include_str!("shaders/eval/cylinder.wgsl")
);

/// The view pass (camera rays, footprints, modes, progressive ground truth).
pub const VIEW: &str = include_str!("shaders/view.wgsl");

/// The object view's files [HN12] (#19): each of `object/` mirrors the core module of its name in
/// `core/src/object/`; `object_view.wgsl` is the compute pass.
pub const OBJECT_FILES: &[(&str, &str)] = wgsl_files![
    "object/coverage_mask.wgsl",
    "object/voxel_field.wgsl",
    "object/shading.wgsl",
    "object/cone_trace.wgsl",
    "object_view.wgsl",
];

/// The object view unit: every file of [`OBJECT_FILES`].
pub fn object() -> &'static str {
    static OBJECT: LazyLock<String> = LazyLock::new(|| {
        OBJECT_FILES
            .iter()
            .map(|(path, src)| format!("// ======== {path}\n{src}"))
            .collect::<Vec<_>>()
            .join("\n")
    });
    &OBJECT
}

/// The object view's parameters and buffers: the `ObjectParams` struct (generated from
/// [`crate::gpu_types::ObjectParams`]), the mask table's constants from core, and bindings 4–9.
pub fn object_bindings() -> &'static str {
    static OBJECT_BINDINGS: LazyLock<String> = LazyLock::new(|| {
        use crate::gpu_types::{GpuStruct, ObjectParams};
        use lodestone_core::object::coverage_mask::{MASK_ANGLES, MASK_BITS, MASK_OFFSETS};
        let (x, w) = lodestone_core::object::shading::visible_cosine_rule();
        let list = |v: &[f64]| {
            v.iter()
                .map(|a| format!("{a:.9}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let rule = format!(
            "const VC_X = array<f32, {n}>({});\nconst VC_W = array<f32, {n}>({});\n",
            list(x),
            list(w),
            n = x.len()
        );
        format!(
            "// Generated by lodestone-render's shaders.rs from Rust: do not edit.\n{}\n{rule}\
             const MASK_BITS: u32 = {MASK_BITS}u;\n\
             const MASK_ANGLES: u32 = {MASK_ANGLES}u;\n\
             const MASK_OFFSETS: u32 = {MASK_OFFSETS}u;\n\
             @group(0) @binding(4) var<storage, read> object: ObjectParams;\n\
             @group(0) @binding(5) var<storage, read> object_slots: array<vec4<u32>>;\n\
             @group(0) @binding(6) var<storage, read> object_voxels: array<vec4<u32>>;\n\
             @group(0) @binding(7) var<storage, read> object_masks: array<vec2<u32>>;\n\
             @group(0) @binding(8) var<storage, read_write> object_out: array<vec4<f32>>;\n\
             @group(0) @binding(9) var<storage, read_write> object_cut: array<atomic<u32>>;\n",
            ObjectParams::wgsl()
        )
    });
    &OBJECT_BINDINGS
}

/// The material unit: the generated constants prelude, then every file of [`MATERIAL_FILES`].
pub fn material() -> &'static str {
    static MATERIAL: LazyLock<String> = LazyLock::new(|| {
        let mut s = crate::gpu_codes::wgsl_prelude().to_owned();
        for (path, src) in MATERIAL_FILES {
            s.push_str(&format!("\n// ======== {path}\n"));
            s.push_str(src);
        }
        s
    });
    &MATERIAL
}

/// How the views read the material's data: `shaders/data_texture.wgsl`, which replaces
/// `bindings.wgsl`'s storage block in [`view_material`].
pub const DATA_TEXTURE: &str = include_str!("shaders/data_texture.wgsl");

/// The material unit as the views use it: [`material`] with the data read from a texture
/// ([`DATA_TEXTURE`]) instead of the storage buffer the exported snippet binds.
pub fn view_material() -> &'static str {
    static VIEW_MATERIAL: LazyLock<String> = LazyLock::new(|| {
        let m = material();
        let begin = "// data-access: storage (begin)";
        let end = "// data-access: storage (end)";
        let (Some(a), Some(b)) = (m.find(begin), m.find(end)) else {
            panic!("bindings.wgsl marks its storage block");
        };
        format!("{}{}{}", &m[..a], DATA_TEXTURE, &m[b + end.len()..])
    });
    &VIEW_MATERIAL
}

/// The view's parameters: the `ViewParams` struct (generated from
/// [`crate::gpu_types::ViewParams`]) and its binding, read by the view and cylinder units.
pub fn view_bindings() -> &'static str {
    static VIEW_BINDINGS: LazyLock<String> = LazyLock::new(|| {
        use crate::gpu_types::{GpuStruct, ViewParams};
        format!(
            "// Generated by lodestone-render's gpu_types.rs from Rust: do not edit.\n{}\n@group(0) @binding(3) var<storage, read> view_params: ViewParams;\n",
            ViewParams::wgsl()
        )
    });
    &VIEW_BINDINGS
}

/// Every unit with its name; each is validated together with the units it needs ([`prelude_for`]).
pub fn all() -> [(&'static str, &'static str); 6] {
    [
        ("special", SPECIAL),
        ("material", material()),
        ("image_driver", IMAGE_DRIVER),
        ("cylinder", CYLINDER),
        ("view", VIEW),
        ("object", object()),
    ]
}

/// Every WGSL file with its path under `shaders/` (the units' files).
pub fn files() -> Vec<(&'static str, &'static str)> {
    let mut v = vec![("math/special.wgsl", SPECIAL)];
    v.extend_from_slice(MATERIAL_FILES);
    v.extend([
        ("driver/image.wgsl", IMAGE_DRIVER),
        (
            "scene/cylinder.wgsl",
            include_str!("shaders/scene/cylinder.wgsl"),
        ),
        (
            "eval/cylinder.wgsl",
            include_str!("shaders/eval/cylinder.wgsl"),
        ),
        ("view.wgsl", VIEW),
        ("data_texture.wgsl", DATA_TEXTURE),
    ]);
    v.extend_from_slice(OBJECT_FILES);
    v
}

/// The units a unit needs before it (WGSL has no includes; units are concatenated in this order).
pub fn prelude_for(name: &str) -> Vec<&'static str> {
    match name {
        // The material and the image driver call each other (module scope is order-free in WGSL).
        "material" => vec![SPECIAL, IMAGE_DRIVER],
        "image_driver" => vec![SPECIAL, material()],
        "cylinder" => vec![SPECIAL, view_material(), IMAGE_DRIVER, view_bindings()],
        "view" => vec![
            SPECIAL,
            view_material(),
            IMAGE_DRIVER,
            view_bindings(),
            CYLINDER,
        ],
        "object" => vec![SPECIAL, material(), IMAGE_DRIVER, object_bindings()],
        _ => vec![],
    }
}

/// Names of the functions `math/special.wgsl` mirrors from `lodestone_core::math::special_f32` (same names).
pub const SPECIAL_MIRRORED: &[&str] = &[
    "erf",
    "erfc",
    "erfcx",
    "norm_pdf",
    "norm_cdf",
    "log_norm_cdf",
    "smith_lambda",
    "norm_quantile",
    "acklam",
    "lower_quantile",
    "erf_series_sum",
    "cf_tail",
];
