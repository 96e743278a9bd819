// Mirror of `core/src/driver/field.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

// DriverField::value_and_gradient: (f, ∂f/∂x, ∂f/∂y) of the noise (SumOfSines) or the image.
fn value_and_gradient(x: vec2<f32>) -> vec3<f32> {
//#if image
    if (params.driver_kind == DRIVER_IMAGE) {
        let v = image_value_and_gradient(image_texel(x));
        return vec3<f32>(v.x, v.yz * params.image_scale);
    }
//#endif
//#if noise
    // Eight waves per iteration: see UNROLL.
    note_work((params.wave_count + 7u) / 8u);
    var s = vec3<f32>(0.0);
    let n8 = params.wave_count & ~7u;
    var i = 0u;
    for (; i < n8; i = i + 8u) {
        s = s + wave_term(i, x) + wave_term(i + 1u, x) + wave_term(i + 2u, x) + wave_term(i + 3u, x)
            + wave_term(i + 4u, x) + wave_term(i + 5u, x) + wave_term(i + 6u, x) + wave_term(i + 7u, x);
    }
    for (; i < params.wave_count; i = i + 1u) {
        s = s + wave_term(i, x);
    }
    note_cut(i < params.wave_count);
    return s;
//#else
    return vec3<f32>(0.0);
//#endif
}

// DriverField::filtered (SumOfSines::filtered for the noise) with footprint covariance (xx, yy, xy).
fn filtered_driver(x: vec2<f32>, fp: vec3<f32>) -> FilteredDriver {
//#if image
    if (params.driver_kind == DRIVER_IMAGE) {
        return image_filtered_driver(x, fp);
    }
//#endif
    var r: FilteredDriver;
    r.mean = 0.0;
    r.mean_gradient = vec2<f32>(0.0);
    r.gradient_cov = vec3<f32>(0.0);
    var var_sum = 0.0;
//#if noise
    for (var i = 0u; i < params.wave_count; i = i + 1u) {
        let w = wave(i);
        let q = w.x * w.x * fp.x + 2.0 * w.x * w.y * fp.z + w.y * w.y * fp.y;
        let g = exp(-2.0 * PI * PI * q);
        let ph = TAU * dot(w.xy, x) + w.w;
        r.mean = r.mean + w.z * g * cos(ph);
        r.mean_gradient = r.mean_gradient - w.xy * (w.z * g * TAU * sin(ph));
        let u = w.z * w.z * (1.0 - g * g) * 0.5;
        var_sum = var_sum + u;
        r.gradient_cov = r.gradient_cov + vec3<f32>(w.x * w.x, w.y * w.y, w.x * w.y) * (u * TAU * TAU);
    }
//#endif
    r.std_dev = sqrt(max(var_sum, 0.0));
    return r;
}
