//! The closest point of a triangle to a point, and which feature (face, edge, corner) it lies on
//! (Ericson, *Real-Time Collision Detection*, 5.1.5): what a mesh's signed distance needs
//! ([`crate::object::mesh`]).

use glam::DVec3;

/// The feature of a triangle a closest point lies on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Feature {
    /// Inside the triangle.
    Face,
    /// On the edge between corners i and j (0, 1, 2).
    Edge(u32, u32),
    /// At corner i.
    Vertex(u32),
}

/// The closest point of triangle (a, b, c) to p and the feature it lies on (Ericson, Real-Time
/// Collision Detection, 5.1.5).
pub fn closest_on_triangle(p: DVec3, [a, b, c]: [DVec3; 3]) -> (DVec3, Feature) {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::Vertex(0));
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, Feature::Edge(0, 1));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, Feature::Edge(0, 2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, Feature::Edge(1, 2));
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (a + ab * v + ac * w, Feature::Face)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::splitmix;

    /// Against brute force: the closest of a dense sampling of the triangle is never nearer than
    /// the returned point, and is within the sampling's spacing of it.
    #[test]
    fn the_closest_point_is_the_nearest_of_the_triangle() {
        let mut rng = 1u64;
        let mut r = || {
            DVec3::new(splitmix(&mut rng), splitmix(&mut rng), splitmix(&mut rng)) * 2.0
                - DVec3::ONE
        };
        for _ in 0..200 {
            let t = [r(), r(), r()];
            let p = r() * 2.0;
            let (q, _) = closest_on_triangle(p, t);
            let k = 120;
            let mut best = f64::INFINITY;
            for i in 0..=k {
                for j in 0..=(k - i) {
                    let (u, v) = (i as f64 / k as f64, j as f64 / k as f64);
                    let x = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
                    best = best.min((x - p).length());
                }
            }
            let d = (q - p).length();
            assert!(d <= best + 1e-12 && d >= best - 0.05, "{d} {best}");
        }
    }
}
