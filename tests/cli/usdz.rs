//! `.usdc` and `.usdz` outputs (issue 22): the same layer as the `.usda` of the same input
//! (usd-core reads the same specs, values and time samples, and UsdSkel evaluates the
//! same, exactly: tools/same_usd.py), packages that pass every usd-core validator that
//! applies to them (tools/check_usdz.py), textures packed with relative asset paths.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::*;

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// Runs a tools/ script with the usd-core Python; returns (success, output).
fn tool(python: &Path, script: &str, args: &[&Path]) -> (bool, String) {
    let out = Command::new(python)
        .arg(repo().join("tools").join(script))
        .args(args)
        .output()
        .expect("python runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.success(), text)
}

/// `demo.glb` written by `rigport demo` into `dir`.
fn demo_glb() -> PathBuf {
    crate::common::demo_outputs().join("demo.glb")
}

/// (name, data start, stored, data) of every member, in order.
fn members(usdz: &Path) -> Vec<(String, u64, bool, Vec<u8>)> {
    let file = std::fs::File::open(usdz).unwrap();
    let mut archive = zip::ZipArchive::new(file).unwrap();
    (0..archive.len())
        .map(|i| {
            let mut m = archive.by_index(i).unwrap();
            let mut data = Vec::new();
            let (name, start) = (m.name().to_string(), m.data_start());
            let stored = m.compression() == zip::CompressionMethod::Stored;
            m.read_to_end(&mut data).unwrap();
            (name, start, stored, data)
        })
        .collect()
}

#[test]
fn demo_usdz_passes_every_usd_core_validator() {
    let dir = scratch();
    let glb = demo_glb();
    let usdz = dir.path().join("demo.usdz");
    rigport_ok(&["convert", s(&glb), "-o", s(&usdz), "--quiet"]);
    // The package: a .usdc root layer first, every member stored and 64-byte aligned.
    let m = members(&usdz);
    assert_eq!(m[0].0, "demo.usdc");
    assert!(m[0].3.starts_with(b"PXR-USDC\x00\x08\x00"));
    for (name, start, stored, _) in &m {
        assert!(
            *stored && start % 64 == 0,
            "{name}: stored {stored}, at {start}"
        );
    }
    // No file beside it: the package is the whole output.
    let beside: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(beside.len(), 1, "{beside:?}");
    let Some(py) = crate::usd::python() else {
        return;
    };
    let (ok, text) = tool(&py, "check_usdz.py", &[&usdz]);
    eprintln!("{text}");
    assert!(ok && text.contains("0 findings"), "{text}");
    // `usdchecker --arkit`: with an older usd-core that still has the ComplianceChecker.
    if let Some(arkit_py) = std::env::var_os("RIGPORT_ARKIT_PYTHON") {
        let (ok, text) = tool(Path::new(&arkit_py), "check_usdz.py", &[&usdz]);
        eprintln!("{text}");
        assert!(ok && text.contains("ARKitShaderChecker"), "{text}");
    }
    // rigport's own UsdSkel checks too.
    let (ok, text) = crate::usd::check_usd(&py, &usdz, None);
    assert!(ok, "{text}");
}

/// The inputs the `.usdc` / `.usdz` outputs are compared on: (label, rigport arguments).
fn inputs() -> Vec<(String, Vec<PathBuf>)> {
    let mut out = vec![("demo".to_string(), vec![demo_glb()])];
    let pinocchio = PINOCCHIO_RIGS[0];
    if let (Some(m), Some(sk), Some(a)) = (
        corpus(pinocchio.1),
        corpus(pinocchio.2),
        corpus(pinocchio.3),
    ) {
        out.push((pinocchio.0.to_string(), vec![m, sk, a]));
    }
    let asf = "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik";
    if let (Some(asf), Some(amc)) = (
        corpus(&format!("{asf}/07-walk.asf")),
        corpus(&format!("{asf}/07_05-walk.amc")),
    ) {
        out.push(("asf_amc".into(), vec![asf, amc]));
    }
    for (label, rel) in [
        (
            "bvh",
            "4_bvh/bandai_namco_ds1/dataset-1_kick_normal_001.bvh",
        ),
        ("gltf", GLTF_SAMPLES[2]),
        ("usda", "6_usd/ustc_cg_24_hw10__USTC-CG/arm.usda"),
        (
            "usdc",
            "6_usd/tinyusdz_tests__lighttransport/tests_usdc_usdskel-001.usdc",
        ),
        ("usdz", "6_usd/usdz_test_assets__usd-wg/BoxAnimated.usdz"),
    ] {
        if let Some(p) = corpus(rel) {
            out.push((label.into(), vec![p]));
        }
    }
    out
}

/// The `rigport convert` arguments for an input's files.
fn convert_args(files: &[PathBuf], out: &Path) -> Vec<String> {
    let mut args = vec!["convert".to_string()];
    match files {
        [mesh, skeleton, attachment] => {
            args.extend([s(mesh).into(), "--skeleton".into(), s(skeleton).into()]);
            args.extend(["--attachment".into(), s(attachment).into()]);
        }
        [asf, amc] => args.extend([s(asf).into(), "--motion".into(), s(amc).into()]),
        [one] => args.push(s(one).into()),
        _ => unreachable!(),
    }
    args.extend(["-o".into(), s(out).into(), "--quiet".into()]);
    args
}

#[test]
fn usdc_and_usdz_hold_the_usda_layer_and_evaluate_the_same() {
    let dir = scratch();
    let py = crate::usd::python();
    let mut compared = 0;
    for (label, files) in inputs() {
        let out = |ext: &str| dir.path().join(format!("{label}.{ext}"));
        for ext in ["usda", "usdc", "usdz"] {
            let args = convert_args(&files, &out(ext));
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            rigport_ok(&args);
        }
        // Our reader reads the .usdc and the .usdz to the asset it reads from the .usda.
        let glb = |ext: &str| {
            let glb = dir.path().join(format!("{label}_{ext}.glb"));
            rigport_ok(&["convert", s(&out(ext)), "-o", s(&glb), "--quiet"]);
            std::fs::read(glb).unwrap()
        };
        let from_text = glb("usda");
        assert!(
            glb("usdc") == from_text,
            "{label}: .usdc imports differently"
        );
        assert!(
            glb("usdz") == from_text,
            "{label}: .usdz imports differently"
        );
        // Deterministic bytes (the same file name: it names the textures).
        std::fs::create_dir_all(dir.path().join("again")).unwrap();
        for ext in ["usdc", "usdz"] {
            let again = dir.path().join("again").join(format!("{label}.{ext}"));
            let args = convert_args(&files, &again);
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            rigport_ok(&args);
            let same = std::fs::read(&again).unwrap() == std::fs::read(out(ext)).unwrap();
            assert!(same, "{label}.{ext}: a second run wrote other bytes");
        }
        if let Some(py) = &py {
            // The .usdz is compared for the demo only (the same crate file is its root
            // layer everywhere; usdz_packs_the_textures_with_relative_paths checks the
            // textured glTF's package).
            let exts: &[&str] = if label == "demo" {
                &["usdc", "usdz"]
            } else {
                &["usdc"]
            };
            for ext in exts {
                let (ok, text) = tool(py, "same_usd.py", &[&out("usda"), &out(ext)]);
                eprintln!("{label}.{ext}: {}", text.trim());
                assert!(ok, "{label}.{ext}: {text}");
            }
            compared += 1;
        }
    }
    eprintln!("{compared} inputs compared with usd-core");
}

#[test]
fn usdz_packs_the_textures_with_relative_paths() {
    let Some(src) = corpus(GLTF_SAMPLES[2]) else {
        return;
    };
    let dir = scratch();
    let usdz = dir.path().join("man.usdz");
    let usdc = dir.path().join("man.usdc");
    rigport_ok(&["convert", s(&src), "-o", s(&usdz), "--quiet"]);
    rigport_ok(&["convert", s(&src), "-o", s(&usdc), "--quiet"]);
    let m = members(&usdz);
    let names: Vec<&str> = m.iter().map(|x| x.0.as_str()).collect();
    assert_eq!(names, ["man.usdc", "man_image0.jpg"]);
    // The texture is the one a .usdc writes beside itself, byte for byte.
    let beside = std::fs::read(dir.path().join("man_image0.jpg")).unwrap();
    assert_eq!(m[1].3, beside);
    for (name, start, stored, _) in &m {
        assert!(
            *stored && start % 64 == 0,
            "{name}: stored {stored}, at {start}"
        );
    }
    let Some(py) = crate::usd::python() else {
        return;
    };
    // Every validator, and every asset path resolving inside the package.
    let (ok, text) = tool(&py, "check_usdz.py", &[&usdz]);
    assert!(ok && text.contains("0 findings"), "{text}");
}

#[test]
fn usd_without_an_encoding_is_refused() {
    let dir = scratch();
    let glb = demo_glb();
    let out = rigport(&["convert", s(&glb), "-o", s(&dir.path().join("x.usd"))]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(".usda (text), .usdc (binary) or .usdz (package)"),
        "{err}"
    );
}

/// The images a `.glb` embeds (bufferView images), in `images` order.
fn glb_images(glb: &Path) -> Vec<Vec<u8>> {
    let bytes = std::fs::read(glb).unwrap();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let bin_start = 20 + json_len + 8;
    let views = json["bufferViews"].as_array().cloned().unwrap_or_default();
    json["images"]
        .as_array()
        .cloned()
        .unwrap_or_default()
        .iter()
        .map(|image| {
            let view = &views[image["bufferView"].as_u64().unwrap() as usize];
            let offset = view["byteOffset"].as_u64().unwrap_or(0) as usize;
            let len = view["byteLength"].as_u64().unwrap() as usize;
            bytes[bin_start + offset..bin_start + offset + len].to_vec()
        })
        .collect()
}

/// Every corpus `.usdz` converted to `.glb` keeps the textures its package holds, byte for
/// byte (Reality Converter's `0/…` members included), with a valid glb, and the material
/// binds them (no 0.18 grey fallback).
#[test]
fn usdz_textures_are_kept_in_the_glb_byte_for_byte() {
    let dir = corpus_dir().join("6_usd");
    if require("the corpus (../shared/corpus)", dir.is_dir().then_some(())).is_none() {
        return;
    }
    let mut packages: Vec<PathBuf> = Vec::new();
    let mut stack = vec![dir];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap().flatten() {
            let p = entry.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|e| e == "usdz") {
                packages.push(p);
            }
        }
    }
    let mut textured = 0;
    for usdz in packages {
        let mut archive = zip::ZipArchive::new(std::fs::File::open(&usdz).unwrap()).unwrap();
        let mut members: Vec<Vec<u8>> = Vec::new();
        for i in 1..archive.len() {
            let mut file = archive.by_index(i).unwrap();
            let name = file.name().to_ascii_lowercase();
            if name.ends_with(".png") || name.ends_with(".jpg") || name.ends_with(".jpeg") {
                let mut data = Vec::new();
                file.read_to_end(&mut data).unwrap();
                members.push(data);
            }
        }
        if members.is_empty() {
            continue;
        }
        textured += 1;
        let out = tempfile::tempdir().unwrap();
        let glb = out.path().join("out.glb");
        let log = rigport_ok(&["convert", s(&usdz), "-o", s(&glb)]);
        assert!(!log.contains("cannot be read"), "{}: {log}", usdz.display());
        let images = glb_images(&glb);
        for member in &members {
            assert!(
                images.contains(member),
                "{}: a texture of the package is not in the glb byte for byte",
                usdz.display()
            );
        }
        assert_valid(&glb);
    }
    assert!(textured > 0, "no corpus .usdz holds textures");
}
