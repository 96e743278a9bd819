//! Every WGSL file validates with naga, and the WGSL mirrors agree with lodestone-core on the GPU
//! adapter (llvmpipe on CI) over ≥ 10,000 inputs, extremes included.

use lodestone_core::material::features::FeatureSet;
use lodestone_core::math::{special, special_f32};
use lodestone_render::gpu_types::{GpuStruct, MaterialParams, ObjectParams, ViewParams};
use lodestone_render::{compute::eval_unary, shaders};

/// Parse and validate a file together with the files it needs.
fn module_for(name: &str, file: &str) -> naga::Module {
    let mut parts = shaders::prelude_for(name);
    parts.push(file);
    let src = lodestone_render::specialize::specialize(&parts.join("\n"), FeatureSet::all())
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let module = naga::front::wgsl::parse_str(&src)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}: {e:?}"));
    module
}

#[test]
fn every_wgsl_file_validates() {
    for (name, file) in shaders::all() {
        let module = module_for(name, file);
        // The mirrored functions exist under core's names.
        if name == "special" {
            for f in shaders::SPECIAL_MIRRORED {
                assert!(
                    module
                        .functions
                        .iter()
                        .any(|(_, func)| func.name.as_deref() == Some(f)),
                    "{f} missing"
                );
            }
        }
    }
}

/// `(WGSL file, WGSL function, core file, core function)`: every function of every WGSL file mirrors
/// the core function named here (a method is named without its type), or is GPU-only ([`GPU_ONLY`]).
/// Same name, same folder unless the entry says otherwise.
#[rustfmt::skip]
const MIRRORS: &[(&str, &str, &str, &str)] = &[
    ("math/special.wgsl", "erfc_upper", "math/special_f32.rs", "erfc_upper"),
    ("math/special.wgsl", "erf_small", "math/special_f32.rs", "erf_small"),
    ("math/special.wgsl", "norm_quantile", "math/special_f32.rs", "norm_quantile"),
    ("math/special.wgsl", "acklam", "math/special_f32.rs", "acklam"),
    ("math/special.wgsl", "lower_quantile", "math/special_f32.rs", "lower_quantile"),
    ("microfacet/slope_density.wgsl", "unresolved_term", "driver/noise.rs", "unresolved_gradient_terms"),
    ("eval/filtered.wgsl", "lobe_density_ratio", "eval/filtered.rs", "lobe_density_ratio"),
    ("math/piecewise.wgsl", "poly_eval", "math/piecewise.rs", "eval"),
    ("math/gaussian_weight.wgsl", "gaussian_weight_along", "math/gaussian_weight.rs", "along"),
    ("math/gaussian_weight.wgsl", "gaussian_weight_powf", "math/gaussian_weight.rs", "powf"),
    ("math/gaussian_weight.wgsl", "gaussian_weight_mul", "math/gaussian_weight.rs", "mul"),
    ("math/gaussian_weight.wgsl", "gaussian_weight_at", "math/gaussian_weight.rs", "at"),
    ("math/gaussian_weight.wgsl", "gaussian_weight_expect_under", "math/gaussian_weight.rs", "expect_under"),
    ("math/gaussian_weight.wgsl", "gaussian_weight_tilted", "math/gaussian_weight.rs", "tilted"),
    ("math/piecewise.wgsl", "poly_max_abs_on", "math/piecewise.rs", "max_abs_on"),
    ("microfacet/smith.wgsl", "projected_std", "microfacet/slopes.rs", "projected_std"),
    ("microfacet/masking_shadowing.wgsl", "masking_shadowing", "microfacet/masking_shadowing.rs", "from_directions"),
    ("microfacet/visible_slopes.wgsl", "slope_node", "microfacet/visible_slopes.rs", "slope_rule"),
    ("math/preconvolved.wgsl", "split_coord", "math/preconvolved.rs", "split"),
    ("math/preconvolved.wgsl", "table_sample", "math/preconvolved.rs", "sample"),
    ("microfacet/transfer.wgsl", "transfer_eval", "microfacet/transfer.rs", "eval"),
    ("material/merl.wgsl", "merl_eval", "material/merl.rs", "eval"),
    ("microfacet/brdf.wgsl", "specular_lobe", "microfacet/brdf.rs", "specular_with"),
    ("microfacet/brdf.wgsl", "filtered_lobe", "microfacet/brdf.rs", "filtered_specular"),
    ("material/measured.wgsl", "measured_eval_facet", "material/measured.rs", "eval_facet"),
    ("microfacet/transfer.wgsl", "transfer_moments", "eval/compiled.rs", "moments"),
    ("driver/noise.wgsl", "wave_term", "driver/noise.rs", "value_and_gradient"),
    ("driver/field.wgsl", "filtered_driver", "driver/field.rs", "filtered"),
    ("driver/image.wgsl", "image_wrap", "driver/mip_level.rs", "cell"),
    ("driver/image.wgsl", "image_cell", "driver/mip_level.rs", "cell"),
    ("driver/image.wgsl", "image_at_level", "driver/mip_level.rs", "at_level"),
    ("driver/image.wgsl", "image_bilerp", "driver/mip_level.rs", "bilerp"),
    ("driver/image.wgsl", "image_value_and_gradient", "driver/image.rs", "value_and_gradient"),
    ("driver/image.wgsl", "image_plan", "driver/image.rs", "plan"),
    ("driver/image.wgsl", "image_level_moments", "driver/mip_level.rs", "level_moments"),
    ("driver/image.wgsl", "image_mix", "driver/image.rs", "moments_at"),
    ("driver/image.wgsl", "image_split_lod", "driver/image.rs", "split_lod"),
    ("driver/image.wgsl", "image_moments_at", "driver/image.rs", "moments_at"),
    ("driver/image.wgsl", "image_footprint_moments", "driver/image.rs", "footprint_moments"),
    ("driver/image.wgsl", "image_level_mean", "driver/mip_level.rs", "level_mean"),
    ("driver/image.wgsl", "image_footprint_mean", "driver/image.rs", "footprint_mean"),
    ("driver/image.wgsl", "image_mean_std", "driver/image.rs", "mean_std"),
    ("driver/image.wgsl", "image_texel", "driver/field.rs", "texels_per_unit"),
    ("driver/image.wgsl", "image_grad_cov", "driver/mip_level.rs", "grad_cov"),
    ("driver/image.wgsl", "image_filtered_driver", "driver/field.rs", "filtered"),
    ("driver/image.wgsl", "image_lipschitz_along", "driver/field.rs", "lipschitz_along"),
    ("driver/image.wgsl", "image_lod_lipschitz", "driver/image.rs", "lod_lipschitz"),
    ("driver/image.wgsl", "image_lod_lipschitz_along", "driver/field.rs", "lod_lipschitz_along"),
    ("scene/direction.wgsl", "basis_t", "scene/direction.rs", "basis"),
    ("scene/direction.wgsl", "basis_b", "scene/direction.rs", "basis"),
    ("scene/surface.wgsl", "surface_height", "scene/surface.rs", "height"),
    ("scene/cylinder.wgsl", "cylinder_to_surface", "scene/cylinder.rs", "to_surface"),
    ("scene/cylinder.wgsl", "cylinder_frame", "scene/cylinder.rs", "frame"),
    ("scene/cylinder.wgsl", "cylinder_intersect", "scene/cylinder.rs", "intersect"),
    ("eval/cylinder.wgsl", "cylinder_gap", "eval/cylinder.rs", "cylinder_march"),
    ("eval/cylinder.wgsl", "cylinder_refine", "scene/march.rs", "refine"),
    ("scene/march.wgsl", "gap_at", "scene/march.rs", "march_heightfield"),
    ("scene/octave_march.wgsl", "octave_ray", "scene/octave_march.rs", "ray"),
    ("scene/octave_march.wgsl", "octave_term", "scene/octave_march.rs", "march"),
    ("scene/octave_march.wgsl", "octave_partial", "scene/octave_march.rs", "march"),
    ("scene/octave_march.wgsl", "octave_height", "scene/octave_march.rs", "march"),
    ("scene/octave_march.wgsl", "octave_step", "scene/octave_march.rs", "step"),
    ("scene/octave_march.wgsl", "octave_bracket_width", "scene/crossing.rs", "bracket_width"),
    ("scene/octave_march.wgsl", "first_root", "scene/crossing.rs", "first_root"),
    ("scene/octave_march.wgsl", "octave_cubic_step", "scene/crossing.rs", "cubic_step"),
    ("scene/octave_march.wgsl", "octave_cubic_bracket", "scene/crossing.rs", "cubic_bracket"),
    ("scene/grid_skip.wgsl", "octave_grid_gap", "scene/grid_skip.rs", "grid_gap"),
    ("scene/grid_skip.wgsl", "octave_grid_skip", "scene/grid_skip.rs", "grid_skip"),
    ("scene/field_grid.wgsl", "field_sample", "scene/field_grid.rs", "sample"),
    ("scene/field_grid.wgsl", "field_corner", "scene/field_grid.rs", "sample"),
    ("scene/field_grid.wgsl", "field_probe", "scene/field_grid.rs", "probe"),
    ("scene/field_step.wgsl", "octave_field_step", "scene/field_step.rs", "field_step"),
    ("scene/field_step.wgsl", "octave_field_crossing_ahead", "scene/field_step.rs", "field_crossing_ahead"),
    ("scene/bound_grid.wgsl", "grid_range", "scene/bound_grid.rs", "range"),
    ("scene/bound_grid.wgsl", "grid_view_range", "scene/bound_grid.rs", "range"),
    ("scene/local_slope.wgsl", "lipschitz_on", "scene/local_slope.rs", "lipschitz_on"),
    ("scene/local_slope.wgsl", "march_g_lip", "eval/lod_surface.rs", "lod_march"),
    ("driver/footprint.wgsl", "footprint_min_std", "driver/footprint.rs", "min_std"),
    ("math/table_slope.wgsl", "table_slope_entry", "math/table_slope.rs", "entry"),
    ("math/table_slope.wgsl", "table_slope_at", "math/table_slope.rs", "at"),
    ("math/table_slope.wgsl", "table_slope_max", "math/table_slope.rs", "max"),
    ("math/table_slope.wgsl", "table_slope_on", "math/table_slope.rs", "lipschitz_on"),
    ("scene/octave_march.wgsl", "octave_local_step", "scene/octave_march.rs", "local_step"),
    ("scene/octave_march.wgsl", "octave_march", "scene/octave_march.rs", "march"),
    ("scene/octave_march.wgsl", "level_end", "driver/noise.rs", "level_ends"),
    ("scene/cylinder.wgsl", "tangent_footprint", "scene/cylinder.rs", "tangent_footprint"),
    ("eval/compiled.wgsl", "point_input", "eval/compiled.rs", "at_point"),
    ("eval/compiled.wgsl", "color_at", "eval/evaluator.rs", "color_at"),
    ("eval/compiled.wgsl", "color_of_distribution", "eval/compiled.rs", "of_distribution"),
    ("eval/naive.wgsl", "eval_naive", "eval/naive.rs", "naive"),
    ("eval/view_independent.wgsl", "eval_view_independent", "eval/view_independent.rs", "view_independent"),
    ("eval/view_independent.wgsl", "slope_color_mean", "microfacet/visible_slopes.rs", "slope_mean"),
    ("eval/filtered.wgsl", "eval_filtered", "eval/filtered.rs", "filtered"),
    ("eval/masking/transfer_masking_table.wgsl", "transfer_slope_sigma", "eval/masking/transfer_masking_table.rs", "slope_sigma"),
    ("eval/masking/transfer_masking_table.wgsl", "transfer_ray", "eval/masking/transfer_masking_table.rs", "new"),
    ("eval/masking/transfer_masking_table.wgsl", "transfer_rays_new", "eval/masking/transfer_masking_table.rs", "new"),
    ("eval/masking/transfer_masking_table.wgsl", "length_cell", "eval/masking/transfer_moments.rs", "length_cell"),
    ("eval/masking/transfer_masking_table.wgsl", "moments_at", "eval/masking/transfer_moments.rs", "moments_at"),
    ("eval/mixture_bins.wgsl", "shade_under", "eval/mixture_bins.rs", "filtered_bins"),
    ("eval/mixture_bins.wgsl", "conditioned_bin", "eval/mixture_bins.rs", "filtered_bins"),
    ("eval/mixture_bins.wgsl", "shading_add", "eval/shading.rs", "add"),
    ("eval/masking/slope_masking_table.wgsl", "azimuth_coordinate", "eval/masking/slope_masking_table.rs", "azimuth_coordinate"),
    ("eval/masking/slope_masking_table.wgsl", "nu_coordinate", "eval/masking/slope_masking_table.rs", "nu_coordinate"),
    ("eval/masking/slope_masking_table.wgsl", "slope_masking_lookup", "eval/masking/slope_masking_table.rs", "lookup"),
    ("eval/masking/slope_weights.wgsl", "slope_weights_at", "eval/masking/slope_weights.rs", "at"),
    ("eval/masking/slope_weights.wgsl", "slope_weights_coordinate", "eval/masking/slope_weights.rs", "coordinate"),
    ("eval/masking/slope_weights.wgsl", "slope_heights", "eval/masking/slope_weights.rs", "heights"),
    ("eval/masking/slope_weights.wgsl", "weighted_term", "eval/masking/slope_weights.rs", "weighted_terms"),
    ("eval/ground_truth.wgsl", "shade_point", "eval/ground_truth.rs", "shade_hit"),
    ("eval/lod_surface.wgsl", "lod_prepare", "driver/field.rs", "lod_moments"),
    ("eval/lod_surface.wgsl", "lod_term", "driver/field.rs", "lod_moments"),
    ("eval/lod_surface.wgsl", "lod_mean", "driver/field.rs", "lod_moments"),
    ("eval/pixel.wgsl", "analytic_pixel", "eval/pixel.rs", "pixel_in_frame"),
    ("view.wgsl", "raw_dir", "scene/camera.rs", "raw_dir"),
    ("view.wgsl", "plane_footprint", "scene/camera.rs", "plane_footprint"),
    ("object/coverage_mask.wgsl", "mask_lookup", "object/coverage_mask.rs", "lookup"),
    ("object/voxel_field.wgsl", "voxel_sample", "object/voxel_field.rs", "sample"),
    ("object/voxel_field.wgsl", "mix_samples", "object/voxel_field.rs", "mix"),
    ("object/cone_trace.wgsl", "coverage_add", "object/cone_trace.rs", "add"),
    ("object/cone_trace.wgsl", "coverage_share", "object/cone_trace.rs", "share"),
    ("object/cone_trace.wgsl", "coverage_full", "object/cone_trace.rs", "full"),
    ("object/cone_trace.wgsl", "march_start", "object/cone_trace.rs", "march"),
    ("object/cone_trace.wgsl", "march_step", "object/cone_trace.rs", "march"),
    ("object/cone_trace.wgsl", "cone_radius", "object/cone_trace.rs", "radius"),
    ("object/shading.wgsl", "mean_attribute", "microfacet/attribute.rs", "mean_attribute"),
];

/// WGSL functions with no core counterpart, and why.
#[rustfmt::skip]
const GPU_ONLY: &[(&str, &str, &str)] = &[
    ("driver/noise.wgsl", "wave", "reads wave i from the data buffer"),
    ("driver/noise.wgsl", "cached_wave", "reads wave i from the uniform wave table"),
    ("driver/image.wgsl", "image_level", "reads a pyramid level's record from the data buffer"),
    ("math/preconvolved.wgsl", "texel4", "reads a table texel from the data buffer"),
    ("eval/masking/slope_weights.wgsl", "bucket", "bucket j of the private bucket arrays as a SlopeShading"),
    ("microfacet/slope_masking.wgsl", "profile_node", "node j of a profile packed in a 3 × 3 matrix"),
    ("eval/shading.wgsl", "has_environment", "the parameter flag for an environment"),
    ("scene/octave_march.wgsl", "octave_count", "the waves summed: lod_prepare's count of those the footprint leaves above 1e-10"),
    ("scene/octave_march.wgsl", "octave_amplitude", "reads wave i's amplitude, attenuated on the level-of-detail surface"),
    ("scene/field_grid.wgsl", "field_vertex", "reads vertex k of the field table from the data buffer"),
    ("scene/surface.wgsl", "field_height", "selects the explicit or level-of-detail surface for the one march"),
    ("view.wgsl", "pcg", "per-pixel random numbers of the progressive ground truth"),
    ("view.wgsl", "view_main", "the compute entry point"),
    ("view.wgsl", "truth_sample", "one progressive ground-truth ray of a pixel (core: Evaluator::trace_ray)"),
    ("view.wgsl", "listed_ray", "the ray a listed pass traces (Renderer::draw_planned and the cut-ray retry)"),
    ("view.wgsl", "sum_runs", "adds each pixel's listed rays to its sums (Renderer::draw_planned)"),
    ("view.wgsl", "analytic_view", "one pixel of an analytic mode (core: Evaluator::plane_pixel, cylinder_pixel)"),
    ("view.wgsl", "pixel_centre", "a pixel's centre from its index"),
    ("view.wgsl", "add_ray", "adds one ground-truth ray to a pixel's sums"),
    ("view.wgsl", "count_cut", "counts pixels or rays whose march loops the adapter cut"),
    ("math/gaussian_weight.wgsl", "symmetric_matrix", "a symmetric 2 × 2 matrix stored as (xx, xy, yy): GLSL's std140 has no two-row matrices"),
    ("bindings.wgsl", "datum", "reads entry i of the material's data (the snippet's storage buffer)"),
    ("data_texture.wgsl", "datum", "reads entry i of the material's data (the views' texture)"),
    ("bindings.wgsl", "note_cut", "records a loop the adapter cut (Mesa's loop limiter)"),
    ("bindings.wgsl", "budget_step", "note_budget's state, one step on (a linear congruential step)"),
    ("bindings.wgsl", "note_budget", "records whether the invocation's loop budget ran out (Mesa's loop limiter)"),
    ("view.wgsl", "budget_two", "2, as a value the shader compiler cannot fold (note_budget)"),
    ("eval/shading.wgsl", "sh9_coefficient", "reads coefficient i of the environment's Sh9 from the data buffer"),
    ("eval/masking/transfer_masking_table.wgsl", "add_corner", "one corner of moments_at (its loop body, four per iteration)"),
    ("math/special.wgsl", "erf_series_term", "one term of erf_series_sum (its loop body, eight per iteration)"),
    ("math/special.wgsl", "cf_step", "one level of cf_tail (its loop body, eight per iteration)"),
    ("bindings.wgsl", "note_work", "adds to a truth ray's work (its cost, for cost-aware adaptive plans)"),
    ("object/voxel_field.wgsl", "orthonormal_pair", "glam's DVec3::any_orthonormal_pair, which core calls"),
    ("object/voxel_field.wgsl", "voxel_at", "unpacks voxel i's words (render/src/object/voxel_store.rs)"),
    ("object/voxel_field.wgsl", "slot_hash", "the hash of a voxel key (voxel_store.rs slot_hash; core uses a HashMap)"),
    ("object/voxel_field.wgsl", "probe_slot", "one probe of find_voxel (written out MAX_PROBES times)"),
    ("object/voxel_field.wgsl", "find_voxel", "probes the hash table for a voxel (voxel_store.rs GpuVoxels::find)"),
    ("object/voxel_field.wgsl", "voxel_centre", "a voxel's centre, which its stored plane offset is relative to"),
    ("object/voxel_field.wgsl", "voxel_corner", "one corner of sample_level (its loop body, written out eight times)"),
    ("object/cone_trace.wgsl", "bisect_empty", "one bisection step of skip (its loop body, written out four times)"),
    ("object/cone_trace.wgsl", "axis_slab", "one axis of cube_span and box_exit (their loop body, written out three times)"),
    ("object/shading.wgsl", "visible_cosine_node", "one node of visible_cosine (its loop body, the inner axis written out)"),
    ("object/shading.wgsl", "object_local", "a vector in the element's frame (shading.rs local)"),
    ("object_view.wgsl", "object_two", "2, as a value the shader compiler cannot fold (note_budget)"),
    ("object_view.wgsl", "object_main", "the compute entry point"),
];

/// Functions defined at module scope of a WGSL source.
fn wgsl_functions(src: &str) -> Vec<&str> {
    src.lines()
        .filter_map(|l| l.strip_prefix("fn "))
        .filter_map(|l| l.split('(').next())
        .collect()
}

/// Every WGSL function of every file mirrors a named core function, found in the named core file
/// (or is listed as GPU-only); without an entry, a function mirrors the function of the same name
/// in the core file at the same path.
#[test]
fn every_wgsl_function_mirrors_a_core_function() {
    let core = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../core/src");
    let defines = |file: &str, f: &str| {
        let src = std::fs::read_to_string(core.join(file))
            .unwrap_or_else(|e| panic!("core/src/{file}: {e}"));
        src.contains(&format!("fn {f}(")) || src.contains(&format!("fn {f}<"))
    };
    let mut checked = 0;
    for (path, src) in shaders::files() {
        let fns = wgsl_functions(src);
        assert!(
            !fns.is_empty() || src.contains("\nstruct ") || path == "bindings.wgsl",
            "{path} declares neither a function nor a struct"
        );
        for f in fns {
            if GPU_ONLY.iter().any(|(p, g, _)| *p == path && *g == f) {
                continue;
            }
            let (file, name) = match MIRRORS.iter().find(|(p, g, _, _)| *p == path && *g == f) {
                Some((_, _, file, name)) => (file.to_string(), *name),
                None => (path.replace(".wgsl", ".rs"), f),
            };
            assert!(
                defines(&file, name),
                "{path}: `{f}` mirrors no `fn {name}` in core/src/{file}; add it to MIRRORS or GPU_ONLY"
            );
            checked += 1;
        }
    }
    for (path, f, ..) in MIRRORS.iter().map(|(p, f, a, b)| (p, f, a, b)) {
        let src = shaders::files()
            .into_iter()
            .find(|(p, _)| p == path)
            .map(|(_, s)| s);
        assert!(
            src.is_some_and(|s| wgsl_functions(s).contains(f)),
            "MIRRORS names {path}::{f}, which does not exist"
        );
    }
    assert!(checked > 90, "only {checked} functions checked");
}

/// The Rust offsets of a [`GpuStruct`] equal naga's layout of its generated WGSL.
fn check_layout<T: GpuStruct>(module: &naga::Module) {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(T::WGSL_NAME))
        .unwrap_or_else(|| panic!("struct {}", T::WGSL_NAME));
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("{} is not a struct", T::WGSL_NAME)
    };
    let rust = T::offsets();
    assert_eq!(members.len(), rust.len(), "field count");
    for (m, (name, off)) in members.iter().zip(&rust) {
        assert_eq!(m.name.as_deref(), Some(*name), "field order");
        assert_eq!(m.offset as usize, *off, "offset of {name}");
    }
    assert_eq!(
        *span as usize,
        std::mem::size_of::<T>(),
        "size of {}",
        T::WGSL_NAME
    );
}

#[test]
fn gpu_params_match_the_wgsl_layout() {
    check_layout::<MaterialParams>(&module_for("material", shaders::material()));
    check_layout::<ViewParams>(&module_for("view", shaders::VIEW));
    check_layout::<ObjectParams>(&module_for("object", shaders::object()));
}

fn inputs(lo: f32, hi: f32, n: usize, extremes: &[f32]) -> Vec<f32> {
    let mut v: Vec<f32> = (0..n)
        .map(|i| lo + (hi - lo) * (i as f32 + 0.37) / n as f32)
        .collect();
    v.extend_from_slice(extremes);
    v
}

/// Relative error allowed per unit of conditioning: 10x the worst measured on llvmpipe (1.0e-6,
/// smith_lambda); WGSL's `exp` and `log` may be a few ULP off elsewhere.
const REL_TOL: f64 = 1e-5;

/// `|x·f′(x)/f(x)|` by a central difference of core's f64 function (0 where f is 0 or not finite).
fn condition(f: fn(f64) -> f64, x: f64) -> f64 {
    let fx = f(x);
    if x == 0.0 || fx == 0.0 || !fx.is_finite() {
        return 0.0;
    }
    let d = 1e-6;
    let k = ((f(x * (1.0 + d)) - f(x * (1.0 - d))) / (2.0 * d * fx)).abs();
    if k.is_finite() { k } else { 0.0 }
}

#[test]
fn wgsl_special_functions_match_core_on_the_adapter() {
    let Some(ctx) = lodestone_tests::gpu("the GPU mirror test") else {
        return;
    };
    type Case = (&'static str, fn(f64) -> f64, fn(f32) -> f32, f32, f32);
    let cases: [Case; 7] = [
        ("erf", special::erf, special_f32::erf, -6.0, 6.0),
        ("erfc", special::erfc, special_f32::erfc, -6.0, 9.0),
        ("erfcx", special::erfcx, special_f32::erfcx, -9.0, 1e4),
        (
            "norm_pdf",
            special::norm_pdf,
            special_f32::norm_pdf,
            -13.0,
            13.0,
        ),
        (
            "norm_cdf",
            special::norm_cdf,
            special_f32::norm_cdf,
            -13.0,
            8.0,
        ),
        (
            "log_norm_cdf",
            special::log_norm_cdf,
            special_f32::log_norm_cdf,
            -1e3,
            8.0,
        ),
        (
            "smith_lambda",
            special::smith_lambda,
            special_f32::smith_lambda,
            0.0,
            10.0,
        ),
    ];
    let extremes = [
        0.0, -0.0, 1e-30, 1e-7, 0.999_999, 1.0, 1.000_001, 10.4, 10.6, -1e-7, 3.0e38,
    ];
    let mut total = 0;
    for (name, f64_fn, f32_fn, lo, hi) in cases {
        let xs = inputs(lo, hi, 12_000, &extremes);
        let gpu = eval_unary(&ctx, shaders::SPECIAL, name, &xs);
        let mut worst = 0.0f64;
        for (x, g) in xs.iter().zip(&gpu) {
            let want = f64_fn(f64::from(*x));
            let cpu32 = f64::from(f32_fn(*x));
            let g = f64::from(*g);
            assert!(
                g.is_finite() || !want.is_finite(),
                "{name}({x}): GPU gave {g}"
            );
            // Beyond f32's range, and below its normal range (where a GPU may flush to zero),
            // there is nothing to compare.
            if !want.is_finite() || want.abs() > 3e38 || (want != 0.0 && want.abs() < 1.2e-38) {
                continue;
            }
            // Relative, scaled by the function's conditioning at x (the tails carry an error of
            // about ε·κ from rounding x² in f32: κ = 2x² for erfc), and no absolute floor: the
            // erfc tail, norm_cdf far below −4.75 and Λ beyond ν ≈ 3.4 are checked like the rest.
            let kappa = condition(f64_fn, f64::from(*x));
            let rel = (g - want).abs() / want.abs().max(1e-300);
            let ok = if want == 0.0 {
                g.abs() < 1.2e-38
            } else {
                rel <= REL_TOL * (1.0 + kappa)
            };
            assert!(
                ok,
                "{name}({x}): GPU {g:e}, core {want:e} (core f32 {cpu32:e}), relative {rel:.2e}, κ {kappa:.2e}"
            );
            if want != 0.0 {
                worst = worst.max(rel / (1.0 + kappa));
            }
        }
        eprintln!(
            "{name}: {} inputs, worst relative error / (1 + κ) vs f64 core {worst:.2e}",
            xs.len()
        );
        total += xs.len();
    }
    assert!(total >= 10_000);
}

/// norm_quantile (the mixture's bin samples): the WGSL Acklam approximation against core's f64
/// quantile (with Newton steps) over p in [1e-7, 1 − 1e-7], relative to (1 + κ) like the rest;
/// and finite at 0, 1 and beyond.
#[test]
fn wgsl_norm_quantile_matches_core_on_the_adapter() {
    let Some(ctx) = lodestone_tests::gpu("the GPU mirror test") else {
        return;
    };
    let mut xs: Vec<f32> = (0..4000).map(|i| (i as f32 + 0.5) / 4000.0).collect();
    xs.extend((1..=7).flat_map(|e| {
        let t = 10f32.powi(-e);
        [t, 1.0 - t, 3.0 * t]
    }));
    xs.extend([0.5, 0.0, 1.0, -1.0, 2.0]);
    let gpu = eval_unary(&ctx, shaders::SPECIAL, "norm_quantile", &xs);
    let mut worst = 0.0f64;
    for (x, g) in xs.iter().zip(&gpu) {
        assert!(
            g.is_finite() && g.abs() < 11.5,
            "norm_quantile({x}): GPU gave {g}"
        );
        if !(*x >= 1e-7 && *x <= 1.0 - 1e-7) {
            continue;
        }
        let want = special::norm_quantile(f64::from(*x));
        let cpu32 = f64::from(special_f32::norm_quantile(*x));
        let kappa = condition(special::norm_quantile, f64::from(*x));
        let err = (f64::from(*g) - want).abs();
        let rel = if want == 0.0 { err } else { err / want.abs() };
        assert!(
            rel <= REL_TOL * (1.0 + kappa) || err < 1e-6,
            "norm_quantile({x}): GPU {g:e}, core {want:e} (core f32 {cpu32:e}), relative {rel:.2e}, κ {kappa:.2e}"
        );
        worst = worst.max(rel / (1.0 + kappa));
    }
    eprintln!(
        "norm_quantile: {} inputs, worst relative error / (1 + κ) {worst:.2e}",
        xs.len()
    );
}

/// bindings.wgsl's blocks that say whether a loop was cut (`loop_cut`, `note_cut`, `note_budget`).
fn loop_detector() -> String {
    include_str!("../src/shaders/bindings.wgsl")
        .split("\n\n")
        .filter(|b| b.contains("loop_cut") || b.contains("fn budget_step"))
        .collect::<Vec<_>>()
        .join("\n\n")
}

/// The cut-loop detector (`bindings.wgsl` `note_cut`) on the adapter: a loop that ends short of
/// its own condition is noticed, and one that runs to its end is not. On Mesa's software
/// adapters a loop is cut after 65535 iterations; on other adapters nothing is cut and the flag
/// stays down. Either way the flag says exactly whether the loop ran its course.
#[test]
fn loops_the_adapter_cuts_are_noticed() {
    let Some(ctx) = lodestone_tests::gpu("the cut-loop test") else {
        return;
    };
    let detector = loop_detector();
    assert!(detector.contains("fn note_cut"), "{detector}");
    let lib = format!(
        "{detector}\nfn run(x: f32) -> f32 {{ let n = u32(x); var c = 0u; var i = 0u; \
         for (; i < n; i = i + 1u) {{ c = c + 1u; }} note_cut(i < n); \
         return f32(c) + select(0.0, 0.5, loop_cut); }}"
    );
    let n = [1000.0f32, 60000.0, 70000.0, 300000.0];
    let out = lodestone_render::compute::eval_unary(&ctx, &lib, "run", &n);
    for (x, y) in n.iter().zip(&out) {
        let (count, flagged) = (y.floor(), y.fract() > 0.25);
        assert!(count <= *x, "{x}: {y}");
        assert_eq!(
            flagged,
            count < *x,
            "{x} iterations: ran {count}, flag {flagged}"
        );
    }
    assert_eq!(out[0], 1000.0);
}

/// The adapter's loop budget belongs to the whole invocation, not to one loop (bindings.wgsl
/// `loop_cut`): a loop far below the limit is cut once earlier loops have spent it, and
/// `note_budget` notices that although no loop reports it. Flagged exactly when a loop fell
/// short; on a software adapter a first loop of 65 500 iterations leaves too little for a second
/// of about 100, and one of 65 400 does not.
#[test]
fn a_spent_loop_budget_is_noticed() {
    let Some(ctx) = lodestone_tests::gpu("the loop-budget test") else {
        return;
    };
    let detector = loop_detector();
    assert!(detector.contains("fn note_budget"), "{detector}");
    // Neither loop calls note_cut. Their counts have no bound the compiler can see (or it would
    // unroll them) and their results no closed form (or it would drop the loop). Returns 1 when
    // both loops ran their course, plus 2 when the budget was flagged.
    let lcg_n = |n: u32| {
        (0..n).fold(0u32, |s, _| {
            s.wrapping_mul(1664525).wrapping_add(1013904223)
        })
    };
    let cases = [
        (vec![10u32, 30000, 65400], false),
        (vec![65500, 70000], true),
    ];
    // lcg_n's values for the inputs and the second loop's lengths, computed here.
    let mut expected = vec!["fn lcg_of(n: u32) -> u32 {".to_string()];
    for &n in cases.iter().flat_map(|(v, _)| v) {
        for k in [n, 100 + n % 7] {
            expected.push(format!("    if (n == {k}u) {{ return {}u; }}", lcg_n(k)));
        }
    }
    expected.push("    return 0u;\n}".into());
    let lib = format!(
        "{detector}\nfn lcg(s: u32) -> u32 {{ return s * 1664525u + 1013904223u; }}\n\
         fn lcg_n(n: u32) -> u32 {{ var s = 0u; for (var i = 0u; i < n; i = i + 1u) {{ s = lcg(s); }} return s; }}\n\
         fn run(x: f32) -> f32 {{ let n = u32(x); let c = lcg_n(n); \
         let m = 100u + n % 7u + (n >> 31u) * 65535u; let d = lcg_n(m); \
         note_budget(2u + (n >> 31u) * 65535u); \
         return select(0.0, 1.0, c == lcg_of(n) && d == lcg_of(m)) + select(0.0, 2.0, loop_cut); }}\n{}",
        expected.join("\n")
    );
    // Separate dispatches: the eight lanes of a SIMD batch share one budget.
    for (inputs, spent) in cases {
        let inputs: Vec<f32> = inputs.iter().map(|&n| n as f32).collect();
        let out = lodestone_render::compute::eval_unary(&ctx, &lib, "run", &inputs);
        for (x, y) in inputs.iter().zip(&out) {
            let (ran, flagged) = (y % 2.0 == 1.0, *y >= 2.0);
            assert_eq!(flagged, !ran, "{x}: {y}");
            if ctx.is_software() {
                assert_eq!(flagged, spent, "{x}: {y} on {}", ctx.describe());
            }
        }
    }
}
