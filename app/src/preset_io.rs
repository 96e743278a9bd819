//! Reading and writing preset files, shared by the command line and the editor.
//!
//! Saves are atomic: the text goes to a temporary file beside the target, is flushed to disk, then
//! renamed over the target, so a crash mid-save never leaves a truncated preset.

use lodestone_core::driver::DriverError;
use lodestone_core::driver::image::ImageDriver;
use lodestone_core::eval::Evaluator;
use lodestone_core::material::environment::{Environment, EnvironmentSource, EquirectMap};
use lodestone_core::material::{Driver, Material, MaterialError};
use lodestone_core::math::sh::Sh9;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The built-in default preset.
pub const DEFAULT_PRESET: &str = include_str!("../../presets/default.ron");

/// Why a preset could not be loaded or saved. (The wrapped errors are part of the message, not a
/// `source`, so `{:#}` chains do not print them twice.)
#[derive(Debug, thiserror::Error)]
pub enum PresetError {
    /// The file cannot be read.
    #[error("cannot read {path}: {error}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        error: std::io::Error,
    },
    /// The file is not a valid material (line and column inside).
    #[error("{path}: {error}")]
    Material {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        error: MaterialError,
    },
    /// The material's image driver cannot be used.
    #[error("{preset}: driver image {image}: {reason}")]
    Image {
        /// The preset.
        preset: PathBuf,
        /// The image file, resolved against the preset's folder.
        image: PathBuf,
        /// What is wrong (missing, not an image, too large, not finite).
        reason: String,
    },
    /// The lighting's environment file cannot be used.
    #[error("{preset}: environment {file}: {reason}")]
    Environment {
        /// The preset.
        preset: PathBuf,
        /// The environment file, resolved against the preset's folder.
        file: PathBuf,
        /// What is wrong (missing, not an image, too large, not finite).
        reason: String,
    },
    /// The file cannot be written.
    #[error("cannot save {path}: {error}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The OS error.
        error: std::io::Error,
    },
}

/// The built-in default material.
pub fn default_material() -> Material {
    Material::from_ron(DEFAULT_PRESET).unwrap_or_default()
}

/// Load and validate a preset file.
pub fn load(path: &Path) -> Result<Material, PresetError> {
    load_resolved(path).map(|r| r.material)
}

/// A material together with the decoded image its driver needs (none for a noise driver).
#[derive(Clone, Debug)]
pub struct Resolved {
    /// The material.
    pub material: Material,
    /// The driver image, decoded and mip-mapped.
    pub image: Option<Arc<ImageDriver>>,
    /// The SH9 radiance of the lighting's environment file (before its intensity); `None` without
    /// a file (the procedural sky needs none).
    pub environment: Option<Sh9>,
}

impl Resolved {
    /// A material whose driver needs no file (an image driver's image stays unloaded).
    pub fn without_image(material: Material) -> Self {
        Self {
            material,
            image: None,
            environment: None,
        }
    }

    /// The material's tables and surface, ready for the CPU reference and the GPU.
    pub fn prepare(&self) -> Result<Evaluator, DriverError> {
        let mut p = Evaluator::with_image(&self.material, self.image.clone(), None)?;
        if let Some(sh) = &self.environment {
            p.set_environment_radiance(sh);
        }
        Ok(p)
    }
}

/// Load a preset and, for an image driver, its image (resolved against the preset's folder).
pub fn load_resolved(path: &Path) -> Result<Resolved, PresetError> {
    let text = std::fs::read_to_string(path).map_err(|error| PresetError::Read {
        path: path.to_owned(),
        error,
    })?;
    let material = Material::from_ron(&text).map_err(|error| PresetError::Material {
        path: path.to_owned(),
        error,
    })?;
    let image = driver_image(&material, Some(path))?;
    let environment = environment_file(&material, Some(path))?;
    Ok(Resolved {
        material,
        image,
        environment,
    })
}

/// The SH9 radiance of `material`'s environment file, its path relative to the folder of `preset`;
/// `None` without an environment file.
pub fn environment_file(
    material: &Material,
    preset: Option<&Path>,
) -> Result<Option<Sh9>, PresetError> {
    let Some(Environment {
        source: EnvironmentSource::File { path },
        ..
    }) = &material.lighting.environment
    else {
        return Ok(None);
    };
    let dir = preset.and_then(|p| p.parent()).unwrap_or(Path::new("."));
    let full = dir.join(path);
    load_environment(preset.unwrap_or(Path::new("(unsaved material)")), &full).map(Some)
}

/// Largest side of an environment file (projection reads every texel once).
pub const MAX_ENVIRONMENT_SIDE: u32 = 8192;

/// Load an equirectangular `.exr` or `.hdr` (any format the image crate reads) and project it to SH9.
pub fn load_environment(preset: &Path, file: &Path) -> Result<Sh9, PresetError> {
    let err = |reason: String| PresetError::Environment {
        preset: preset.to_owned(),
        file: file.to_owned(),
        reason,
    };
    let (w, h) = image::image_dimensions(file).map_err(|e| err(e.to_string()))?;
    if w > MAX_ENVIRONMENT_SIDE || h > MAX_ENVIRONMENT_SIDE {
        return Err(err(format!(
            "{w}×{h} is larger than the {MAX_ENVIRONMENT_SIDE}×{MAX_ENVIRONMENT_SIDE} limit"
        )));
    }
    let img = image::open(file)
        .map_err(|e| err(e.to_string()))?
        .to_rgb32f();
    let texels = img.pixels().map(|p| p.0).collect();
    EquirectMap::new(w as usize, h as usize, texels)
        .map(|m| m.sh())
        .map_err(|e| err(e.to_string()))
}

/// The image of `material`'s driver, its path taken relative to the folder of `preset` (the
/// current directory when there is no preset file); `None` for a noise driver.
pub fn driver_image(
    material: &Material,
    preset: Option<&Path>,
) -> Result<Option<Arc<ImageDriver>>, PresetError> {
    let Driver::Image { path: image, .. } = &material.driver else {
        return Ok(None);
    };
    let dir = preset.and_then(|p| p.parent()).unwrap_or(Path::new("."));
    let full = dir.join(image);
    load_image_driver(preset.unwrap_or(Path::new("(unsaved material)")), &full)
        .map(|d| Some(Arc::new(d)))
}

/// Load and check a driver image: it must exist, decode, fit [`ImageDriver::MAX_SIDE`] (checked
/// before decoding) and hold finite values.
pub fn load_image_driver(preset: &Path, image: &Path) -> Result<ImageDriver, PresetError> {
    let err = |reason: String| PresetError::Image {
        preset: preset.to_owned(),
        image: image.to_owned(),
        reason,
    };
    let (w, h) = image::image_dimensions(image).map_err(|e| err(e.to_string()))?;
    let max = ImageDriver::MAX_SIDE as u32;
    if w > max || h > max {
        return Err(err(format!("{w}×{h} is larger than the {max}×{max} limit")));
    }
    let img = image::open(image)
        .map_err(|e| err(e.to_string()))?
        .to_luma32f();
    ImageDriver::new(w as usize, h as usize, img.as_raw()).map_err(|e| err(e.to_string()))
}

/// Write `text` to `path` atomically (temporary file in the same directory, fsync, rename).
pub fn write_atomic(path: &Path, text: &str) -> Result<(), PresetError> {
    let err = |error| PresetError::Write {
        path: path.to_owned(),
        error,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "preset".into());
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(text.as_bytes())?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(err)
}

/// Write the engine bundle of `m` into `dir` (created if needed); returns the files written.
pub fn export_bundle(m: &Resolved, dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    use anyhow::Context;
    let prepared = m.prepare()?;
    let files = lodestone_render::export::bundle(&prepared)?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut written = Vec::new();
    for (name, bytes) in files {
        let p = dir.join(name);
        std::fs::write(&p, bytes).with_context(|| format!("writing {}", p.display()))?;
        written.push(p);
    }
    Ok(written)
}

/// Save a material as a preset (atomically).
pub fn save(path: &Path, m: &Material) -> Result<(), PresetError> {
    write_atomic(path, &m.to_ron())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("lodestone-io-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).expect("temp dir");
        d
    }

    #[test]
    fn save_then_load_round_trips_and_leaves_no_temporaries() {
        let d = scratch("roundtrip");
        let p = d.join("m.ron");
        let mut m = default_material();
        m.heights.sigma_h = 0.123;
        save(&p, &m).expect("save");
        assert_eq!(load(&p).expect("load"), m);
        let names: Vec<_> = std::fs::read_dir(&d)
            .expect("dir")
            .map(|e| e.expect("entry").file_name())
            .collect();
        assert_eq!(names.len(), 1, "{names:?}");
    }

    #[test]
    fn a_failed_save_keeps_the_old_file() {
        let d = scratch("failed");
        let p = d.join("m.ron");
        save(&p, &default_material()).expect("save");
        let before = std::fs::read_to_string(&p).expect("read");
        // A directory in the way of the rename makes the save fail.
        let blocked = d.join("dir.ron");
        std::fs::create_dir_all(blocked.join("x")).expect("dir");
        assert!(save(&blocked, &default_material()).is_err());
        assert_eq!(std::fs::read_to_string(&p).expect("read"), before);
    }

    #[test]
    fn image_drivers_are_checked_on_load() {
        let d = scratch("images");
        let mut m = default_material();
        m.driver = Driver::Image {
            path: "drv.png".into(),
            size: 1.0,
        };
        let p = d.join("img.ron");
        save(&p, &m).expect("save");
        // Missing.
        let e = load(&p).expect_err("missing image").to_string();
        assert!(e.contains("drv.png") && e.contains("img.ron"), "{e}");
        // Not an image.
        std::fs::write(d.join("drv.png"), b"definitely not a png").expect("write");
        let e = load(&p).expect_err("corrupt image").to_string();
        assert!(e.contains("drv.png"), "{e}");
        // A real one.
        image::GrayImage::from_fn(8, 4, |x, y| image::Luma([(x * 30 + y) as u8]))
            .save(d.join("drv.png"))
            .expect("png");
        assert_eq!(load(&p).expect("valid image"), m);
    }

    #[test]
    fn messages_say_it_once() {
        let d = scratch("once");
        let p = d.join("bad.ron");
        std::fs::write(&p, "(version: 1,\n  name: oops").expect("write");
        let e = anyhow::Error::from(load(&p).expect_err("bad"));
        let text = format!("{e:#}");
        assert_eq!(text.matches("line 2").count(), 1, "{text}");
    }

    #[test]
    fn malformed_presets_name_line_and_column() {
        let d = scratch("bad");
        let p = d.join("bad.ron");
        std::fs::write(&p, "(version: 1,\n  name: oops").expect("write");
        let e = load(&p).expect_err("must fail").to_string();
        assert!(e.contains("line 2"), "{e}");
    }
}
