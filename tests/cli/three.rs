//! What three.js shows for our files: `tools/three_eval.mjs` loads a glb with three's own
//! GLTFLoader, plays a clip with its AnimationMixer and reports world-space vertex
//! positions as three computes them (morph targets, then the first four influences).
//! Other test modules call [`three_eval`].

use std::path::Path;
use std::process::Command;

use crate::common::{self, NpyArray};

/// Runs `tools/three_eval.mjs` on `file` with `args` (e.g. `["--clip-index", "0", "--fps",
/// "10"]`): the tool's JSON report and the positions (times x vertices x 3, all meshes in
/// scene order). `None` (skip) when three.js is not installed (`bash tools/setup.sh`),
/// failure in CI.
pub fn three_eval(file: &Path, args: &[&str]) -> Option<(serde_json::Value, NpyArray)> {
    let repo = common::repo();
    let installed = repo.join("tools/node_modules/three/package.json").exists();
    common::require("three.js (bash tools/setup.sh)", installed.then_some(()))?;
    let dir = common::scratch();
    let npy = dir.path().join("positions.npy");
    let out = Command::new("node")
        .arg(repo.join("tools/three_eval.mjs"))
        .arg(file)
        .args(args)
        .arg("--npy")
        .arg(&npy)
        .output()
        .expect("node runs");
    assert!(
        out.status.success(),
        "three_eval failed on {}: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("three_eval JSON");
    Some((report, common::read_npy(&npy)))
}

/// Largest distance between two position arrays over the bounding-box diagonal of the
/// first frame of `a`.
fn relative_max_deviation(a: &NpyArray, b: &[f64]) -> f64 {
    assert_eq!(a.numbers.len(), b.len(), "same number of positions");
    let frame = a.shape[1] * 3;
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in a.numbers[..frame].chunks_exact(3) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let diag = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let max = a
        .numbers
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    max / diag
}

/// `ours` (frames x vertices x 3, rigport's mesh order) with its meshes in three's scene
/// order: each of three's meshes is paired with rigport's mesh of the same vertex count
/// (`rigport inspect`), which the demo's files make unique.
pub fn in_three_order(glb: &Path, report: &serde_json::Value, ours: &NpyArray) -> Vec<f64> {
    let out = common::rigport(&["inspect", "--json", glb.to_str().unwrap()]);
    assert!(out.status.success(), "inspect {}", glb.display());
    let listing: serde_json::Value = serde_json::from_slice(&out.stdout).expect("inspect JSON");
    let counts: Vec<usize> = listing[0]["meshes"]
        .as_array()
        .expect("meshes")
        .iter()
        .map(|m| m["vertices"].as_u64().expect("vertex count") as usize)
        .collect();
    let starts: Vec<usize> = counts
        .iter()
        .scan(0, |start, &n| {
            let s = *start;
            *start += n;
            Some(s)
        })
        .collect();
    let names: Vec<&str> = listing[0]["meshes"]
        .as_array()
        .expect("meshes")
        .iter()
        .map(|m| m["name"].as_str().unwrap_or(""))
        .collect();
    // Each of three's meshes is the rigport mesh of its name and size, else the first
    // unmatched one of its size (two meshes of one size must not both map to the first).
    let mut used = vec![false; counts.len()];
    let order: Vec<(usize, usize)> = report["meshes"]
        .as_array()
        .expect("meshes")
        .iter()
        .map(|mesh| {
            let n = mesh["vertex_count"].as_u64().expect("vertex_count") as usize;
            let name = mesh["name"].as_str().unwrap_or("");
            let free = |k: &usize| !used[*k] && counts[*k] == n;
            let k = (0..counts.len())
                .find(|k| free(k) && names[*k] == name)
                .or_else(|| (0..counts.len()).find(free))
                .expect("a mesh of that size");
            used[k] = true;
            (k, n)
        })
        .collect();
    let vertices = ours.shape[1];
    let mut out = Vec::with_capacity(ours.numbers.len());
    for frame in ours.numbers.chunks_exact(vertices * 3) {
        for &(k, n) in &order {
            out.extend_from_slice(&frame[starts[k] * 3..(starts[k] + n) * 3]);
        }
    }
    out
}

/// three.js plays rigport's glb as it plays the source glTF. (bevy's SimpleSkin.gltf is
/// left out: its rotation keys are not unit quaternions (|q| - 1 up to 2.3e-4, which the
/// glTF spec forbids); three slerps them unnormalized while rigport writes unit keys, so
/// the two differ by 4.5e-4 of the diagonal between keys.)
#[test]
fn three_plays_our_glb_as_it_plays_the_source_gltf() {
    for rel in [
        "5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb",
        "5_gltf/khronos_samples__nobuyuki83_delfem2/RiggedFigure.glb",
        "5_gltf/blender_io_roundtrip__KhronosGroup/03_skinned_cylinder.gltf",
    ] {
        let Some(src) = common::corpus(rel) else {
            continue;
        };
        let dir = common::scratch();
        let glb = dir.path().join("out.glb");
        common::rigport_ok(&[
            "convert",
            "-q",
            src.to_str().unwrap(),
            "-o",
            glb.to_str().unwrap(),
        ]);
        let args = ["--clip-index", "0", "--fps", "7"];
        let Some((_, theirs)) = three_eval(&src, &args) else {
            return;
        };
        let (_, ours) = three_eval(&glb, &args).expect("three.js is installed");
        assert_eq!(theirs.shape, ours.shape, "{rel}: frames x vertices x 3");
        let dev = relative_max_deviation(&theirs, &ours.numbers);
        eprintln!("{rel}: three.js, source vs ours: {dev:.2e} of the diagonal");
        assert!(dev <= 1e-5, "{rel}: {dev:e} of the diagonal");
    }
}
