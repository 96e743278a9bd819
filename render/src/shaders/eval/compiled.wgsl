// Mirror of `core/src/eval/compiled.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

// CompiledColor::at_point (input selection): (colour-map input, standardized height) at driver value f.
fn point_input(f: f32) -> vec2<f32> {
    let t = (transfer_eval(f).x - params.g_mean) / params.g_std;
    if (params.color_kind == COLOR_DRIVER) {
        return vec2<f32>(f, t);
    }
    return vec2<f32>(t, t);
}

// Evaluator::color_at.
fn color_at(f: f32) -> vec3<f32> {
    let it = point_input(f);
//#if attribute_color
    if (params.color_kind == COLOR_ATTRIBUTE) {
        let s = attribute_shape(it.y);
        return max(params.attr_mean + params.attr_corr * s, vec3<f32>(0.0));
    }
//#endif
//#if driver_color|height_color
    let k = params.cp_knots;
    return vec3<f32>(poly_eval(params.cp_offset, k, 3u, 0u, it.x), poly_eval(params.cp_offset, k, 3u, 1u, it.x), poly_eval(params.cp_offset, k, 3u, 2u, it.x));
//#else
    return vec3<f32>(0.0);
//#endif
}

// CompiledColor::of_distribution.
fn color_of_distribution(mean: f32, sd: f32, l: f32, far: vec2<f32>, w: f32) -> vec3<f32> {
//#if attribute_color
    if (params.color_kind == COLOR_ATTRIBUTE) {
        let g = erf(mean / sqrt(2.0 * (1.0 + sd * sd)));
        let gf = erf(far.x / sqrt(2.0 * (1.0 + far.y * far.y)));
        let s = g + clamp(w, 0.0, 1.0) * (mean_attribute_shape(l) - gf);
        return max(params.attr_mean + params.attr_corr * s, vec3<f32>(0.0));
    }
//#endif
//#if driver_color|height_color
    return table_sample(params.ct_offset, params.ct_size_m, params.ct_size_s, params.ct_m_min, params.ct_m_max, params.ct_sigma_max, mean, sd).xyz;
//#else
    return vec3<f32>(0.0);
//#endif
}

// CompiledColor::input_distribution.
fn input_distribution(loc: FootprintStats) -> vec2<f32> {
    var ms = vec2<f32>((loc.transfer.mean - params.g_mean) / params.g_std, loc.transfer.std_dev / params.g_std);
    if (params.color_kind == COLOR_DRIVER) {
        ms = vec2<f32>(loc.driver.mean, loc.driver.std_dev);
    }
//#if image_histogram
    if (params.ht_size_m > 0u) {
        let v = table_sample(params.ht_offset, params.ht_size_m, params.ht_size_s, params.ht_m_min, params.ht_m_max, params.ht_sigma_max, ms.x, ms.y);
        return vec2<f32>(v.x, max(v.y, 0.0));
    }
//#endif
    return ms;
}
