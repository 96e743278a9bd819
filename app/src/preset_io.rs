//! Reading and writing preset files, shared by the command line and the editor.
//!
//! Saves are atomic: the text goes to a temporary file beside the target, is flushed to disk, then
//! renamed over the target, so a crash mid-save never leaves a truncated preset.

use lodestone_core::driver::DriverError;
use lodestone_core::driver::image::ImageDriver;
use lodestone_core::eval::Evaluator;
use lodestone_core::material::environment::{Environment, EnvironmentSource, EquirectMap};
use lodestone_core::material::measured::MeasuredBrdf;
use lodestone_core::material::merl::MerlBrdf;
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
    /// The base BRDF's measured file cannot be used.
    #[error("{preset}: measured BRDF {file}: {reason}")]
    Measured {
        /// The preset.
        preset: PathBuf,
        /// The MERL file, resolved against the preset's folder.
        file: PathBuf,
        /// What is wrong (missing, wrong size, not finite, too many negative entries).
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
    /// The base BRDF's measured table and its fit; `None` for the analytic BRDF.
    pub measured: Option<Arc<MeasuredBrdf>>,
}

impl Resolved {
    /// A material whose driver needs no file (an image driver's image stays unloaded).
    pub fn without_image(material: Material) -> Self {
        Self {
            material,
            image: None,
            environment: None,
            measured: None,
        }
    }

    /// The material's tables and surface, ready for the CPU reference and the GPU.
    pub fn prepare(&self) -> Result<Evaluator, DriverError> {
        let mut p = Evaluator::with_image(&self.material, self.image.clone(), None)?;
        if let Some(sh) = &self.environment {
            p.set_environment_radiance(sh);
        }
        if let Some(m) = &self.measured {
            p.set_measured(m.clone());
        }
        Ok(p)
    }
}

/// Largest preset file read (the largest valid preset, 1024 stops and curve points, is under 200 KB).
pub const MAX_PRESET_BYTES: u64 = 16 << 20;

/// Largest driver image or environment file read (an 8192² RGBA f32 EXR, uncompressed, is 1 GiB).
pub const MAX_IMAGE_FILE_BYTES: u64 = 1 << 30;

/// Refuse, before opening it, anything but a regular file of at most `max` bytes: opening a FIFO
/// blocks until a writer comes, and a device such as `/dev/zero` never ends (#16: both used to hang
/// or grow to gigabytes). Symbolic links are followed.
pub fn check_regular_file(path: &Path, max: u64) -> std::io::Result<()> {
    use std::io::{Error, ErrorKind};
    let meta = std::fs::metadata(path)?;
    if meta.is_dir() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "is a directory, not a file",
        ));
    }
    if !meta.is_file() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "is not a regular file (a pipe, socket or device); Lodestone reads only regular files",
        ));
    }
    if meta.len() > max {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            format!("is {} bytes, more than the {max}-byte limit", meta.len()),
        ));
    }
    Ok(())
}

/// The text of a regular file of at most `max` bytes ([`check_regular_file`]; a file that grows
/// while it is read is cut at `max + 1` bytes and refused).
pub fn read_text_capped(path: &Path, max: u64) -> std::io::Result<String> {
    use std::io::Read;
    check_regular_file(path, max)?;
    let mut text = String::new();
    std::fs::File::open(path)?
        .take(max + 1)
        .read_to_string(&mut text)?;
    if text.len() as u64 > max {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("grew past the {max}-byte limit while being read"),
        ));
    }
    Ok(text)
}

/// Load a preset and, for an image driver, its image (resolved against the preset's folder).
pub fn load_resolved(path: &Path) -> Result<Resolved, PresetError> {
    let text = read_text_capped(path, MAX_PRESET_BYTES).map_err(|error| PresetError::Read {
        path: path.to_owned(),
        error,
    })?;
    let material = Material::from_ron(&text).map_err(|error| PresetError::Material {
        path: path.to_owned(),
        error,
    })?;
    let image = driver_image(&material, Some(path))?;
    let environment = environment_file(&material, Some(path))?;
    let measured = measured_file(&material, Some(path))?;
    Ok(Resolved {
        material,
        image,
        environment,
        measured,
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

/// The measured base BRDF `material` names (a MERL file, its path relative to the folder of
/// `preset`), read, checked and fitted; `None` for the analytic BRDF.
pub fn measured_file(
    material: &Material,
    preset: Option<&Path>,
) -> Result<Option<Arc<MeasuredBrdf>>, PresetError> {
    let Some(path) = &material.brdf.measured else {
        return Ok(None);
    };
    let dir = preset.and_then(|p| p.parent()).unwrap_or(Path::new("."));
    load_measured(
        preset.unwrap_or(Path::new("(unsaved material)")),
        &dir.join(path),
    )
    .map(|m| Some(Arc::new(m)))
}

/// Read a MERL file (a regular file of exactly the format's size, every entry finite, at most
/// [`lodestone_core::material::merl::MAX_UNMEASURED_SHARE`] negative) and fit it.
pub fn load_measured(preset: &Path, file: &Path) -> Result<MeasuredBrdf, PresetError> {
    let err = |reason: String| PresetError::Measured {
        preset: preset.to_owned(),
        file: file.to_owned(),
        reason,
    };
    check_regular_file(file, MAX_IMAGE_FILE_BYTES).map_err(|e| {
        let hint = if file.exists() {
            ""
        } else {
            " (a file of the MERL database, or an analytic one written by `lodestone merl --out FILE`)"
        };
        err(format!("{e}{hint}"))
    })?;
    let table = MerlBrdf::read(file).map_err(|e| err(e.to_string()))?;
    Ok(MeasuredBrdf::new(table))
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
    check_regular_file(file, MAX_IMAGE_FILE_BYTES).map_err(|e| err(e.to_string()))?;
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
    check_regular_file(image, MAX_IMAGE_FILE_BYTES).map_err(|e| err(e.to_string()))?;
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

/// Write `text` to `path` atomically: a temporary file in the same folder, flushed to disk, given
/// the old file's permissions, renamed over the target, then the folder flushed so the rename
/// itself survives a power cut. A symbolic link is kept: its target is replaced. Temporary files
/// that an earlier, crashed save of the same target left behind are removed.
pub fn write_atomic(path: &Path, text: &str) -> Result<(), PresetError> {
    write_atomic_with(path, text.as_bytes(), |_| Ok(()))
}

/// [`write_atomic`] for bytes (rendered images).
pub fn write_atomic_bytes(path: &Path, bytes: &[u8]) -> Result<(), PresetError> {
    write_atomic_with(path, bytes, |_| Ok(()))
}

/// [`write_atomic`] with `before_rename` run on the written temporary file just before the rename
/// (tests interrupt a save there).
fn write_atomic_with(
    path: &Path,
    bytes: &[u8],
    before_rename: impl FnOnce(&Path) -> std::io::Result<()>,
) -> Result<(), PresetError> {
    let err = |error| PresetError::Write {
        path: path.to_owned(),
        error,
    };
    // Through a symbolic link (chains too) to the file it names.
    let target = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => std::fs::canonicalize(path).map_err(err)?,
        _ => path.to_owned(),
    };
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "preset".into());
    let prefix = format!(".{name}.");
    remove_stale_temps(&dir, &prefix);
    let tmp = dir.join(format!("{prefix}{}.tmp", std::process::id()));
    let old = std::fs::metadata(&target).ok();
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        if let Some(m) = &old {
            f.set_permissions(m.permissions())?;
        }
        f.sync_all()?;
        drop(f);
        before_rename(&tmp)?;
        std::fs::rename(&tmp, &target)?;
        sync_dir(&dir)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(err)
}

/// Remove `dir/{prefix}{pid}.tmp` files of other processes (saves that crashed before their rename).
fn remove_stale_temps(dir: &Path, prefix: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let ours = format!("{prefix}{}.tmp", std::process::id());
    for e in entries.flatten() {
        let n = e.file_name().to_string_lossy().into_owned();
        let stale = n
            .strip_prefix(prefix)
            .and_then(|r| r.strip_suffix(".tmp"))
            .is_some_and(|pid| !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()));
        if stale && n != ours {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// Flush a folder's entries (the rename) to disk; a no-op where folders cannot be opened (Windows).
fn sync_dir(dir: &Path) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        std::fs::File::open(dir)?.sync_all()
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        Ok(())
    }
}

/// Write the engine bundle of `m` into `dir` (created if needed); returns the files written.
///
/// The files a preset names (a driver image, an environment file, a measured BRDF), resolved against the folder of
/// `preset` (the current folder without one), are copied beside it and the bundle's `material.ron`
/// names the copies, so the bundle reopens anywhere. Every file is first written to a temporary
/// name in `dir` and flushed; only then are they renamed into place, `manifest.json` last, so an
/// interrupted export leaves the previous bundle (plus temporaries the next export removes), never
/// a mix of new and old files.
pub fn export_bundle(
    m: &Resolved,
    preset: Option<&Path>,
    dir: &Path,
) -> anyhow::Result<Vec<PathBuf>> {
    use anyhow::Context;
    let prepared = m.prepare()?;
    let mut files = lodestone_render::export::bundle(&prepared)?;
    let (material, copies) = bundled_material(&m.material, preset)?;
    for (name, bytes) in &mut files {
        if name == "material.ron" {
            *bytes = material.to_ron().into_bytes();
        }
    }
    for (name, from) in copies {
        let bytes = std::fs::read(&from).with_context(|| format!("reading {}", from.display()))?;
        files.push((name, bytes));
    }
    // The manifest goes last: a bundle with a manifest is complete.
    files.sort_by_key(|(name, _)| name == "manifest.json");
    write_set(dir, &files)
}

/// Write a set of files into `dir` (created if needed) so that it is never seen half written:
/// every file first goes to a temporary name in `dir` and is flushed; only then are they renamed
/// into place, in the order given (put the file that marks a set complete last). An interrupted
/// write leaves the previous set, plus temporaries that the next write of the same names removes.
/// Returns the files written.
pub fn write_set(dir: &Path, files: &[(String, Vec<u8>)]) -> anyhow::Result<Vec<PathBuf>> {
    use anyhow::Context;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let staged: Vec<(PathBuf, PathBuf)> = files
        .iter()
        .map(|(name, _)| {
            let prefix = format!(".{name}.");
            remove_stale_temps(dir, &prefix);
            (
                dir.join(format!("{prefix}{}.tmp", std::process::id())),
                dir.join(name),
            )
        })
        .collect();
    let result = (|| -> anyhow::Result<()> {
        for ((tmp, _), (_, bytes)) in staged.iter().zip(files) {
            let mut f =
                std::fs::File::create(tmp).with_context(|| format!("writing {}", tmp.display()))?;
            f.write_all(bytes)
                .and_then(|()| f.sync_all())
                .with_context(|| format!("writing {}", tmp.display()))?;
        }
        for (tmp, to) in &staged {
            std::fs::rename(tmp, to).with_context(|| format!("writing {}", to.display()))?;
        }
        sync_dir(dir).with_context(|| format!("flushing {}", dir.display()))
    })();
    if result.is_err() {
        for (tmp, _) in &staged {
            let _ = std::fs::remove_file(tmp);
        }
    }
    result?;
    Ok(staged.into_iter().map(|(_, to)| to).collect())
}

/// The material as a bundle stores it, with the files it names renamed to their bare file names,
/// and those files (bundle name, source path resolved against `preset`'s folder).
fn bundled_material(
    m: &Material,
    preset: Option<&Path>,
) -> Result<(Material, Vec<(String, PathBuf)>), PresetError> {
    let dir = preset.and_then(|p| p.parent()).unwrap_or(Path::new("."));
    let preset_name = preset.unwrap_or(Path::new("(unsaved material)"));
    let mut out = m.clone();
    let mut copies = Vec::new();
    let mut bundle = |path: &mut String, prefix: &str| -> Result<(), PresetError> {
        let from = dir.join(&*path);
        let file = from
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        check_regular_file(&from, MAX_IMAGE_FILE_BYTES).map_err(|e| {
            let (preset, reason) = (preset_name.to_owned(), e.to_string());
            match prefix {
                "driver-" => PresetError::Image {
                    preset,
                    image: from.clone(),
                    reason,
                },
                "brdf-" => PresetError::Measured {
                    preset,
                    file: from.clone(),
                    reason,
                },
                _ => PresetError::Environment {
                    preset,
                    file: from.clone(),
                    reason,
                },
            }
        })?;
        // The driver image and the environment keep distinct names even when theirs agree.
        let name = format!("{prefix}{file}");
        *path = name.clone();
        copies.push((name, from));
        Ok(())
    };
    if let Driver::Image { path, .. } = &mut out.driver {
        bundle(path, "driver-")?;
    }
    if let Some(Environment {
        source: EnvironmentSource::File { path },
        ..
    }) = &mut out.lighting.environment
    {
        bundle(path, "environment-")?;
    }
    if let Some(path) = &mut out.brdf.measured {
        bundle(path, "brdf-")?;
    }
    Ok((out, copies))
}

/// `m`, whose file paths are relative to the folder of `from` (the current folder without one),
/// with those paths rewritten to name the same files from the folder of `to`: relative where the
/// file lies inside that folder, absolute otherwise. Absolute paths stay. (Saving a preset into
/// another folder used to keep paths that no longer resolved, #16.)
pub fn relocate(m: &Material, from: Option<&Path>, to: &Path) -> Material {
    let from_dir = from.and_then(|p| p.parent()).unwrap_or(Path::new("."));
    let to_dir = to.parent().unwrap_or(Path::new("."));
    let absolute = |d: &Path| std::path::absolute(d).unwrap_or_else(|_| d.to_owned());
    let (from_dir, to_dir) = (absolute(from_dir), absolute(to_dir));
    let mut out = m.clone();
    let fix = |path: &mut String| {
        let p = Path::new(path.as_str());
        if p.is_absolute() || from_dir == to_dir {
            return;
        }
        let file = from_dir.join(p);
        let file = std::fs::canonicalize(&file).unwrap_or(file);
        let to_dir = std::fs::canonicalize(&to_dir).unwrap_or_else(|_| to_dir.clone());
        *path = match file.strip_prefix(&to_dir) {
            Ok(rel) => rel.to_string_lossy().into_owned(),
            Err(_) => file.to_string_lossy().into_owned(),
        };
    };
    if let Driver::Image { path, .. } = &mut out.driver {
        fix(path);
    }
    if let Some(Environment {
        source: EnvironmentSource::File { path },
        ..
    }) = &mut out.lighting.environment
    {
        fix(path);
    }
    if let Some(path) = &mut out.brdf.measured {
        fix(path);
    }
    out
}

/// Save a material as a preset (atomically).
pub fn save(path: &Path, m: &Material) -> Result<(), PresetError> {
    write_atomic(path, &m.to_ron())
}

#[cfg(test)]
mod tests;
