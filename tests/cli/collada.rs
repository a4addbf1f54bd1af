//! End-to-end tests: COLLADA in (issue 29, second step).
//!
//! Every COLLADA file of the corpus (assimp's test models, `8_collada` in `MANIFEST.tsv`:
//! `.dae` and a `.zae`) converts to a `.glb` the Khronos glTF-Validator passes with no error
//! and no warning, and to a `.usda` usd-core's validators pass; `library_animation_clips.dae`
//! gives its named clips; a document with another extension is told by its root element;
//! `inspect` and `eval` read it; broken files fail with exit 1, a location and no output.

use crate::common::*;

const DIR: &str = "8_collada/assimp_test_models__assimp";

#[test]
fn every_corpus_collada_converts_to_a_valid_glb() {
    // None of assimp's five files is broken: each must convert.
    let Some(files) = corpus_section("8_collada") else {
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
fn every_corpus_collada_converts_to_a_clean_usda() {
    let Some(files) = corpus_section("8_collada") else {
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

#[test]
fn library_animation_clips_become_named_clips() {
    let Some(file) = corpus(&format!("{DIR}/library_animation_clips.dae")) else {
        return;
    };
    let out = rigport(&["inspect", "--json", file.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let clips = json[0]["clips"]
        .as_array()
        .unwrap_or_else(|| panic!("no clips in {json}"));
    let names: Vec<&str> = clips.iter().filter_map(|c| c["name"].as_str()).collect();
    assert_eq!(names, ["bend", "turn"]);
    // The glb carries both, by name.
    let dir = scratch();
    let glb = dir.path().join("clips.glb");
    rigport_ok(&[
        "convert",
        file.to_str().unwrap(),
        "-o",
        glb.to_str().unwrap(),
    ]);
    let (doc, _, _) = gltf::import(&glb).unwrap();
    let names: Vec<String> = doc
        .animations()
        .filter_map(|a| a.name().map(str::to_string))
        .collect();
    assert_eq!(names, ["bend", "turn"]);
}

#[test]
fn a_z_up_file_comes_out_y_up_and_eval_reads_it() {
    // box_nested_animation.dae is Z_UP: the cube's extent along the file's z (0..2) is
    // the glb's extent along +Y.
    let Some(file) = corpus(&format!("{DIR}/box_nested_animation.dae")) else {
        return;
    };
    let dir = scratch();
    let glb = dir.path().join("box.glb");
    rigport_ok(&[
        "convert",
        file.to_str().unwrap(),
        "-o",
        glb.to_str().unwrap(),
    ]);
    let (doc, buffers, _) = gltf::import(&glb).unwrap();
    let (mut lo, mut hi) = (f32::MAX, f32::MIN);
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            for p in reader.read_positions().unwrap() {
                lo = lo.min(p[1]);
                hi = hi.max(p[1]);
            }
        }
    }
    assert!(
        (lo - 0.0).abs() < 1e-5 && (hi - 2.0).abs() < 1e-5,
        "{lo}..{hi}"
    );
    let npz = dir.path().join("box.npz");
    rigport_ok(&["eval", file.to_str().unwrap(), "-o", npz.to_str().unwrap()]);
    let arrays = read_npz(&npz);
    assert!(arrays.contains_key("positions"), "{:?}", arrays.keys());
}

#[test]
fn a_collada_document_with_another_extension_is_told_by_its_root_element() {
    let Some(file) = corpus(&format!("{DIR}/duck.dae")) else {
        return;
    };
    let dir = scratch();
    let renamed = dir.path().join("duck.xml");
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
/// `expected`.
fn broken(name: &str, bytes: &[u8], expected: &str) {
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
}

#[test]
fn broken_collada_fails_with_a_location_and_no_output() {
    let Some(file) = corpus(&format!("{DIR}/library_animation_clips.dae")) else {
        return;
    };
    let text = std::fs::read_to_string(file).unwrap();
    // Cut in half: truncated at the last line.
    let half = &text[..text.len() / 2];
    let lines = half.trim_end().lines().count();
    broken(
        "cut.dae",
        half.as_bytes(),
        &format!("cut.dae:{lines}: truncated"),
    );
    // A reference to an id that is not there, at the referring element's line.
    let missing = text.replacen("url=\"#", "url=\"#nothing-", 1);
    let line = 1 + missing
        .lines()
        .position(|l| l.contains("#nothing-"))
        .unwrap();
    broken(
        "missing.dae",
        missing.as_bytes(),
        &format!("missing.dae:{line}:"),
    );
    // Bad XML.
    broken(
        "bad.dae",
        b"<?xml version=\"1.0\"?>\n<COLLADA>\n<asset></asst>\n</COLLADA>\n",
        "bad.dae:3:",
    );
    // A package without a document.
    broken(
        "empty.zae",
        b"PK\x05\x06\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0",
        "holds no .dae",
    );
}

#[test]
fn a_zae_reads_its_root_document_and_the_texture_inside_the_package() {
    // human.zae holds human.dae and textures/brown_eye.png; its primitives carry no
    // material symbol, so each instance's one bound material applies.
    let Some(file) = corpus(&format!("{DIR}/human.zae")) else {
        return;
    };
    let dir = scratch();
    let glb = dir.path().join("human.glb");
    let stderr = rigport_ok(&[
        "convert",
        file.to_str().unwrap(),
        "-o",
        glb.to_str().unwrap(),
    ]);
    assert!(!stderr.contains("warning"), "{stderr}");
    let (doc, _, images) = gltf::import(&glb).unwrap();
    let names: Vec<&str> = doc.materials().filter_map(|m| m.name()).collect();
    assert_eq!(names, ["DefaultSkin", "Eye_brown"]);
    assert_eq!(images.len(), 1);
    let eye = doc.materials().nth(1).unwrap();
    assert!(eye.pbr_metallic_roughness().base_color_texture().is_some());
    assert!(doc
        .meshes()
        .all(|m| m.primitives().all(|p| p.material().index().is_some())));
}
