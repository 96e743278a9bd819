// Mirror of `core/src/math/table_slope.rs`, function for function (names in render/tests/shaders.rs's MIRRORS).
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
//#if noise
//#if transfer_curve
// The two transfer-table rows the level-of-detail surface blends at its σ_f (TableSlope::at), and
// the bound of |G′| over the whole row pair (RowSlope::max, capped at g_lip). Set by lod_prepare.
var<private> lod_rows: vec2<u32>;
var<private> lod_g_lip: f32;

// TableSlope::entry: level k's entry i of row j of the slope pyramids.
fn table_slope_entry(j: u32, k: u32, i: u32) -> f32 {
    let p2 = 2u * params.ts_p;
    return datum(params.ts_offset + j * p2 + p2 - (p2 >> k) + i);
}

// TableSlope::at: the rows the transfer table's sampler blends at σ (split_coord as table_sample).
fn table_slope_at(sigma: f32) -> vec2<u32> {
    let ns = params.tt_size_s;
    let v = split_coord(sigma / params.tt_sigma_max * f32(ns - 1u), ns);
    return vec2<u32>(u32(v.x), u32(v.y));
}

// RowSlope::max: the pyramids' tops of both rows.
fn table_slope_max(rows: vec2<u32>) -> f32 {
    let top = countTrailingZeros(params.ts_p);
    return max(table_slope_entry(rows.x, top, 0u), table_slope_entry(rows.y, top, 0u));
}

// RowSlope::lipschitz_on: the largest slope of both rows over the column intervals [lo, hi] meets,
// widened by one interval each side; the rows' bound for a NaN or reversed range.
fn table_slope_on(rows: vec2<u32>, lo: f32, hi: f32) -> f32 {
    if (!(lo <= hi)) {
        return table_slope_max(rows);
    }
    let last = params.tt_size_m - 2u;
    let dm = (params.tt_m_max - params.tt_m_min) / f32(params.tt_size_m - 1u);
    let ua = clamp(floor((lo - params.tt_m_min) / dm), 0.0, f32(last));
    let ub = clamp(floor((hi - params.tt_m_min) / dm), 0.0, f32(last));
    let a = max(u32(ua), 1u) - 1u;
    let b = min(u32(ub) + 1u, last);
    var k = 0u;
    while ((b >> k) - (a >> k) > 1u) {
        k = k + 1u;
    }
    let r0 = max(table_slope_entry(rows.x, k, a >> k), table_slope_entry(rows.x, k, b >> k));
    let r1 = max(table_slope_entry(rows.y, k, a >> k), table_slope_entry(rows.y, k, b >> k));
    return max(r0, r1);
}
//#endif
//#endif
//#endif
