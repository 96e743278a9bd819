// Mirror of `core/src/math/bessel.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if noise
//#if specular
// I0 for |x| ≤ 3.75 as a polynomial in t² = (x/3.75)² [A&S 9.8.1].
fn i0_small(t2: f32) -> f32 {
    return 1.0 + t2 * (3.5156229 + t2 * (3.0899424 + t2 * (1.2067492 + t2 * (0.2659732 + t2 * (0.0360768 + t2 * 0.0045813)))));
}

// I1(x)/x for |x| ≤ 3.75 [A&S 9.8.3].
fn i1_over_x_small(t2: f32) -> f32 {
    return 0.5 + t2 * (0.87890594 + t2 * (0.51498869 + t2 * (0.15084934 + t2 * (0.02658733 + t2 * (0.00301532 + t2 * 0.00032411)))));
}

// √x e^{−x} I0(x) for x ≥ 3.75, t = 3.75/x [A&S 9.8.2].
fn i0_large(t: f32) -> f32 {
    return 0.39894228 + t * (0.01328592 + t * (0.00225319 + t * (-0.00157565 + t * (0.00916281 + t * (-0.02057706 + t * (0.02635537 + t * (-0.01647633 + t * 0.00392377)))))));
}

// √x e^{−x} I1(x) for x ≥ 3.75 [A&S 9.8.4].
fn i1_large(t: f32) -> f32 {
    return 0.39894228 + t * (-0.03988024 + t * (-0.00362018 + t * (0.00163801 + t * (-0.01031555 + t * (0.02282967 + t * (-0.02895312 + t * (0.01787654 - t * 0.00420059)))))));
}

// (ln I0(x), A(x), A′(x)) in one evaluation of the polynomials.
fn bessel_terms(x: f32) -> vec3<f32> {
    let a = abs(x);
    var ln_i0: f32;
    var r: f32;
    var q: f32;
    if (a <= 3.75) {
        let t = a / 3.75;
        let i0 = i0_small(t * t);
        q = i1_over_x_small(t * t) / i0;
        r = a * q;
        ln_i0 = log(i0);
    } else {
        let t = 3.75 / a;
        let i0 = i0_large(t);
        r = i1_large(t) / i0;
        q = r / a;
        ln_i0 = a - 0.5 * log(a) + log(i0);
    }
    return vec3<f32>(ln_i0, select(r, -r, x < 0.0), clamp(1.0 - q - r * r, 1e-12, 0.5));
}

// (A′, A″, A‴), the series below |x| = 0.3.
fn bessel_ratio_derivatives(x: f32) -> vec3<f32> {
    let t = bessel_terms(x);
    let a = t.y;
    let a1 = t.z;
    if (abs(x) < 0.3) {
        let x2 = x * x;
        return vec3<f32>(a1, x * (-0.375 + x2 * 5.0 / 24.0), -0.375 + 0.625 * x2);
    }
    let a2 = -a1 / x + a / (x * x) - 2.0 * a * a1;
    let a3 = -a2 / x + 2.0 * a1 / (x * x) - 2.0 * a / (x * x * x) - 2.0 * a1 * a1 - 2.0 * a * a2;
    return vec3<f32>(a1, a2, a3);
}
//#endif
//#endif
