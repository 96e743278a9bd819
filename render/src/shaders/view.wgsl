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
fn view_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) local: u32) {
//#if noise
    fill_wave_cache(local, 64u);
//#endif
    if (gid.x >= view_params.width || gid.y >= view_params.height) {
        return;
    }
    let idx = gid.y * view_params.width + gid.x;
    let centre = vec2<f32>(f32(gid.x) + 0.5, f32(gid.y) + 0.5);
    let wi = view_params.light;
//#if curved
    if (view_params.shape == SHAPE_CYLINDER) {
        if (view_params.mode < MODE_TRUTH) {
            let dx = view_params.right * (2.0 * view_params.tan_half_fov * view_params.aspect / f32(view_params.width));
            let dy = view_params.up * (-2.0 * view_params.tan_half_fov / f32(view_params.height));
            accum[idx] = vec4<f32>(cylinder_pixel(view_params.mode, raw_dir(centre), dx, dy, wi), 1.0);
            return;
        }
    } else if (view_params.mode < MODE_TRUTH) {
//#else
    if (view_params.mode < MODE_TRUTH) {
//#endif
        let fp = plane_footprint(centre);
        var c = vec3<f32>(0.0);
        if (fp.hit) {
            c = analytic_pixel(view_params.mode, view_params.eye, normalize(raw_dir(centre)), wi, fp.cov);
        }
        accum[idx] = vec4<f32>(c, 1.0);
        return;
    }
    // Ground truth, one sample per frame: sample s of the R2 low-discrepancy sequence (fixed-point
    // golden-ratio generalisation), Cranley–Patterson rotated per pixel, mapped through Box–Muller
    // onto the Gaussian pixel filter. Every prefix of the sequence is evenly spread, so progressive
    // images are unbiased at any sample count.
    let s = view_params.frame;
    let r1 = s * 3242174889u + pcg(idx * 2u + 1u);
    let r2 = s * 2447445413u + pcg(idx * 2u + 2u);
    let u1 = (f32(r1 >> 8u) + 0.5) * (1.0 / 16777216.0);
    let u2 = (f32(r2 >> 8u) + 0.5) * (1.0 / 16777216.0);
    let rad = sqrt(-2.0 * log(u1)) * view_params.pixel_sigma;
    let off = vec2<f32>(rad * cos(TAU * u2), rad * sin(TAU * u2));
    let d = normalize(raw_dir(centre + off));
    var c: vec3<f32>;
//#if curved
    if (view_params.shape == SHAPE_CYLINDER) {
        c = cylinder_trace_ray(view_params.eye, d, wi);
    } else {
        c = trace_ray(view_params.eye, d, wi);
    }
//#else
    c = trace_ray(view_params.eye, d, wi);
//#endif
    let prev = select(vec4<f32>(0.0), accum[idx], s > 0u);
    accum[idx] = prev + vec4<f32>(c, 1.0);
    let y = dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
    let prev2 = select(vec4<f32>(0.0), moments[idx], s > 0u);
    moments[idx] = prev2 + vec4<f32>(c * c, y * y);
}
