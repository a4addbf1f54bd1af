//! The fuzz entry points: one function per rigport importer, taking the raw bytes a fuzzer
//! made. Each writes the bytes to the file (or files) the importer reads, runs the same
//! entry point the CLI runs, and checks what must hold for any input:
//!
//! - no panic (a panic is the crash the fuzzer reports);
//! - an error formats to a message (its `Display` does not panic);
//! - an imported asset passes [`rigport_model::Asset::validate`] (importers promise it).
//!
//! Multi-file formats take one input split at NUL bytes: Pinocchio `mesh.obj \0
//! skeleton.out \0 attachment.out`; CSCI 520 `hierarchy \0 rest transforms \0 weights \0
//! mesh.obj` beside a fixed `skin.config`. AMC inputs are read against a fixed ASF and the
//! JSON inputs (POSE/KEYS/HANDLES) against a fixed skeleton, both from `fixtures/`.
//!
//! `cargo fuzz` drives these through `fuzz_targets/` (see `fuzz/README.md`); the test
//! `fuzz/tests/regressions.rs` replays the corpus and every crash input kept in the repo.
#![warn(missing_docs)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use rigport_import::{asf_amc, bvh, collada, csci520, gltf, json, obj, pinocchio, usda, Imported};
use rigport_model::Skeleton;

/// The fixed ASF the AMC target reads motions against.
const AMC_SKELETON: &str = include_str!("../../fixtures/asf_amc/root_frame.asf");
/// The BVH whose skeleton the JSON targets name joints of.
const JSON_SKELETON: &str = include_str!("../../fixtures/bvh/end_sites.bvh");
/// The CSCI 520 config beside the fuzzed files.
const CSCI520_CONFIG: &str =
    "*meshFilename\nmesh.obj\n*jointHierarchyFilename\njointHierarchy.txt\n\
*jointRestTransformsFilename\njointRestTransforms.txt\n*jointWeightsFilename\njointWeights.txt\n\
*IKJointIDs\n0\n";

/// A folder of this process for the files the importers read.
fn scratch() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let shm = Path::new("/dev/shm");
        let base = if shm.is_dir() {
            shm.to_path_buf()
        } else {
            std::env::temp_dir()
        };
        let dir = base.join(format!("rigport-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch folder for fuzz inputs");
        dir
    })
}

/// Writes `bytes` to `name` in the scratch folder and returns its path.
fn file(name: &str, bytes: &[u8]) -> PathBuf {
    let path = scratch().join(name);
    std::fs::write(&path, bytes).expect("write fuzz input");
    path
}

/// The NUL-separated parts of `data`, padded with empty parts to `n`.
fn parts(data: &[u8], n: usize) -> Vec<&[u8]> {
    let mut parts: Vec<&[u8]> = data.splitn(n, |&b| b == 0).collect();
    parts.resize(n, &[]);
    parts
}

/// Checks what an import must give for any input.
fn check<E: std::fmt::Display>(result: Result<Imported, E>) {
    match result {
        Ok(imported) => {
            if let Err(e) = imported.asset.validate() {
                panic!("an importer returned an invalid asset: {e:?}");
            }
            for w in &imported.warnings {
                let _ = w.to_string();
            }
        }
        Err(e) => {
            let _ = e.to_string();
        }
    }
}

/// An OBJ mesh (as rigport reads the mesh of a Pinocchio rig).
pub fn obj(data: &[u8]) {
    check(obj::import(&file("mesh.obj", data)));
}

/// A Pinocchio rig: `mesh.obj \0 skeleton.out \0 attachment.out`.
pub fn pinocchio(data: &[u8]) {
    let p = parts(data, 3);
    let mesh = file("mesh.obj", p[0]);
    let skeleton = file("skeleton.out", p[1]);
    let attachment = file("attachment.out", p[2]);
    check(pinocchio::import(&mesh, &skeleton, &attachment));
}

/// A USC CSCI 520 rig: `jointHierarchy.txt \0 jointRestTransforms.txt \0 jointWeights.txt
/// \0 mesh.obj`, beside a fixed `skin.config`.
pub fn csci520(data: &[u8]) {
    let p = parts(data, 4);
    file("jointHierarchy.txt", p[0]);
    file("jointRestTransforms.txt", p[1]);
    file("jointWeights.txt", p[2]);
    file("mesh.obj", p[3]);
    let config = file("skin.config", CSCI520_CONFIG.as_bytes());
    check(csci520::import(&config).map(|rig| rig.imported));
}

/// An Acclaim ASF skeleton alone.
pub fn asf(data: &[u8]) {
    check(asf_amc::import(&file("skeleton.asf", data), &[], 120.0));
}

/// An Acclaim AMC motion, read against a fixed ASF.
pub fn amc(data: &[u8]) {
    let asf = file("skeleton.asf", AMC_SKELETON.as_bytes());
    let amc = file("motion.amc", data);
    check(asf_amc::import(&asf, &[amc], 120.0));
}

/// A BVH motion.
pub fn bvh(data: &[u8]) {
    check(bvh::import(&file("motion.bvh", data)));
}

/// A glTF JSON or GLB file (the file name says `.glb`; the reader goes by content).
pub fn gltf(data: &[u8]) {
    check(gltf::import(&file("asset.glb", data)));
}

/// A USD layer: `.usda` text, a `.usdc` crate file or a `.usdz` package (told apart by
/// their first bytes, as the CLI does).
pub fn usd(data: &[u8]) {
    check(usda::import(&file("stage.usd", data)));
}

/// A COLLADA document or `.zae` package, through the importer's byte entry point
/// (`collada::import_slice`, which tells a package by its zip signature).
pub fn collada(data: &[u8]) {
    check(collada::import_slice(data, &scratch().join("scene.dae")));
}

/// The skeleton the JSON targets name joints of.
fn json_skeleton() -> &'static Skeleton {
    static SKELETON: OnceLock<Skeleton> = OnceLock::new();
    SKELETON.get_or_init(|| {
        let path = file("skeleton.bvh", JSON_SKELETON.as_bytes());
        bvh::import(&path)
            .expect("fixtures/bvh/end_sites.bvh imports")
            .asset
            .skeleton
    })
}

/// A POSE.json for a fixed skeleton.
pub fn json_pose(data: &[u8]) {
    let skeleton = json_skeleton();
    if let Err(e) = json::pose::read(&file("pose.json", data), skeleton) {
        let _ = e.to_string();
    }
}

/// A KEYS.json for a fixed skeleton.
pub fn json_keys(data: &[u8]) {
    let skeleton = json_skeleton();
    if let Err(e) = json::keys::read(&file("keys.json", data), skeleton) {
        let _ = e.to_string();
    }
}

/// A HANDLES.json for a fixed skeleton.
pub fn json_handles(data: &[u8]) {
    let skeleton = json_skeleton();
    if let Err(e) = json::handles::read(&file("handles.json", data), skeleton) {
        let _ = e.to_string();
    }
}

/// A fuzz entry point.
pub type Target = fn(&[u8]);

/// Every target by name, for the regression test and tools.
pub const TARGETS: [(&str, Target); 12] = [
    ("obj", obj),
    ("pinocchio", pinocchio),
    ("csci520", csci520),
    ("asf", asf),
    ("amc", amc),
    ("bvh", bvh),
    ("gltf", gltf),
    ("usd", usd),
    ("collada", collada),
    ("json_pose", json_pose),
    ("json_keys", json_keys),
    ("json_handles", json_handles),
];
