//! FBX importer tests: error classes on bytes made here, and the corpus's files.

use std::path::Path;

use rigport_testkit::corpus;

use super::*;

const FBX: &str = "7_fbx/assimp_test_models__assimp";

fn error_of(bytes: &[u8]) -> ImportError {
    match import_slice(bytes, Path::new("x.fbx")) {
        Ok(_) => panic!("imported a broken file"),
        Err(e) => e,
    }
}

#[test]
fn garbage_after_the_binary_magic_is_an_unsupported_version_at_byte_23() {
    let mut bytes = b"Kaydara FBX Binary  \0\x1a\0".to_vec();
    bytes.extend((0..600u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8 | 0x80));
    let e = error_of(&bytes);
    assert_eq!(e.location.to_string(), "x.fbx: at byte 23", "{e}");
    assert!(e.to_string().contains("unsupported FBX version"), "{e}");
}

#[test]
fn a_binary_record_past_the_end_is_truncated_at_its_offset() {
    let mut bytes = b"Kaydara FBX Binary  \0\x1a\0".to_vec();
    bytes.extend(7400u32.to_le_bytes());
    // One record that claims to end at byte 5000 of a file of 60 bytes.
    bytes.extend(5000u32.to_le_bytes());
    bytes.extend(0u32.to_le_bytes());
    bytes.extend(0u32.to_le_bytes());
    bytes.push(18);
    bytes.extend(b"FBXHeaderExtension");
    let e = error_of(&bytes);
    assert_eq!(e.location.to_string(), "x.fbx: at byte 27", "{e}");
    assert!(matches!(e.problem, Problem::Truncated(_)), "{e}");
    assert!(e.to_string().contains("\"FBXHeaderExtension\""), "{e}");
}

#[test]
fn an_ascii_file_cut_inside_a_block_is_truncated_at_its_last_line() {
    let text = "; FBX 7.3.0 project file\nFBXHeaderExtension:  {\n\tFBXHeaderVersion: 1003\n\tFBXVersion: 7300\nObjects:  {\n\tModel: 1, \"Model::a\", \"Mesh\" {\n\t\tVersion: 2";
    let e = error_of(text.as_bytes());
    assert_eq!(e.location.to_string(), "x.fbx:7", "{e}");
    assert!(e.to_string().contains("opened on line 6"), "{e}");
}

#[test]
fn empty_input_is_empty() {
    assert!(matches!(error_of(b"  \n").problem, Problem::Empty));
}

#[test]
fn skinned_corpus_file_keeps_bones_clusters_and_every_influence() {
    let Some(path) = corpus(&format!("{FBX}/huesitos.fbx")) else {
        return;
    };
    let imported = import(&path).expect("imports");
    let asset = &imported.asset;
    assert!(asset.meters_per_unit.is_some_and(|m| m > 0.0));
    assert_eq!(asset.skins.len(), 1);
    let skin = &asset.skins[0];
    assert_eq!(skin.joints.len(), skin.inv_bind.len());
    // Every joint of the palette is a bone or lies above one; parents come first.
    for (k, joint) in asset.skeleton.joints().iter().enumerate() {
        assert!(joint.parent.is_none_or(|p| (p.0 as usize) < k));
    }
    // The clusters' weights reach the mesh: every vertex has at least one influence.
    assert!(skin.influences.rows().all(|row| !row.is_empty()));
    assert_eq!(asset.clips.len(), 1);
}

#[test]
fn every_animation_stack_is_a_named_clip() {
    let Some(path) = corpus(&format!("{FBX}/multiple_animations_test.fbx")) else {
        return;
    };
    let asset = import(&path).expect("imports").asset;
    let names: Vec<&str> = asset.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["anim 1", "anim 2", "spin"]);
    for clip in &asset.clips {
        assert!(clip.tracks.iter().all(|t| t.times.first() >= Some(&0.0)));
        assert!(clip.duration() > 0.0);
    }
}

#[test]
fn a_file_without_bones_or_animation_is_static_meshes() {
    let Some(path) = corpus(&format!("{FBX}/spider.fbx")) else {
        return;
    };
    let imported = import(&path).expect("imports");
    let asset = &imported.asset;
    assert!(asset.skeleton.is_empty());
    assert!(asset.skins.is_empty() && asset.clips.is_empty());
    assert!(!asset.meshes.is_empty());
    assert!(asset.meshes.iter().all(|m| m.material.is_some()));
    // Its textures are paths on the author's disk: warnings, not errors.
    assert!(imported
        .warnings
        .iter()
        .any(|w| matches!(w, Warning::Incomplete { message, .. } if message.contains("texture"))));
}
