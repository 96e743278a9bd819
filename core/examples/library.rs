//! Print one of the generated presets of the library as RON (the curves of these come from code, so
//! the files are regenerated rather than hand-edited):
//! `cargo run -p lodestone-core --example library -- NAME > presets/NAME.ron`
//! for NAME in sponge, terraces, bumpy-specular, colormapped-noise, cobblestones.

use lodestone_core::driver::noise::NoiseParams;
use lodestone_core::material::colormap::{ColorStop, Gradient, Interpolation};
use lodestone_core::material::{ColorModel, ColorSource, Driver, Heights, Material, Slopes};
use lodestone_core::microfacet::brdf::BaseBrdf;
use lodestone_core::microfacet::transfer::{Curve, TransferFunction};

fn preset(name: &str) -> Option<(&'static str, Material)> {
    let base = Material::default();
    Some(match name {
        "sponge" => (
            "Sponge [HNPN14 Figs. 11–12]: a flat top pierced by steep pits (transfer function), coloured by height.",
            Material {
                name: "Sponge (transfer function)".into(),
                driver: Driver::Noise(NoiseParams {
                    seed: 5,
                    components: 64,
                    ..NoiseParams::default()
                }),
                heights: Heights {
                    sigma_h: 0.06,
                    transfer: TransferFunction::Curve(Curve::sponge()),
                },
                slopes: Slopes {
                    sigma_nx: 0.45,
                    sigma_ny: 0.45,
                },
                color: ColorModel::Gradient {
                    map: Gradient {
                        stops: vec![
                            ColorStop {
                                position: -2.0,
                                color: [0.05, 0.03, 0.01],
                            },
                            ColorStop {
                                position: -0.5,
                                color: [0.35, 0.22, 0.06],
                            },
                            ColorStop {
                                position: 0.5,
                                color: [0.80, 0.62, 0.25],
                            },
                        ],
                        interpolation: Interpolation::Smooth,
                    },
                    source: ColorSource::Height,
                },
                brdf: BaseBrdf {
                    albedo: 1.0,
                    specular: 0.02,
                    roughness: 0.3,
                    measured: None,
                },
                ..base
            },
        ),
        "terraces" => (
            "Terraces [HNPN14 Sec. 7]: flat shelves joined by steep risers; a step colour map by height.",
            Material {
                name: "Terraces (transfer function)".into(),
                driver: Driver::Noise(NoiseParams {
                    seed: 9,
                    octaves: 2,
                    ..NoiseParams::default()
                }),
                heights: Heights {
                    sigma_h: 0.08,
                    transfer: TransferFunction::Curve(Curve::terraces(4)),
                },
                slopes: Slopes {
                    sigma_nx: 0.3,
                    sigma_ny: 0.3,
                },
                color: ColorModel::Gradient {
                    map: Gradient::terrain(-1.5, 1.5),
                    source: ColorSource::Height,
                },
                ..base
            },
        ),
        "bumpy-specular" => (
            "A bumpy specular surface [HN12 Fig. 12]: sharp glints up close turn into a rough, wide lobe at \
             distance (σ² = σ_n0² + σ_n²); the naive view keeps the sharp lobe and gets it wrong.",
            Material {
                name: "Bumpy specular".into(),
                heights: Heights {
                    sigma_h: 0.03,
                    transfer: TransferFunction::Identity,
                },
                slopes: Slopes {
                    sigma_nx: 0.3,
                    sigma_ny: 0.3,
                },
                color: ColorModel::Gradient {
                    map: Gradient::two(-2.0, [0.02, 0.02, 0.025], 2.0, [0.06, 0.06, 0.07]),
                    source: ColorSource::Driver,
                },
                brdf: BaseBrdf {
                    albedo: 1.0,
                    specular: 0.6,
                    roughness: 0.04,
                    measured: None,
                },
                ..base
            },
        ),
        "colormapped-noise" => (
            "Colour-mapped noise [HNPN14 Figs. 4–5]: a flat surface (σ_h = 0) whose colour is a sharp map of the \
             driver; filtering the driver then mapping (naive) loses the map's detail, the pre-convolved table keeps it.",
            Material {
                name: "Colour-mapped noise".into(),
                driver: Driver::Noise(NoiseParams {
                    seed: 21,
                    components: 64,
                    octaves: 4,
                    gain: 0.6,
                    frequency: 2.0,
                    ..NoiseParams::default()
                }),
                heights: Heights {
                    sigma_h: 0.0,
                    transfer: TransferFunction::Identity,
                },
                slopes: Slopes {
                    sigma_nx: 0.0,
                    sigma_ny: 0.0,
                },
                color: ColorModel::Gradient {
                    map: Gradient {
                        stops: vec![
                            ColorStop {
                                position: -0.5,
                                color: [0.02, 0.05, 0.25],
                            },
                            ColorStop {
                                position: -0.2,
                                color: [0.9, 0.85, 0.7],
                            },
                            ColorStop {
                                position: 0.2,
                                color: [0.9, 0.85, 0.7],
                            },
                            ColorStop {
                                position: 0.5,
                                color: [0.6, 0.05, 0.02],
                            },
                        ],
                        interpolation: Interpolation::Constant,
                    },
                    source: ColorSource::Driver,
                },
                brdf: BaseBrdf {
                    albedo: 1.0,
                    specular: 0.0,
                    roughness: 0.2,
                    measured: None,
                },
                ..base
            },
        ),
        "cobblestones" => (
            "Cobblestones [HNPN14 Fig. 6]: explicit, non-Gaussian data (an image driver: flat-topped stones, a \
             tail of mortar; skewness -0.27, excess kurtosis -0.78) filtered with the Gaussian approximation. \
             The image is written by `cargo run -p lodestone --example cobblestones`.",
            Material {
                name: "Cobblestones (image driver)".into(),
                driver: Driver::Image {
                    path: "images/cobblestones.png".into(),
                    size: 1.0,
                },
                heights: Heights {
                    sigma_h: 0.004,
                    transfer: TransferFunction::Identity,
                },
                // Image drivers take their slopes from the image; these are not used.
                slopes: Slopes {
                    sigma_nx: 0.3,
                    sigma_ny: 0.3,
                },
                color: ColorModel::Gradient {
                    map: Gradient {
                        stops: vec![
                            ColorStop {
                                position: -3.0,
                                color: [0.03, 0.025, 0.02],
                            },
                            ColorStop {
                                position: -1.6,
                                color: [0.09, 0.07, 0.05],
                            },
                            ColorStop {
                                position: -0.9,
                                color: [0.35, 0.3, 0.24],
                            },
                            ColorStop {
                                position: 0.3,
                                color: [0.5, 0.46, 0.4],
                            },
                            ColorStop {
                                position: 1.4,
                                color: [0.75, 0.68, 0.55],
                            },
                        ],
                        interpolation: Interpolation::Linear,
                    },
                    source: ColorSource::Driver,
                },
                brdf: BaseBrdf {
                    albedo: 1.0,
                    specular: 0.04,
                    roughness: 0.25,
                    measured: None,
                },
                ..base
            },
        ),
        _ => return None,
    })
}

fn main() {
    let name = std::env::args().nth(1).unwrap_or_default();
    match preset(&name) {
        Some((comment, m)) => {
            println!("// {comment}");
            println!(
                "// Generated: cargo run -p lodestone-core --example library -- {name} > presets/{name}.ron"
            );
            println!("{}", m.to_ron());
        }
        None => {
            eprintln!(
                "usage: library sponge|terraces|bumpy-specular|colormapped-noise|cobblestones"
            );
            std::process::exit(2);
        }
    }
}
