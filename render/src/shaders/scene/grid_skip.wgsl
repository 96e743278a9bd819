// Mirror of `core/src/scene/grid_skip.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
//#if noise
// OctaveSurface::grid_gap: a lower bound of the gap along the segment from a to b from the grid's
// range of f over its box, as (gap, 1), or (0, 0) outside the grid. On the level-of-detail surface
// the box is dilated by lod_dilate (GridView::level_of_detail; GPU only: without core's second,
// shifted lookup, which cost llvmpipe more than it saved). GPU only: a margin of
// GRID_MARGIN·Σ|a_i| for the f32 sums (phases near the target are accurate to ~1e-5 rad).
fn octave_grid_gap(a: vec3<f32>, b: vec3<f32>, lod: bool, sf: f32) -> vec2<f32> {
    var dilate = vec2<f32>(0.0);
    var tail = GRID_MARGIN * params.grid_amp;
    if (lod) {
        dilate = lod_dilate;
        tail = tail + 8e-9 * params.grid_amp;
    }
    let r = grid_view_range(a.xy, b.xy, dilate, tail);
    if (r.z == 0.0) {
        return vec2<f32>(0.0);
    }
    var h = octave_height(r.y, lod, sf);
    if (params.transfer_monotone == 2u) {
        h = octave_height(r.x, lod, sf);
    } else if (params.transfer_monotone == 0u) {
        let l = lipschitz_on(r.x, r.y, lod);
        h = octave_height(0.5 * (r.x + r.y), lod, sf) + params.sigma_h * l * 0.5 * (r.y - r.x);
    }
    return vec2<f32>(min(a.z, b.z) - h, 1.0);
}

// OctaveSurface::grid_skip: (t1, gap, 1) at the furthest point the grid proves the ray clear to, or
// (t, 0, 0); segments double while clear and halve when not, down to one cell (len carries the
// length between calls).
fn octave_grid_skip(o: vec3<f32>, d: vec3<f32>, t: f32, len: ptr<function, f32>, lod: bool, sf: f32) -> vec3<f32> {
    let cell = params.grid_cell;
    var best = vec3<f32>(t, 0.0, 0.0);
    var l = max(*len, 2.0 * cell);
    var i = 0u;
    var left = false;
    for (; i < GRID_TRIES; i = i + 1u) {
        let t1 = best.x + l;
        let g = octave_grid_gap(o + d * best.x, o + d * t1, lod, sf);
        if (g.y > 0.0 && g.x > 0.0) {
            best = vec3<f32>(t1, g.x, 1.0);
            l = l * 2.0;
        } else {
            if (l <= cell) {
                left = true;
                break;
            }
            l = l * 0.5;
        }
    }
    note_cut(!left && i < GRID_TRIES);
    *len = l;
    return best;
}
//#endif
//#endif
