//! A closed triangle mesh as a base shape (#19): loaded from OBJ (the `tobj` crate), checked,
//! and given an exact signed distance through a bounding-volume hierarchy.
//!
//! **Checks** (each a [`MeshError`] with its reason, never a panic): the text parses; there is at
//! least one triangle and at most [`MAX_TRIANGLES`]; every coordinate is finite and within
//! [`MAX_EXTENT`] of the origin; no triangle is degenerate (zero area); and the mesh is closed and
//! consistently oriented: every directed edge a→b appears once and its reverse b→a once (vertices
//! at identical positions are welded first, as exporters often split them). A mesh wound inward
//! (negative volume) is turned outward.
//!
//! **Signed distance**: the distance to the closest point of the closest triangle (Ericson's
//! closest point on a triangle, with the feature it lies on), its sign from that feature's
//! angle-weighted pseudo-normal (Bærentzen & Aanæs 2005: face normal, the sum of an edge's two face
//! normals, the angle-weighted sum at a vertex), which is exact for a closed, consistently oriented
//! mesh. It is 1-Lipschitz, as sphere tracing needs.

use crate::object::triangle::{Feature, closest_on_triangle};
use glam::DVec3;
use std::collections::HashMap;

/// Most triangles a mesh may have.
pub const MAX_TRIANGLES: usize = 1 << 20;

/// Largest coordinate accepted (world units).
pub const MAX_EXTENT: f64 = 1e6;

/// Why a mesh is refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// The OBJ text does not parse.
    #[error("the OBJ file does not parse: {0}")]
    Parse(String),
    /// No triangles.
    #[error("the mesh has no triangles")]
    Empty,
    /// Too many triangles.
    #[error("the mesh has {0} triangles; at most {MAX_TRIANGLES} are accepted")]
    TooLarge(usize),
    /// A coordinate that is not finite or beyond [`MAX_EXTENT`].
    #[error("vertex {index} is not a finite point within {MAX_EXTENT} of the origin")]
    BadVertex {
        /// 0-based vertex index.
        index: usize,
    },
    /// A triangle of zero area.
    #[error("triangle {index} is degenerate (zero area)")]
    Degenerate {
        /// 0-based triangle index.
        index: usize,
    },
    /// Not closed or not consistently oriented.
    #[error(
        "the mesh is not closed and consistently oriented: {edges} edges lack exactly one opposite edge (a hole, a seam or a flipped triangle)"
    )]
    NotClosed {
        /// How many directed edges are unmatched or repeated.
        edges: usize,
    },
}

/// A node of the hierarchy: a box and either two children or a run of triangles.
#[derive(Clone, Debug, PartialEq)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Children (`left`, `left + 1`) when `count == 0`, else the first triangle of the run.
    start: u32,
    count: u32,
}

/// A closed, outward-oriented triangle mesh with its signed-distance structure.
#[derive(Clone, Debug, PartialEq)]
pub struct TriMesh {
    /// Vertex positions (welded).
    pub vertices: Vec<DVec3>,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    face_normals: Vec<DVec3>,
    vertex_normals: Vec<DVec3>,
    edge_normals: HashMap<(u32, u32), DVec3>,
    nodes: Vec<Node>,
    /// Triangle order of the hierarchy's leaves.
    order: Vec<u32>,
}

impl TriMesh {
    /// Parses OBJ text (faces triangulated; materials, normals and texture coordinates ignored).
    pub fn from_obj(text: &str) -> Result<Self, MeshError> {
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: false,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| {
            Ok((Vec::new(), HashMap::new()))
        })
        .map_err(|e| MeshError::Parse(e.to_string()))?;
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for m in &models {
            let base = vertices.len() as u32;
            for p in m.mesh.positions.chunks_exact(3) {
                vertices.push(DVec3::new(
                    f64::from(p[0]),
                    f64::from(p[1]),
                    f64::from(p[2]),
                ));
            }
            for t in m.mesh.indices.chunks_exact(3) {
                triangles.push([base + t[0], base + t[1], base + t[2]]);
            }
        }
        Self::new(vertices, triangles)
    }

    /// A mesh from positions and triangles, checked and welded (module docs).
    pub fn new(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        if triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if triangles.len() > MAX_TRIANGLES {
            return Err(MeshError::TooLarge(triangles.len()));
        }
        if let Some(index) = vertices
            .iter()
            .position(|v| !(v.is_finite() && v.abs().max_element() <= MAX_EXTENT))
        {
            return Err(MeshError::BadVertex { index });
        }
        // Weld identical positions.
        let mut welded: Vec<DVec3> = Vec::new();
        let mut remap = Vec::with_capacity(vertices.len());
        let mut seen: HashMap<[u64; 3], u32> = HashMap::new();
        for v in &vertices {
            let key = [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
            let id = *seen.entry(key).or_insert_with(|| {
                welded.push(*v);
                welded.len() as u32 - 1
            });
            remap.push(id);
        }
        let mut tris = Vec::with_capacity(triangles.len());
        for (index, t) in triangles.iter().enumerate() {
            let t = t.map(|i| remap.get(i as usize).copied());
            let [Some(a), Some(b), Some(c)] = t else {
                return Err(MeshError::Parse(format!(
                    "triangle {index} names a missing vertex"
                )));
            };
            let (pa, pb, pc) = (welded[a as usize], welded[b as usize], welded[c as usize]);
            if !((pb - pa).cross(pc - pa).length() > 1e-14 * (pb - pa).length_squared().max(1e-300))
            {
                return Err(MeshError::Degenerate { index });
            }
            tris.push([a, b, c]);
        }
        // Closed and consistently oriented: each directed edge once, with its reverse.
        let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &tris {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        let bad = directed
            .iter()
            .filter(|&(&(a, b), &n)| n != 1 || directed.get(&(b, a)) != Some(&1))
            .count();
        if bad > 0 {
            return Err(MeshError::NotClosed { edges: bad });
        }
        // Outward: positive volume.
        let volume: f64 = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| welded[i as usize]);
                a.dot(b.cross(c))
            })
            .sum();
        if volume < 0.0 {
            for t in &mut tris {
                t.swap(1, 2);
            }
        }
        Ok(Self::build(welded, tris))
    }

    fn build(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Self {
        let corner = |t: &[u32; 3], k: usize| vertices[t[k] as usize];
        let face_normals: Vec<DVec3> = triangles
            .iter()
            .map(|t| {
                (corner(t, 1) - corner(t, 0))
                    .cross(corner(t, 2) - corner(t, 0))
                    .normalize()
            })
            .collect();
        let mut vertex_normals = vec![DVec3::ZERO; vertices.len()];
        let mut edge_normals: HashMap<(u32, u32), DVec3> = HashMap::new();
        for (t, n) in triangles.iter().zip(&face_normals) {
            for k in 0..3 {
                let (a, b, c) = (corner(t, k), corner(t, (k + 1) % 3), corner(t, (k + 2) % 3));
                let angle = (b - a).angle_between(c - a);
                vertex_normals[t[k] as usize] += *n * angle;
                let (i, j) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
                *edge_normals.entry((i, j)).or_insert(DVec3::ZERO) += *n;
            }
        }
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let centroids: Vec<DVec3> = triangles
            .iter()
            .map(|t| (corner(t, 0) + corner(t, 1) + corner(t, 2)) / 3.0)
            .collect();
        let mut nodes = vec![Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            start: 0,
            count: 0,
        }];
        split(
            &mut nodes, 0, &mut order, 0, &centroids, &triangles, &vertices,
        );
        Self {
            vertices,
            triangles,
            face_normals,
            vertex_normals,
            edge_normals,
            nodes,
            order,
        }
    }

    /// The total area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|i| self.triangle_area(i))
            .sum()
    }

    fn triangle_area(&self, i: usize) -> f64 {
        let [a, b, c] = self.triangles[i].map(|k| self.vertices[k as usize]);
        0.5 * (b - a).cross(c - a).length()
    }

    /// The largest distance of a vertex from the origin.
    pub fn bounding_radius(&self) -> f64 {
        self.vertices.iter().map(|v| v.length()).fold(0.0, f64::max)
    }

    /// The closest surface point to p, its feature's pseudo-normal, and the squared distance.
    fn closest(&self, p: DVec3) -> (DVec3, DVec3, f64) {
        let mut best = (p, DVec3::Z, f64::INFINITY);
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            if self.box_distance(n, p) >= best.2 {
                continue;
            }
            let node = &self.nodes[n as usize];
            if node.count == 0 {
                let (l, r) = (node.start, node.start + 1);
                // Nearer child last, so it is popped first.
                let dl = self.box_distance(l, p);
                let dr = self.box_distance(r, p);
                if dl < dr {
                    stack.extend([r, l]);
                } else {
                    stack.extend([l, r]);
                }
                continue;
            }
            for &t in &self.order[node.start as usize..(node.start + node.count) as usize] {
                let tri = self.triangles[t as usize];
                let (q, feature) = closest_on_triangle(p, tri.map(|k| self.vertices[k as usize]));
                let d = (q - p).length_squared();
                if d < best.2 {
                    let normal = match feature {
                        Feature::Face => self.face_normals[t as usize],
                        Feature::Edge(i, j) => {
                            let (a, b) = (tri[i as usize], tri[j as usize]);
                            self.edge_normals[&(a.min(b), a.max(b))]
                        }
                        Feature::Vertex(i) => self.vertex_normals[tri[i as usize] as usize],
                    };
                    best = (q, normal, d);
                }
            }
        }
        best
    }

    /// The squared distance from p to node n's box (0 inside).
    fn box_distance(&self, n: u32, p: DVec3) -> f64 {
        let node = &self.nodes[n as usize];
        (node.lo - p)
            .max(p - node.hi)
            .max(DVec3::ZERO)
            .length_squared()
    }

    /// The signed distance (negative inside), exact.
    pub fn distance(&self, p: DVec3) -> f64 {
        let (q, n, d2) = self.closest(p);
        let d = d2.sqrt();
        if (p - q).dot(n) < 0.0 { -d } else { d }
    }

    /// The unit gradient of the distance: along p − q (signed), the feature's pseudo-normal on the
    /// surface itself.
    pub fn normal(&self, p: DVec3) -> DVec3 {
        let (q, n, d2) = self.closest(p);
        let pn = n.try_normalize().unwrap_or(DVec3::Z);
        if d2 <= 1e-24 {
            return pn;
        }
        let dir = (p - q) / d2.sqrt();
        if dir.dot(n) < 0.0 { -dir } else { dir }
    }

    /// About `count` points spread over the surface with the area each stands for: every triangle
    /// gets its share of `count` by area (systematic sampling over the cumulative area, so the
    /// shares add up exactly), each point uniform in its triangle from `seed`.
    pub fn surface_points(&self, count: usize, seed: u64) -> Vec<(DVec3, f64)> {
        let total = self.area();
        let count = count.max(1);
        let step = total / count as f64;
        let mut rng = seed;
        let mut next = step * crate::math::random::splitmix(&mut rng);
        let mut acc = 0.0;
        let mut out = Vec::with_capacity(count + 1);
        for (i, t) in self.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|k| self.vertices[k as usize]);
            acc += self.triangle_area(i);
            while next < acc {
                let (mut u, mut v) = (
                    crate::math::random::splitmix(&mut rng),
                    crate::math::random::splitmix(&mut rng),
                );
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                out.push((a + (b - a) * u + (c - a) * v, step));
                next += step;
            }
        }
        out
    }

    /// The least thickness of the solid, sampled: from up to 4096 triangle centroids, the
    /// distance travelled inward along the face normal (sphere traced on the exact distance) to
    /// the opposite surface. What a relief may not reach half of.
    pub fn thickness(&self) -> f64 {
        let every = (self.triangles.len() / 4096).max(1);
        let mut least = f64::INFINITY;
        for (i, t) in self.triangles.iter().enumerate().step_by(every) {
            let c = t.map(|k| self.vertices[k as usize]).iter().sum::<DVec3>() / 3.0;
            let n = self.face_normals[i];
            let eps = 1e-6 * self.bounding_radius().max(1e-12);
            let mut s = 4.0 * eps;
            for _ in 0..512 {
                let d = self.distance(c - n * s);
                if d > -eps {
                    break;
                }
                s += -d;
            }
            least = least.min(s);
        }
        least
    }
}

/// Splits node `n` over `order[start..]` (its triangles) at the median centroid of its longest
/// axis, down to leaves of at most 4.
#[allow(clippy::too_many_arguments)]
fn split(
    nodes: &mut Vec<Node>,
    n: usize,
    order: &mut [u32],
    start: u32,
    centroids: &[DVec3],
    triangles: &[[u32; 3]],
    vertices: &[DVec3],
) {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for &t in order.iter() {
        for &k in &triangles[t as usize] {
            lo = lo.min(vertices[k as usize]);
            hi = hi.max(vertices[k as usize]);
        }
    }
    nodes[n].lo = lo;
    nodes[n].hi = hi;
    if order.len() <= 4 {
        nodes[n].start = start;
        nodes[n].count = order.len() as u32;
        return;
    }
    let axis = (hi - lo).max_position();
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |a, b| {
        centroids[*a as usize][axis].total_cmp(&centroids[*b as usize][axis])
    });
    let left = nodes.len();
    nodes[n].start = left as u32;
    nodes[n].count = 0;
    for _ in 0..2 {
        nodes.push(Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            start: 0,
            count: 0,
        });
    }
    let (a, b) = order.split_at_mut(mid);
    split(nodes, left, a, start, centroids, triangles, vertices);
    split(
        nodes,
        left + 1,
        b,
        start + mid as u32,
        centroids,
        triangles,
        vertices,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::splitmix;
    use crate::object::cube_obj;
    use crate::object::icosphere::icosphere_obj;

    /// The cube's signed distance is the box's, exactly, inside and out, at edges and corners.
    #[test]
    fn a_cube_has_the_box_distance() {
        let m = TriMesh::from_obj(&cube_obj()).unwrap();
        assert_eq!(m.triangles.len(), 12);
        assert!((m.area() - 24.0).abs() < 1e-12);
        let mut rng = 4u64;
        for _ in 0..2000 {
            let p = DVec3::new(splitmix(&mut rng), splitmix(&mut rng), splitmix(&mut rng)) * 4.0
                - DVec3::splat(2.0);
            let q = p.abs() - DVec3::ONE;
            let exact = q.max(DVec3::ZERO).length() + q.max_element().min(0.0);
            assert!(
                (m.distance(p) - exact).abs() < 1e-12,
                "{p}: {} vs {exact}",
                m.distance(p)
            );
            let e = 1e-7;
            if exact.abs() > 1e-3 {
                let fd = crate::object::central_gradient(|x| m.distance(x), p, e);
                assert!(
                    (m.normal(p) - fd).length() < 1e-5,
                    "{p}: {} {fd}",
                    m.normal(p)
                );
            }
        }
        assert!((m.thickness() - 2.0).abs() < 1e-5, "{}", m.thickness());
    }

    /// An icosphere's distance is within its chords' sagitta of the sphere's, with the right sign.
    #[test]
    fn an_icosphere_is_a_sphere_to_its_sagitta() {
        let m = TriMesh::from_obj(&icosphere_obj(1.0, 3)).unwrap();
        assert_eq!(m.triangles.len(), 20 * 64);
        let mut rng = 6u64;
        for _ in 0..1000 {
            let p = DVec3::new(splitmix(&mut rng), splitmix(&mut rng), splitmix(&mut rng)) * 3.0
                - DVec3::splat(1.5);
            assert!((m.distance(p) - (p.length() - 1.0)).abs() < 0.01, "{p}");
        }
        let pts = m.surface_points(5000, 1);
        let total: f64 = pts.iter().map(|q| q.1).sum();
        assert!((total - m.area()).abs() < 1e-9 * m.area());
        assert!(pts.len().abs_diff(5000) <= 1);
        for (p, _) in pts.iter().step_by(50) {
            assert!(m.distance(*p).abs() < 1e-12);
        }
    }

    /// A displaced icosphere traces as the displaced sphere does, to the chords' sagitta: the
    /// mesh's distance drives the same relief and march.
    #[test]
    fn a_displaced_mesh_traces_like_its_shape() {
        use crate::material::Material;
        use crate::object::base_shape::BaseShape;
        use crate::object::displaced::DisplacedObject;
        let mut m = Material::default();
        m.heights.sigma_h = 0.02;
        let mesh = std::sync::Arc::new(TriMesh::from_obj(&icosphere_obj(1.0, 4)).unwrap());
        assert!(
            (mesh.thickness() - 2.0).abs() < 0.01,
            "{}",
            mesh.thickness()
        );
        let a = DisplacedObject::new(&m, BaseShape::Mesh(mesh)).unwrap();
        let b = DisplacedObject::new(&m, BaseShape::Sphere { radius: 1.0 }).unwrap();
        let mut rng = 12u64;
        let mut compared = 0;
        for _ in 0..100 {
            let o = DVec3::new(
                splitmix(&mut rng) - 0.5,
                splitmix(&mut rng) - 0.5,
                splitmix(&mut rng) - 0.5,
            )
            .normalize()
                * 3.0;
            let d = (DVec3::new(splitmix(&mut rng), splitmix(&mut rng), splitmix(&mut rng)) * 0.8
                - DVec3::splat(0.4)
                - o)
                .normalize();
            if let (Some(ha), Some(hb)) = (a.trace(o, d), b.trace(o, d)) {
                // Level 4: chords of about 0.08, sagitta under 0.001, steep relief multiplying it.
                assert!((ha.t - hb.t).abs() < 0.02, "{} {}", ha.t, hb.t);
                compared += 1;
            }
        }
        assert!(compared > 60, "{compared}");
    }

    /// Bad meshes are refused with the reason.
    #[test]
    fn bad_meshes_say_why() {
        let open = cube_obj().replace("f 2 4 8 6\n", "");
        assert!(matches!(
            TriMesh::from_obj(&open),
            Err(MeshError::NotClosed { .. })
        ));
        let flipped = cube_obj().replace("f 2 4 8 6", "f 2 6 8 4");
        assert!(matches!(
            TriMesh::from_obj(&flipped),
            Err(MeshError::NotClosed { .. })
        ));
        assert_eq!(TriMesh::from_obj("# nothing\n"), Err(MeshError::Empty));
        assert!(matches!(
            TriMesh::from_obj("v 1 2\nf 1 2 3\n"),
            Err(MeshError::Parse(_))
        ));
        assert!(matches!(
            TriMesh::from_obj("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"),
            Err(MeshError::Degenerate { index: 0 })
        ));
        let huge = cube_obj().replace("v 1 1 1", "v 1e300 1 1");
        assert!(matches!(
            TriMesh::from_obj(&huge),
            Err(MeshError::BadVertex { .. })
        ));
        let nan = cube_obj().replace("v 1 1 1", "v nan 1 1");
        assert!(TriMesh::from_obj(&nan).is_err());
        for e in [
            MeshError::Empty,
            MeshError::NotClosed { edges: 3 },
            MeshError::TooLarge(5),
        ] {
            assert!(!e.to_string().is_empty());
        }
        // Inward winding is turned outward.
        let inward = cube_obj()
            .lines()
            .map(|l| match l.strip_prefix("f ") {
                Some(f) => format!("f {}\n", f.split(' ').rev().collect::<Vec<_>>().join(" ")),
                None => format!("{l}\n"),
            })
            .collect::<String>();
        let m = TriMesh::from_obj(&inward).unwrap();
        assert!(m.distance(DVec3::ZERO) < 0.0 && m.distance(DVec3::splat(2.0)) > 0.0);
    }
}
