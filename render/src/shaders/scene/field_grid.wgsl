// Mirror of `core/src/scene/field_grid.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
//#if noise
// hermite_basis: the cubic Hermite basis on [0, 1] at s (value at 0, value at 1, slope at 0, slope
// at 1) and its derivative.
struct HermiteBasis {
    v: vec4<f32>,
    d: vec4<f32>,
}

fn hermite_basis(s: f32) -> HermiteBasis {
    let s2 = s * s;
    let s3 = s2 * s;
    var b: HermiteBasis;
    b.v = vec4<f32>(2.0 * s3 - 3.0 * s2 + 1.0, -2.0 * s3 + 3.0 * s2, s3 - 2.0 * s2 + s, s3 - s2);
    b.d = vec4<f32>(6.0 * s2 - 6.0 * s, -6.0 * s2 + 6.0 * s, 3.0 * s2 - 4.0 * s + 1.0, 3.0 * s2 - 2.0 * s);
    return b;
}

// Vertex k of the table: [f, c·f_x, c·f_y, c²·f_xy].
fn field_vertex(k: u32) -> vec4<f32> {
    let o = params.field_offset + 4u * k;
    return vec4<f32>(datum(o), datum(o + 1u), datum(o + 2u), datum(o + 3u));
}

// One corner's share of (F, ∂F/∂s, ∂F/∂t): value basis (a, b) and slope basis (da, db) along s,
// (e, f) and (de, df) along t.
fn field_corner(c: vec4<f32>, vs: vec2<f32>, ds: vec2<f32>, vt: vec2<f32>, dt: vec2<f32>) -> vec3<f32> {
    return vec3<f32>(
        c.x * vs.x * vt.x + c.y * vs.y * vt.x + c.z * vs.x * vt.y + c.w * vs.y * vt.y,
        c.x * ds.x * vt.x + c.y * ds.y * vt.x + c.z * ds.x * vt.y + c.w * ds.y * vt.y,
        c.x * vs.x * dt.x + c.y * vs.y * dt.x + c.z * vs.x * dt.y + c.w * vs.y * dt.y,
    );
}

// FieldGrid::sample: the table's value and gradient at x (relative to the camera target) as
// (F, F_x, F_y, 1), or 0 outside the table (or without one: field_n = 0).
fn field_sample(x: vec2<f32>) -> vec4<f32> {
    if (params.field_n == 0u) {
        return vec4<f32>(0.0);
    }
    let n = f32(params.field_n);
    let u = (x - vec2<f32>(params.field_x0, params.field_y0)) / params.field_cell;
    if (!(u.x >= 0.0 && u.y >= 0.0 && u.x <= n && u.y <= n)) {
        return vec4<f32>(0.0);
    }
    let i = min(u32(floor(u.x)), params.field_n - 1u);
    let j = min(u32(floor(u.y)), params.field_n - 1u);
    let hs = hermite_basis(u.x - f32(i));
    let ht = hermite_basis(u.y - f32(j));
    let v = params.field_n + 1u;
    let k = j * v + i;
    // Corner (di, dj) uses the value basis hs.v[di] and slope basis hs.v[2 + di] along s, likewise t.
    let s0 = vec2<f32>(hs.v.x, hs.v.z);
    let s1 = vec2<f32>(hs.v.y, hs.v.w);
    let ds0 = vec2<f32>(hs.d.x, hs.d.z);
    let ds1 = vec2<f32>(hs.d.y, hs.d.w);
    let t0 = vec2<f32>(ht.v.x, ht.v.z);
    let t1 = vec2<f32>(ht.v.y, ht.v.w);
    let dt0 = vec2<f32>(ht.d.x, ht.d.z);
    let dt1 = vec2<f32>(ht.d.y, ht.d.w);
    let acc = field_corner(field_vertex(k), s0, ds0, t0, dt0)
        + field_corner(field_vertex(k + 1u), s1, ds1, t0, dt0)
        + field_corner(field_vertex(k + v), s0, ds0, t1, dt1)
        + field_corner(field_vertex(k + v + 1u), s1, ds1, t1, dt1);
    return vec4<f32>(acc.x, acc.y / params.field_cell, acc.z / params.field_cell, 1.0);
}

// FieldView::probe on the explicit surface (FieldView::explicit; the level-of-detail march does not
// use the table, see Evaluator::lod_march): (value, error, slope along dxy, slope error) of f at x,
// or error < 0 outside the table.
fn field_probe(x: vec2<f32>, dxy: vec2<f32>) -> vec4<f32> {
    let s = field_sample(x);
    if (s.w == 0.0) {
        return vec4<f32>(0.0, -1.0, 0.0, 0.0);
    }
    let se = vec2<f32>(params.field_slope_error_x, params.field_slope_error_y);
    return vec4<f32>(s.x, params.field_error, dot(s.yz, dxy), dot(abs(dxy), se));
}
//#endif
//#endif
