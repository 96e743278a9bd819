//! Materials and a far patch shared by the tests and the measurements (`core/tests/measurements/`):
//! fixtures, not part of the model.

use crate::material::Material;

use crate::driver::noise::NoiseParams;
use crate::material::colormap::Gradient;
use crate::material::{ColorModel, ColorSource, Heights, Slopes};
use crate::microfacet::brdf::BaseBrdf;
use crate::microfacet::transfer::TransferFunction;

/// A Gaussian, height-correlated material: identity transfer, colour map of the driver (= height).
pub fn gaussian_material() -> Material {
    Material {
        name: "test: Gaussian height-correlated".into(),
        driver: crate::material::Driver::Noise(NoiseParams {
            components: 32,
            ..NoiseParams::default()
        }),
        heights: Heights {
            sigma_h: 0.1,
            transfer: TransferFunction::Identity,
        },
        slopes: Slopes {
            sigma_nx: 0.5,
            sigma_ny: 0.5,
        },
        color: ColorModel::Gradient {
            map: Gradient::rust(-2.0, 2.0),
            source: ColorSource::Driver,
        },
        brdf: BaseBrdf {
            albedo: 1.0,
            specular: 0.0,
            roughness: 0.1,
            measured: None,
        },
        ..Material::default()
    }
}

/// The far patch the evaluation tests share: a 40-unit isotropic footprint at (3, −7).
pub fn far_patch(wo: glam::DVec3, wi: glam::DVec3) -> crate::eval::FootprintQuery {
    crate::eval::FootprintQuery {
        wo,
        wi,
        x0: glam::DVec2::new(3.0, -7.0),
        footprint: crate::driver::footprint::Footprint::isotropic(40.0),
    }
}

/// A preset of the library by name (`"moss"`), parsed.
pub fn preset(name: &str) -> Material {
    let text = std::fs::read_to_string(format!(
        "{}/../presets/{name}.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("preset");
    Material::from_ron(&text).expect("valid")
}
