// Mirror of `core/src/microfacet/height_mixture.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if transfer_mixture
// MIXTURE_BINS and MAX_KNOT_EDGES come from core (the prelude, gpu_codes.rs).
const KNOT_MARGIN: f32 = 1e-6;

// The edges mixture_edges writes (at most MIXTURE_BINS + MAX_KNOT_EDGES + 1), and the knots'
// quantiles it merges in.
var<private> mixture_edge_buf: array<f32, MIXTURE_BINS + MAX_KNOT_EDGES + 1u>;
var<private> mixture_knot_buf: array<f32, MAX_KNOT_EDGES>;

// mixture_edges: the bin edges in u = Φ(z) for the transfer curve's knots (the polynomial's, at
// params.tp_offset) and the footprint's N(mean, sd²), into mixture_edge_buf; returns their count.
fn mixture_edges(mean: f32, sd: f32) -> u32 {
    let off = params.tp_offset;
    let k = params.tp_knots;
    let inv = 1.0 / max(sd, 1e-30);
    var inside = 0u;
    if (sd > 0.0) {
        for (var i = 0u; i < k; i = i + 1u) {
            let u = norm_cdf((datum(off + i) - mean) * inv);
            if (u > KNOT_MARGIN && u < 1.0 - KNOT_MARGIN) {
                inside = inside + 1u;
            }
        }
    }
    let stride = max((inside + MAX_KNOT_EDGES - 1u) / MAX_KNOT_EDGES, 1u);
    var t = 0u;
    var seen = 0u;
    if (sd > 0.0) {
        for (var i = 0u; i < k; i = i + 1u) {
            let u = norm_cdf((datum(off + i) - mean) * inv);
            if (u > KNOT_MARGIN && u < 1.0 - KNOT_MARGIN) {
                if (seen % stride == 0u && t < MAX_KNOT_EDGES) {
                    mixture_knot_buf[t] = u;
                    t = t + 1u;
                }
                seen = seen + 1u;
            }
        }
    }
    var n = 0u;
    var q = 0u;
    for (var e = 0u; e <= MIXTURE_BINS; e = e + 1u) {
        let edge = f32(e) / f32(MIXTURE_BINS);
        while (q < t && mixture_knot_buf[q] < edge) {
            mixture_edge_buf[n] = mixture_knot_buf[q];
            n = n + 1u;
            q = q + 1u;
        }
        mixture_edge_buf[n] = edge;
        n = n + 1u;
    }
    return n;
}

// bin_masking: a bin's weight times its mean visibility, exp(−above)·hi·(1 − (lo/hi)^{Λ+1})/(Λ + 1).
fn bin_masking(lo: f32, hi: f32, lambda: f32, above: f32) -> f32 {
    if (!(hi > 0.0) || !(hi > lo)) {
        return 0.0;
    }
    let l = max(lambda, 0.0);
    let r = clamp(lo / hi, 0.0, 1.0);
    var rp = 0.0;
    if (r > 0.0) {
        rp = pow(r, l + 1.0);
    }
    return exp(-above) * hi * (1.0 - rp) / (l + 1.0);
}

// bin_exponent: Λ·ln(hi/lo), 0 for an empty bin or the bottom one.
fn bin_exponent(lo: f32, hi: f32, lambda: f32) -> f32 {
    if (lo > 0.0 && hi > lo) {
        return max(lambda, 0.0) * log(hi / lo);
    }
    return 0.0;
}
//#endif
