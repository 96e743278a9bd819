// One view of the plane or cylinder scene: a compute pass over the image. Needs the special,
// material and view-parameter units (and scene/cylinder.wgsl for curved scenes: its branches are
// `//#if curved`, see specialize.rs). Modes (MODE_*): naive MIP, view-independent filtering,
// filtered, ground truth (progressive: one low-discrepancy, Gaussian-filtered sub-pixel ray per
// pixel per frame; alpha counts samples).

@group(0) @binding(2) var<storage, read_write> accum: array<vec4<f32>>;
// Ground truth's per-pixel sums of squared samples (r², g², b², Y² with Y the Rec. 709 luminance),
// beside accum's sums, so the truth's own Monte Carlo noise is known per pixel
// (render/src/truth_noise.rs). Written by ground truth only.
@group(0) @binding(4) var<storage, read_write> moments: array<vec4<f32>>;
// An adaptive ground truth's rays (Renderer::draw_planned), in two passes per chunk. Phase 0: entry
// i = (pixel, sample) of the first `list_len` is one ray, its colour written to scratch[i]. Phase 1:
// run i = order[runs_at + i] = (first entry, count) of one pixel, whose entries are consecutive and
// in sample order, adds them to the pixel's sums (in the order a progressive accumulation adds them).
// Unread when list_len is 0.
@group(0) @binding(5) var<storage, read> order: array<vec2<u32>>;
@group(0) @binding(6) var<storage, read_write> scratch: array<vec4<f32>>;
// Element 0: the pixels (analytic modes) or rays (ground truth) whose march had a loop cut
// (bindings.wgsl `loop_cut`) since the target started (ViewTarget::cut_count).
@group(0) @binding(7) var<storage, read_write> cut_count: array<atomic<u32>>;

// Ground truth's work per pixel: the sum over its rays of each ray's `work` (bindings.wgsl: eight
// waves summed per unit, plus one per march step), so a pixel's cost per ray is known
// (ViewTarget::read_work; cost-aware adaptive plans). Cleared with the sums.
@group(0) @binding(8) var<storage, read_write> work_sum: array<atomic<u32>>;

// GPU only: count this invocation's pixel or ray when a loop of it was cut.
fn count_cut() {
    if (loop_cut) {
        atomicAdd(&cut_count[0], 1u);
    }
}

const PIXEL_SIGMA_DEFAULT: f32 = 0.5;

// Camera::raw_dir (unnormalised), pixel coordinates with centres at +0.5.
fn raw_dir(p: vec2<f32>) -> vec3<f32> {
    let nx = (p.x / f32(view_params.width)) * 2.0 - 1.0;
    let ny = 1.0 - (p.y / f32(view_params.height)) * 2.0;
    return view_params.forward + view_params.right * (nx * view_params.tan_half_fov * view_params.aspect) + view_params.up * (ny * view_params.tan_half_fov);
}

// Camera::plane_footprint: (x0.x, x0.y) and covariance (xx, yy, xy); w = 0 marks the sky.
struct PlaneFootprint {
    x0: vec2<f32>,
    cov: vec3<f32>,
    hit: bool,
}

fn plane_footprint(p: vec2<f32>) -> PlaneFootprint {
    var r: PlaneFootprint;
    let e = view_params.eye;
    let d = raw_dir(p);
    r.hit = d.z < 0.0;
    if (!r.hit) {
        return r;
    }
    let dx = view_params.right * (2.0 * view_params.tan_half_fov * view_params.aspect / f32(view_params.width));
    let dy = view_params.up * (-2.0 * view_params.tan_half_fov / f32(view_params.height));
    let hit = e - d * (e.z / d.z);
    let jx = -(dx * d.z - d * dx.z) * (e.z / (d.z * d.z));
    let jy = -(dy * d.z - d * dy.z) * (e.z / (d.z * d.z));
    let s2 = view_params.pixel_sigma * view_params.pixel_sigma;
    r.x0 = hit.xy;
    r.cov = vec3<f32>(jx.x * jx.x + jy.x * jy.x, jx.y * jx.y + jy.y * jy.y, jx.x * jx.y + jy.x * jy.y) * s2;
    return r;
}

// PCG hash (Jarzynski and Olano 2020).
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}


@compute @workgroup_size(8, 8)
fn view_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let listed = view_params.list_len > 0u;
    if (listed && view_params.phase == 1u) {
        sum_runs(gid.y * view_params.width + gid.x);
        return;
    }
    // The ray this invocation traces: (pixel, sample, slot, 1), or w = 0 for none. One call of
    // truth_sample below serves every path (each call site inlines the whole march).
    var ray = vec4<u32>(0u);
    if (listed) {
        ray = listed_ray(gid.xy);
    } else {
        if (gid.x >= view_params.width || gid.y >= view_params.height) {
            return;
        }
        let idx = gid.y * view_params.width + gid.x;
        if (view_params.mode < MODE_TRUTH) {
            analytic_view(idx);
            return;
        }
        ray = vec4<u32>(idx, view_params.frame, idx, 1u);
    }
    if (ray.w == 0u) {
        return;
    }
    let c = truth_sample(ray.x, ray.y, view_params.light);
    note_budget(budget_two());
    let slot = ray.z;
    if (view_params.phase == 0u) {
        atomicAdd(&work_sum[ray.x], work);
    }
    if (!listed) {
        // Ground truth, one ray per frame. A cut ray is traced again alone (phase 3) instead of
        // added here.
        if (view_params.retry_cut == 1u) {
            scratch[slot] = vec4<f32>(0.0, 0.0, 0.0, select(0.0, 1.0, loop_cut));
            if (loop_cut) {
                return;
            }
        }
        add_ray(ray.x, c);
    } else if (view_params.phase == 0u) {
        let retry = loop_cut && view_params.retry_cut == 1u;
        scratch[slot] = vec4<f32>(c, select(0.0, 1.0, retry));
        if (retry) {
            return;
        }
    } else if (view_params.phase == 2u) {
        scratch[slot] = vec4<f32>(c, 0.0);
    } else {
        add_ray(ray.x, c);
        scratch[slot] = vec4<f32>(0.0);
    }
    // Still cut (after a retry, or with none): counted as unreliable.
    count_cut();
}

// An analytic mode's pixel idx.
fn analytic_view(idx: u32) {
    let centre = pixel_centre(idx);
    let wi = view_params.light;
//#if curved
    if (view_params.shape == SHAPE_CYLINDER) {
        let dx = view_params.right * (2.0 * view_params.tan_half_fov * view_params.aspect / f32(view_params.width));
        let dy = view_params.up * (-2.0 * view_params.tan_half_fov / f32(view_params.height));
        accum[idx] = vec4<f32>(cylinder_pixel(view_params.mode, raw_dir(centre), dx, dy, wi), 1.0);
        note_budget(budget_two());
        count_cut();
        return;
    }
//#endif
    let fp = plane_footprint(centre);
    var c = vec3<f32>(0.0);
    if (fp.hit) {
        c = analytic_pixel(view_params.mode, view_params.eye, normalize(raw_dir(centre)), wi, fp.cov);
    }
    accum[idx] = vec4<f32>(c, 1.0);
    note_budget(budget_two());
    count_cut();
}

// 2, for note_budget, as a value whose bound the compiler cannot see (a width is below 2³¹): a
// loop with a small known bound is unrolled, and spends no budget.
fn budget_two() -> u32 {
    return 2u + (view_params.width >> 31u) * 65535u;
}

// The centre of pixel idx, in pixels.
fn pixel_centre(idx: u32) -> vec2<f32> {
    return vec2<f32>(f32(idx % view_params.width) + 0.5, f32(idx / view_params.width) + 0.5);
}

// Add one ground-truth ray's colour to pixel idx's sums (frame 0 starts them afresh).
fn add_ray(idx: u32, c: vec3<f32>) {
    let fresh = view_params.frame == 0u;
    let y = dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
    accum[idx] = select(accum[idx], vec4<f32>(0.0), fresh) + vec4<f32>(c, 1.0);
    moments[idx] = select(moments[idx], vec4<f32>(0.0), fresh) + vec4<f32>(c * c, y * y);
}

// One ground-truth ray of pixel idx: sample s of the R2 low-discrepancy sequence (fixed-point
// golden-ratio generalisation), Cranley–Patterson rotated per pixel, mapped through Box–Muller
// onto the Gaussian pixel filter. Every prefix of the sequence is evenly spread, so progressive
// images are unbiased at any sample count.
fn truth_sample(idx: u32, s: u32, wi: vec3<f32>) -> vec3<f32> {
    let r1 = s * 3242174889u + pcg(idx * 2u + 1u);
    let r2 = s * 2447445413u + pcg(idx * 2u + 2u);
    let u1 = (f32(r1 >> 8u) + 0.5) * (1.0 / 16777216.0);
    let u2 = (f32(r2 >> 8u) + 0.5) * (1.0 / 16777216.0);
    let rad = sqrt(-2.0 * log(u1)) * view_params.pixel_sigma;
    let off = vec2<f32>(rad * cos(TAU * u2), rad * sin(TAU * u2));
    let d = normalize(raw_dir(pixel_centre(idx) + off));
//#if curved
    if (view_params.shape == SHAPE_CYLINDER) {
        return cylinder_trace_ray(view_params.eye, d, wi);
    }
//#endif
    return trace_ray(view_params.eye, d, wi);
}

// The listed passes (Renderer::draw_planned, and the retry of Renderer::draw): phase 0 traces
// entry i into scratch[i]; phase 1 adds run i's rays to its pixel (sum_runs); phases 2 (entries)
// and 3 (pixels) trace again the rays phase 0 or a frame marked cut (scratch w = 1), one per SIMD
// batch of eight lanes (`gid.x` a multiple of 8: the other seven lanes idle), so no other lane's
// loops count against the adapter's loop limit. Returns (pixel, sample, slot, 1), or w = 0 when
// this invocation has no ray.
fn listed_ray(gid: vec2<u32>) -> vec4<u32> {
    if (view_params.phase >= 2u) {
        let k = gid.y * ((view_params.width + 7u) / 8u) + gid.x / 8u;
        if (gid.x % 8u != 0u || k >= view_params.list_len || scratch[k].w == 0.0) {
            return vec4<u32>(0u);
        }
        if (view_params.phase == 2u) {
            return vec4<u32>(order[k].x, order[k].y, k, 1u);
        }
        return vec4<u32>(k, view_params.frame, k, 1u);
    }
    let i = gid.y * view_params.width + gid.x;
    if (i >= view_params.list_len) {
        return vec4<u32>(0u);
    }
    return vec4<u32>(order[i].x, order[i].y, i, 1u);
}

// Phase 1: add run i's rays (consecutive entries of one pixel, in sample order) to the pixel's
// sums, in the order a progressive accumulation adds them (frame 0 starts the pixel afresh).
fn sum_runs(i: u32) {
    if (i >= view_params.list_len) {
        return;
    }
    let run = order[view_params.runs_at + i];
    let idx = order[run.x].x;
    let fresh = view_params.frame == 0u;
    var acc = select(accum[idx], vec4<f32>(0.0), fresh);
    var acc2 = select(moments[idx], vec4<f32>(0.0), fresh);
    for (var j = 0u; j < run.y; j = j + 1u) {
        let c = scratch[run.x + j].xyz;
        acc = acc + vec4<f32>(c, 1.0);
        let y = dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
        acc2 = acc2 + vec4<f32>(c * c, y * y);
    }
    accum[idx] = acc;
    moments[idx] = acc2;
}
