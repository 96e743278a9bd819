//! Tests of [`super`].

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

/// A set of files (render --mode all, export) that fails while being written leaves the
/// previous set as it was and no temporaries (#16: render --mode all left partial sets).
#[test]
fn a_failed_set_keeps_the_previous_set() {
    let d = scratch("set");
    let set = |v: &str| -> Vec<(String, Vec<u8>)> {
        ["a.png", "b.exr", "c.png"]
            .iter()
            .map(|n| (n.to_string(), v.as_bytes().to_vec()))
            .collect()
    };
    let written = write_set(&d, &set("old")).expect("first set");
    assert_eq!(written.len(), 3);
    // The third file cannot be staged (its folder does not exist): nothing is replaced.
    let mut bad = set("new");
    bad[2].0 = "missing/c.png".into();
    assert!(write_set(&d, &bad).is_err());
    for n in ["a.png", "b.exr", "c.png"] {
        assert_eq!(
            std::fs::read_to_string(d.join(n)).expect("kept"),
            "old",
            "{n}"
        );
    }
    let names: Vec<_> = std::fs::read_dir(&d)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 3, "temporaries left: {names:?}");
    write_set(&d, &set("new")).expect("second set");
    assert_eq!(std::fs::read_to_string(d.join("b.exr")).expect("b"), "new");
}

/// A save of the same file interrupted after its temporary file is written keeps the old file
/// whole and leaves nothing behind; a temporary file left by a crashed save is removed by the
/// next save.
#[test]
fn an_interrupted_save_keeps_the_old_file() {
    let d = scratch("failed");
    let p = d.join("m.ron");
    save(&p, &default_material()).expect("save");
    let before = std::fs::read_to_string(&p).expect("read");
    let mut m = default_material();
    m.name = "changed".into();
    let mut seen = String::new();
    let r = write_atomic_with(&p, m.to_ron().as_bytes(), |tmp| {
        seen = std::fs::read_to_string(tmp)?;
        Err(std::io::Error::other("interrupted"))
    });
    assert!(r.is_err());
    assert!(
        seen.contains("changed"),
        "the temporary file held the new text"
    );
    assert_eq!(std::fs::read_to_string(&p).expect("read"), before);
    let names = |d: &Path| -> Vec<String> {
        let mut v: Vec<_> = std::fs::read_dir(d)
            .expect("dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    assert_eq!(names(&d), ["m.ron"]);
    // A crash leaves a temporary file (another process's id); the next save removes it.
    std::fs::write(d.join(".m.ron.4000000001.tmp"), "half a preset").expect("write");
    save(&p, &m).expect("save");
    assert_eq!(names(&d), ["m.ron"]);
    assert_eq!(load(&p).expect("load").name, "changed");
}

/// Saving keeps the file's permissions and a symbolic link (its target is replaced).
#[cfg(unix)]
#[test]
fn saving_keeps_permissions_and_symbolic_links() {
    use std::os::unix::fs::PermissionsExt;
    let d = scratch("perms");
    let real = d.join("real.ron");
    save(&real, &default_material()).expect("save");
    std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o640)).expect("chmod");
    let link = d.join("link.ron");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink("real.ron", &link).expect("symlink");
    let mut m = default_material();
    m.name = "through the link".into();
    save(&link, &m).expect("save through the link");
    assert!(
        std::fs::symlink_metadata(&link)
            .expect("link")
            .file_type()
            .is_symlink()
    );
    assert_eq!(load(&real).expect("load").name, "through the link");
    let mode = std::fs::metadata(&real).expect("meta").permissions().mode() & 0o777;
    assert_eq!(mode, 0o640);
}

/// An exported bundle of a preset with a driver image and an environment file carries copies
/// of both and reopens from its own folder; no temporaries are left (#16).
#[test]
fn bundles_carry_the_files_their_material_names() {
    let d = scratch("bundle");
    let presets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../presets");
    let src = presets.join("cobblestones.ron");
    let r = load_resolved(&src).expect("cobblestones");
    let out = d.join("bundle");
    // A leftover of an interrupted export is cleaned up.
    std::fs::create_dir_all(&out).expect("dir");
    std::fs::write(out.join(".data.bin.4000000001.tmp"), "half").expect("write");
    let written = export_bundle(&r, Some(&src), &out).expect("export");
    assert!(written.last().is_some_and(|p| p.ends_with("manifest.json")));
    let reopened = load_resolved(&out.join("material.ron")).expect("the bundle reopens");
    assert!(reopened.image.is_some());
    assert!(out.join("driver-cobblestones.png").is_file());
    let stray: Vec<_> = std::fs::read_dir(&out)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(stray.is_empty(), "{stray:?}");
    // Saved into another folder, the material still finds its image.
    let elsewhere = d.join("elsewhere").join("c.ron");
    std::fs::create_dir_all(elsewhere.parent().unwrap()).expect("dir");
    save(&elsewhere, &relocate(&r.material, Some(&src), &elsewhere)).expect("save");
    assert!(load_resolved(&elsewhere).expect("reopens").image.is_some());
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
