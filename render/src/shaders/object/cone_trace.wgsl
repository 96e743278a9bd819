// Mirror of `core/src/object/cone_trace.rs` [HN12 Alg. 1]: a cone marched through the voxel field
// in elements as long as they are wide, the level from the cone's radius, each element's sub-pixel
// mask combined A-buffer style (or alpha blended [CNLE09], or nearest voxels as opaque blocks),
// shadow cones toward the sun. Core's march visits elements through a closure; here `march_next`
// returns them one at a time.

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

// ConeTracer::element_mask: the element's mask in the cone's frame (e1, e2, d); nearest voxels are
// opaque.
fn element_mask(s: VoxelSample, e1: vec3<f32>, e2: vec3<f32>, d: vec3<f32>, r: f32, mode: u32) -> vec2<u32> {
    if (mode == MODE_NEAREST) {
        return vec2<u32>(0xffffffffu, 0xffffffffu);
    }
    let n = vec3<f32>(dot(s.normal, e1), dot(s.normal, e2), dot(s.normal, d));
    let p = element_mask_params(r, r, n, s.distance);
    return mask_lookup(p.x, p.y);
}

// cube_span: the ray's span (t0, t1) inside the cube [−half, half]³; z = 1 when it meets it.
fn cube_span(o: vec3<f32>, d: vec3<f32>, half: f32) -> vec3<f32> {
    var t0 = 0.0;
    var t1 = 3.0e38;
    for (var a = 0u; a < 3u; a = a + 1u) {
        if (abs(d[a]) < 1e-30) {
            if (abs(o[a]) > half) {
                return vec3<f32>(0.0);
            }
            continue;
        }
        let u = (-half - o[a]) / d[a];
        let v = (half - o[a]) / d[a];
        t0 = max(t0, min(u, v));
        t1 = min(t1, max(u, v));
    }
    return vec3<f32>(t0, t1, select(0.0, 1.0, t1 > t0));
}

// box_exit: where the ray leaves the box [lo, hi].
fn box_exit(o: vec3<f32>, d: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> f32 {
    var t1 = 3.0e38;
    for (var a = 0u; a < 3u; a = a + 1u) {
        if (abs(d[a]) > 1e-30) {
            let u = (lo[a] - o[a]) / d[a];
            let v = (hi[a] - o[a]) / d[a];
            t1 = min(t1, max(u, v));
        }
    }
    return t1;
}

// ConeTracer::skip: past the largest empty voxel around the element (t itself when every level
// down to the element's is occupied there).
fn skip(cone: Cone, t: f32, r: f32, level: f32) -> f32 {
    let c = cone.origin + cone.dir * (t + r);
    let fine = u32(clamp(floor(level), 0.0, f32(object.depth)));
    var empty = fine + 1u;
    for (var l = 0u; l <= fine; l = l + 1u) {
        if (nearest(c, l) < 0) {
            empty = l;
            break;
        }
    }
    if (empty > fine) {
        return t;
    }
    let size = voxel_size(empty);
    let lo = floor((c + vec3<f32>(object.half)) / size) * size - vec3<f32>(object.half);
    let exit = box_exit(cone.origin, cone.dir, lo, lo + vec3<f32>(size));
    return exit - voxel_size(fine) - r;
}

// Where a march is: the next element's distance, the span's end, elements taken.
struct MarchState {
    t: f32,
    t1: f32,
    steps: u32,
}

// One element of a march: the field there, its centre and radius; `sample.found` false at the end.
struct Element {
    sample: VoxelSample,
    c: vec3<f32>,
    r: f32,
}

// ConeTracer::march, first half: the span inside the octree's cube (an empty span where it misses).
fn march_start(cone: Cone) -> MarchState {
    let span = cube_span(cone.origin, cone.dir, object.half);
    if (span.z == 0.0) {
        return MarchState(1.0, 0.0, 0u);
    }
    return MarchState(span.x, span.y, 0u);
}

// ConeTracer::march, its loop: the next element that holds a sample (empty space skipped).
fn march_next(cone: Cone, mode: u32, st: ptr<function, MarchState>) -> Element {
    var e: Element;
    e.sample.found = false;
    loop {
        if ((*st).t >= (*st).t1) {
            return e;
        }
        if ((*st).steps >= MAX_ELEMENTS) {
            note_cut(true);
            return e;
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
            }
        } else {
            s = voxel_sample(c, level);
        }
        if (s.found) {
            (*st).t = t + 2.0 * r;
            return Element(s, c, r);
        }
        (*st).t = max(skip(cone, t, r, level), t + 2.0 * r);
    }
    return e;
}

// ConeTracer::trace: a pixel's colour (rgb) and covered share (a).
fn trace(cone: Cone, mode: u32) -> vec4<f32> {
    let fr = orthonormal_pair(cone.dir);
    var cover = Coverage(vec2<u32>(0u, 0u), 0.0);
    var color = vec3<f32>(0.0);
    var st = march_start(cone);
    loop {
        let e = march_next(cone, mode, &st);
        if (!e.sample.found) {
            break;
        }
        let s = e.sample;
        let mask = element_mask(s, fr.t1, fr.t2, cone.dir, e.r, mode);
        if (mask.x == 0u && mask.y == 0u) {
            continue;
        }
        let weight = coverage_add(&cover, mask, mode);
        let lit = dot(s.normal, -cone.dir) > 0.0 && dot(s.normal, object.light) > 0.0;
        if (weight > 0.0 && lit) {
            var sun = 1.0;
            if (object.shadows != 0u) {
                sun = sun_visibility(e.c - s.normal * s.distance, s.normal, e.r, mode);
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
        let e = march_next(shadow, mode, &st);
        if (!e.sample.found) {
            break;
        }
        coverage_add(&cover, element_mask(e.sample, fr.t1, fr.t2, light, e.r, mode), mode);
        if (coverage_full(cover, mode)) {
            break;
        }
    }
    return 1.0 - coverage_share(cover, mode);
}
