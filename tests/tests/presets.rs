//! Every preset in presets/ loads, validates and round-trips (load → save → load gives an equal value).

use lodestone_core::footprint::{Config, Prepared};
use lodestone_core::material::Material;
use lodestone_core::smith::direction;

fn presets() -> Vec<(String, String)> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../presets");
    let mut out = vec![];
    for entry in std::fs::read_dir(&dir).expect("presets/ exists") {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "ron") {
            out.push((
                path.display().to_string(),
                std::fs::read_to_string(&path).unwrap(),
            ));
        }
    }
    out.sort();
    out
}

#[test]
fn every_preset_loads_validates_and_round_trips() {
    let all = presets();
    assert!(
        all.len() >= 4,
        "expected the preset library, found {}",
        all.len()
    );
    for (path, text) in all {
        let m = Material::from_ron(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
        let again =
            Material::from_ron(&m.to_ron()).unwrap_or_else(|e| panic!("{path} after saving: {e}"));
        assert_eq!(m, again, "{path} does not round-trip");
    }
}

#[test]
fn every_preset_evaluates_finite() {
    for (path, text) in presets() {
        let m = Material::from_ron(&text).unwrap();
        let p = Prepared::new(&m).unwrap_or_else(|e| panic!("{path}: {e}"));
        for deg in [0.0_f64, 60.0, 89.0] {
            let cfg = Config::far(&p, direction(deg.to_radians(), 0.2), direction(0.6, 2.0));
            for v in [
                p.naive(&cfg),
                p.view_independent(&cfg),
                p.filtered(&cfg),
                p.ground_truth(&cfg, 200, 1).mean,
            ] {
                assert!(
                    v.iter().all(|c| c.is_finite() && *c >= 0.0),
                    "{path} at {deg}°: {v:?}"
                );
            }
        }
    }
}

#[test]
fn default_preset_is_the_core_default() {
    let text = include_str!("../../presets/default.ron");
    assert_eq!(Material::from_ron(text).unwrap(), Material::default());
}
