// Mirror of `core/src/scene/cylinder.rs`: the curved test object. A cylinder of radius
// R = view_params.radius around an axis parallel to x through (·, 0, −R); surface coordinates
// (u, v) = (x, R·φ); micro-geometry displaced along the outward normal.

// A world point in the cylinder's coordinates: surface position (u, v), distance ρ from the axis
// and angle φ from +z toward +y.
struct CylinderPoint {
    uv: vec2<f32>,
    rho: f32,
    phi: f32,
}

// cylinder::to_surface.
fn cylinder_to_surface(p: vec3<f32>) -> CylinderPoint {
    let r = view_params.radius;
    let y = p.y;
    let z = p.z + r;
    let phi = atan2(y, z);
    return CylinderPoint(vec2<f32>(p.x, r * phi), sqrt(y * y + z * z), phi);
}

// cylinder::frame: columns t_u, t_v, n.
fn cylinder_frame(phi: f32) -> mat3x3<f32> {
    let s = sin(phi);
    let c = cos(phi);
    return mat3x3<f32>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, c, -s), vec3<f32>(0.0, s, c));
}

// cylinder::intersect: entry and exit of o + t·d through the coaxial cylinder of radius a;
// (-1, -1) on a miss.
fn cylinder_intersect(a: f32, o: vec3<f32>, d: vec3<f32>) -> vec2<f32> {
    let oy = o.y;
    let oz = o.z + view_params.radius;
    let qa = d.y * d.y + d.z * d.z;
    let miss = vec2<f32>(-1.0, -1.0);
    if (!(qa > 1e-30)) {
        return miss;
    }
    let qb = oy * d.y + oz * d.z;
    let qc = oy * oy + oz * oz - a * a;
    let disc = qb * qb - qa * qc;
    if (!(disc >= 0.0)) {
        return miss;
    }
    let sq = sqrt(disc);
    let q = -(qb + select(-sq, sq, qb >= 0.0));
    var t1 = 0.0;
    var t2 = 0.0;
    if (q != 0.0) {
        let x = q / qa;
        let y = qc / q;
        t1 = min(x, y);
        t2 = max(x, y);
    }
    if (t2 < 0.0) {
        return miss;
    }
    return vec2<f32>(max(t1, 0.0), t2);
}

// Camera::tangent_footprint (view.wgsl's pixel steps dx, dy): covariance (xx, yy, xy) in (t_u, t_v).
fn tangent_footprint(d: vec3<f32>, dx: vec3<f32>, dy: vec3<f32>, point: vec3<f32>, fr: mat3x3<f32>) -> vec3<f32> {
    let n = fr[2];
    let dn = dot(d, n);
    let s = dot(point - view_params.eye, n) / dn;
    let jx = (dx - d * (dot(dx, n) / dn)) * s;
    let jy = (dy - d * (dot(dy, n) / dn)) * s;
    let ju = vec2<f32>(dot(jx, fr[0]), dot(jy, fr[0]));
    let jv = vec2<f32>(dot(jx, fr[1]), dot(jy, fr[1]));
    let s2 = view_params.pixel_sigma * view_params.pixel_sigma;
    return vec3<f32>(dot(ju, ju), dot(jv, jv), dot(ju, jv)) * s2;
}
