//! Whole objects with procedural micro-relief (#19, [HN12]): a closed base shape given by its
//! signed distance ([`base_shape`]), displaced by the material's relief extended to space
//! ([`solid_noise`], [`displaced`]). What the object views' ground truth traces; the voxel octree
//! and its cone tracing [HN12 Secs. 4–5] are built from it.

pub mod base_shape;
pub mod cone_trace;
pub mod coverage_mask;
pub mod cube_section;
pub mod displaced;
pub mod dolly;
pub mod icosphere;
pub mod mesh;
pub mod object_truth;
pub mod octree;
pub mod shading;
pub mod solid_noise;
pub mod surface_samples;
pub mod triangle;
pub mod view_error;
pub mod voxel_field;
pub mod voxel_stats;

/// The module tests' bumpy material: the default preset with σ_h = 0.02 and isotropic slope std
/// `slope_std` (a relief well within a unit shape's quarter radius).
#[cfg(test)]
pub(crate) fn bumpy_material(slope_std: f64) -> crate::material::Material {
    let mut m = crate::material::Material::default();
    m.heights.sigma_h = 0.02;
    m.slopes.sigma_nx = slope_std;
    m.slopes.sigma_ny = slope_std;
    m
}

/// A cube of side 2 centred on the origin as OBJ text (quads, counter-clockwise seen from
/// outside; tobj triangulates them), for the module's tests.
#[cfg(test)]
pub(crate) fn cube_obj() -> String {
    let mut s = String::new();
    for z in [-1.0, 1.0] {
        for y in [-1.0, 1.0] {
            for x in [-1.0, 1.0] {
                s += &format!("v {x} {y} {z}\n");
            }
        }
    }
    for f in [
        "1 3 4 2", "5 6 8 7", "1 2 6 5", "3 7 8 4", "1 5 7 3", "2 4 8 6",
    ] {
        s += &format!("f {f}\n");
    }
    s
}

/// The camera of the module's tests: 60° from the pole, azimuth 30°, a 30° field of view, looking
/// at the origin from `distance`.
#[cfg(test)]
pub(crate) fn test_camera(distance: f64) -> crate::scene::camera::Camera {
    crate::scene::camera::Camera {
        elevation_deg: 60.0,
        azimuth_deg: 30.0,
        distance,
        target: [0.0, 0.0],
        fov_deg: 30.0,
    }
}

/// The central-difference gradient of `f` at p with step e (for the module's tests).
#[cfg(test)]
pub(crate) fn central_gradient(
    f: impl Fn(glam::DVec3) -> f64,
    p: glam::DVec3,
    e: f64,
) -> glam::DVec3 {
    use glam::DVec3;
    DVec3::new(
        f(p + DVec3::X * e) - f(p - DVec3::X * e),
        f(p + DVec3::Y * e) - f(p - DVec3::Y * e),
        f(p + DVec3::Z * e) - f(p - DVec3::Z * e),
    ) / (2.0 * e)
}
