// Mirror of `core/src/scene/march.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
// surface::march_heightfield (over-relaxed; backs off when the safe intervals of two points do not
// cover the step, before concluding anything at the new point): t of the first crossing, or -1 when
// the ray leaves the slab.
fn march_heightfield(o: vec3<f32>, d: vec3<f32>, rate: f32, lod: bool, sf: f32) -> f32 {
    if (!(rate > 0.0)) {
        return -1.0;
    }
    let top = params.h_max * (1.0 + 1e-6) + 1e-30;
    // f32 guard (core marches in f64 and needs none): a step must move the point by more than the
    // rounding of its coordinates, or a march leaving the surface never leaves it (its rounding-level
    // negative gap then reads as a crossing: false shadows at extreme frequencies, σ_n ≫ σ_h).
    let min_step = max(params.min_step, 4.8e-7 * (max(max(abs(o.x), abs(o.y)), abs(o.z)) + top));
    var t = 0.0;
    var prev_t = 0.0;
    var prev_r = 0.0;
    var prev_g = 0.0;
    var relaxed = false;
    for (var it = 0u; it < 20000u; it = it + 1u) {
        note_work(1u);
        let p = o + d * t;
        var gap = p.z - field_height(p.xy, lod, sf);
        if (gap < 0.0 && t == 0.0) {
            // The origin is on the surface by contract: a negative gap here is rounding.
            gap = 0.0;
        }
        let r = max(gap, 0.0) / rate;
        if (relaxed && t - prev_t > prev_r + r) {
            // The relaxed step left a stretch no safe interval covers: back off and step safely.
            t = prev_t + max(prev_r, min_step);
            relaxed = false;
            continue;
        }
        if ((d.z >= 0.0 && p.z > top) || (d.z < 0.0 && p.z < -top - 1.0)) {
            return -1.0;
        }
        if (gap < 0.0) {
            return refine(o, d, prev_t, prev_g, t, gap, lod, sf);
        }
        prev_t = t;
        prev_r = r;
        prev_g = gap;
        let safe = max(r, min_step);
        let step = max(RELAXATION * r, min_step);
        relaxed = step > safe;
        t = t + step;
    }
    // 20000 steps, or the loop was cut: the answer is not known.
    note_cut(true);
    return -1.0;
}

// The gap z − h above the heightfield at o + t·d.
fn gap_at(o: vec3<f32>, d: vec3<f32>, t: f32, lod: bool, sf: f32) -> f32 {
    let q = o + d * t;
    return q.z - field_height(q.xy, lod, sf);
}

// refine: the crossing bracketed by a (gap ga ≥ 0) and b (gap gb < 0), as core's scene::surface::refine:
// bisection (MARCH_REFERENCE, 24 halvings) or the Illinois method to the same bracket width (MARCH_FAST).
// Returns the last point found above the heightfield (explicit, or level-of-detail with `lod`).
fn refine(o: vec3<f32>, d: vec3<f32>, a_in: f32, ga_in: f32, b_in: f32, gb_in: f32, lod: bool, sf: f32) -> f32 {
    var a = a_in;
    var b = b_in;
    if (params.march == MARCH_REFERENCE) {
        for (var j = 0u; j < 24u; j = j + 1u) {
            let m = 0.5 * (a + b);
            if (gap_at(o, d, m, lod, sf) >= 0.0) {
                a = m;
            } else {
                b = m;
            }
        }
        return a;
    }
    var ga = ga_in;
    var gb = gb_in;
    let width = max((b - a) * 5.9604645e-8, FAST_WIDTH * max(abs(b), 1.0));
    var side = 0;
    for (var j = 0u; j < 48u; j = j + 1u) {
        if (b - a <= width) {
            break;
        }
        var c = (a * gb - b * ga) / (gb - ga);
        if (!(c > a && c < b)) {
            c = 0.5 * (a + b);
        }
        // Half a width inside the bracket, so a converged secant closes it (core's refine).
        c = clamp(c, a + 0.5 * width, b - 0.5 * width);
        let gc = gap_at(o, d, c, lod, sf);
        if (gc >= 0.0) {
            a = c;
            ga = gc;
            if (side == 1) {
                gb = 0.5 * gb;
            }
            side = 1;
        } else {
            b = c;
            gb = gc;
            if (side == -1) {
                ga = 0.5 * ga;
            }
            side = -1;
        }
    }
    return a;
}
//#endif
