//! End-to-end tests: FBX in (issue 29, first step).
//!
//! Every FBX of the corpus (assimp's test models, `7_fbx` in `MANIFEST.tsv`) converts to a
//! `.glb` the Khronos glTF-Validator passes with no error and no warning; a skinned file
//! comes out at its height in the file's unit times the file's metres per unit; an FBX with
//! another extension is told by its bytes; broken files fail with exit 1, a location and
//! no output. The same files convert to `.usda` that usd-core's validators pass.

use std::path::Path;

use crate::common::*;

#[test]
fn every_corpus_fbx_converts_to_a_valid_glb() {
    // None of assimp's six files is broken: each must convert (a broken one would be
    // listed here with its expected located error).
    let Some(files) = corpus_section("7_fbx") else {
        return;
    };
    let dir = scratch();
    for file in files {
        let name = file.file_stem().unwrap().to_string_lossy().into_owned();
        let glb = dir.path().join(format!("{name}.glb"));
        rigport_ok(&[
            "convert",
            file.to_str().unwrap(),
            "-o",
            glb.to_str().unwrap(),
        ]);
        assert_valid(&glb);
    }
}

#[test]
fn every_corpus_fbx_converts_to_a_clean_usda() {
    // The USD writer states the file's unit (metres per unit from `UnitScaleFactor`);
    // usd-core's validators and rigport's checks (tools/check_usd.py) pass it.
    let Some(files) = corpus_section("7_fbx") else {
        return;
    };
    let Some(python) = crate::usd::python() else {
        return;
    };
    let dir = scratch();
    for file in files {
        let name = file.file_stem().unwrap().to_string_lossy().into_owned();
        let usda = dir.path().join(format!("{name}.usda"));
        rigport_ok(&[
            "convert",
            file.to_str().unwrap(),
            "-o",
            usda.to_str().unwrap(),
        ]);
        let (ok, text) = crate::usd::check_usd(&python, &usda, None);
        assert!(ok, "{name}: {text}");
    }
}

/// Extent along the file's own up axis of the skinned meshes' points at bind time, in the
/// file's unit, read by ufbx without any conversion (bind time: each skin's first cluster's
/// `TransformLink` times its geometry-to-bone matrix); and the file's metres per unit.
pub fn source_height(file: &Path) -> (f64, f64) {
    let scene = ufbx::load_file(file.to_str().unwrap(), ufbx::LoadOpts::default()).unwrap();
    let up = scene.settings.axes.up as usize;
    // ufbx's axes: +X, -X, +Y, -Y, +Z, -Z.
    let (axis, sign) = (up / 2, if up % 2 == 0 { 1.0 } else { -1.0 });
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for mesh in scene.meshes.iter() {
        let Some(skin) = mesh.skin_deformers.first() else {
            continue;
        };
        let c = &skin.clusters[0];
        let m = ufbx::matrix_mul(&c.bind_to_world, &c.geometry_to_bone);
        for p in mesh.vertices.iter() {
            let w = [
                m.m00 * p.x + m.m01 * p.y + m.m02 * p.z + m.m03,
                m.m10 * p.x + m.m11 * p.y + m.m12 * p.z + m.m13,
                m.m20 * p.x + m.m21 * p.y + m.m22 * p.z + m.m23,
            ];
            lo = lo.min(sign * w[axis]);
            hi = hi.max(sign * w[axis]);
        }
    }
    (hi - lo, scene.settings.unit_meters)
}

/// Extent along +Y of the skinned meshes' bind-space points in a `.glb`.
pub fn glb_height(glb: &Path) -> f64 {
    let (doc, buffers, _) = gltf::import(glb).unwrap();
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for node in doc.nodes().filter(|n| n.skin().is_some()) {
        for prim in node.mesh().unwrap().primitives() {
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            for p in reader.read_positions().unwrap() {
                lo = lo.min(f64::from(p[1]));
                hi = hi.max(f64::from(p[1]));
            }
        }
    }
    hi - lo
}

#[test]
fn skinned_files_stand_at_their_height_times_metres_per_unit() {
    // The Mixamo rule (a centimetre character comes out at human height in metres),
    // checked on the corpus's skinned files: neither is a character, but the rule is the
    // same. 1e-5 relative: f32 points.
    for name in ["huesitos.fbx", "animation_with_skeleton.fbx"] {
        let Some(file) = corpus(&format!("7_fbx/assimp_test_models__assimp/{name}")) else {
            return;
        };
        let dir = scratch();
        let glb = dir.path().join("out.glb");
        rigport_ok(&[
            "convert",
            file.to_str().unwrap(),
            "-o",
            glb.to_str().unwrap(),
        ]);
        let (height, meters_per_unit) = source_height(&file);
        let expected = height * meters_per_unit;
        let got = glb_height(&glb);
        assert!(
            ((got - expected) / expected).abs() < 1e-5,
            "{name}: {got} m in the glb, {height} x {meters_per_unit} = {expected} m in the file"
        );
    }
}

#[test]
fn an_fbx_with_another_extension_is_told_by_its_bytes() {
    let Some(file) = corpus("7_fbx/assimp_test_models__assimp/Granate.fbx") else {
        return;
    };
    let dir = scratch();
    let renamed = dir.path().join("granate.dat");
    std::fs::copy(&file, &renamed).unwrap();
    let glb = dir.path().join("out.glb");
    rigport_ok(&[
        "convert",
        renamed.to_str().unwrap(),
        "-o",
        glb.to_str().unwrap(),
    ]);
    assert_valid(&glb);
}

/// Converts `bytes` written as `name`: asserts exit 1, no output, and that stderr holds
/// `expected`; returns stderr.
fn broken(name: &str, bytes: &[u8], expected: &str) -> String {
    let dir = scratch();
    let input = dir.path().join(name);
    std::fs::write(&input, bytes).unwrap();
    let glb = dir.path().join("out.glb");
    let out = rigport(&[
        "convert",
        input.to_str().unwrap(),
        "-o",
        glb.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(!glb.exists(), "an output was written for a broken input");
    assert!(
        stderr.contains(name) && stderr.contains(expected),
        "{stderr}"
    );
    stderr
}

#[test]
fn truncated_and_garbage_fbx_fail_with_a_location() {
    let mut garbage = b"Kaydara FBX Binary  \0\x1a\0".to_vec();
    garbage.extend((0..4000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 11) as u8 | 1));
    broken(
        "garbage.fbx",
        &garbage,
        "at byte 23: unsupported FBX version",
    );
    let Some(binary) = corpus("7_fbx/assimp_test_models__assimp/huesitos.fbx") else {
        return;
    };
    let bytes = std::fs::read(binary).unwrap();
    broken(
        "cut.fbx",
        &bytes[..bytes.len() / 2],
        "cut.fbx: at byte 12934: truncated: the node record \"Objects\"",
    );
    let Some(ascii) = corpus("7_fbx/assimp_test_models__assimp/Granate.fbx") else {
        return;
    };
    let text = std::fs::read(ascii).unwrap();
    let half = &text[..text.len() / 2];
    let lines = 1 + half.iter().filter(|&&b| b == b'\n').count();
    broken(
        "cut_ascii.fbx",
        half,
        &format!("cut_ascii.fbx:{lines}: truncated: the file ends inside"),
    );
}
