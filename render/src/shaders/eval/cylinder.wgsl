// Mirror of `core/src/eval/cylinder.rs`: ground truth on the explicit displaced cylinder and the
// analytic views in the tangent plane where the ray meets the mean cylinder. Needs the special,
// material and view-parameter units and scene/cylinder.wgsl.

fn cylinder_gap(p: vec3<f32>) -> f32 {
    let s = cylinder_to_surface(p);
    return s.rho - view_params.radius - surface_height(s.uv);
}

// Evaluator::cylinder_march: t of the crossing, or -1.
fn cylinder_march(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> f32 {
    let r = view_params.radius;
    let rho_min = max(r - params.h_max, 1e-6 * r);
    let k = params.slope_bound * r / rho_min;
    let rate = sqrt(1.0 + k * k);
    var t = 0.0;
    var prev_t = 0.0;
    var prev_r = 0.0;
    var prev_g = 0.0;
    var relaxed = false;
    for (var it = 0u; it < 20000u; it = it + 1u) {
        var gap = cylinder_gap(o + d * t);
        if (gap < 0.0 && t == 0.0) {
            gap = 0.0;
        }
        let rr = max(gap, 0.0) / rate;
        if (relaxed && t - prev_t > prev_r + rr) {
            t = prev_t + max(prev_r, params.min_step);
            relaxed = false;
            continue;
        }
        if (t > t_max) {
            return -1.0;
        }
        if (gap < 0.0) {
            return cylinder_refine(o, d, prev_t, prev_g, t, gap);
        }
        prev_t = t;
        prev_r = rr;
        prev_g = gap;
        let safe = max(rr, params.min_step);
        let step = max(RELAXATION * rr, params.min_step);
        relaxed = step > safe;
        t = t + step;
    }
    return -1.0;
}

// refine: the crossing bracketed by a (gap ga ≥ 0) and b (gap gb < 0), as core's scene::surface::refine:
// bisection (MARCH_REFERENCE, 24 halvings) or the Illinois method to the same bracket width (MARCH_FAST).
// The cylinder's version (WGSL has no closures: the same loop on cylinder_gap).
fn cylinder_refine(o: vec3<f32>, d: vec3<f32>, a_in: f32, ga_in: f32, b_in: f32, gb_in: f32) -> f32 {
    var a = a_in;
    var b = b_in;
    if (params.march == MARCH_REFERENCE) {
        for (var j = 0u; j < 24u; j = j + 1u) {
            let m = 0.5 * (a + b);
            if (cylinder_gap(o + d * m) >= 0.0) {
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
        let gc = cylinder_gap(o + d * c);
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

// Evaluator::cylinder_trace_ray.
fn cylinder_trace_ray(origin: vec3<f32>, dir: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let r = view_params.radius;
    let outer = r + params.h_max * 1.001 + 1e-6;
    let span = cylinder_intersect(outer, origin, dir);
    if (span.y < 0.0) {
        return vec3<f32>(0.0);
    }
    let o = origin + dir * span.x;
    let t = cylinder_march(o, dir, span.y - span.x);
    if (t < 0.0) {
        return vec3<f32>(0.0);
    }
    let p = o + dir * t;
    let s = cylinder_to_surface(p);
    let fg = value_and_gradient(s.uv);
    let gd = transfer_eval(fg.x);
    let grad = fg.yz * (params.sigma_h * gd.y);
    let n = normal_of(vec2<f32>(grad.x, grad.y * r / max(s.rho, 1e-30)));
    shading_frame = cylinder_frame(s.phi);
    let fr = transpose(shading_frame);
    let wo_l = fr * -dir;
    let wi_l = fr * wi;
    // Evaluator::shade_hit with the cylinder's shadow ray.
    let lit = dot(n, wi_l) > 0.0 && params.sun > 0.0;
    if (!lit && !has_environment()) {
        return vec3<f32>(0.0);
    }
    var v = select(0.0, 1.0, lit);
    if (lit) {
        let shadow = cylinder_intersect(outer, p, wi);
        if (shadow.y >= 0.0 && cylinder_march(p, wi, shadow.y) >= 0.0) {
            v = 0.0;
        }
    }
    return shade_point(fg.x, n, wo_l, wi_l, v);
}

// Evaluator::cylinder_pixel, for the unnormalised camera direction d of a pixel.
fn cylinder_pixel(method: u32, d: vec3<f32>, dx: vec3<f32>, dy: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let dir = normalize(d);
    let span = cylinder_intersect(view_params.radius, view_params.eye, dir);
    if (span.y < 0.0) {
        return vec3<f32>(0.0);
    }
    let hit = view_params.eye + dir * span.x;
    let s = cylinder_to_surface(hit);
    let fr = cylinder_frame(s.phi);
    shading_frame = fr;
    let fp = tangent_footprint(d, dx, dy, hit, fr);
    let frt = transpose(fr);
    let q = frt * (view_params.eye - hit);
    let o = vec3<f32>(s.uv.x + q.x, s.uv.y + q.y, q.z);
    return analytic_pixel(method, o, frt * dir, frt * wi, fp);
}
