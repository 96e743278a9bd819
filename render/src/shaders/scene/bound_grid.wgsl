// Mirror of `core/src/scene/bound_grid.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
//#if noise
// BoundGrid::range: the range of f over the box [lo, hi] (relative to the camera target) as
// (lo, hi, 1), or (0, 0, 0) where the box leaves the grid (or there is none: grid_n = 0).
fn grid_range(lo: vec2<f32>, hi: vec2<f32>) -> vec3<f32> {
    if (params.grid_n == 0u) {
        return vec3<f32>(0.0);
    }
    let n = f32(params.grid_n);
    let origin = vec2<f32>(params.grid_x0, params.grid_y0);
    let u0 = (lo - origin) / params.grid_cell;
    let u1 = (hi - origin) / params.grid_cell;
    if (!(u0.x >= 0.0 && u0.y >= 0.0 && u1.x <= n && u1.y <= n && u0.x <= u1.x && u0.y <= u1.y)) {
        return vec3<f32>(0.0);
    }
    // The finest level at which the box spans at most two cells per axis (one more on log2 rounding).
    let span = max(max(u1.x - u0.x, u1.y - u0.y), 1.0);
    let top = params.grid_levels - 1u;
    var k = min(u32(ceil(log2(span))), top);
    var size = params.grid_n >> k;
    var scale = f32(1u << k);
    var i0 = u32(clamp(floor(u0.x / scale), 0.0, f32(size - 1u)));
    var i1 = u32(clamp(floor(u1.x / scale), 0.0, f32(size - 1u)));
    var j0 = u32(clamp(floor(u0.y / scale), 0.0, f32(size - 1u)));
    var j1 = u32(clamp(floor(u1.y / scale), 0.0, f32(size - 1u)));
    if (i1 > i0 + 1u || j1 > j0 + 1u) {
        k = min(k + 1u, top);
        size = params.grid_n >> k;
        scale = f32(1u << k);
        i0 = u32(clamp(floor(u0.x / scale), 0.0, f32(size - 1u)));
        i1 = u32(clamp(floor(u1.x / scale), 0.0, f32(size - 1u)));
        j0 = u32(clamp(floor(u0.y / scale), 0.0, f32(size - 1u)));
        j1 = u32(clamp(floor(u1.y / scale), 0.0, f32(size - 1u)));
    }
    // Levels are stored one after the other: Σ_{j<k} (n >> j)² = 4(n² − size²)/3 cells before k.
    let base = params.grid_offset + 2u * ((4u * (params.grid_n * params.grid_n - size * size)) / 3u);
    var a = 3.0e38;
    var b = -3.0e38;
    var j = j0;
    for (; j <= j1; j = j + 1u) {
        var i = i0;
        for (; i <= i1; i = i + 1u) {
            let c = base + 2u * (j * size + i);
            a = min(a, datum(c));
            b = max(b, datum(c + 1u));
        }
        note_cut(i <= i1);
    }
    note_cut(j <= j1);
    return vec3<f32>(a, b, 1.0);
}

// GridView::range without the shifted second lookup (GPU only: on llvmpipe it cost more than it
// saved): the range over the segment from a to b, its box dilated by `dilate`, widened by `tail`;
// (0, 0, 0) outside the grid. Looser than core's where core intersects, never tighter: rigorous.
fn grid_view_range(a: vec2<f32>, b: vec2<f32>, dilate: vec2<f32>, tail: f32) -> vec3<f32> {
    let r = grid_range(min(a, b) - dilate, max(a, b) + dilate);
    if (r.z == 0.0) {
        return r;
    }
    return vec3<f32>(r.x - tail, r.y + tail, 1.0);
}
//#endif
//#endif
