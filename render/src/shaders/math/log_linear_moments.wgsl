// Mirror of `core/src/math/log_linear_moments.rs`, function for function under the same names:
// the exact moments of exp(ℓ(t)) under N(0, s²), ℓ piecewise linear on the evenly spaced knots
// `first + step·k` of the transfer masking table's slope column (TRANSFER_SLOPE_NODES values, all
// the GPU asks of it) and constant beyond. In f32, ℓ is clamped to [−87, 80] (exp's range) where
// core clamps to [−745, 300]; every exponent below stays at or under the integrand's own
// logarithm, so nothing cancels (core's cell_mass docs); E[t² g] = s²E[g] + s⁴(…) does cancel as
// s grows past the knots' span (1.6e-3 of E[g]s² at s = 25; 2e-5 up to s = 3, where the table's
// projections live, render/tests/gaussian_weights.rs).
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if transfer_mixture
// log_linear_moments: (E[g], E[t g], E[t² g]) for t ~ N(0, s²).
fn log_linear_moments(
    values: array<f32, TRANSFER_SLOPE_NODES>,
    first: f32,
    step: f32,
    s_in: f32,
) -> vec3<f32> {
    let n = TRANSFER_SLOPE_NODES;
    var v = values;
    for (var k = 0u; k < n; k = k + 1u) {
        v[k] = clamp(v[k], -87.0, 80.0);
    }
    let s = min(s_in, LOG_LINEAR_MAX_DEVIATION);
    if (!(s > LOG_LINEAR_MIN_DEVIATION)) {
        // ℓ(0), linear between the knots around it.
        let u = clamp(-first / step, 0.0, f32(n - 1u));
        let k = min(u32(u), n - 2u);
        var lo = 0.0;
        var hi = 0.0;
        for (var j = 0u; j < n; j = j + 1u) {
            lo = select(lo, v[j], j == k);
            hi = select(hi, v[j], j == k + 1u);
        }
        return vec3<f32>(exp(lo + (u - f32(k)) * (hi - lo)), 0.0, 0.0);
    }
    let last = first + step * f32(n - 1u);
    var m0 = exp(v[0]) * norm_cdf(first / s) + exp(v[n - 1u]) * norm_cdf(-last / s);
    var sb = 0.0;
    var sbb = 0.0;
    var nodes = 0.0;
    var beta_left = 0.0;
    for (var k = 0u; k < n; k = k + 1u) {
        var beta_right = 0.0;
        var next = v[k];
        if (k + 1u < n) {
            next = v[k + 1u];
            beta_right = (next - v[k]) / step;
        }
        let t = first + step * f32(k);
        nodes = nodes + (beta_right - beta_left) * (exp(v[k]) * norm_pdf(t / s) / s);
        if (k + 1u < n) {
            let i = cell_mass(t, t + step, v[k], beta_right, s);
            m0 = m0 + i;
            sb = sb + beta_right * i;
            sbb = sbb + beta_right * beta_right * i;
        }
        beta_left = beta_right;
    }
    let s2 = s * s;
    return vec3<f32>(m0, s2 * sb, s2 * m0 + s2 * s2 * (sbb + nodes));
}

// cell_mass: ∫_a^b exp(l + β(t − a)) N(t; 0, s²) dt, the integrand's largest value factored out.
fn cell_mass(a: f32, b: f32, l: f32, beta: f32, s: f32) -> f32 {
    let shift = beta * s;
    let ua = a / s - shift;
    let ub = b / s - shift;
    if (ub <= 0.0) {
        let lb = l + beta * (b - a) - 0.5 * (b / s) * (b / s);
        let ratio = scaled_cdf(ua) / scaled_cdf(ub) * exp(-0.5 * (ua - ub) * (ua + ub));
        return exp(lb) * scaled_cdf(ub) * max(1.0 - ratio, 0.0);
    }
    if (ua >= 0.0) {
        let la = l - 0.5 * (a / s) * (a / s);
        let ratio = scaled_cdf(-ub) / scaled_cdf(-ua) * exp(-0.5 * (ub - ua) * (ub + ua));
        return exp(la) * scaled_cdf(-ua) * max(1.0 - ratio, 0.0);
    }
    let t = beta * s * s;
    let peak = l + beta * (t - a) - 0.5 * (t / s) * (t / s);
    return exp(peak) * max(norm_cdf(ub) - norm_cdf(ua), 0.0);
}

// scaled_cdf: Φ(u)·e^{u²/2} = ½erfcx(−u/√2).
fn scaled_cdf(u: f32) -> f32 {
    return 0.5 * erfcx(-u * FRAC_1_SQRT_2);
}
//#endif
