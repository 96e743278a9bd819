// Special functions in f32: the WGSL mirror of lodestone-core's `special_f32` module, function for
// function and under the same names. See that module for the algorithms and their accuracy:
// series below 1, Laplace's continued fraction (depth 48) at and above 1 [A&S 7.1.6, 7.1.14],
// Smith's Λ cancellation-free [HN12 Eq. 6].

const SQRT_PI: f32 = 1.7724539;
const FRAC_1_SQRT_2PI: f32 = 0.3989423;
const FRAC_2_SQRT_PI: f32 = 1.1283792;
const FRAC_1_SQRT_2: f32 = 0.70710677;
const NU_MIN: f32 = 1e-30;
const F32_MAX: f32 = 3.4028235e38;
const CF_THRESHOLD: f32 = 1.0;
const CF_DEPTH: u32 = 48u;
const SERIES_TERMS: u32 = 24u;

// The series and the continued fraction take eight terms per loop iteration (the same terms in
// the same order): every iteration counts against the software adapter's per-invocation loop
// budget (bindings.wgsl), and these run in every Λ and Φ.
const_assert SERIES_TERMS % 8u == 0u && CF_DEPTH % 8u == 0u;

fn erf_series_term(term: f32, x2: f32, n: u32) -> f32 {
    return term * (2.0 * x2 / (2.0 * f32(n) + 1.0));
}

fn erf_series_sum(x: f32) -> f32 {
    let x2 = x * x;
    var term = x;
    var sum = x;
    for (var n = 1u; n <= SERIES_TERMS; n = n + 8u) {
        term = erf_series_term(term, x2, n);
        sum = sum + term;
        term = erf_series_term(term, x2, n + 1u);
        sum = sum + term;
        term = erf_series_term(term, x2, n + 2u);
        sum = sum + term;
        term = erf_series_term(term, x2, n + 3u);
        sum = sum + term;
        term = erf_series_term(term, x2, n + 4u);
        sum = sum + term;
        term = erf_series_term(term, x2, n + 5u);
        sum = sum + term;
        term = erf_series_term(term, x2, n + 6u);
        sum = sum + term;
        term = erf_series_term(term, x2, n + 7u);
        sum = sum + term;
    }
    return sum;
}

fn cf_step(t: f32, x: f32, n: u32) -> f32 {
    return x + (f32(n) + 1.0) * 0.5 / t;
}

fn cf_tail(x: f32) -> f32 {
    var t = x;
    for (var n = CF_DEPTH; n >= 8u; n = n - 8u) {
        t = cf_step(t, x, n);
        t = cf_step(t, x, n - 1u);
        t = cf_step(t, x, n - 2u);
        t = cf_step(t, x, n - 3u);
        t = cf_step(t, x, n - 4u);
        t = cf_step(t, x, n - 5u);
        t = cf_step(t, x, n - 6u);
        t = cf_step(t, x, n - 7u);
    }
    return t;
}

fn erfc_upper(x: f32) -> f32 {
    if (x > 10.5) {
        return 0.0;
    }
    return exp(-x * x) / (SQRT_PI * (x + 0.5 / cf_tail(x)));
}

fn erf_small(x: f32) -> f32 {
    return FRAC_2_SQRT_PI * exp(-x * x) * erf_series_sum(x);
}

fn erfcx(x: f32) -> f32 {
    if (x >= CF_THRESHOLD) {
        if (x > 1e18) {
            return 1.0 / (SQRT_PI * x);
        }
        return 1.0 / (SQRT_PI * (x + 0.5 / cf_tail(x)));
    } else if (x > -CF_THRESHOLD) {
        return exp(x * x) - FRAC_2_SQRT_PI * erf_series_sum(x);
    }
    let y = -x;
    if (x * x > 88.7) {
        return F32_MAX;
    }
    return 2.0 * exp(x * x) - 1.0 / (SQRT_PI * (y + 0.5 / cf_tail(y)));
}

fn erf(x: f32) -> f32 {
    let a = abs(x);
    var v: f32;
    if (a < CF_THRESHOLD) {
        v = erf_small(a);
    } else {
        v = 1.0 - erfc_upper(a);
    }
    return select(v, -v, x < 0.0);
}

fn erfc(x: f32) -> f32 {
    if (x >= CF_THRESHOLD) {
        return erfc_upper(x);
    } else if (x > -CF_THRESHOLD) {
        return 1.0 - erf_small(x);
    }
    return 2.0 - erfc_upper(-x);
}

fn norm_pdf(z: f32) -> f32 {
    return FRAC_1_SQRT_2PI * exp(-0.5 * z * z);
}

fn norm_cdf(z: f32) -> f32 {
    return 0.5 * erfc(-z * FRAC_1_SQRT_2);
}

// special_f32::norm_quantile: Acklam's approximation, p clamped to [1e-30, 1 − 2⁻²⁴].
fn norm_quantile(p_in: f32) -> f32 {
    var p = 1e-30;
    if (p_in > 1e-30) {
        p = min(p_in, 1.0 - 5.9604645e-8);
    }
    if (p > 0.5) {
        return -lower_quantile(1.0 - p);
    }
    return lower_quantile(p);
}

// special_f32::lower_quantile: Acklam, then one Newton step below p = 0.2.
fn lower_quantile(p: f32) -> f32 {
    let x = acklam(p);
    if (p < 0.2) {
        let d = norm_pdf(x);
        if (d > 0.0) {
            return x - (norm_cdf(x) - p) / d;
        }
    }
    return x;
}

// special_f32::acklam, 0 < p ≤ 0.5.
fn acklam(p: f32) -> f32 {
    if (p < 0.02425) {
        let q = sqrt(-2.0 * log(p));
        return (((((-7.784894e-3 * q - 3.2239646e-1) * q - 2.4007583) * q - 2.5497325) * q + 4.374664) * q + 2.938164)
            / ((((7.784696e-3 * q + 3.2246713e-1) * q + 2.4451341) * q + 3.7544086) * q + 1.0);
    }
    let q = p - 0.5;
    let r = q * q;
    return (((((-3.969683e1 * r + 2.209461e2) * r - 2.759285e2) * r + 1.3835775e2) * r - 3.0664798e1) * r + 2.5066283) * q
        / (((((-5.44761e1 * r + 1.6158584e2) * r - 1.5569898e2) * r + 6.680131e1) * r - 1.3280681e1) * r + 1.0);
}

fn log_norm_cdf(z: f32) -> f32 {
    if (z < -3.0) {
        // x² overflows f32 beyond x ≈ 1.8e19: saturate at core's f32::MIN (WGSL cannot test for
        // infinity reliably, so the argument is compared instead).
        let x = -z * FRAC_1_SQRT_2;
        if (x >= 1.8e19) {
            return -3.4028235e38;
        }
        return max(log(0.5 * erfcx(x)) - x * x, -3.4028235e38);
    } else if (z < 0.0) {
        return log(norm_cdf(z));
    }
    let q = 0.5 * erfc(z * FRAC_1_SQRT_2);
    if (q < 0.05) {
        return -q * (1.0 + q * (0.5 + q * (1.0 / 3.0 + q * (0.25 + q * 0.2))));
    }
    return log(1.0 - q);
}

fn smith_lambda(nu_in: f32) -> f32 {
    let nu = max(nu_in, NU_MIN);
    if (nu >= CF_THRESHOLD) {
        if (nu > 10.5) {
            return 0.0;
        }
        let tail = 0.5 / cf_tail(nu);
        let k = nu + tail;
        return exp(-nu * nu) / (2.0 * SQRT_PI) * tail / (nu * k);
    }
    return 0.5 * (exp(-nu * nu) / (nu * SQRT_PI) - erfc(nu));
}
