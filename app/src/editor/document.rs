//! The document being edited: the material, its undo history, the file it came from and what was
//! last saved there, and the files it references (driver image, environment map), each loaded once
//! per resolved path.

use super::history::History;
use crate::preset_io;
use lodestone_core::driver::image::ImageDriver;
use lodestone_core::material::environment::{Environment, EnvironmentSource};
use lodestone_core::material::{Driver, Material};
use lodestone_core::math::sh::Sh9;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A material with its history and file.
#[derive(Debug)]
pub struct Document {
    /// The material as edited.
    pub material: Material,
    /// The material as last saved or opened (unsaved changes are the difference).
    pub saved: Material,
    /// The file it came from or was saved to.
    pub path: Option<PathBuf>,
    /// Undo and redo.
    pub history: History,
    /// The driver image: resolved path and what loading it gave (cached; reloaded when the path
    /// or the preset's folder changes).
    image: Option<(PathBuf, Result<Arc<ImageDriver>, String>)>,
    /// The lighting's environment file: resolved path and its SH9 radiance (cached likewise).
    environment: Option<(PathBuf, Result<Sh9, String>)>,
}

/// The files a document references, as loaded: what loaded, and the failures that are new since
/// the last call (each failure is reported once per path).
#[derive(Debug, Default)]
pub struct LoadedFiles {
    /// The driver image (image drivers whose file loaded).
    pub image: Option<Arc<ImageDriver>>,
    /// The environment file's SH9 radiance.
    pub environment: Option<Sh9>,
    /// Failures loaded just now.
    pub new_errors: Vec<String>,
}

/// A file loaded once per resolved path: the cache's result when `full` is the cached path, else
/// `load()` (stored). Returns the result and whether it was loaded just now.
fn cached_load<T: Clone>(
    cache: &mut Option<(PathBuf, Result<T, String>)>,
    full: PathBuf,
    load: impl FnOnce() -> Result<T, String>,
) -> (Result<T, String>, bool) {
    let fresh = cache.as_ref().is_none_or(|(p, _)| *p != full);
    if fresh {
        *cache = Some((full, load()));
    }
    let r = cache
        .as_ref()
        .map_or_else(|| Err("not loaded".to_owned()), |(_, r)| r.clone());
    (r, fresh)
}

impl Document {
    /// A document of `material`, last saved as `saved` at `path`.
    pub fn new(material: Material, saved: Material, path: Option<PathBuf>) -> Self {
        Self {
            history: History::new(&material),
            material,
            saved,
            path,
            image: None,
            environment: None,
        }
    }

    /// Replace the material (a file opened at `path`, or a new material without one): the history
    /// restarts and the material counts as saved.
    pub fn replace(&mut self, material: Material, path: Option<PathBuf>) {
        self.history.reset(&material);
        self.saved = material.clone();
        self.material = material;
        self.path = path;
    }

    /// Record that the material was saved to `path`.
    pub fn mark_saved(&mut self, path: &Path) {
        self.saved = self.material.clone();
        self.path = Some(path.to_owned());
    }

    /// Whether the material differs from the file.
    pub fn dirty(&self) -> bool {
        self.material != self.saved
    }

    /// Undo one step.
    pub fn undo(&mut self) -> bool {
        self.history.undo(&mut self.material)
    }

    /// Redo one step.
    pub fn redo(&mut self) -> bool {
        self.history.redo(&mut self.material)
    }

    /// The folder the material's files are relative to: the preset's, or the current directory
    /// for an unsaved material.
    pub fn dir(&self) -> PathBuf {
        self.path
            .as_ref()
            .and_then(|p| p.parent())
            .unwrap_or(Path::new("."))
            .to_owned()
    }

    /// The loaded driver image, when the material has an image driver and its file loaded.
    pub fn driver_image(&self) -> Option<Arc<ImageDriver>> {
        match (&self.material.driver, &self.image) {
            (Driver::Image { .. }, Some((_, Ok(img)))) => Some(img.clone()),
            _ => None,
        }
    }

    /// The driver image and environment radiance, from the cache unless a path changed (cheap
    /// enough for every frame: nothing is cloned but the `Arc`).
    pub fn load_files(&mut self) -> LoadedFiles {
        let dir = self.dir();
        let (material, preset) = (&self.material, self.path.as_deref());
        let image = match &material.driver {
            Driver::Noise(_) => None,
            Driver::Image { path, .. } => {
                Some(cached_load(&mut self.image, dir.join(path), || {
                    preset_io::driver_image(material, preset)
                        .map_err(|e| e.to_string())
                        .and_then(|i| i.ok_or_else(|| "no image".to_owned()))
                }))
            }
        };
        let environment = match &material.lighting.environment {
            Some(Environment {
                source: EnvironmentSource::File { path },
                ..
            }) => Some(cached_load(&mut self.environment, dir.join(path), || {
                preset_io::environment_file(material, preset)
                    .map_err(|e| e.to_string())
                    .and_then(|i| i.ok_or_else(|| "no environment".to_owned()))
            })),
            _ => None,
        };
        let mut loaded = LoadedFiles::default();
        loaded.image = image.and_then(|r| take(r, &mut loaded.new_errors));
        loaded.environment = environment.and_then(|r| take(r, &mut loaded.new_errors));
        loaded
    }
}

/// The value of a [`cached_load`]; a fresh failure goes to `errors`.
fn take<T>(r: (Result<T, String>, bool), errors: &mut Vec<String>) -> Option<T> {
    match r {
        (Ok(v), _) => Some(v),
        (Err(e), fresh) => {
            if fresh {
                errors.push(e);
            }
            None
        }
    }
}
