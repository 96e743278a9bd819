// Mirror of `core/src/eval/masking/transfer_masking_table.rs` and `transfer_moments.rs`: a transfer-curve
// material's masking conditioned on the driver's value and slope (#17), as the Gaussian moments
// of its columns, at `base` in the material's data: σ_f, the driver's global gradient covariance
// (xx, xy, yy), then TABLE_AZIMUTHS × TABLE_NUS moment blocks (ν fastest) of
// TRANSFER_VALUE_NODES × TRANSFER_LENGTH_NODES × (E[g], E[a g], E[a² g]). Reads are on demand: a
// ray keeps its four (azimuth, ν) blocks and their weights instead of core's blended block.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

//#if transfer_mixture
// One ray against the table (core's RayMasking): the moment blocks (a0 n0, a0 n1, a1 n0, a1 n1)
// it blends, their weights, its ν and the projection of the footprint's whitened driver gradient
// on its azimuth (σ units of the table).
struct TransferRay {
    entries: vec4<u32>,
    weights: vec4<f32>,
    nu: f32,
    projection: vec2<f32>,
}

// TransferRays: the footprint's view and light against the table. `lit` is core's `i.is_some()`.
struct TransferRays {
    chol: vec3<f32>,
    o: TransferRay,
    i: TransferRay,
    lit: bool,
    k: f32,
    mean: f32,
    std_dev: f32,
    far: f32,
}

// The eye's and the joint term's weights (core's `[Option<GaussianWeight>; 2]`).
struct VisibilityWeights {
    eye: GaussianWeight,
    joint: GaussianWeight,
}

// node_cell: the nodes i, i + 1 of an evenly spaced axis around x and the weight of i + 1,
// clamped to the ends, as (i, weight).
fn node_cell(x: f32, first: f32, step: f32, n: u32) -> vec2<f32> {
    let u = clamp((x - first) / step, 0.0, f32(n - 1u));
    let i = min(u32(u), n - 2u);
    return vec2<f32>(f32(i), u - f32(i));
}

// far_weight: (σ_footprint/σ_global)² in [0, 1]; 0 without a global spread.
fn far_weight(footprint_std: f32, global_std: f32) -> f32 {
    if (!(global_std > 0.0)) {
        return 0.0;
    }
    let r = footprint_std / global_std;
    return clamp(r * r, 0.0, 1.0);
}

// TransferMaskingTable::slope_sigma: the driver's global slope deviation along the unit `dir`.
fn transfer_slope_sigma(base: u32, dir: vec2<f32>) -> f32 {
    let xx = datum(base + 1u);
    let xy = datum(base + 2u);
    let yy = datum(base + 3u);
    return sqrt(max(dir.x * dir.x * xx + 2.0 * dir.x * dir.y * xy + dir.y * dir.y * yy, 0.0));
}

// transfer_ray: TransferRays::new's ray of direction w (in the mean normal's frame), `chol` the
// footprint's unresolved driver-gradient Cholesky factor (l11, l21, l22).
fn transfer_ray(base: u32, w: vec3<f32>, chol: vec3<f32>, sigma_h: f32) -> TransferRay {
    let r = length(w.xy);
    var dir = vec2<f32>(1.0, 0.0);
    if (r > 0.0) {
        dir = w.xy / r;
    }
    let st = max(transfer_slope_sigma(base, dir), 1e-30);
    var ray: TransferRay;
    ray.nu = 3.0e38;
    if (r > 0.0) {
        ray.nu = max(w.z, 0.0) / r / (max(sigma_h, 1e-30) * st);
    }
    ray.projection = vec2<f32>(dir.x * chol.x + dir.y * chol.y, dir.y * chol.z) / st;
    // The azimuth over [0, π) and ln ν, as slope_masking_table's.
    let ca = azimuth_coordinate(dir);
    let a0 = u32(ca.x);
    let fa = ca.y;
    let a1 = (a0 + 1u) % TABLE_AZIMUTHS;
    let cn = nu_coordinate(ray.nu);
    let n0 = u32(cn.x);
    let fnu = cn.y;
    let e = base + 4u;
    ray.entries = vec4<u32>(
        e + (a0 * TABLE_NUS + n0) * TRANSFER_MOMENT_ENTRY,
        e + (a0 * TABLE_NUS + n0 + 1u) * TRANSFER_MOMENT_ENTRY,
        e + (a1 * TABLE_NUS + n0) * TRANSFER_MOMENT_ENTRY,
        e + (a1 * TABLE_NUS + n0 + 1u) * TRANSFER_MOMENT_ENTRY,
    );
    ray.weights = vec4<f32>((1.0 - fa) * (1.0 - fnu), (1.0 - fa) * fnu, fa * (1.0 - fnu), fa * fnu);
    return ray;
}

// TransferRays::new: for the footprint's driver d, wo and wi in the frame of its mean normal.
fn transfer_rays_new(
    base: u32,
    d: FilteredDriver,
    wo: vec3<f32>,
    wi: vec3<f32>,
    sun_lit: bool,
    sigma_h: f32,
    correlation: u32,
) -> TransferRays {
    var rays: TransferRays;
    rays.chol = cholesky(d.gradient_cov);
    rays.o = transfer_ray(base, wo, rays.chol, sigma_h);
    rays.lit = sun_lit;
    if (sun_lit) {
        rays.i = transfer_ray(base, wi, rays.chol, sigma_h);
    }
    rays.k = 1.0;
    if (correlation == CORRELATION_HEIGHT_DIRECTION) {
        rays.k = azimuth_factor(azimuth_difference(wo, wi));
    }
    let sf = max(datum(base), 1e-30);
    rays.mean = d.mean / sf;
    rays.std_dev = d.std_dev / sf;
    rays.far = far_weight(d.std_dev, datum(base));
    // A ray flatter than the table's first ν node is outside it: Smith's bins take it.
    if (rays.o.nu < TABLE_NU_MIN || (sun_lit && rays.i.nu < TABLE_NU_MIN)) {
        rays.far = 0.0;
    }
    return rays;
}

// length_cell: the length nodes k, k + 1 around len and the weight of k + 1, clamped to [0, 1].
fn length_cell(len: f32) -> vec2<f32> {
    let step = 1.0 / f32(TRANSFER_LENGTH_NODES - 1u);
    let u = clamp(len / step, 0.0, f32(TRANSFER_LENGTH_NODES - 1u));
    let k = min(u32(u), TRANSFER_LENGTH_NODES - 2u);
    return vec2<f32>(f32(k), u - f32(k));
}

// moments_at: (E[g], E[a g], E[a² g]) of the ray at driver value x (global σ) and projection
// length len, its four blocks blended, bilinear in the value and the length.
fn moments_at(ray: TransferRay, x: f32, len: f32) -> vec3<f32> {
    let ci = node_cell(x, -TRANSFER_VALUE_DEPTH, TRANSFER_VALUE_STEP, TRANSFER_VALUE_NODES);
    let ck = length_cell(len);
    let i = u32(ci.x);
    let k = u32(ck.x);
    // The four blocks' corners one iteration per (value, length) corner, in core's order (every
    // iteration counts against the software adapter's per-invocation loop budget, bindings.wgsl).
    var m = vec3<f32>(0.0);
    for (var c = 0u; c < 16u; c = c + 4u) {
        m = add_corner(m, ray, c, ci.y, ck.y, i, k);
        m = add_corner(m, ray, c + 1u, ci.y, ck.y, i, k);
        m = add_corner(m, ray, c + 2u, ci.y, ck.y, i, k);
        m = add_corner(m, ray, c + 3u, ci.y, ck.y, i, k);
    }
    return m;
}

// moments_at's corner c (block c & 3, value step bit 2, length step bit 3) added to m.
fn add_corner(m: vec3<f32>, ray: TransferRay, c: u32, fi: f32, fk: f32, i: u32, k: u32) -> vec3<f32> {
    let corner = c & 3u;
    let di = (c >> 2u) & 1u;
    let dk = (c >> 3u) & 1u;
    let w = ray.weights[corner] * select(1.0 - fi, fi, di == 1u) * select(1.0 - fk, fk, dk == 1u);
    if (w != 0.0) {
        let o = ray.entries[corner] + ((i + di) * TRANSFER_LENGTH_NODES + k + dk) * 3u;
        return m + w * vec3<f32>(datum(o), datum(o + 1u), datum(o + 2u));
    }
    return m;
}

// TransferRays::ray_weight: the conditioned G1 of the eye's ray (the light's when `light`) at
// driver value x as a Gaussian function of the whitened driver slopes, from the table's moments;
// ok = false with the sun down or nothing visible.
fn ray_weight(rays: TransferRays, x: f32, light: bool) -> GaussianWeight {
    var r = rays.o;
    if (light) {
        if (!rays.lit) {
            return GaussianWeight(0.0, vec3<f32>(0.0), vec2<f32>(0.0), false);
        }
        r = rays.i;
    }
    let len = length(r.projection);
    var e = vec2<f32>(1.0, 0.0);
    if (len > 1e-12) {
        e = r.projection / len;
    }
    let m = moments_at(r, x, len);
    return gaussian_weight_along(e, m.x, m.y, m.z);
}

// TransferRays::visibility_weights: the eye's G1 and the joint term lo·hi^k as Gaussian
// functions of the whitened driver slopes; where the product has no Gaussian, the masses
// multiplied with the more masked one's tilt.
fn visibility_weights(rays: TransferRays, x: f32) -> VisibilityWeights {
    var out: VisibilityWeights;
    out.eye = ray_weight(rays, x, false);
    out.joint = GaussianWeight(0.0, vec3<f32>(0.0), vec2<f32>(0.0), false);
    if (!(out.eye.ok && rays.lit)) {
        return out;
    }
    let i = ray_weight(rays, x, true);
    if (!i.ok) {
        return out;
    }
    let to = gaussian_weight_tilted(out.eye);
    let ti = gaussian_weight_tilted(i);
    let mo = select(0.0, to.mass, to.ok);
    let mi = select(0.0, ti.mass, ti.ok);
    var lo = out.eye;
    var hi = i;
    var m_hi = mi;
    if (!(mo <= mi)) {
        lo = i;
        hi = out.eye;
        m_hi = mo;
    }
    let joint = gaussian_weight_mul(lo, gaussian_weight_powf(hi, rays.k));
    if (gaussian_weight_tilted(joint).ok) {
        out.joint = joint;
    } else {
        out.joint = lo;
        out.joint.log_scale = lo.log_scale + rays.k * log(max(m_hi, 1e-30));
    }
    return out;
}
//#endif
