// Mirror of `core/src/object/voxel_field.rs` [HN12 Sec. 5.3]: the octree's descriptors read as a
// field, trilinear within a level over the occupied voxels (each mean plane blended as a distance
// function, slope covariances as world tensors), linear between levels (quadrilinear). The voxels
// are found through an open-addressing hash of (level, x, y, z) (`object_slots`, built by
// `render/src/object/voxel_store.rs`), each 32 bytes (`object_voxels`, two vec4<u32>).

// VoxelSample: the field at a point and level; `found` false where no voxel is near.
struct VoxelSample {
    distance: f32,
    normal: vec3<f32>,
    height_var: f32,
    // The slope covariance (xx, yy, xy) in the frame (t1, t2) of `normal`.
    slope_cov: vec3<f32>,
    t1: vec3<f32>,
    t2: vec3<f32>,
    color_mean: vec3<f32>,
    color_height: vec3<f32>,
    support: f32,
    occupancy: f32,
    found: bool,
}

// One voxel's descriptor as stored: the mean plane's offset from the voxel's centre along its
// normal, the normal, σ_h², the slope covariance in the normal's `orthonormal_pair` frame, ā, a_s.
struct Voxel {
    offset: f32,
    normal: vec3<f32>,
    height_var: f32,
    slope_cov: vec3<f32>,
    color_mean: vec3<f32>,
    color_height: vec3<f32>,
    occupancy: f32,
}

// An orthonormal tangent pair of the unit vector n.
struct Frame {
    t1: vec3<f32>,
    t2: vec3<f32>,
}

// GPU only: glam's `DVec3::any_orthonormal_pair` (Duff et al. 2017), sign(0) = +1 as Rust's signum.
fn orthonormal_pair(n: vec3<f32>) -> Frame {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    return Frame(
        vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        vec3<f32>(b, s + n.y * n.y * a, -n.y),
    );
}

// GPU only: unpacks voxel i (voxel_store.rs `encode_voxel`: offset as f32, the rest as f16 pairs).
fn voxel_at(i: u32) -> Voxel {
    let a = object_voxels[2u * i];
    let b = object_voxels[2u * i + 1u];
    let nxy = unpack2x16float(a.y);
    let nz_hv = unpack2x16float(a.z);
    let sxx_syy = unpack2x16float(a.w);
    let sxy_r = unpack2x16float(b.x);
    let gb = unpack2x16float(b.y);
    let hr_hg = unpack2x16float(b.z);
    let hb_occ = unpack2x16float(b.w);
    return Voxel(
        bitcast<f32>(a.x),
        normalize(vec3<f32>(nxy, nz_hv.x)),
        nz_hv.y,
        vec3<f32>(sxx_syy, sxy_r.x),
        vec3<f32>(sxy_r.y, gb),
        vec3<f32>(hr_hg, hb_occ.x),
        hb_occ.y,
    );
}

// GPU only: the hash slot of a key (voxel_store.rs `slot_hash`, the same integer steps).
fn slot_hash(k: vec2<u32>) -> u32 {
    var h = (k.x * 0x9E3779B1u) ^ k.y;
    h = h ^ (h >> 15u);
    h = h * 0x85EBCA77u;
    return h ^ (h >> 13u);
}

// GPU only: what slot s says of key k: the voxel's index, −1 when the slot is free (k is not in
// the table), −2 when it holds another key (probe on).
fn probe_slot(k: vec2<u32>, s: u32) -> i32 {
    let e = object_slots[s];
    if (e.x == k.x && e.y == k.y) {
        return i32(e.z);
    }
    return select(-2, -1, e.y == 0u);
}

// GPU only: the index of voxel `c` of `level`, or −1 where it is empty: linear probing over at
// most MAX_PROBES slots, written out with no loop. The table is built so that every key lies within
// MAX_PROBES of its hash (voxel_store.rs), so a key not met by then is not in it. A loop here, even
// one entered on a few lookups in a thousand, spent the adapter's loop budget (bindings.wgsl): a
// torus filling the view had 1% of its pixels cut.
fn find_voxel(level: u32, c: vec3<u32>) -> i32 {
    let k = vec2<u32>(c.x | (c.y << 16u), c.z | (level << 16u) | 0x80000000u);
    let m = object.slot_mask;
    let h = slot_hash(k) & m;
    var r = probe_slot(k, h);
    if (r != -2) {
        return r;
    }
    r = probe_slot(k, (h + 1u) & m);
    if (r != -2) {
        return r;
    }
    r = probe_slot(k, (h + 2u) & m);
    if (r != -2) {
        return r;
    }
    r = probe_slot(k, (h + 3u) & m);
    if (r != -2) {
        return r;
    }
    r = probe_slot(k, (h + 4u) & m);
    if (r != -2) {
        return r;
    }
    r = probe_slot(k, (h + 5u) & m);
    if (r != -2) {
        return r;
    }
    r = probe_slot(k, (h + 6u) & m);
    if (r != -2) {
        return r;
    }
    return max(probe_slot(k, (h + 7u) & m), -1);
}

// VoxelField::voxel_size.
fn voxel_size(level: u32) -> f32 {
    return 2.0 * object.half / f32(1u << level);
}

// GPU only: the centre of voxel `c` of `level` (core keeps the centroid itself).
fn voxel_centre(level: u32, c: vec3<u32>) -> vec3<f32> {
    return (vec3<f32>(c) + 0.5) * voxel_size(level) - vec3<f32>(object.half);
}

// VoxelField::nearest: the voxel of `level` holding x (−1: none).
fn nearest(x: vec3<f32>, level_in: u32) -> i32 {
    let level = min(level_in, object.depth);
    let cells = f32(1u << level);
    let q = (x + vec3<f32>(object.half)) / (2.0 * object.half) * cells;
    if (!(min(q.x, min(q.y, q.z)) >= 0.0 && max(q.x, max(q.y, q.z)) < cells)) {
        return -1;
    }
    return find_voxel(level, vec3<u32>(q));
}

// tensor: the slope covariance c in the frame (t1, t2) as a world tensor.
fn tensor(t1: vec3<f32>, t2: vec3<f32>, c: vec3<f32>) -> mat3x3<f32> {
    let a = mat3x3<f32>(t1 * t1.x, t1 * t1.y, t1 * t1.z);
    let b = mat3x3<f32>(t2 * t2.x, t2 * t2.y, t2 * t2.z);
    let m = mat3x3<f32>(t1 * t2.x, t1 * t2.y, t1 * t2.z);
    return a * c.x + b * c.y + (m + transpose(m)) * c.z;
}

// in_frame: a world tensor's slope covariance in the frame (t1, t2).
fn in_frame(t1: vec3<f32>, t2: vec3<f32>, s: mat3x3<f32>) -> vec3<f32> {
    return vec3<f32>(max(dot(t1, s * t1), 0.0), max(dot(t2, s * t2), 0.0), dot(t1, s * t2));
}

// sample_level's running sums over the corners.
struct FieldSum {
    w: f32,
    dist: f32,
    normal: vec3<f32>,
    hv: f32,
    slopes: mat3x3<f32>,
    am: vec3<f32>,
    ah: vec3<f32>,
    occ: f32,
}

// GPU only: one corner `off` of sample_level (its loop body, written out eight times).
fn voxel_corner(acc: ptr<function, FieldSum>, x: vec3<f32>, level: u32, base: vec3<f32>, frac: vec3<f32>, off: vec3<u32>) {
    let idx = vec3<i32>(base) + vec3<i32>(off);
    let cells = i32(1u << level);
    if (any(idx < vec3<i32>(0)) || any(idx >= vec3<i32>(cells))) {
        return;
    }
    let i = find_voxel(level, vec3<u32>(idx));
    if (i < 0) {
        return;
    }
    let wv = select(vec3<f32>(1.0) - frac, frac, off == vec3<u32>(1u));
    let w = wv.x * wv.y * wv.z;
    if (w <= 0.0) {
        return;
    }
    let d = voxel_at(u32(i));
    let f = orthonormal_pair(d.normal);
    (*acc).w += w;
    (*acc).dist += w * (dot(x - voxel_centre(level, vec3<u32>(idx)), d.normal) + d.offset);
    (*acc).normal += w * d.normal;
    (*acc).hv += w * d.height_var;
    (*acc).slopes += tensor(f.t1, f.t2, d.slope_cov) * w;
    (*acc).am += w * d.color_mean;
    (*acc).ah += w * d.color_height;
    (*acc).occ += w * d.occupancy;
}

// VoxelField::sample_level: the trilinear blend of the occupied voxels around x at one level.
fn sample_level(x: vec3<f32>, level_in: u32) -> VoxelSample {
    var out: VoxelSample;
    out.found = false;
    let level = min(level_in, object.depth);
    let cells = f32(1u << level);
    let q = (x + vec3<f32>(object.half)) / (2.0 * object.half) * cells - vec3<f32>(0.5);
    let base = floor(q);
    let frac = q - base;
    var acc = FieldSum(0.0, 0.0, vec3<f32>(0.0), 0.0, mat3x3<f32>(), vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    voxel_corner(&acc, x, level, base, frac, vec3<u32>(0u, 0u, 0u));
    voxel_corner(&acc, x, level, base, frac, vec3<u32>(1u, 0u, 0u));
    voxel_corner(&acc, x, level, base, frac, vec3<u32>(0u, 1u, 0u));
    voxel_corner(&acc, x, level, base, frac, vec3<u32>(1u, 1u, 0u));
    voxel_corner(&acc, x, level, base, frac, vec3<u32>(0u, 0u, 1u));
    voxel_corner(&acc, x, level, base, frac, vec3<u32>(1u, 0u, 1u));
    voxel_corner(&acc, x, level, base, frac, vec3<u32>(0u, 1u, 1u));
    voxel_corner(&acc, x, level, base, frac, vec3<u32>(1u, 1u, 1u));
    if (!(acc.w > 1e-12)) {
        return out;
    }
    let inv = 1.0 / acc.w;
    let nl = length(acc.normal * inv);
    if (!(nl > 1e-20)) {
        return out;
    }
    let normal = acc.normal * inv / nl;
    let f = orthonormal_pair(normal);
    out.distance = acc.dist * inv;
    out.normal = normal;
    out.height_var = acc.hv * inv;
    out.slope_cov = in_frame(f.t1, f.t2, acc.slopes * inv);
    out.t1 = f.t1;
    out.t2 = f.t2;
    out.color_mean = acc.am * inv;
    out.color_height = acc.ah * inv;
    out.support = acc.w;
    out.occupancy = acc.occ * inv;
    out.found = true;
    return out;
}

// VoxelField::sample: linear between the two levels around `level` (quadrilinear in all).
fn voxel_sample(x: vec3<f32>, level_in: f32) -> VoxelSample {
    let level = clamp(level_in, 0.0, f32(object.depth));
    let lo = u32(floor(level));
    let f = level - f32(lo);
    let a = sample_level(x, lo);
    if (f <= 1e-9 || lo == object.depth) {
        return a;
    }
    let b = sample_level(x, lo + 1u);
    if (a.found && b.found) {
        return mix_samples(a, b, f);
    }
    if (a.found) {
        return a;
    }
    return b;
}

// voxel_field::mix: two samples blended, normals renormalised, slopes as world tensors.
fn mix_samples(a: VoxelSample, b: VoxelSample, f: f32) -> VoxelSample {
    var normal = a.normal * (1.0 - f) + b.normal * f;
    let nl = length(normal);
    normal = select(a.normal, normal / nl, nl > 1e-20);
    let fr = orthonormal_pair(normal);
    let s = tensor(a.t1, a.t2, a.slope_cov) * (1.0 - f) + tensor(b.t1, b.t2, b.slope_cov) * f;
    var out: VoxelSample;
    out.distance = mix(a.distance, b.distance, f);
    out.normal = normal;
    out.height_var = mix(a.height_var, b.height_var, f);
    out.slope_cov = in_frame(fr.t1, fr.t2, s);
    out.t1 = fr.t1;
    out.t2 = fr.t2;
    out.color_mean = mix(a.color_mean, b.color_mean, vec3<f32>(f));
    out.color_height = mix(a.color_height, b.color_height, vec3<f32>(f));
    out.support = mix(a.support, b.support, f);
    out.occupancy = mix(a.occupancy, b.occupancy, f);
    out.found = true;
    return out;
}
