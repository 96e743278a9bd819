//! Reading and writing preset files, shared by the command line and the editor.
//!
//! Saves are atomic: the text goes to a temporary file beside the target, is flushed to disk, then
//! renamed over the target, so a crash mid-save never leaves a truncated preset.

use lodestone_core::material::{Material, MaterialError};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The built-in default preset.
pub const DEFAULT_PRESET: &str = include_str!("../../presets/default.ron");

/// Why a preset could not be loaded or saved.
#[derive(Debug, thiserror::Error)]
pub enum PresetError {
    /// The file cannot be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not a valid material (line and column inside).
    #[error("{path}: {source}")]
    Material {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        source: MaterialError,
    },
    /// The file cannot be written.
    #[error("cannot save {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
}

/// The built-in default material.
pub fn default_material() -> Material {
    Material::from_ron(DEFAULT_PRESET).unwrap_or_default()
}

/// Load and validate a preset file.
pub fn load(path: &Path) -> Result<Material, PresetError> {
    let text = std::fs::read_to_string(path).map_err(|source| PresetError::Read {
        path: path.to_owned(),
        source,
    })?;
    Material::from_ron(&text).map_err(|source| PresetError::Material {
        path: path.to_owned(),
        source,
    })
}

/// Write `text` to `path` atomically (temporary file in the same directory, fsync, rename).
pub fn write_atomic(path: &Path, text: &str) -> Result<(), PresetError> {
    let err = |source| PresetError::Write {
        path: path.to_owned(),
        source,
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
    fn malformed_presets_name_line_and_column() {
        let d = scratch("bad");
        let p = d.join("bad.ron");
        std::fs::write(&p, "(version: 1,\n  name: oops").expect("write");
        let e = load(&p).expect_err("must fail").to_string();
        assert!(e.contains("line 2"), "{e}");
    }
}
