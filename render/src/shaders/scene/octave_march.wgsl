// Mirror of `core/src/scene/octave_march.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if relief
//#if noise
// OctaveSurface::ray's per-ray level bounds: residual amplitude R, first-order K, curvature M and
// third-order J per level (at most MAX_LEVELS = 4).
struct OctaveRay {
    total: f32,
    resid: vec4<f32>,
    lip: vec4<f32>,
    curv: vec4<f32>,
    jerk: vec4<f32>,
}

// Wave i's amplitude on the explicit surface, or times its footprint attenuation (lod_prepare) on
// the level-of-detail surface.
fn octave_amplitude(i: u32, lod: bool) -> f32 {
    if (lod) {
        return cached_wave(i).z * lod_att[i];
    }
    return cached_wave(i).z;
}

// The waves the march sums: all on the explicit surface; on the level-of-detail surface those before
// the last one the footprint leaves above 1e-10 (lod_prepare's lod_count; the rest change no f32 sum).
fn octave_count(lod: bool) -> u32 {
    if (lod) {
        return lod_count;
    }
    return params.wave_count;
}

// The end of level l (noise::level_ends, packed eight bits each; the last level ends at the wave
// count), at most octave_count(lod).
fn level_end(l: u32, lod: bool) -> u32 {
    let n = octave_count(lod);
    if (l + 1u >= params.level_count) {
        return n;
    }
    return min((params.level_ends >> (8u * l)) & 255u, n);
}

// OctaveSurface::ray: the level bounds along direction d.
fn octave_ray(d: vec3<f32>, lod: bool) -> OctaveRay {
    var r: OctaveRay;
    let n = octave_count(lod);
    var total = 0.0;
    for (var i = 0u; i < n; i = i + 1u) {
        total = total + abs(octave_amplitude(i, lod));
    }
    r.total = total;
    var k = 0.0;
    var m = 0.0;
    var jk = 0.0;
    var below = 0.0;
    var start = 0u;
    for (var l = 0u; l < min(params.level_count, 4u); l = l + 1u) {
        let e = level_end(l, lod);
        for (var i = start; i < e; i = i + 1u) {
            let a = abs(octave_amplitude(i, lod));
            let om = TAU * dot(cached_wave(i).xy, d.xy);
            k = k + a * abs(om);
            m = m + a * om * om;
            jk = jk + a * abs(om * om * om);
            below = below + a;
        }
        start = e;
        r.lip[l] = k;
        r.curv[l] = m;
        r.jerk[l] = jk;
        if (e < n) {
            r.resid[l] = max(total - below, 0.0);
        }
    }
    return r;
}

// Wave i's (value, slope, second derivative along dxy) at x, for OctaveSurface::march's partial sums.
fn octave_term(i: u32, x: vec2<f32>, dxy: vec2<f32>, lod: bool) -> vec3<f32> {
    let w = cached_wave(i);
    let a = octave_amplitude(i, lod);
    let ph = TAU * dot(w.xy, x) + w.w;
    let om = TAU * dot(w.xy, dxy);
    let c = a * cos(ph);
    return vec3<f32>(c, -a * om * sin(ph), -om * om * c);
}

// (f, f′, f″ along dxy) over waves [first, end) at x. Eight waves per iteration: see UNROLL.
fn octave_partial(first: u32, end: u32, x: vec2<f32>, dxy: vec2<f32>, lod: bool) -> vec3<f32> {
    var acc = vec3<f32>(0.0);
    var i = first;
    if (end > first) {
        note_work((end - first + 7u) / 8u);
        let n8 = first + ((end - first) & ~7u);
        for (; i < n8; i = i + 8u) {
            acc = acc + octave_term(i, x, dxy, lod) + octave_term(i + 1u, x, dxy, lod)
                + octave_term(i + 2u, x, dxy, lod) + octave_term(i + 3u, x, dxy, lod)
                + octave_term(i + 4u, x, dxy, lod) + octave_term(i + 5u, x, dxy, lod)
                + octave_term(i + 6u, x, dxy, lod) + octave_term(i + 7u, x, dxy, lod);
        }
    }
    for (; i < end; i = i + 1u) {
        acc = acc + octave_term(i, x, dxy, lod);
    }
    note_cut(i < end);
    return acc;
}

// σ_h·g(f) on the explicit surface, σ_h·E[g(f + σ_f Z)] on the level-of-detail surface.
fn octave_height(f: f32, lod: bool, sf: f32) -> f32 {
    if (lod) {
        return params.sigma_h * transfer_moments(f, sf).mean;
    }
    return params.sigma_h * transfer_eval(f).x;
}

// OctaveSurface::step: the longer of the first- and second-order safe steps; 1e30 stands for "the
// gap cannot shrink" (core: infinity).
fn octave_step(gap: f32, fd: f32, lip: f32, curv: f32, dz: f32, sg: f32) -> f32 {
    let rate = sg * lip - dz;
    var first = 1e30;
    if (rate > 0.0) {
        first = gap / rate;
    }
    var beta = sg * abs(fd) - dz;
    if (params.transfer_kind == TRANSFER_IDENTITY) {
        beta = params.sigma_h * fd - dz;
    }
    let c = 0.5 * sg * curv;
    var second = 1e30;
    if (c > 0.0) {
        let root = sqrt(beta * beta + 4.0 * c * gap);
        if (beta >= 0.0) {
            second = 0.0;
            if (beta + root > 0.0) {
                second = 2.0 * gap / (beta + root);
            }
        } else {
            second = (root - beta) / (2.0 * c);
        }
    } else if (beta > 0.0) {
        second = gap / beta;
    }
    return max(first, second);
}

// OctaveSurface::local_step: lengthen the level's (step, gap, found) by the local Lipschitz constant
// of G over the range f can reach in trial steps growing 8× (at most four); above = z − σ_h·G(f_l).
// cubic = (f_l″, J_l) for the third-order step, (0, −1) to leave it out (the field table's steps).
fn octave_local_step(found_in: vec3<f32>, above: f32, f: f32, fd: f32, lip: f32, curv: f32, resid: f32, dz: f32, lod: bool, sf: f32, min_step: f32, cubic: vec2<f32>) -> vec3<f32> {
    var found = found_in;
//#if transfer_curve
    if (params.transfer_kind == TRANSFER_IDENTITY || (found.z > 0.0 && found.x >= 1e30)) {
        return found;
    }
    var trial = 8.0 * max(select(0.0, found.x, found.z > 0.0), min_step);
    var i = 0u;
    var left = false;
    for (; i < 4u; i = i + 1u) {
        let reach = resid + lip * trial;
        let sg = params.sigma_h * lipschitz_on(f - reach, f + reach, lod);
        let gap = above - sg * resid;
        if (!(gap >= 0.0)) {
            left = true;
            break;
        }
        var s = octave_step(gap, fd, lip, curv, dz, sg);
        if (cubic.y >= 0.0) {
            s = max(s, octave_cubic_step(gap, fd, cubic.x, cubic.y, curv, dz, min(s, trial), min_step, sg));
        }
        let step = min(s, trial);
        if (found.z > 0.0) {
            found = vec3<f32>(max(found.x, step), max(found.y, gap), 1.0);
        } else {
            found = vec3<f32>(step, gap, 1.0);
        }
        if (s < trial) {
            left = true;
            break;
        }
        trial = trial * 8.0;
    }
    note_cut(!left && i < 4u);
//#endif
    return found;
}

// OctaveSurface::bracket_width: (s_lo, width) of the first crossing's bracket ahead of exact gap
// `gap` for the identity transfer; width −1 when the conditions do not hold.
fn octave_bracket_width(gap: f32, fd: f32, curv: f32, dz: f32) -> vec2<f32> {
    if (params.transfer_kind != TRANSFER_IDENTITY || !(gap > 0.0)) {
        return vec2<f32>(0.0, -1.0);
    }
    let beta = params.sigma_h * fd - dz;
    let c = 0.5 * params.sigma_h * curv;
    let dp = beta * beta + 4.0 * c * gap;
    let dm = beta * beta - 4.0 * c * gap;
    if (!(beta > 0.0 && dm >= 0.0)) {
        return vec2<f32>(0.0, -1.0);
    }
    let rp = sqrt(dp);
    let rm = sqrt(dm);
    let lo = 2.0 * gap / (beta + rp);
    let width = 16.0 * c * gap * gap / ((rp + rm) * (beta + rm) * (beta + rp));
    return vec2<f32>(lo, width);
}

// crossing::first_root: the first positive root of γ − βs − cs², 1e30 when it stays positive.
fn first_root(gap: f32, beta: f32, c: f32) -> f32 {
    let disc = beta * beta + 4.0 * c * gap;
    if (!(disc >= 0.0)) {
        return 1e30;
    }
    let den = beta + sqrt(disc);
    if (den > 0.0) {
        return 2.0 * gap / den;
    }
    if (gap == 0.0 && c > 0.0) {
        return 0.0;
    }
    return 1e30;
}

// GPU only: f″ summed in f32 is off by at most about this fraction of the level's M (a few ulps per
// term over at most 256 terms); the third-order bounds widen q by it.
const CUBIC_MARGIN: f32 = 1e-4;

// OctaveSurface::cubic_step: the safe step from the gap's third-order bound (the identity, or a
// transfer curve with |G′| ≤ sg/σ_h), windows 2·safe (a step already proven safe) then each step
// found; 0 when the gap is not positive.
fn octave_cubic_step(gap: f32, fd: f32, fdd: f32, jerk: f32, curv: f32, dz: f32, safe: f32, min_step: f32, sg: f32) -> f32 {
    if (!(gap > 0.0)) {
        return 0.0;
    }
    var beta = sg * abs(fd) - dz;
    var q = 0.5 * sg * (abs(fdd) + CUBIC_MARGIN * curv);
    var r = sg * jerk / 6.0;
    if (params.transfer_kind == TRANSFER_IDENTITY) {
        beta = params.sigma_h * fd - dz;
        q = 0.5 * params.sigma_h * (fdd + CUBIC_MARGIN * curv);
        r = params.sigma_h * jerk / 6.0;
    }
    var window = 2.0 * max(safe, min_step);
    var best = 0.0;
    for (var k = 0u; k < 3u; k = k + 1u) {
        let s = first_root(gap, beta, q + r * window);
        best = max(best, min(s, window));
        if (!(s < 1e30 && s > 0.0)) {
            break;
        }
        window = s;
    }
    return best;
}

// OctaveSurface::cubic_bracket: (s_lo, width) of the first crossing's bracket from the gap's
// third-order bounds; width −1 when the conditions do not hold.
fn octave_cubic_bracket(gap: f32, fd: f32, fdd: f32, jerk: f32, curv: f32, dz: f32) -> vec2<f32> {
    if (params.transfer_kind != TRANSFER_IDENTITY || !(gap > 0.0)) {
        return vec2<f32>(0.0, -1.0);
    }
    let beta = params.sigma_h * fd - dz;
    let q = 0.5 * params.sigma_h * fdd;
    // The f32 margin on f″ widens both bounds: it joins the window's cubic term.
    let r = params.sigma_h * jerk / 6.0;
    let qm = 0.5 * params.sigma_h * CUBIC_MARGIN * curv;
    var window = 1.25 * first_root(gap, beta, q);
    for (var k = 0u; k < 2u; k = k + 1u) {
        if (!(window < 1e30)) {
            return vec2<f32>(0.0, -1.0);
        }
        let spread = r * window + qm;
        let dp = beta * beta + 4.0 * (q + spread) * gap;
        let dm = beta * beta + 4.0 * (q - spread) * gap;
        if (!(dp >= 0.0 && dm >= 0.0)) {
            return vec2<f32>(0.0, -1.0);
        }
        let rp = sqrt(dp);
        let rm = sqrt(dm);
        if (!(beta + rm > 0.0)) {
            return vec2<f32>(0.0, -1.0);
        }
        let hi = 2.0 * gap / (beta + rm);
        if (hi <= window) {
            let lo = 2.0 * gap / (beta + rp);
            let width = 16.0 * spread * gap * gap / ((rp + rm) * (beta + rm) * (beta + rp));
            return vec2<f32>(lo, width);
        }
        window = 1.25 * hi;
    }
    return vec2<f32>(0.0, -1.0);
}

// OctaveSurface::march on the explicit (lod = false) or level-of-detail surface (lod = true, after
// lod_prepare, whose σ_f is sf): t of the first crossing, or -1 when the ray leaves the slab.
fn octave_march(o: vec3<f32>, d: vec3<f32>, lod: bool, sf: f32) -> f32 {
    let levels = clamp(params.level_count, 1u, 4u);
    let last = levels - 1u;
    let rw = octave_ray(d, lod);
    let sg = params.sigma_h * march_g_lip(lod);
    // The slab: |h| ≤ h_max and |G(f)| ≤ |G(0)| + g_lip Σ|a_i| (thin in the far field).
    let top = min(params.h_max, abs(octave_height(0.0, lod, sf)) + sg * rw.total) * (1.0 + 1e-6) + 1e-30;
    // The f32 guard of march_heightfield.
    let min_step = max(params.min_step, 4.8e-7 * (max(max(abs(o.x), abs(o.y)), abs(o.z)) + top));
    var t = 0.0;
    var prev_t = 0.0;
    var prev_g = 0.0;
    var j = 0u;
    // A camera ray may settle on the surface; a shadow ray must cross it (core's module docs).
    let settle = HIT_GAP * top;
    let settle_f = FIELD_SETTLE * top;
    var may_settle = 0u;
    var skip = 0.0;
    // The crossing's bracket [prev_t, t] is refined once, after the loop: a GPU (and llvmpipe,
    // which runs every branch of an `if` under a mask) would otherwise carry the whole refinement
    // inside every step.
    var crossed = false;
    var cross_gap = 0.0;
    for (var it = 0u; it < 20000u; it = it + 1u) {
        note_work(1u);
        let p = o + d * t;
        if ((d.z >= 0.0 && p.z > top) || (d.z < 0.0 && p.z < -top - 1.0)) {
            return -1.0;
        }
        // Near the surface, step (and let a camera ray settle) on the table of f; a ray clear of the
        // surface by 1000 ε on it may settle (a camera ray), as after an exact evaluation.
        if (params.field_n > 0u && !lod) {
            let crawl = may_settle == 1u;
            let fs = octave_field_step(p, d, rw.lip[last], rw.curv[last], lod, sf, settle_f, crawl, min_step);
            if (fs.x == 1.0 && crawl && t > 0.0) {
                return t;
            }
            if (fs.x == 2.0 && (may_settle != 0u || fs.z > 1e3 * settle)) {
                if (may_settle == 0u) {
                    may_settle = 1u;
                }
                prev_t = t;
                prev_g = fs.z;
                t = t + fs.y;
                continue;
            }
        }
        // After the first evaluation (which decides whether the ray may settle), skip what the
        // grid proves clear: on the explicit surface only. GPU only: on the level-of-detail
        // surface the skips cost more than the steps they save, on llvmpipe and on an H200 alike
        // (`lodestone bench --no-bound-grid` A/B, 2026-12-04: default preset's naive frames 5–30% and filtered
        // 3–12% faster without them; dirt-in-crevices and terraces likewise); ground truth is
        // even there, so it keeps them. Core's march may skip: both are rigorous, and a hit moves
        // by at most the settle width.
        if (params.grid_n > 0u && may_settle != 0u && !lod) {
            let sk = octave_grid_skip(o, d, t, &skip, lod, sf);
            if (sk.z > 0.0) {
                prev_t = sk.x;
                prev_g = sk.y;
                t = sk.x;
                continue;
            }
        }
        var acc = vec3<f32>(0.0);
        var start = 0u;
        var have = false;
        var best_s = 0.0;
        var best_l = 0u;
        var best_g = 0.0;
        var known = 0.0;
        var deepest = 0u;
        var l = 0u;
        var left = false;
        for (; l < levels; l = l + 1u) {
            let e = level_end(l, lod);
            acc = acc + octave_partial(start, e, p.xy, d.xy, lod);
            start = e;
            deepest = l;
            let above = p.z - octave_height(acc.x, lod, sf);
            var gap = above - sg * rw.resid[l];
            if (l == last && t > 0.0 && gap >= 0.0 && gap <= settle && may_settle == 1u) {
                return t;
            }
            if (lod && l == last && t > 0.0 && may_settle == 1u) {
                let br = octave_bracket_width(gap, acc.y, rw.curv[l], d.z);
                if (br.y >= 0.0 && br.y <= lod_settle) {
                    return t + br.x;
                }
                let bc = octave_cubic_bracket(gap, acc.y, acc.z, rw.jerk[l], rw.curv[l], d.z);
                if (bc.y >= 0.0 && bc.y <= lod_settle) {
                    return t + bc.x;
                }
            }
            if (l == last && gap < 0.0) {
                if (t > 0.0) {
                    crossed = true;
                    cross_gap = gap;
                    left = true;
                    break;
                }
                // The origin is on the surface by contract: a negative gap here is rounding.
                gap = 0.0;
            }
            var found = vec3<f32>(0.0);
            if (gap >= 0.0) {
                let s = octave_step(gap, acc.y, rw.lip[l], rw.curv[l], d.z, sg);
                let sc = octave_cubic_step(gap, acc.y, acc.z, rw.jerk[l], rw.curv[l], d.z, s, min_step, sg);
                found = vec3<f32>(max(s, sc), gap, 1.0);
            }
            found = octave_local_step(found, above, acc.x, acc.y, rw.lip[l], rw.curv[l], rw.resid[l], d.z, lod, sf, min_step, vec2<f32>(acc.z, rw.jerk[l]));
            if (found.z > 0.0) {
                known = max(known, found.y);
                if (!have || found.x > best_s) {
                    have = true;
                    best_s = found.x;
                    best_l = l;
                    best_g = found.y;
                }
            }
            if (l >= j && have) {
                left = true;
                break;
            }
        }
        note_cut(!left && l < levels);
        if (crossed) {
            break;
        }
        if (!have) {
            return -1.0;
        }
        if (best_s < min_step && deepest < last) {
            // Too close for the coarse bounds: look again with every wave.
            j = last;
            continue;
        }
        if (best_l < j) {
            j = best_l;
        } else if (best_l < last && best_g < sg * (rw.resid[best_l] - rw.resid[best_l + 1u])) {
            j = best_l + 1u;
        }
        prev_t = t;
        prev_g = known;
        if (may_settle == 0u) {
            may_settle = select(2u, 1u, known > 1e3 * settle);
        }
        if (best_s >= 1e30) {
            // Nothing below can be met: jump out of the slab.
            var exit = (-top - 1.0 - p.z) / d.z;
            if (d.z > 0.0) {
                exit = (top - p.z) / d.z;
            }
            t = t + max(exit, min_step) * (1.0 + 1e-6) + min_step;
            continue;
        }
        t = t + max(best_s, min_step);
    }
    if (crossed) {
        return refine(o, d, prev_t, prev_g, t, cross_gap, lod, sf);
    }
    // 20000 steps, or the loop was cut: the answer is not known.
    note_cut(true);
    return -1.0;
}
//#endif
//#endif
