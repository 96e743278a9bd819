//! The document being edited: the material, its undo history, the file it came from and what was
//! last saved there, and the files it references (driver image, environment map, measured BRDF),
//! each loaded once
//! per resolved path on a thread of its own (a 1 GiB image or an 8192² environment decodes for
//! seconds; the window keeps painting meanwhile).

use super::history::History;
use crate::preset_io;
use lodestone_core::driver::image::ImageDriver;
use lodestone_core::material::environment::{Environment, EnvironmentSource};
use lodestone_core::material::measured::MeasuredBrdf;
use lodestone_core::material::{Driver, Material};
use lodestone_core::math::sh::Sh9;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError, channel};

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
    image: Option<Slot<Arc<ImageDriver>>>,
    /// The lighting's environment file: resolved path and its SH9 radiance (cached likewise).
    environment: Option<Slot<Sh9>>,
    /// The base BRDF's measured file: resolved path, its table and fit (cached likewise).
    measured: Option<Slot<Arc<MeasuredBrdf>>>,
}

/// A referenced file: being loaded on its own thread, or loaded (or failed).
#[derive(Debug)]
enum Slot<T> {
    Loading(PathBuf, Receiver<Result<T, String>>),
    Done(PathBuf, Result<T, String>),
}

impl<T> Slot<T> {
    fn path(&self) -> &Path {
        match self {
            Self::Loading(p, _) | Self::Done(p, _) => p,
        }
    }
}

/// Where a [`cached_load`] stands.
enum Load<T> {
    /// Still loading.
    Pending,
    /// Loaded (or failed), and whether just now.
    Ready(Result<T, String>, bool),
}

/// The files a document references, as loaded: what loaded, and the failures that are new since
/// the last call (each failure is reported once per path).
#[derive(Debug, Default)]
pub struct LoadedFiles {
    /// The driver image (image drivers whose file loaded).
    pub image: Option<Arc<ImageDriver>>,
    /// The environment file's SH9 radiance.
    pub environment: Option<Sh9>,
    /// The measured base BRDF.
    pub measured: Option<Arc<MeasuredBrdf>>,
    /// Failures loaded just now.
    pub new_errors: Vec<String>,
    /// Files still loading (resolved paths): the material cannot be rendered yet.
    pub pending: Vec<PathBuf>,
}

/// A file loaded once per resolved path: the cache's result when `full` is the cached path, else
/// `load()` started on a thread of its own (its result is picked up by a later call).
fn cached_load<T: Clone + Send + 'static>(
    cache: &mut Option<Slot<T>>,
    full: PathBuf,
    load: impl FnOnce() -> Result<T, String> + Send + 'static,
) -> Load<T> {
    if cache.as_ref().is_none_or(|c| c.path() != full) {
        let (tx, rx) = channel();
        let spawned = std::thread::Builder::new()
            .name("lodestone-load".into())
            .spawn(move || {
                let _ = tx.send(load());
            });
        *cache = Some(match spawned {
            Ok(_) => Slot::Loading(full.clone(), rx),
            Err(e) => Slot::Done(full.clone(), Err(format!("cannot start loading: {e}"))),
        });
    }
    let slot = cache.take().expect("set above");
    let (slot, out) = match slot {
        Slot::Loading(p, rx) => match rx.try_recv() {
            Ok(r) => (Slot::Done(p, r.clone()), Load::Ready(r, true)),
            Err(TryRecvError::Empty) => (Slot::Loading(p, rx), Load::Pending),
            Err(TryRecvError::Disconnected) => {
                let r = Err(format!("loading {} failed", p.display()));
                (Slot::Done(p, r.clone()), Load::Ready(r, true))
            }
        },
        Slot::Done(p, r) => {
            let out = Load::Ready(r.clone(), false);
            (Slot::Done(p, r), out)
        }
    };
    *cache = Some(slot);
    out
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
            measured: None,
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
            (Driver::Image { .. }, Some(Slot::Done(_, Ok(img)))) => Some(img.clone()),
            _ => None,
        }
    }

    /// The loaded measured BRDF, when the material names one and its file loaded.
    pub fn measured(&self) -> Option<Arc<MeasuredBrdf>> {
        match (&self.material.brdf.measured, &self.measured) {
            (Some(_), Some(Slot::Done(_, Ok(m)))) => Some(m.clone()),
            _ => None,
        }
    }

    /// The driver image and environment radiance, from the cache unless a path changed (cheap
    /// enough for every frame: nothing is cloned but the `Arc`).
    pub fn load_files(&mut self) -> LoadedFiles {
        let dir = self.dir();
        let (material, preset) = (&self.material, self.path.as_deref());
        let (m, p) = (material.clone(), preset.map(Path::to_owned));
        let image = match &material.driver {
            Driver::Noise(_) => None,
            Driver::Image { path, .. } => {
                let full = dir.join(path);
                Some((
                    full.clone(),
                    cached_load(&mut self.image, full, move || {
                        preset_io::driver_image(&m, p.as_deref())
                            .map_err(|e| e.to_string())
                            .and_then(|i| i.ok_or_else(|| "no image".to_owned()))
                    }),
                ))
            }
        };
        let (m, p) = (material.clone(), preset.map(Path::to_owned));
        let environment = match &material.lighting.environment {
            Some(Environment {
                source: EnvironmentSource::File { path },
                ..
            }) => {
                let full = dir.join(path);
                Some((
                    full.clone(),
                    cached_load(&mut self.environment, full, move || {
                        preset_io::environment_file(&m, p.as_deref())
                            .map_err(|e| e.to_string())
                            .and_then(|i| i.ok_or_else(|| "no environment".to_owned()))
                    }),
                ))
            }
            _ => None,
        };
        let (m, p) = (material.clone(), preset.map(Path::to_owned));
        let measured = material.brdf.measured.as_ref().map(|path| {
            let full = dir.join(path);
            (
                full.clone(),
                cached_load(&mut self.measured, full, move || {
                    preset_io::measured_file(&m, p.as_deref())
                        .map_err(|e| e.to_string())
                        .and_then(|i| i.ok_or_else(|| "no measured BRDF".to_owned()))
                }),
            )
        });
        let mut loaded = LoadedFiles::default();
        loaded.image = image.and_then(|r| loaded.take(r));
        loaded.environment = environment.and_then(|r| loaded.take(r));
        loaded.measured = measured.and_then(|r| loaded.take(r));
        loaded
    }
}

impl LoadedFiles {
    /// The value of a [`cached_load`] of `path`; a fresh failure goes to `new_errors`, a file
    /// still loading to `pending`.
    fn take<T>(&mut self, (path, load): (PathBuf, Load<T>)) -> Option<T> {
        match load {
            Load::Pending => {
                self.pending.push(path);
                None
            }
            Load::Ready(Ok(v), _) => Some(v),
            Load::Ready(Err(e), fresh) => {
                if fresh {
                    self.new_errors.push(e);
                }
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    /// A slow file does not block: the first call starts it and returns Pending at once, a later
    /// call gets it (fresh, then cached), and a new path starts a new load.
    #[test]
    fn a_slow_load_runs_on_its_own_thread() {
        let mut cache: Option<Slot<u32>> = None;
        let slow = |v: u32| {
            move || {
                std::thread::sleep(Duration::from_millis(300));
                Ok(v)
            }
        };
        let t0 = Instant::now();
        assert!(matches!(
            cached_load(&mut cache, "a".into(), slow(1)),
            Load::Pending
        ));
        assert!(
            t0.elapsed() < Duration::from_millis(200),
            "{:?}",
            t0.elapsed()
        );
        let got = loop {
            match cached_load(&mut cache, "a".into(), slow(99)) {
                Load::Pending => std::thread::sleep(Duration::from_millis(5)),
                Load::Ready(r, fresh) => break (r, fresh),
            }
        };
        assert_eq!(got, (Ok(1), true));
        assert!(matches!(
            cached_load(&mut cache, "a".into(), slow(99)),
            Load::Ready(Ok(1), false)
        ));
        assert!(matches!(
            cached_load(&mut cache, "b".into(), slow(2)),
            Load::Pending
        ));
        // A loader that panics is a failure, not a hang.
        let mut cache: Option<Slot<u32>> = None;
        let _ = cached_load(&mut cache, "c".into(), || panic!("decoder bug"));
        let t0 = Instant::now();
        loop {
            match cached_load(&mut cache, "c".into(), || Ok(0)) {
                Load::Pending => {
                    assert!(t0.elapsed() < Duration::from_secs(10));
                    std::thread::sleep(Duration::from_millis(5));
                }
                Load::Ready(r, _) => {
                    assert!(r.is_err());
                    break;
                }
            }
        }
    }
}
