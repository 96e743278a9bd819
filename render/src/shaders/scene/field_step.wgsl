// Mirror of `core/src/scene/field_step.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
//#if noise
// OctaveSurface::field_step at p on a ray along d, with the exact surface's first-order and curvature
// bounds along the ray: (1, 0, 0) where a camera ray may settle (the true gap is within
// [0, settle]), (2, step, gap) for a safe step from the gap's lower bound, (0, 0, 0) where the table
// cannot tell (the waves are summed).
fn octave_field_step(p: vec3<f32>, d: vec3<f32>, lip: f32, curv: f32, lod: bool, sf: f32, settle: f32, crawl: bool, min_step: f32) -> vec3<f32> {
    let pr = field_probe(p.xy, d.xy);
    if (pr.y < 0.0) {
        return vec3<f32>(0.0);
    }
    let e = pr.y;
    let g = min(lipschitz_on(pr.x - e, pr.x + e, lod), params.g_lip);
    let above = p.z - octave_height(pr.x, lod, sf);
    let band = params.sigma_h * g * e;
    let lo = above - band;
    let hi = above + band;
    if (!(lo >= 0.0)) {
        return vec3<f32>(0.0);
    }
    if (hi <= settle) {
        return octave_field_crossing_ahead(p, d, pr, hi + 2.0 * band, lod, sf);
    }
    if (!(lo >= 2.0 * band || (crawl && 4.0 * band <= settle))) {
        return vec3<f32>(0.0);
    }
    var fd = abs(pr.z) + pr.w;
    if (params.transfer_kind == TRANSFER_IDENTITY) {
        fd = pr.z + pr.w;
    }
    let sg = params.sigma_h * params.g_lip;
    let found = vec3<f32>(octave_step(lo, fd, lip, curv, d.z, sg), lo, 1.0);
    let best = octave_local_step(found, above, pr.x, fd, lip, curv, e, d.z, lod, sf, min_step, vec2<f32>(0.0, -1.0));
    if (best.z > 0.0 && best.x < 1e30 && best.x >= min_step) {
        return vec3<f32>(2.0, best.x, best.y);
    }
    return vec3<f32>(0.0);
}

// OctaveSurface::field_crossing_ahead: (1, 0, 0) (settle) when the table proves the ray below the
// surface δ = 2·reach/rate ahead, else (0, 0, 0); pr is the probe at p.
fn octave_field_crossing_ahead(p: vec3<f32>, d: vec3<f32>, pr: vec4<f32>, reach: f32, lod: bool, sf: f32) -> vec3<f32> {
    let eps = pr.y / max(abs(pr.z), 1e-30);
    let rate = (octave_height(pr.x + pr.z * eps, lod, sf) - octave_height(pr.x, lod, sf)) / eps - d.z;
    if (!(rate > 0.0 && eps < 1e30)) {
        return vec3<f32>(0.0);
    }
    let q = p + d * (2.0 * reach / rate);
    let pq = field_probe(q.xy, d.xy);
    if (pq.y < 0.0) {
        return vec3<f32>(0.0);
    }
    let g = min(lipschitz_on(pq.x - pq.y, pq.x + pq.y, lod), params.g_lip);
    if (q.z - octave_height(pq.x, lod, sf) + params.sigma_h * g * pq.y < 0.0) {
        return vec3<f32>(1.0, 0.0, 0.0);
    }
    return vec3<f32>(0.0);
}
//#endif
//#endif
