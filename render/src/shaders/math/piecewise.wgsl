// Mirror of `core/src/math/piecewise.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if driver_color|height_color|transfer_curve|slope_color
// Layout at `off`: knots[k], then per segment per channel 4 coefficients, then left[ch], right[ch].
fn poly_eval(off: u32, k: u32, channels: u32, ch: u32, x: f32) -> f32 {
    let coeff = off + k;
    let tails = coeff + 4u * channels * (k - 1u);
    if (x < data[off]) {
        return data[tails + ch];
    }
    if (x >= data[off + k - 1u]) {
        return data[tails + channels + ch];
    }
    // Last knot ≤ x.
    var seg = 0u;
    for (var i = 1u; i < k - 1u; i = i + 1u) {
        if (data[off + i] <= x) {
            seg = i;
        }
    }
    let a = data[off + seg];
    let b = data[off + seg + 1u];
    let t = (x - a) / (b - a);
    let c = coeff + 4u * (seg * channels + ch);
    return ((data[c + 3u] * t + data[c + 2u]) * t + data[c + 1u]) * t + data[c];
}
//#endif
