// Mirror of `core/src/object/cone_trace.rs` [HN12 Alg. 1]: a cone marched through the voxel field
// in elements as long as they are wide, the level from the cone's radius, each element's sub-pixel
// mask combined A-buffer style (or alpha blended [CNLE09], or nearest voxels as opaque blocks),
// shadow cones toward the sun. Core's march visits elements through a closure; here `march_step`
// takes one step at a time.

const MODE_MASKS: u32 = 0u;
const MODE_ALPHA_BLEND: u32 = 1u;
const MODE_NEAREST: u32 = 2u;

// Elements one march may take before it is cut (noted; core allows 65536).
const MAX_ELEMENTS: u32 = 4096u;

// Cone: apex `origin`, unit axis `dir`, radius `cone_radius` at distance t (a thin lens of radius
// `lens` focused at `focus` widens it; lens 0 is a pinhole).
struct Cone {
    origin: vec3<f32>,
    dir: vec3<f32>,
    radius0: f32,
    spread: f32,
    lens: f32,
    focus: f32,
}

// Cone::radius [HN12 Sec. 4.1, Fig. 1d]: the footprint and the lens's circle of confusion as
// independent discs, √(a² + b²).
fn cone_radius(cone: Cone, t: f32) -> f32 {
    let a = cone.radius0 + cone.spread * t;
    if (!(cone.lens > 0.0 && cone.focus > 0.0)) {
        return a;
    }
    let b = cone.lens * (1.0 - t / cone.focus);
    return sqrt(a * a + b * b);
}

// Coverage: the A-buffer's covered sub-rays (masks, nearest) or the opacity (alpha blending).
struct Coverage {
    covered: vec2<u32>,
    opacity: f32,
}

// Coverage::add: the share of the pixel a new element's mask adds.
fn coverage_add(c: ptr<function, Coverage>, mask: vec2<u32>, mode: u32) -> f32 {
    if (mode == MODE_ALPHA_BLEND) {
        let a = f32(countOneBits(mask.x) + countOneBits(mask.y)) / f32(MASK_BITS);
        let w = (1.0 - (*c).opacity) * a;
        (*c).opacity += w;
        return w;
    }
    let fresh = mask & ~(*c).covered;
    (*c).covered = (*c).covered | mask;
    return f32(countOneBits(fresh.x) + countOneBits(fresh.y)) / f32(MASK_BITS);
}

// Coverage::share: the share covered so far.
fn coverage_share(c: Coverage, mode: u32) -> f32 {
    if (mode == MODE_ALPHA_BLEND) {
        return c.opacity;
    }
    return f32(countOneBits(c.covered.x) + countOneBits(c.covered.y)) / f32(MASK_BITS);
}

// Coverage::full: nothing more can show.
fn coverage_full(c: Coverage, mode: u32) -> bool {
    if (mode == MODE_ALPHA_BLEND) {
        return c.opacity >= 1.0 - 1e-6;
    }
    return c.covered.x == 0xffffffffu && c.covered.y == 0xffffffffu;
}

// ConeTracer::element_mask: the element's mask in the cone's frame (e1, e2, d), thinned to the
// sample's occupancy unless the element lies more than its radius inside (the floor); nearest
// voxels are opaque.
fn element_mask(s: VoxelSample, e1: vec3<f32>, e2: vec3<f32>, d: vec3<f32>, r: f32, mode: u32) -> vec2<u32> {
    if (mode == MODE_NEAREST) {
        return vec2<u32>(0xffffffffu, 0xffffffffu);
    }
    let n = vec3<f32>(dot(s.normal, e1), dot(s.normal, e2), dot(s.normal, d));
    let p = element_mask_params(r, r, n, s.distance);
    let mask = mask_lookup(p.x, p.y);
    if (s.distance < -r) {
        return mask;
    }
    return mask & thinning(s.occupancy);
}

// GPU only: the slab of one axis, (entry, exit) of the ray between lo and hi along it; the whole
// line (or none of it) when the ray is parallel to the slab. Written per axis, not looped: a loop
// spends the adapter's loop budget (bindings.wgsl).
fn axis_slab(o: f32, d: f32, lo: f32, hi: f32) -> vec2<f32> {
    if (abs(d) < 1e-30) {
        return select(vec2<f32>(3.0e38, -3.0e38), vec2<f32>(-3.0e38, 3.0e38), o >= lo && o <= hi);
    }
    let u = (lo - o) / d;
    let v = (hi - o) / d;
    return vec2<f32>(min(u, v), max(u, v));
}

// cube_span: the ray's span (t0, t1) inside the cube [−half, half]³; z = 1 when it meets it.
fn cube_span(o: vec3<f32>, d: vec3<f32>, half: f32) -> vec3<f32> {
    let x = axis_slab(o.x, d.x, -half, half);
    let y = axis_slab(o.y, d.y, -half, half);
    let z = axis_slab(o.z, d.z, -half, half);
    let t0 = max(0.0, max(x.x, max(y.x, z.x)));
    let t1 = min(x.y, min(y.y, z.y));
    return vec3<f32>(t0, t1, select(0.0, 1.0, t1 > t0));
}

// box_exit: where the ray leaves the box [lo, hi].
fn box_exit(o: vec3<f32>, d: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> f32 {
    let x = axis_slab(o.x, d.x, lo.x, hi.x);
    let y = axis_slab(o.y, d.y, lo.y, hi.y);
    let z = axis_slab(o.z, d.z, lo.z, hi.z);
    return min(x.y, min(y.y, z.y));
}

// ConeTracer::skip: past the coarsest empty voxel around the element (t itself when every level
// down to the element's is occupied there). Emptiness only grows with the level, so the coarsest
// empty level is bisected: four steps, written out (no loop), cover the 13 levels of the deepest
// octree (MAX_DEPTH 12).
fn skip(cone: Cone, t: f32, r: f32, level: f32) -> f32 {
    let c = cone.origin + cone.dir * (t + r);
    let fine = u32(clamp(floor(level), 0.0, f32(object.depth)));
    var lo = 0u;
    var hi = fine + 1u;
    bisect_empty(c, &lo, &hi);
    bisect_empty(c, &lo, &hi);
    bisect_empty(c, &lo, &hi);
    bisect_empty(c, &lo, &hi);
    if (lo > fine) {
        return t;
    }
    let size = voxel_size(lo);
    let base = floor((c + vec3<f32>(object.half)) / size) * size - vec3<f32>(object.half);
    let exit = box_exit(cone.origin, cone.dir, base, base + vec3<f32>(size));
    return exit - voxel_size(fine) - r;
}

// GPU only: one bisection step of skip (its loop body): the coarsest empty level lies in [lo, hi].
fn bisect_empty(c: vec3<f32>, lo: ptr<function, u32>, hi: ptr<function, u32>) {
    if (*lo >= *hi) {
        return;
    }
    let mid = (*lo + *hi) / 2u;
    if (nearest(c, mid) < 0) {
        *hi = mid;
    } else {
        *lo = mid + 1u;
    }
}

// Where a march is: the next element's distance, the span's end, elements taken.
struct MarchState {
    t: f32,
    t1: f32,
    steps: u32,
}

// One element of a march: the field there, its centre and radius; `sample.found` false where the
// step met no support.
struct Element {
    sample: VoxelSample,
    c: vec3<f32>,
    r: f32,
}

// One step of a march and whether the march has ended.
struct Step {
    e: Element,
    done: bool,
}

// ConeTracer::march, first half: the span inside the octree's cube (an empty span where it misses).
fn march_start(cone: Cone) -> MarchState {
    let span = cube_span(cone.origin, cone.dir, object.half);
    if (span.z == 0.0) {
        return MarchState(1.0, 0.0, 0u);
    }
    return MarchState(span.x, span.y, 0u);
}

// ConeTracer::march, one pass of its loop: the element at the state's distance, or a skip past
// empty space (`sample.found` false); `done` once the span has ended. trace and sun_visibility
// call it once per pass of their loops (its own search for the next element would be a loop
// inside theirs: more of the adapter's loop budget, bindings.wgsl).
fn march_step(cone: Cone, mode: u32, st: ptr<function, MarchState>) -> Step {
    var out: Step;
    out.e.sample.found = false;
    out.done = false;
    if ((*st).t >= (*st).t1) {
        out.done = true;
        return out;
    }
    if ((*st).steps >= MAX_ELEMENTS) {
        note_cut(true);
        out.done = true;
        return out;
    }
    (*st).steps += 1u;
    let t = (*st).t;
    let r = max(cone_radius(cone, t), 1e-9 * object.half);
    let c = cone.origin + cone.dir * (t + r);
    let level = clamp(log2(object.half / r), 0.0, f32(object.depth));
    var s: VoxelSample;
    if (mode == MODE_NEAREST) {
        let lv = u32(floor(level + 0.5));
        let i = nearest(c, lv);
        s.found = i >= 0;
        if (s.found) {
            let d = voxel_at(u32(i));
            let f = orthonormal_pair(d.normal);
            s.distance = -1.0;
            s.normal = d.normal;
            s.height_var = d.height_var;
            s.slope_cov = d.slope_cov;
            s.t1 = f.t1;
            s.t2 = f.t2;
            s.color_mean = d.color_mean;
            s.color_height = d.color_height;
            s.support = 1.0;
            s.occupancy = 1.0;
        }
    } else {
        s = voxel_sample(c, level);
    }
    if (s.found) {
        (*st).t = t + 2.0 * r;
        out.e = Element(s, c, r);
        return out;
    }
    (*st).t = max(skip(cone, t, r, level), t + 2.0 * r);
    return out;
}

// ConeTracer::trace: a pixel's colour (rgb) and covered share (a).
fn trace(cone: Cone, mode: u32) -> vec4<f32> {
    let fr = orthonormal_pair(cone.dir);
    var cover = Coverage(vec2<u32>(0u, 0u), 0.0);
    var color = vec3<f32>(0.0);
    var st = march_start(cone);
    loop {
        let step = march_step(cone, mode, &st);
        if (step.done) {
            break;
        }
        if (!step.e.sample.found) {
            continue;
        }
        let s = step.e.sample;
        let mask = element_mask(s, fr.t1, fr.t2, cone.dir, step.e.r, mode);
        if (mask.x == 0u && mask.y == 0u) {
            continue;
        }
        let weight = coverage_add(&cover, mask, mode);
        let lit = dot(s.normal, -cone.dir) > 0.0 && dot(s.normal, object.light) > 0.0;
        if (weight > 0.0 && lit) {
            var sun = 1.0;
            if (object.shadows != 0u) {
                sun = sun_visibility(step.e.c - s.normal * s.distance, s.normal, step.e.r, mode);
            }
            color += weight * element_radiance(s, -cone.dir, sun);
        }
        if (coverage_full(cover, mode)) {
            break;
        }
    }
    return vec4<f32>(color, coverage_share(cover, mode));
}

// ConeTracer::sun_visibility: the share of a shadow cone from the element's mean plane toward the
// sun that nothing covers; it starts where an element of it clears that plane.
fn sun_visibility(c: vec3<f32>, normal: vec3<f32>, r: f32, mode: u32) -> f32 {
    let light = object.light;
    let cs = max(dot(normal, light), 1.0 / 16.0);
    let start = r * (1.0 + sqrt(max(1.0 - cs * cs, 0.0)) / cs);
    let shadow = Cone(c + light * start, light, r, 0.0, 0.0, 1.0);
    let fr = orthonormal_pair(light);
    var cover = Coverage(vec2<u32>(0u, 0u), 0.0);
    var st = march_start(shadow);
    loop {
        let step = march_step(shadow, mode, &st);
        if (step.done) {
            break;
        }
        if (step.e.sample.found) {
            coverage_add(&cover, element_mask(step.e.sample, fr.t1, fr.t2, light, step.e.r, mode), mode);
            if (coverage_full(cover, mode)) {
                break;
            }
        }
    }
    return 1.0 - coverage_share(cover, mode);
}
