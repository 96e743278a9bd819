// Mirror of `core/src/math/preconvolved.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

fn texel4(off: u32, i: u32) -> vec4<f32> {
    let b = off + 4u * i;
    return vec4<f32>(datum(b), datum(b + 1u), datum(b + 2u), datum(b + 3u));
}

//#if driver_color|height_color|transfer_curve
// (i0, i1, blend) of a continuous texel coordinate, clamped (mirror of preconvolved::split).
fn split_coord(f_in: f32, n: u32) -> vec3<f32> {
    let f = clamp(f_in, 0.0, f32(n - 1u));
    let i0 = min(u32(floor(f)), n - 2u);
    return vec3<f32>(f32(i0), f32(i0 + 1u), f - f32(i0));
}

// PreconvolvedTable::sample: bilinear, clamp-to-edge.
fn table_sample(off: u32, nm: u32, ns: u32, m_min: f32, m_max: f32, sigma_max: f32, m: f32, sigma: f32) -> vec4<f32> {
    let u = split_coord((m - m_min) / (m_max - m_min) * f32(nm - 1u), nm);
    let v = split_coord(sigma / sigma_max * f32(ns - 1u), ns);
    let i0 = u32(u.x);
    let i1 = u32(u.y);
    let j0 = u32(v.x);
    let j1 = u32(v.y);
    let top = mix(texel4(off, j0 * nm + i0), texel4(off, j0 * nm + i1), u.z);
    let bot = mix(texel4(off, j1 * nm + i0), texel4(off, j1 * nm + i1), u.z);
    return mix(top, bot, v.z);
}
//#endif
