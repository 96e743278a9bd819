//! One pixel of an analytic view: the camera ray meets the level-of-detail surface, the method is
//! evaluated there with the pixel's footprint, and a real shadow ray on h̄ decides the sun.

use crate::driver::footprint::Footprint;
use crate::eval::interception::Interception;
use crate::eval::{Evaluator, FootprintQuery, Method};
use crate::scene::camera::Camera;
use glam::{DMat3, DVec2, DVec3};

impl Evaluator {
    /// One pixel of an analytic view: the camera ray (origin, unit dir) meets the level-of-detail
    /// surface; the method is evaluated there with the pixel's footprint `fp`, and the result is 0 where
    /// the resolved geometry shadows the light (a real shadow ray on h̄).
    pub fn pixel(
        &self,
        method: Method,
        origin: DVec3,
        dir: DVec3,
        wi: DVec3,
        fp: Footprint,
    ) -> [f64; 3] {
        self.pixel_in_frame(method, origin, dir, wi, fp, &DMat3::IDENTITY)
    }

    /// [`Evaluator::pixel`] in a tangent frame whose axes in the world are `frame`'s columns (the
    /// cylinder's): slope colour and environment are looked up at world normals.
    pub fn pixel_in_frame(
        &self,
        method: Method,
        origin: DVec3,
        dir: DVec3,
        wi: DVec3,
        fp: Footprint,
        frame: &DMat3,
    ) -> [f64; 3] {
        let Some((o, t)) = self.pixel_hit(origin, dir, fp) else {
            return [0.0; 3];
        };
        let at_hit = self.shade_footprint(method, o + dir * t, dir, wi, fp, frame);
        if method == Method::Naive || self.interception == Interception::Off {
            return at_hit;
        }
        let Some(stop) = self.interception(o, dir, t, fp) else {
            return at_hit;
        };
        // The crest, on h̄ below the point of the ray where the relief most likely stopped it.
        let q = o + dir * stop.t;
        let crest = DVec3::new(q.x, q.y, self.lod_height(DVec2::new(q.x, q.y), fp));
        let on_crest = self.shade_footprint(method, crest, dir, wi, fp, frame);
        let w = stop.weight;
        std::array::from_fn(|k| w * on_crest[k] + (1.0 - w) * at_hit[k])
    }

    /// The method at the footprint `fp` around point `p` of h̄ seen along `dir`, lit where a shadow
    /// ray on h̄ reaches the light.
    fn shade_footprint(
        &self,
        method: Method,
        p: DVec3,
        dir: DVec3,
        wi: DVec3,
        fp: Footprint,
        frame: &DMat3,
    ) -> [f64; 3] {
        let (cfg, sun_visible) = self.footprint_at(p, dir, wi, fp);
        if !sun_visible && self.environment.is_none() {
            return [0.0; 3];
        }
        let v = if sun_visible { 1.0 } else { 0.0 };
        match method {
            Method::Naive => self.naive_lit(&cfg, v, frame),
            Method::ViewIndependent => self.view_independent_lit(&cfg, v, frame),
            Method::Filtered => self.filtered_lit(&cfg, v, frame),
        }
    }

    /// Where the camera ray (origin, unit dir) meets h̄ for footprint `fp`: the ray's start on top
    /// of the slab and t from there; None for a ray that misses (sky).
    fn pixel_hit(&self, origin: DVec3, dir: DVec3, fp: Footprint) -> Option<(DVec3, f64)> {
        if dir.z >= 0.0 {
            return None;
        }
        let top = self.surface.h_max * 1.001 + 1e-6;
        let t0 = ((origin.z - top) / -dir.z).max(0.0);
        let o = origin + dir * t0;
        Some((o, self.lod_march(o, dir, fp)?))
    }

    /// Where an analytic view's pixel is evaluated: the camera ray (origin, unit dir) meets the
    /// level-of-detail surface at the query's centre, with the pixel's footprint `fp`; and whether
    /// a shadow ray on h̄ from there reaches the light. None where the ray misses (sky).
    pub fn pixel_query(
        &self,
        origin: DVec3,
        dir: DVec3,
        wi: DVec3,
        fp: Footprint,
    ) -> Option<(FootprintQuery, bool)> {
        let (o, t) = self.pixel_hit(origin, dir, fp)?;
        Some(self.footprint_at(o + dir * t, dir, wi, fp))
    }

    /// The query of the footprint `fp` around point `p` of h̄ seen along `dir`, and whether a shadow
    /// ray on h̄ from `p` reaches the light.
    fn footprint_at(
        &self,
        p: DVec3,
        dir: DVec3,
        wi: DVec3,
        fp: Footprint,
    ) -> (FootprintQuery, bool) {
        let sun_visible = wi.z > 0.0 && self.lod_march(p, wi, fp).is_none();
        let cfg = FootprintQuery {
            wo: -dir,
            wi,
            x0: DVec2::new(p.x, p.y),
            footprint: fp,
        };
        (cfg, sun_visible)
    }

    /// One pixel of an analytic view of the plane: pixel centre `p` of a `width × height` image of
    /// `camera` (lifted clear of the relief: [`crate::scene::surface::Surface::clear_camera`]), its footprint on the
    /// mean plane, then [`Evaluator::pixel`] (0 for sky pixels). The plane's counterpart of
    /// [`Evaluator::cylinder_pixel`].
    pub fn plane_pixel(
        &self,
        method: Method,
        camera: &Camera,
        p: DVec2,
        (width, height): (u32, u32),
        wi: DVec3,
    ) -> [f64; 3] {
        let camera = self.surface.clear_camera(camera);
        let Some((_, cov)) = camera.plane_footprint(p, width, height) else {
            return [0.0; 3];
        };
        let ray = camera.ray(p, width, height);
        self.pixel(method, ray.origin, ray.dir, wi, Footprint { cov })
    }
}
