// Mirror of `core/src/eval/masking/slope_masking_table.rs`: the material's table of slope-conditioned
// masking (#17), at params.cm_offset: r0, the ln step between footprint levels, then
// TABLE_AZIMUTHS × TABLE_LEVELS × TABLE_NUS entries (ν fastest) of TABLE_ENTRY values, ln r at
// HEIGHT_NODES × SLOPE_NODES nodes (height-major).
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
// SlopeMaskingTable::lookup: multilinear over the azimuth (periodic over π), ln r and ln ν,
// clamped at the ends, into joint_masking at the height rows rows.x..=rows.y (the rest stay 0).
fn slope_masking_lookup(dir: vec2<f32>, r: f32, nu: f32, rows: vec2<u32>) {
    let base = params.cm_offset;
    let r0 = datum(base);
    let level_step = datum(base + 1u);
    let ca = azimuth_coordinate(dir);
    let a0 = u32(ca.x);
    let fa = ca.y;
    let a1 = (a0 + 1u) % TABLE_AZIMUTHS;
    var lv = f32(TABLE_LEVELS - 1u);
    if (r > 0.0) {
        lv = clamp(log(r0 / r) / level_step, 0.0, f32(TABLE_LEVELS - 1u));
    }
    let l0 = min(u32(lv), TABLE_LEVELS - 2u);
    let fl = lv - f32(l0);
    let cn = nu_coordinate(nu);
    let n0 = u32(cn.x);
    let fn_ = cn.y;
    // Every index into joint_masking depends on loop counters alone (the same in every lane):
    // llvmpipe reads and writes a private array at a lane-varying index one lane at a time.
    for (var j = 0u; j < TABLE_ENTRY; j = j + 1u) {
        joint_masking[j] = 0.0;
    }
    for (var k = 0u; k < 8u; k = k + 1u) {
        let a = select(a0, a1, (k & 1u) != 0u);
        let l = l0 + ((k >> 1u) & 1u);
        let n = n0 + ((k >> 2u) & 1u);
        let w = select(1.0 - fa, fa, (k & 1u) != 0u)
            * select(1.0 - fl, fl, ((k >> 1u) & 1u) != 0u)
            * select(1.0 - fn_, fn_, ((k >> 2u) & 1u) != 0u);
        let e = base + 2u + ((a * TABLE_LEVELS + l) * TABLE_NUS + n) * TABLE_ENTRY;
        // Only the front slopes of the rows asked for are read: the back faces hold the last
        // front value.
        let front = front_columns(n);
        for (var row = 0u; row < HEIGHT_NODES; row = row + 1u) {
            let on = w != 0.0 && row >= rows.x && row <= rows.y;
            var v = 0.0;
            for (var j = 0u; j < SLOPE_NODES; j = j + 1u) {
                if (on && j < front) {
                    v = datum(e + row * SLOPE_NODES + j);
                }
                joint_masking[row * SLOPE_NODES + j] = joint_masking[row * SLOPE_NODES + j] + w * v;
            }
        }
    }
}

// azimuth_coordinate: the azimuth node a0 (over [0, π), periodic) below dir and the weight of
// the next, as (a0, weight).
fn azimuth_coordinate(dir: vec2<f32>) -> vec2<f32> {
    let pi = 3.14159265358979;
    var phi = atan2(dir.y, dir.x);
    if (phi < 0.0) {
        phi = phi + pi;
    }
    if (phi >= pi) {
        phi = phi - pi;
    }
    let xa = phi / pi * f32(TABLE_AZIMUTHS);
    let a0 = min(u32(max(floor(xa), 0.0)), TABLE_AZIMUTHS - 1u);
    return vec2<f32>(f32(a0), clamp(xa - f32(a0), 0.0, 1.0));
}

// nu_coordinate: the ν nodes n0, n0 + 1 around nu (linear in ln ν, clamped; ν ≤ 0 reads the
// first) and the weight of n0 + 1, as (n0, weight).
fn nu_coordinate(nu: f32) -> vec2<f32> {
    var nv = 0.0;
    if (nu > 0.0) {
        nv = clamp(log(nu / TABLE_NU_MIN) / log(TABLE_NU_RATIO), 0.0, f32(TABLE_NUS - 1u));
    }
    let n0 = min(u32(nv), TABLE_NUS - 2u);
    return vec2<f32>(f32(n0), nv - f32(n0));
}

// front_columns: the slope columns of ν node n that are front faces, z_j = j − 4 < ν_n.
fn front_columns(n: u32) -> u32 {
    let nu_n = TABLE_NU_MIN * pow(TABLE_NU_RATIO, f32(n));
    return clamp(u32(ceil(nu_n + 4.0)), 1u, SLOPE_NODES);
}
//#endif
