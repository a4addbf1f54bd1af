//! Writing files: atomic writes, nothing left on error, percent-encoded URIs, the `.bin`
//! buffer, symlinks.

//! Round trips through an independent reader (the `gltf` crate), layout rules read from the
//! JSON, determinism and atomic writing.

use std::path::Path;

use serde_json::Value;

use super::*;
use crate::test_assets;

fn dir_names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("read dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn write_gltf_is_atomic_and_leaves_nothing_on_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let asset = test_assets::rig();
    let opts = GltfOptions::default();

    let mut bad = asset.clone();
    bad.meshes[0].positions[3].x = f32::NAN;
    for name in ["bad.glb", "bad.gltf", "bad.GLTF"] {
        let err = write_gltf(&bad, &dir.path().join(name), &opts).unwrap_err();
        assert!(matches!(err, ExportError::Invalid { .. }), "{err:?}");
    }
    let err = write_gltf(&asset, &dir.path().join("rig.obj"), &opts).unwrap_err();
    assert!(matches!(err, ExportError::UnsupportedExtension { .. }));
    let err = write_gltf(&asset, &dir.path().join("rig"), &opts).unwrap_err();
    assert!(matches!(err, ExportError::UnsupportedExtension { .. }));
    assert_eq!(
        dir_names(dir.path()),
        Vec::<String>::new(),
        "no file after failures"
    );

    let warnings = write_gltf(&asset, &dir.path().join("my rig.gltf"), &opts).expect("gltf");
    let w2 = write_gltf(&asset, &dir.path().join("rig.glb"), &opts).expect("glb");
    assert_eq!(warnings, w2);
    assert_eq!(
        dir_names(dir.path()),
        ["my rig.bin", "my rig.gltf", "rig.glb"]
    );
    let json: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("my rig.gltf")).expect("read"))
            .expect("json");
    assert_eq!(json["buffers"][0]["uri"], "my%20rig.bin");
    assert_eq!(
        std::fs::read(dir.path().join("rig.glb")).expect("read"),
        glb(&asset, 4).glb
    );
    // Overwriting keeps the directory clean; a failure leaves the previous files intact.
    write_gltf(&asset, &dir.path().join("rig.glb"), &opts).expect("overwrite");
    assert!(write_gltf(&bad, &dir.path().join("rig.glb"), &opts).is_err());
    assert_eq!(
        std::fs::read(dir.path().join("rig.glb")).expect("read"),
        glb(&asset, 4).glb
    );
    assert_eq!(
        dir_names(dir.path()),
        ["my rig.bin", "my rig.gltf", "rig.glb"]
    );

    // Prepared exports write nothing until asked.
    let prepared = prepare_gltf(&asset, &dir.path().join("later.gltf"), &opts).expect("prepare");
    assert_eq!(prepared.warnings(), &warnings[..]);
    assert_eq!(prepared.path(), dir.path().join("later.gltf"));
    assert_eq!(
        dir_names(dir.path()),
        ["my rig.bin", "my rig.gltf", "rig.glb"]
    );
    prepared.write().expect("write");
    assert_eq!(
        dir_names(dir.path()),
        [
            "later.bin",
            "later.gltf",
            "my rig.bin",
            "my rig.gltf",
            "rig.glb"
        ]
    );
    std::fs::remove_file(dir.path().join("later.bin")).expect("rm");
    std::fs::remove_file(dir.path().join("later.gltf")).expect("rm");

    // An unwritable target (a directory in the way) is an Io error and leaves no temp files.
    std::fs::create_dir(dir.path().join("taken.gltf")).expect("mkdir");
    std::fs::write(dir.path().join("taken.gltf").join("x"), b"x").expect("write");
    let err = write_gltf(&asset, &dir.path().join("taken.gltf"), &opts).unwrap_err();
    assert!(
        matches!(&err, ExportError::Io { path, .. } if path.ends_with("taken.gltf")),
        "{err:?}"
    );
    assert_eq!(
        dir_names(dir.path()),
        ["my rig.bin", "my rig.gltf", "rig.glb", "taken.gltf"]
    );
}

#[test]
fn percent_encoding_keeps_safe_characters() {
    assert_eq!(percent_encode("walk_01-a.bin"), "walk_01-a.bin");
    assert_eq!(percent_encode("my rig#2?.bin"), "my%20rig%232%3F.bin");
    assert_eq!(percent_encode("c:ü%.bin"), "c%3A%C3%BC%25.bin");
}

#[test]
fn an_asset_without_binary_data_has_no_buffer() {
    let asset = test_assets::bones_only();
    let split = to_gltf(&asset, &GltfOptions::default(), "x.bin").expect("export");
    assert!(split.bin.is_empty());
    let json: Value = serde_json::from_slice(&split.json).expect("json");
    assert!(json.get("buffers").is_none());
    let out = to_glb(&asset, &GltfOptions::default()).expect("export");
    assert_eq!(
        out.glb.len(),
        20 + u32::from_le_bytes(out.glb[12..16].try_into().expect("4")) as usize
    );
    let dir = tempfile::tempdir().expect("tempdir");
    write_gltf(
        &asset,
        &dir.path().join("bones.gltf"),
        &GltfOptions::default(),
    )
    .expect("write");
    assert_eq!(dir_names(dir.path()), ["bones.gltf"]);
    import(&out.glb);
}

#[cfg(unix)]
#[test]
fn symlinked_gltf_is_refused_and_a_bin_directory_too() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("model.gltf"), b"old").expect("write");
    let link = dir.path().join("link.gltf");
    std::os::unix::fs::symlink("model.gltf", &link).expect("symlink");
    let err = write_gltf(&test_assets::rig(), &link, &GltfOptions::default()).unwrap_err();
    assert!(matches!(err, ExportError::Io { .. }), "{err:?}");
    assert_eq!(dir_names(dir.path()), ["link.gltf", "model.gltf"]);
    assert_eq!(
        std::fs::read(dir.path().join("model.gltf")).expect("read"),
        b"old"
    );
    // A directory where the .bin goes is refused before anything is written.
    std::fs::create_dir(dir.path().join("x.bin")).expect("mkdir");
    let err = write_gltf(
        &test_assets::rig(),
        &dir.path().join("x.gltf"),
        &GltfOptions::default(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("x.bin"), "{err}");
    assert_eq!(dir_names(dir.path()), ["link.gltf", "model.gltf", "x.bin"]);
}
