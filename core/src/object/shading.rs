//! How an object's surface is shaded (#19): an explicit facet (the ground truth) and a voxel's
//! statistics (the cone tracer, [HN12 Eq. 13]), under one directional sun, with the material's
//! analytic base BRDF and its colour map of the driver's value. (Environment light, slope colour
//! and measured BRDFs are the plane's; objects do not take them yet.)
//!
//! Both evaluate the specular lobe in slope space relative to a local frame: an explicit facet in
//! its own frame (the base lobe of roughness σ_n0 about the facet's normal,
//! [`crate::microfacet::brdf::BaseBrdf::specular_with`] with n = z), a voxel in the frame of its
//! mean normal n̄ with the lobe widened by its slopes
//! ([`crate::microfacet::brdf::filtered_specular`]): where a voxel resolves the relief (n̄ follows
//! the facets, small slope covariance) the two are the same lobe, and over many facets the widened
//! lobe is their average to first order [HN12 Sec. 5.5]. (The lobe in the frame of the undisplaced
//! base normal, the plane's convention carried over, was measured and dropped: its
//! `1/(4 h_z⁴ ωo_z)` with ωo_z taken to the base normal made the truth's specular of infinite
//! variance near base silhouettes, and left the voxels 5–12% darker than it on a torus seen at 60°.)

use crate::microfacet::attribute::mean_attribute;
use crate::microfacet::brdf::{BaseBrdf, filtered_specular};
use crate::microfacet::masking_shadowing::{Correlation, G2};
use crate::object::voxel_field::VoxelSample;
use glam::{DVec2, DVec3};
use std::f64::consts::FRAC_1_PI;

/// The sun and the BRDF an object is lit and shaded with.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectLighting {
    /// Unit direction toward the sun.
    pub light: DVec3,
    /// The sun's irradiance scale.
    pub sun: f64,
    /// The base BRDF.
    pub brdf: BaseBrdf,
    /// How masking and shadowing combine in a voxel's statistics.
    pub correlation: Correlation,
}

/// `v` in the frame (t₁, t₂, n).
fn local(v: DVec3, t: [DVec3; 2], n: DVec3) -> DVec3 {
    DVec3::new(v.dot(t[0]), v.dot(t[1]), v.dot(n))
}

impl ObjectLighting {
    /// The sun toward unit `light` with `material`'s strength, base BRDF and masking correlation.
    pub fn of_material(material: &crate::material::Material, light: DVec3) -> Self {
        Self {
            light,
            sun: material.lighting.sun,
            brdf: material.brdf.clone(),
            correlation: material.filtering.correlation,
        }
    }

    /// The radiance toward `wo` of an explicit facet of unit normal n and colour c, with the sun
    /// visible (`lit`) or not: Lambert's diffuse and the base lobe about n (module docs). 0 when
    /// the sun or the eye is behind the facet.
    pub fn facet_radiance(&self, c: [f64; 3], n: DVec3, wo: DVec3, lit: bool) -> [f64; 3] {
        if !lit || n.dot(self.light) <= 0.0 {
            return [0.0; 3];
        }
        let diffuse = self.brdf.diffuse(n, self.light);
        let (t1, t2) = n.any_orthonormal_pair();
        let t = [t1, t2];
        let spec = self.brdf.specular_with(
            DVec3::Z,
            local(wo, t, n),
            local(self.light, t, n),
            Default::default(),
        );
        c.map(|ck| self.sun * (diffuse * ck + spec))
    }

    /// The mean radiance toward `wo` of the visible surface a voxel sample describes [HN12 Eq. 13]:
    /// `E·ā(v, l)·ρ̄·(l·n̄)⁺·V̄(l)`, with `ā(v, l)` the attribute model's visible mean [HN12 Eq. 17],
    /// the diffuse BRDF, the base lobe widened by the voxel's slopes, and Smith's mean shadowing of
    /// the visible points; times `sun_visible`, the share of the sun the shadow cone lets through.
    /// 0 where the mean plane faces away from the eye.
    pub fn element_radiance(&self, s: &VoxelSample, wo: DVec3, sun_visible: f64) -> [f64; 3] {
        let (wo_l, wi_l) = (
            local(wo, s.tangents, s.normal),
            local(self.light, s.tangents, s.normal),
        );
        if wo_l.z <= 0.0 || wi_l.z <= 0.0 || sun_visible <= 0.0 {
            return [0.0; 3];
        }
        let g2 = G2::from_directions(wo_l, wi_l, &s.slope_cov, self.correlation);
        let shadow = g2.mean_shadowing();
        let kd = self.brdf.albedo * FRAC_1_PI * wi_l.z;
        let spec = filtered_specular(
            self.brdf.specular,
            self.brdf.roughness,
            DVec2::ZERO,
            &s.slope_cov,
            wo_l,
            wi_l,
        );
        let e = self.sun * sun_visible * shadow;
        [0, 1, 2].map(|k| {
            let a = mean_attribute(s.color_mean[k], s.color_height[k], g2.total).max(0.0);
            e * (kd * a + spec)
        })
    }
}
