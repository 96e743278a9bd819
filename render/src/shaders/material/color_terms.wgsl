// Mirror of `core/src/material/color_terms.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

// ColorTerms::affine: C = a + k ⊙ C_s for colour-model value ch (absent terms have weight 0, which
// is "no contribution" when linear and "white" when multiplicative).
struct Affine {
    a: vec3<f32>,
    k: vec3<f32>,
}

fn affine(ch: vec3<f32>) -> Affine {
    var r: Affine;
    if (params.combine_mode == COMBINE_MULTIPLICATIVE) {
        let p = (vec3<f32>(1.0 - params.kappa0) + params.kappa0 * params.c0) * (vec3<f32>(1.0 - params.kappa1) + params.kappa1 * ch);
        r.a = p * (1.0 - params.kappa2);
        r.k = p * params.kappa2;
        return r;
    }
    r.a = params.kappa0 * params.c0 + params.kappa1 * ch;
    r.k = vec3<f32>(params.kappa2);
    return r;
}
