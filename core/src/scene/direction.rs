//! Directions: from polar angles, and tangent frames around a normal.

use glam::DVec3;

/// A unit direction from polar angle θ (from the normal, +z) and azimuth φ (from +x toward +y),
/// both in radians. Any finite angles give a unit vector; θ > π/2 points below the plane.
pub fn direction(theta: f64, phi: f64) -> DVec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    DVec3::new(st * cp, st * sp, ct)
}

/// An orthonormal tangent basis `(t, b)` for unit `n` (Duff et al. 2017, "Building an orthonormal
/// basis, revisited"), so that `(t, b, n)` is right-handed; the identity axes for n = +z. Continuous
/// everywhere except across n_z = 0 (the sign switch), where it stays orthonormal.
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unit length, the angles it was built from, and an orthonormal right-handed basis.
    #[test]
    fn directions_and_bases() {
        for (t, p) in [(0.0, 0.0), (0.3, 1.0), (1.2, -2.0), (1.4, 3.0), (2.5, 0.4)] {
            let d = direction(t, p);
            assert!((d.length() - 1.0).abs() < 1e-12);
            assert!((d.z.acos() - t).abs() < 1e-9);
            let (a, b) = basis(d);
            assert!(a.dot(b).abs() < 1e-12 && a.dot(d).abs() < 1e-12 && b.dot(d).abs() < 1e-12);
            assert!(
                (a.cross(b) - d).length() < 1e-12,
                "right-handed at {t}, {p}"
            );
        }
        assert_eq!(basis(DVec3::Z), (DVec3::X, DVec3::Y));
    }
}
