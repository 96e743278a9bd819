// Mirror of `core/src/math/piecewise.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if driver_color|height_color|transfer_curve|slope_color
// Layout at `off`: knots[k], then per segment per channel 4 coefficients, then left[ch], right[ch].
fn poly_eval(off: u32, k: u32, channels: u32, ch: u32, x: f32) -> f32 {
    let coeff = off + k;
    let tails = coeff + 4u * channels * (k - 1u);
    if (x < datum(off)) {
        return datum(tails + ch);
    }
    if (x >= datum(off + k - 1u)) {
        return datum(tails + channels + ch);
    }
    // Last knot ≤ x (core's partition_point): bisection on the ascending knots, knot[seg] ≤ x <
    // knot[end] throughout. A scan over the knots cost k iterations per call, and every loop
    // iteration counts against the software adapter's per-invocation budget (bindings.wgsl).
    var seg = 0u;
    var end = k - 1u;
    while (end - seg > 1u) {
        let mid = (seg + end) / 2u;
        if (datum(off + mid) <= x) {
            seg = mid;
        } else {
            end = mid;
        }
    }
    let a = datum(off + seg);
    let b = datum(off + seg + 1u);
    let t = (x - a) / (b - a);
    let c = coeff + 4u * (seg * channels + ch);
    return ((datum(c + 3u) * t + datum(c + 2u)) * t + datum(c + 1u)) * t + datum(c);
}

// PiecewisePoly::max_abs_on: the largest |p_ch| over [lo, hi] for a channel of degree ≤ 2 (interval
// ends, each crossed segment's vertex, the tails); 0 for an empty or NaN interval.
fn poly_max_abs_on(off: u32, k: u32, channels: u32, ch: u32, lo: f32, hi: f32) -> f32 {
    if (!(lo <= hi)) {
        return 0.0;
    }
    let coeff = off + k;
    let tails = coeff + 4u * channels * (k - 1u);
    var best = 0.0;
    if (lo < datum(off)) {
        best = abs(datum(tails + ch));
    }
    if (hi >= datum(off + k - 1u)) {
        best = max(best, abs(datum(tails + channels + ch)));
    }
    for (var seg = 0u; seg + 1u < k; seg = seg + 1u) {
        let a = datum(off + seg);
        let b = datum(off + seg + 1u);
        if (!(b > a) || hi < a || lo > b) {
            continue;
        }
        let c = coeff + 4u * (seg * channels + ch);
        let c0 = datum(c);
        let c1 = datum(c + 1u);
        let c2 = datum(c + 2u);
        let t0 = clamp((lo - a) / (b - a), 0.0, 1.0);
        let t1 = clamp((hi - a) / (b - a), 0.0, 1.0);
        best = max(best, max(abs((c2 * t0 + c1) * t0 + c0), abs((c2 * t1 + c1) * t1 + c0)));
        if (c2 != 0.0) {
            let tv = -c1 / (2.0 * c2);
            if (tv > t0 && tv < t1) {
                best = max(best, abs((c2 * tv + c1) * tv + c0));
            }
        }
    }
    return best;
}
//#endif
