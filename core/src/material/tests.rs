//! Tests of [`super`].

use super::*;
use crate::material::colormap::{ColorStop, Interpolation};

/// A slope colour that changes colour doubles the rule's angles; one colour does not (it
/// must equal the constant term exactly), and neither does a material without one.
#[test]
fn the_slope_rule_follows_the_slope_colour() {
    let text = |name: &str| {
        std::fs::read_to_string(format!(
            "{}/../presets/{name}.ron",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap()
    };
    let snake = Material::from_ron(&text("snake-skin")).unwrap();
    assert_eq!(
        snake.slope_rule(),
        SlopeRule {
            radii: 8,
            angles: 16
        }
    );
    let mut one = snake.clone();
    let t = one.terms.slope.as_mut().unwrap();
    let c = t.color.map.stops[0].color;
    t.color.map.stops.iter_mut().for_each(|s| s.color = c);
    assert_eq!(one.slope_rule(), SlopeRule::square(8));
    let default = Material::from_ron(&text("default")).unwrap();
    assert_eq!(default.slope_rule(), SlopeRule::square(8));
}

#[test]
fn round_trips_through_ron() {
    let m = Material::default();
    let text = m.to_ron();
    let back = Material::from_ron(&text).expect("default material parses");
    assert_eq!(m, back);
}

#[test]
fn parse_errors_have_line_and_column() {
    let text = Material::default()
        .to_ron()
        .replacen("sigma_h: 0.05", "sigma_h: oops", 1);
    match Material::from_ron(&text) {
        Err(MaterialError::Parse { line, column, .. }) => {
            assert!(line > 1 && column > 1, "{line}:{column}")
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
    let unknown = Material::default()
        .to_ron()
        .replacen("sigma_h:", "sigma_hh: 1.0, sigma_h:", 1);
    assert!(matches!(
        Material::from_ron(&unknown),
        Err(MaterialError::Parse { .. })
    ));
}

/// Unknown fields inside enum variants are refused like those of structs (#16: a `sorce:` typo
/// in a Gradient was dropped, silently changing the colour source). Each case parses without
/// its unknown field.
#[test]
fn unknown_fields_inside_enum_variants_are_parse_errors() {
    let base = r#"Material(version: 1, name: "a", driver: DRIVER, heights: (sigma_h: 0.05),
        slopes: (sigma_nx: 0.3, sigma_ny: 0.3), color: COLOR, LIGHTING
        brdf: (albedo: 1.0, specular: 0.04, roughness: 0.2))"#;
    let noise = "Noise(())";
    let attribute = "Attribute(mean: (0.3, 0.3, 0.3), correlation: (0.1, 0.1, 0.1)EXTRA)";
    let gradient =
        "Gradient(map: (stops: [(position: 0.0, color: (0.5, 0.5, 0.5))]), source: Height)";
    let text = |driver: &str, color: &str, lighting: &str| {
        base.replace("DRIVER", driver)
            .replace("COLOR", color)
            .replace("LIGHTING", lighting)
    };
    let file = "lighting: (environment: Some((source: File(path: \"sky.exr\"EXTRA)))),";
    let cases = [
        (
            "Attribute(colour:)",
            text(noise, attribute, ""),
            ", colour: 1.0",
        ),
        (
            "Image(sise:)",
            text(
                "Image(path: \"x.png\", size: 1.0EXTRA)",
                &attribute.replace("EXTRA", ""),
                "",
            ),
            ", sise: 2.0",
        ),
        (
            "File(pth:)",
            text(noise, &attribute.replace("EXTRA", ""), file),
            ", pth: 1",
        ),
        (
            "Gradient(sorce:)",
            text(noise, &gradient.replace("source", "EXTRAsource"), ""),
            "sorce: Driver, ",
        ),
    ];
    for (what, template, extra) in cases {
        let good = template.replace("EXTRA", "");
        assert!(
            Material::from_ron(&good).is_ok(),
            "{what} without the field: {:?}",
            Material::from_ron(&good)
        );
        match Material::from_ron(&template.replace("EXTRA", extra)) {
            Err(MaterialError::Parse { line, message, .. }) => {
                assert!(line >= 1 && message.contains("field"), "{what}: {message}")
            }
            other => panic!("{what}: expected a parse error, got {other:?}"),
        }
    }
}

#[test]
fn newer_versions_are_refused() {
    let text = Material::default()
        .to_ron()
        .replacen("version: 1", "version: 99", 1);
    assert!(matches!(
        Material::from_ron(&text),
        Err(MaterialError::TooNew { found: 99, .. })
    ));
}

#[test]
fn validation_reports_every_invalid_field() {
    let mut m = Material::default();
    m.heights.sigma_h = -1.0;
    m.slopes.sigma_nx = f64::NAN;
    m.brdf.albedo = 2.0;
    m.filtering.table.size_m = 1;
    m.color = ColorModel::Gradient {
        map: Gradient {
            stops: vec![
                ColorStop {
                    position: 1.0,
                    color: [0.1; 3],
                },
                ColorStop {
                    position: 0.0,
                    color: [0.2; 3],
                },
            ],
            interpolation: Interpolation::Linear,
        },
        source: ColorSource::Driver,
    };
    let problems = m.validate().unwrap_err();
    let fields: Vec<_> = problems.iter().map(|p| p.field.as_str()).collect();
    for f in [
        "heights.sigma_h",
        "slopes.sigma_nx",
        "brdf.albedo",
        "filtering.table.size_m",
        "color.map.stops[1].position",
    ] {
        assert!(fields.contains(&f), "{f} missing from {fields:?}");
    }
    assert_eq!(problems.len(), 5);
    // Tables the GPU could not bind are refused at once, not after minutes of building.
    let mut big = Material::default();
    big.filtering.table.size_sigma = 4096;
    let problems = big.validate().unwrap_err();
    assert_eq!(problems.len(), 1);
    assert_eq!(problems[0].field, "filtering.table.size_sigma");
    // Work that grows with the input is bounded: stops, curve points, slopes (#16).
    let mut many = Material {
        color: ColorModel::Gradient {
            map: Gradient {
                stops: (0..=Gradient::MAX_STOPS)
                    .map(|i| ColorStop {
                        position: i as f64,
                        color: [0.5; 3],
                    })
                    .collect(),
                interpolation: Interpolation::Linear,
            },
            source: ColorSource::Driver,
        },
        ..Material::default()
    };
    many.heights.transfer = TransferFunction::Curve(crate::microfacet::transfer::Curve {
        points: (0..=crate::microfacet::transfer::Curve::MAX_POINTS)
            .map(|i| [i as f64 * 0.01, i as f64 * 0.01])
            .collect(),
        interpolation: crate::microfacet::transfer::CurveInterpolation::Linear,
    });
    many.slopes.sigma_ny = MAX_SLOPE_SIGMA * 1.01;
    let problems = many.validate().unwrap_err();
    let fields: Vec<_> = problems.iter().map(|p| p.field.as_str()).collect();
    assert_eq!(
        fields,
        [
            "heights.transfer.points",
            "slopes.sigma_ny",
            "color.map.stops"
        ],
        "{problems:?}"
    );
    many.slopes.sigma_ny = MAX_SLOPE_SIGMA;
    assert_eq!(many.validate().unwrap_err().len(), 2);
}

#[test]
fn noise_has_the_materials_statistics() {
    let m = Material::default();
    let n = m.noise().unwrap();
    let g = n.gradient_cov().scaled(m.heights.sigma_h);
    assert!((g.xx.sqrt() - 0.35).abs() < 1e-9 && (g.yy.sqrt() - 0.35).abs() < 1e-9);
}
