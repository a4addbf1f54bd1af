//! Runs three.js on both sides of a conversion: `tools/three_source_eval.mjs` plays the
//! source with three's own FBXLoader / ColladaLoader, `tools/three_eval.mjs` plays our glb
//! with its GLTFLoader; both write world-space vertex positions (morph targets, then the
//! four influences three keeps, as its shader) at the given clip times, and the scene as
//! loaded. Used by `fbx_fidelity`.

use std::path::Path;
use std::process::Command;

use crate::common::{self, read_npy, NpyArray};
use crate::fidelity_match::Points;

/// What one run reported: its JSON, the positions per time and the rest positions.
pub struct Played {
    pub report: serde_json::Value,
    pub frames: Vec<Points>,
    pub rest: Points,
}

fn frames_of(npy: &NpyArray) -> Vec<Points> {
    let v = npy.shape[1];
    if v == 0 {
        return vec![Vec::new(); npy.shape[0]];
    }
    npy.numbers
        .chunks_exact(v * 3)
        .map(|f| f.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect())
        .collect()
}

/// Comma-separated seconds for `--times`.
pub fn time_list(times: &[f64]) -> String {
    times
        .iter()
        .map(|t| format!("{t}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// Runs `node tools/TOOL FILE ARGS --npy .. --rest-npy ..`. `None` (skip) when three.js is
/// not installed (`bash tools/setup.sh`), failure in CI.
pub fn play(tool: &str, file: &Path, args: &[&str]) -> Option<Played> {
    let repo = common::repo();
    let modules = repo.join("tools/node_modules");
    let installed = ["three", "@xmldom/xmldom"]
        .iter()
        .all(|m| modules.join(m).join("package.json").exists());
    common::require(
        "three.js and xmldom (bash tools/setup.sh)",
        installed.then_some(()),
    )?;
    let dir = common::scratch();
    let (npy, rest) = (dir.path().join("p.npy"), dir.path().join("r.npy"));
    let out = Command::new("node")
        .arg(repo.join("tools").join(tool))
        .arg(file)
        .args(args)
        .arg("--npy")
        .arg(&npy)
        .arg("--rest-npy")
        .arg(&rest)
        .output()
        .expect("node runs");
    assert!(
        out.status.success(),
        "{tool} failed on {}: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let report = serde_json::from_slice(&out.stdout).expect("the tool's JSON");
    let rest = frames_of(&read_npy(&rest)).swap_remove(0);
    Some(Played {
        report,
        frames: frames_of(&read_npy(&npy)),
        rest,
    })
}
