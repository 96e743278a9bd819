//! The area of a plane's section of an axis-aligned cube (#19): the polygon (a triangle to a
//! hexagon) where a voxel's mean plane cuts the voxel, which is the area a flat piece of surface
//! spanning the voxel would have, and so the denominator of the voxel's occupancy
//! ([`crate::object::voxel_stats::VoxelDescriptor::occupancy`]).
//!
//! The polygon's corners are the plane's crossings of the cube's 12 edges, ordered by angle around
//! their mean in the plane; its area follows by the shoelace formula in the plane's own frame.
//!
//! Edge cases: a plane that misses the cube, or only touches it at a corner or an edge, has area 0;
//! one lying in a face has the face's area; a normal that is not finite or has zero length gives 0.

use glam::{DVec2, DVec3};

/// The cube's 12 edges as pairs of corner indices (bit a of a corner index: the upper side along
/// axis a).
const EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// The area of the section of the cube `[lo, lo + size]³` by the plane through `point` with normal
/// `normal` (any length; module docs for the edge cases).
pub fn plane_section_area(point: DVec3, normal: DVec3, lo: DVec3, size: f64) -> f64 {
    let Some(n) = normal.try_normalize() else {
        return 0.0;
    };
    if !(size > 0.0 && size.is_finite() && point.is_finite() && lo.is_finite()) {
        return 0.0;
    }
    let corner = |i: usize| {
        lo + DVec3::new(
            (i & 1) as f64 * size,
            ((i >> 1) & 1) as f64 * size,
            ((i >> 2) & 1) as f64 * size,
        )
    };
    let mut d = [0.0; 8];
    for (i, di) in d.iter_mut().enumerate() {
        *di = (corner(i) - point).dot(n);
    }
    // Counted from the side that holds a corner, so that a plane in a face meets the cube.
    if d.iter().all(|&x| x <= 0.0) {
        d = d.map(|x| -x);
    }
    let (t1, t2) = n.any_orthonormal_pair();
    let mut pts: Vec<DVec2> = Vec::with_capacity(6);
    for (a, b) in EDGES {
        let (pa, pb) = (corner(a), corner(b));
        let (da, db) = (d[a], d[b]);
        // One crossing per change of side; a corner on the plane is met through the edges that
        // leave it to the positive side.
        if (da <= 0.0 && db > 0.0) || (da > 0.0 && db <= 0.0) {
            let x = pa + (pb - pa) * (da / (da - db));
            pts.push(DVec2::new((x - point).dot(t1), (x - point).dot(t2)));
        }
    }
    if pts.len() < 3 {
        return 0.0;
    }
    let c = pts.iter().copied().sum::<DVec2>() / pts.len() as f64;
    pts.sort_by(|p, q| {
        let (a, b) = (p - c, q - c);
        a.y.atan2(a.x).total_cmp(&b.y.atan2(b.x))
    });
    let twice: f64 = (0..pts.len())
        .map(|i| pts[i].perp_dot(pts[(i + 1) % pts.len()]))
        .sum();
    0.5 * twice.abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::splitmix;

    /// Sections whose areas are known: a face-parallel square, the diagonal rectangle, the regular
    /// hexagon through the centre along a main diagonal, the triangle cutting off a corner, a face
    /// itself, and planes that miss or only touch.
    #[test]
    fn known_sections() {
        let (lo, s) = (DVec3::new(-1.0, 2.0, 0.5), 0.5);
        let c = lo + DVec3::splat(0.5 * s);
        let close = |a: f64, b: f64| assert!((a - b).abs() < 1e-12 * (1.0 + b), "{a} vs {b}");
        close(plane_section_area(c, DVec3::Z, lo, s), s * s);
        close(
            plane_section_area(c, DVec3::new(1.0, 1.0, 0.0), lo, s),
            2f64.sqrt() * s * s,
        );
        close(
            plane_section_area(c, DVec3::ONE, lo, s),
            3.0 * 3f64.sqrt() / 4.0 * s * s,
        );
        // x + y + z = s/2 from the lower corner: a triangle of side s/√2.
        close(
            plane_section_area(lo + DVec3::new(0.5 * s, 0.0, 0.0), DVec3::ONE, lo, s),
            3f64.sqrt() / 4.0 * 0.5 * s * s,
        );
        close(plane_section_area(lo, -DVec3::Y, lo, s), s * s);
        assert_eq!(plane_section_area(lo - DVec3::Z, DVec3::Z, lo, s), 0.0);
        assert_eq!(plane_section_area(lo, DVec3::ONE, lo, s), 0.0);
        assert_eq!(plane_section_area(c, DVec3::ZERO, lo, s), 0.0);
        assert_eq!(plane_section_area(c, DVec3::NAN, lo, s), 0.0);
        assert_eq!(plane_section_area(c, DVec3::Z, lo, 0.0), 0.0);
    }

    /// Random planes against brute force: the section's projection on the plane across the
    /// normal's largest axis, counted on a 600² grid (area = projected area / |n_a|).
    #[test]
    fn random_sections_match_counting() {
        let mut rng = 5u64;
        let lo = DVec3::new(0.3, -0.2, 0.1);
        let s = 2.0;
        for _ in 0..40 {
            let n = DVec3::new(
                splitmix(&mut rng) - 0.5,
                splitmix(&mut rng) - 0.5,
                splitmix(&mut rng) - 0.5,
            )
            .normalize();
            let p = lo + DVec3::new(splitmix(&mut rng), splitmix(&mut rng), splitmix(&mut rng)) * s;
            let a = n.abs().max_position();
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let cells = 600;
            let mut hit = 0usize;
            for i in 0..cells {
                for j in 0..cells {
                    let mut x = DVec3::ZERO;
                    x[b] = lo[b] + (i as f64 + 0.5) / cells as f64 * s;
                    x[c] = lo[c] + (j as f64 + 0.5) / cells as f64 * s;
                    // The plane's coordinate along a above (x_b, x_c).
                    let xa = p[a] - (n[b] * (x[b] - p[b]) + n[c] * (x[c] - p[c])) / n[a];
                    if xa >= lo[a] && xa <= lo[a] + s {
                        hit += 1;
                    }
                }
            }
            let counted = hit as f64 / (cells * cells) as f64 * s * s / n[a].abs();
            let exact = plane_section_area(p, n, lo, s);
            assert!(
                (exact - counted).abs() < 0.01 * s * s,
                "{n} {p}: {exact} vs {counted}"
            );
        }
    }
}
