//! The ground truth of an object view (#19): the explicit displaced object
//! ([`DisplacedObject`]) ray traced through the pixel's cone and supersampled, each hit shaded as
//! its own facet ([`ObjectLighting::facet_radiance`]) with a shadow ray toward the sun. No voxel,
//! no statistics: what the cone tracer's views are measured against.
//!
//! The rays fill the cone's cross-section (the same disc the cone tracer's masks cover) on a Vogel
//! spiral turned by a random angle per pixel: stratified, so a silhouette's coverage converges
//! as 1/N rather than 1/√N. Misses are black (coverage counts the hits).

use crate::object::cone_trace::{Cone, ConePixel};
use crate::object::displaced::DisplacedObject;
use crate::object::shading::ObjectLighting;
use std::f64::consts::{PI, TAU};

/// The ground truth's inputs.
#[derive(Clone, Copy)]
pub struct ObjectTruth<'a> {
    /// The explicit object.
    pub object: &'a DisplacedObject,
    /// Sun and BRDF.
    pub lighting: &'a ObjectLighting,
    /// The point colour of a driver value (the material's colour map).
    pub color: &'a (dyn Fn(f64) -> [f64; 3] + Sync),
    /// Shadow rays toward the sun (off: the sun is always visible).
    pub shadows: bool,
}

impl std::fmt::Debug for ObjectTruth<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ObjectTruth")
            .field("object", &self.object.shape)
            .field("lighting", self.lighting)
            .field("shadows", &self.shadows)
            .finish_non_exhaustive()
    }
}

impl ObjectTruth<'_> {
    /// The pixel of `cone` with `rays` rays (at least 1); `seed` turns the spiral. The cone's apex
    /// radius must be 0 (a pixel's cone). With a lens ([`Cone::lens`] > 0) each ray leaves a point
    /// of the lens disc (a second low-discrepancy sequence, R2, turned by the seed) toward the point
    /// its pixel direction meets at the focus distance along the axis: a thin lens whose plane of
    /// focus is perpendicular to the pixel's axis (the cone tracer's circle of confusion).
    pub fn pixel(&self, cone: &Cone, rays: usize, seed: u64) -> ConePixel {
        let n = rays.max(1);
        let (e1, e2) = cone.dir.any_orthonormal_pair();
        let mut rng = seed;
        let turn = TAU * crate::math::random::splitmix(&mut rng);
        let lens_turn = crate::math::random::splitmix(&mut rng);
        let golden = PI * (3.0 - 5f64.sqrt());
        let mut out = ConePixel::default();
        let mut squares = [0.0; 3];
        let mut hits = 0usize;
        for i in 0..n {
            let (r, a) = (
                ((i as f64 + 0.5) / n as f64).sqrt(),
                turn + golden * i as f64,
            );
            let dp =
                (cone.dir + (e1 * (r * a.cos()) + e2 * (r * a.sin())) * cone.spread).normalize();
            let (origin, d) = if cone.lens > 0.0 && cone.focus > 0.0 {
                let u = (0.5 + lens_turn + i as f64 * 0.754_877_666_246_692_8).fract();
                let v = (0.5 + lens_turn + i as f64 * 0.569_840_290_998_053_2).fract();
                let (rl, al) = (cone.lens * u.sqrt(), TAU * v);
                let o = cone.origin + (e1 * al.cos() + e2 * al.sin()) * rl;
                let q = cone.origin + dp * (cone.focus / dp.dot(cone.dir));
                (o, (q - o).normalize())
            } else {
                (cone.origin, dp)
            };
            let Some(hit) = self.object.trace(origin, d) else {
                continue;
            };
            hits += 1;
            let c = (self.color)(self.object.value(hit.p));
            let nrm = self.object.normal(hit.p);
            let lit = !self.shadows || self.object.sees(hit.p, self.lighting.light);
            let l = self.lighting.facet_radiance(c, nrm, -d, lit);
            for k in 0..3 {
                out.color[k] += l[k] / n as f64;
                squares[k] += l[k] * l[k] / n as f64;
            }
        }
        out.coverage = hits as f64 / n as f64;
        // The rays are stratified (a spiral), so s²/n overstates the noise of smooth pixels; it is
        // the right order where a few glints carry the pixel, which is what it is for.
        for k in 0..3 {
            let var = (squares[k] - out.color[k] * out.color[k]).max(0.0);
            out.variance[k] = var / (n.max(2) - 1) as f64;
        }
        out
    }
}

/// The cone through pixel (x, y) of a `width × height` image of `camera` (its orbit target is the
/// object's centre when it is [0, 0]), of the pixel's angular radius (a disc of the pixel's area).
pub fn pixel_cone(
    camera: &crate::scene::camera::Camera,
    x: f64,
    y: f64,
    width: u32,
    height: u32,
) -> Cone {
    let ray = camera.ray(glam::DVec2::new(x, y), width, height);
    let pixel = 2.0 * camera.tan_half_fov() / f64::from(height.max(1));
    // Off-axis a pixel subtends a little less (its area times cos³ of the angle off the axis,
    // 6% at the corner of a 35° view): the axis's value is kept, for the truth and the cone alike.
    Cone {
        origin: ray.origin,
        dir: ray.dir,
        radius0: 0.0,
        spread: pixel / PI.sqrt(),
        lens: 0.0,
        focus: 1.0,
    }
}

/// A thin lens: its radius (world units; 0 for a pinhole) and the distance along each pixel's axis
/// that is in focus (#19, depth of field by wider cones [HN12 Sec. 4.1, Fig. 1d]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Lens {
    /// Lens radius, world units (0: a pinhole).
    pub radius: f64,
    /// Distance in focus, world units (> 0).
    pub focus: f64,
}

impl Lens {
    /// No depth of field.
    pub const PINHOLE: Lens = Lens {
        radius: 0.0,
        focus: 1.0,
    };
}
