//! USD export end to end: every corpus asset rigport converts goes to `.usda`, passes
//! usd-core's validators and rigport's own checks (tools/check_usd.py), and UsdSkel's
//! evaluation of it equals `rigport eval` of the source on every frame, LBS and DQS.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::*;
use crate::motion::{ASF_AMC, BVH};

/// The venv's Python (`RIGPORT_PYTHON`, set by tools/test.sh, else tools/.venv), or skip.
pub fn python() -> Option<PathBuf> {
    let p = std::env::var_os("RIGPORT_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join("tools/.venv/bin/python"));
    require(
        "the usd-core venv (bash tools/setup.sh)",
        p.exists().then_some(p),
    )
}

/// Runs tools/check_usd.py; returns (success, stdout + stderr).
pub fn check_usd(python: &Path, usda: &Path, against: Option<&Path>) -> (bool, String) {
    let mut cmd = Command::new(python);
    cmd.arg(repo().join("tools/check_usd.py")).arg(usda);
    if let Some(dump) = against {
        cmd.arg("--against").arg(dump);
    }
    let out = cmd.output().expect("python runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.success(), text)
}

/// Runs tools/check_usd.py on each (file, dump) in one Python process (`--batch`: usd-core
/// loads once); returns each job's (success, output), in order.
pub fn check_usd_all(python: &Path, jobs: &[(PathBuf, Option<PathBuf>)]) -> Vec<(bool, String)> {
    let argv: Vec<Vec<String>> = jobs
        .iter()
        .map(|(usd, dump)| {
            let mut a = vec![usd.display().to_string()];
            if let Some(d) = dump {
                a.extend(["--against".to_string(), d.display().to_string()]);
            }
            a
        })
        .collect();
    let list = tempfile::NamedTempFile::new().expect("a jobs file");
    std::fs::write(list.path(), serde_json::to_string(&argv).unwrap()).unwrap();
    let out = Command::new(python)
        .arg(repo().join("tools/check_usd.py"))
        .arg("--batch")
        .arg(list.path())
        .output()
        .expect("python runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let mut results = Vec::new();
    let mut text = String::new();
    for line in stdout.lines() {
        if line.starts_with("==> check_usd job ") {
            text.clear();
        } else if let Some(rest) = line.strip_prefix("<== check_usd job ") {
            let rc = rest.rsplit(' ').next().unwrap_or("?");
            results.push((rc == "0", std::mem::take(&mut text)));
        } else {
            text.push_str(line);
            text.push('\n');
        }
    }
    assert_eq!(
        results.len(),
        jobs.len(),
        "check_usd.py --batch ended early ({:?}):\n{stdout}\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    results
}

/// One corpus asset as `rigport` arguments, or `None` when its files are absent.
fn assets() -> Vec<(String, Vec<PathBuf>)> {
    let mut out = Vec::new();
    for (label, m, s, a) in PINOCCHIO_RIGS {
        if let (Some(m), Some(s), Some(a)) = (corpus(m), corpus(s), corpus(a)) {
            out.push((label.to_string(), vec![m, s, a]));
        }
    }
    for rig in ["armadillo", "hand", "star"] {
        let rel = format!("2_csci520_ik_skinning/{rig}");
        if let Some(dir) = require(&format!("CSCI 520 rig {rig}"), find_config(&rel)) {
            out.push((format!("csci520_{rig}"), vec![dir]));
        }
    }
    for (asf, amc) in ASF_AMC {
        if let (Some(asf), Some(amc)) = (corpus(asf), corpus(amc)) {
            let label = amc.file_stem().unwrap().to_string_lossy().into_owned();
            out.push((label, vec![asf, amc]));
        }
    }
    for bvh in BVH {
        if let Some(p) = corpus(bvh) {
            let label = p.file_stem().unwrap().to_string_lossy().into_owned();
            out.push((label, vec![p]));
        }
    }
    for g in GLTF_SAMPLES {
        if let Some(p) = corpus(g) {
            let label = p.file_stem().unwrap().to_string_lossy().into_owned();
            out.push((label, vec![p]));
        }
    }
    out
}

/// The folder holding a CSCI 520 rig's `skin.config` under `rel` (searched one level down).
fn find_config(rel: &str) -> Option<PathBuf> {
    let root = repo().join("../shared/corpus/2_csci520_ik_skinning");
    let want = rel.rsplit('/').next().unwrap().to_ascii_lowercase();
    let mut stack = vec![root];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).ok()?.flatten() {
            let p = e.path();
            if p.is_dir() {
                if p.file_name()
                    .unwrap()
                    .to_string_lossy()
                    .to_ascii_lowercase()
                    == want
                    && p.join("skin.config").exists()
                {
                    return Some(p);
                }
                stack.push(p);
            }
        }
    }
    None
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn corpus_assets_export_to_usd_that_usdskel_evaluates_like_rigport() {
    let Some(py) = python() else {
        return;
    };
    let assets = assets();
    if require("corpus assets", (!assets.is_empty()).then_some(())).is_none() {
        return;
    }
    let dir = scratch();
    let mut failures = Vec::new();
    let mut jobs = Vec::new();
    let mut labels = Vec::new();
    for (label, inputs) in &assets {
        let args: Vec<&str> = inputs.iter().map(|p| s(p)).collect();
        for method in ["lbs", "dqs"] {
            let usda = dir.path().join(format!("{label}_{method}.usda"));
            let dump = dir.path().join(format!("{label}_{method}.npz"));
            let mut convert = vec!["convert"];
            convert.extend(&args);
            convert.extend(["--skinning", method, "-o", s(&usda), "--quiet"]);
            rigport_ok(&convert);
            let mut eval = vec!["eval"];
            eval.extend(&args);
            eval.extend(["--skinning", method, "--out", s(&dump), "--quiet"]);
            rigport_ok(&eval);
            jobs.push((usda, Some(dump)));
            labels.push(format!("{label} {method}"));
        }
    }
    for (label, (ok, text)) in labels.iter().zip(check_usd_all(&py, &jobs)) {
        let summary: Vec<&str> = text
            .lines()
            .filter(|l| l.contains("max") || l.contains("FAIL") || l.contains("error"))
            .take(6)
            .collect();
        eprintln!("{label}: {}", summary.join(" | "));
        if !ok {
            failures.push(format!("{label}:\n{text}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn usda_round_trips_through_rigport_and_matches_the_original_gltf() {
    let Some(py) = python() else {
        return;
    };
    let Some(cesium) = corpus(GLTF_SAMPLES[2]) else {
        return;
    };
    let dir = scratch();
    let p = |n: &str| dir.path().join(n);
    // glTF -> USD -> glTF: UsdSkel's evaluation of the .usda, rigport's evaluation of the
    // original, and rigport's evaluation of the re-imported .usda agree.
    rigport_ok(&["convert", s(&cesium), "-o", s(&p("c.usda")), "--quiet"]);
    rigport_ok(&["eval", s(&cesium), "--out", s(&p("orig.npz")), "--quiet"]);
    rigport_ok(&[
        "eval",
        s(&p("c.usda")),
        "--out",
        s(&p("back.npz")),
        "--quiet",
    ]);
    let (ok, text) = check_usd(&py, &p("c.usda"), Some(&p("orig.npz")));
    assert!(ok, "{text}");
    let a = read_npz(&p("orig.npz"));
    let b = read_npz(&p("back.npz"));
    assert_eq!(a["positions"].shape, b["positions"].shape);
    let diag = {
        let r = &a["rest_positions"].numbers;
        let mut lo = [f64::MAX; 3];
        let mut hi = [f64::MIN; 3];
        for c in r.chunks(3) {
            for k in 0..3 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
    };
    let worst = a["positions"]
        .numbers
        .iter()
        .zip(&b["positions"].numbers)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 1e-5 * diag, "re-imported usda deviates {worst:e}");
    // And back to a validator-clean glTF.
    rigport_ok(&[
        "convert",
        s(&p("c.usda")),
        "-o",
        s(&p("again.glb")),
        "--quiet",
    ]);
    assert_valid(&p("again.glb"));
}

#[test]
fn demo_and_motion_commands_write_usda_too() {
    let Some(py) = python() else {
        return;
    };
    let Some(bvh) = corpus(BVH[3]) else {
        return;
    };
    let dir = scratch();
    let p = |n: &str| dir.path().join(n);
    rigport_ok(&[
        "retime",
        s(&bvh),
        "--speed",
        "2",
        "-o",
        s(&p("fast.usda")),
        "--quiet",
    ]);
    rigport_ok(&[
        "eval",
        s(&p("fast.usda")),
        "--out",
        s(&p("fast.npz")),
        "--quiet",
    ]);
    let (ok, text) = check_usd(&py, &p("fast.usda"), Some(&p("fast.npz")));
    assert!(ok, "{text}");
    let demo = crate::common::demo_outputs();
    let usda = demo.join("demo.usda");
    assert!(usda.exists(), "the demo writes demo.usda");
    let (ok, text) = check_usd(&py, &usda, None);
    assert!(ok, "{text}");
}
