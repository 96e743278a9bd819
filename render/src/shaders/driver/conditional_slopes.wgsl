// Mirror of `core/src/driver/conditional_slopes.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if transfer_mixture
// lerp_table: the `len` values at datum(off) read at fractional index x, linear between entries,
// clamped to the ends (NaN: the first).
fn lerp_table(off: u32, len: u32, x: f32) -> f32 {
    let last = len - 1u;
    if (!(x > 0.0)) {
        return datum(off);
    }
    if (x >= f32(last)) {
        return datum(off + last);
    }
    let i = min(u32(floor(x)), last - 1u);
    let a = x - f32(i);
    return datum(off + i) + a * (datum(off + i + 1u) - datum(off + i));
}

// ImageSlopes::scale_at_gauss: s² at Gaussian-space value g (table at params.is_offset).
fn scale_at_gauss(g: f32) -> f32 {
    return lerp_table(params.is_offset, IMAGE_SLOPE_BINS, norm_cdf(g) * f32(IMAGE_SLOPE_BINS) - 0.5);
}

// ImageSlopes::value_at_gauss: T⁻¹(g) from the uniform table after the scales.
fn value_at_gauss(g: f32) -> f32 {
    let x = (g + HISTOGRAM_G_END) / (2.0 * HISTOGRAM_G_END) * f32(IMAGE_INVERSE_SIZE - 1u);
    return lerp_table(params.is_offset + IMAGE_SLOPE_BINS, IMAGE_INVERSE_SIZE, x);
}
//#endif
