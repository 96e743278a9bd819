// Mirror of `core/src/eval/lod_surface.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
//#if noise
// Per-invocation cache of each wave's footprint attenuation exp(−2π² kᵀΣk): constant along a pixel's
// rays, so the march evaluates only cosines per step. Filled by lod_prepare (MAX_COMPONENTS = 256).
var<private> lod_att: array<f32, 256>;
// The waves f̄ sums: up to the last one whose attenuated amplitude |a_i| g_i is at least 1e-10 (f is
// unit-variance, so the ≤ 256 terms left out move f̄ by less than 3e-8, under half an f32 ulp of 1).
// GPU only: core sums every wave.
var<private> lod_count: u32;
// The footprint's 6σ per axis, by which the octave march dilates the bound grid's boxes
// (GridView::level_of_detail). Set by lod_prepare.
var<private> lod_dilate: vec2<f32>;
// How narrow the first crossing's bracket must be for a camera ray to stop at its low end
// (OctaveSurface::settle_width = LOD_SETTLE × the footprint's smallest deviation). Set by lod_prepare.
var<private> lod_settle: f32;

//#endif
//#endif
//#if relief
//#if image
// The image's probe plan for the pixel's footprint (set by lod_prepare).
var<private> lod_plan: ProbePlan;

//#endif
//#endif
//#if relief
// Fill lod_att (or lod_plan) for footprint fp; returns the position-averaged footprint std σ_f
// (DriverField::lod_moments).
fn lod_prepare(fp: vec3<f32>) -> f32 {
//#if image
    if (params.driver_kind == DRIVER_IMAGE) {
        let cov = fp * (params.image_scale * params.image_scale);
        lod_plan = image_plan(cov);
        let area = sqrt(sqrt(max(cov.x * cov.y - cov.z * cov.z, 0.0)));
        return image_mean_std(lod_for_std(area));
    }
//#endif
    var v = 0.0;
//#if noise
    lod_dilate = 6.0 * sqrt(max(fp.xy, vec2<f32>(0.0)));
    lod_settle = LOD_SETTLE * footprint_min_std(fp);
    lod_count = 0u;
    for (var i = 0u; i < params.wave_count; i = i + 1u) {
        let w = cached_wave(i);
        let q = w.x * w.x * fp.x + 2.0 * w.x * w.y * fp.z + w.y * w.y * fp.y;
        let g = exp(-2.0 * PI * PI * q);
        lod_att[i] = g;
        v = v + w.z * w.z * (1.0 - g * g) * 0.5;
        if (abs(w.z) * g >= 1e-10) {
            lod_count = i + 1u;
        }
    }
//#endif
    let sf = sqrt(max(v, 0.0));
//#if noise
//#if transfer_curve
    if (params.transfer_kind != TRANSFER_IDENTITY) {
        lod_rows = table_slope_at(sf);
        lod_g_lip = min(params.g_lip, table_slope_max(lod_rows));
    }
//#endif
//#endif
    return sf;
}

//#endif
//#if relief
//#if noise
// Wave i's term of f̄(x).
fn lod_term(i: u32, x: vec2<f32>) -> f32 {
    let w = cached_wave(i);
    return w.z * lod_att[i] * cos(TAU * dot(w.xy, x) + w.w);
}

//#endif
//#endif
//#if relief
// f̄(x) with the cached attenuations.
fn lod_mean(x: vec2<f32>) -> f32 {
//#if image
    if (params.driver_kind == DRIVER_IMAGE) {
        return image_footprint_mean(image_texel(x), lod_plan);
    }
//#endif
    var m = 0.0;
//#if noise
    // Eight waves per iteration: see UNROLL.
    let n8 = lod_count & ~7u;
    var i = 0u;
    for (; i < n8; i = i + 8u) {
        m = m + lod_term(i, x) + lod_term(i + 1u, x) + lod_term(i + 2u, x) + lod_term(i + 3u, x)
            + lod_term(i + 4u, x) + lod_term(i + 5u, x) + lod_term(i + 6u, x) + lod_term(i + 7u, x);
    }
    for (; i < lod_count; i = i + 1u) {
        m = m + lod_term(i, x);
    }
    note_cut(i < lod_count);
//#endif
    return m;
}

// Evaluator::lod_height.
fn lod_height(x: vec2<f32>, sf: f32) -> f32 {
    return params.sigma_h * transfer_moments(lod_mean(x), sf).mean;
}

// Evaluator::lod_rate.
fn lod_rate(d: vec3<f32>) -> f32 {
    let r = length(d.xy);
    var k = 0.0;
    if (r > 0.0) {
        let dir = d.xy / r;
//#if image
        if (params.driver_kind == DRIVER_IMAGE) {
            if (params.march == MARCH_REFERENCE) {
                k = image_lipschitz_along(dir);
            } else {
                k = image_lod_lipschitz_along(dir, lod_plan);
            }
        }
//#endif
//#if noise
        for (var i = 0u; i < params.wave_count; i = i + 1u) {
            let w = cached_wave(i);
            k = k + abs(w.z) * lod_att[i] * TAU * abs(dot(w.xy, dir));
        }
//#endif
        k = k * params.sigma_h * params.g_lip;
    }
    return abs(d.z) + k * r;
}

// Evaluator::lod_march (the octave march for a noise driver under MARCH_FAST): t of the first crossing of h̄, or -1 (needs lod_prepare first).
fn lod_march(o: vec3<f32>, d: vec3<f32>, sf: f32) -> f32 {
//#if noise
    if (params.driver_kind == DRIVER_NOISE && params.march == MARCH_FAST) {
        return octave_march(o, d, true, sf);
    }
//#endif
    return march_heightfield(o, d, lod_rate(d), true, sf);
}
//#endif
