//! Helpers shared by the integration tests: the preset library and its driver images.

use lodestone_core::footprint::Prepared;
use lodestone_core::image_driver::ImageDriver;
use lodestone_core::material::{Driver, Material};
use std::sync::Arc;

/// Prepare a preset, decoding its driver image (relative to presets/) when it has one.
pub fn prepare(path: &str, m: &Material) -> Prepared {
    let image = match &m.driver {
        Driver::Image { path: img, .. } => {
            let file = std::path::Path::new(path).parent().unwrap().join(img);
            let luma = image::open(&file)
                .unwrap_or_else(|e| panic!("{path}: driver image {}: {e}", file.display()))
                .to_luma32f();
            let (w, h) = luma.dimensions();
            Some(Arc::new(
                ImageDriver::new(w as usize, h as usize, luma.as_raw()).unwrap(),
            ))
        }
        Driver::Noise(_) => None,
    };
    Prepared::with_image(m, image, None).unwrap_or_else(|e| panic!("{path}: {e}"))
}

pub fn presets() -> Vec<(String, String)> {
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
