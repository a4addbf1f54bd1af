//! Animated transforms above the skeleton become root motion (issue 22): UsdSkel's
//! evaluation (usd-core) of the source is the reference for the `.usda` and the `.glb`.

use std::path::Path;
use std::process::Command;

use crate::common::*;
use crate::frames::{deviation, usd_world};
use crate::usd::{check_usd, python};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Largest deviation over frames, relative to each frame's diagonal.
fn worst(a: &[crate::frames::Frame], b: &[crate::frames::Frame]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| deviation(&x.points, &y.points))
        .fold(0.0, f64::max)
}

#[test]
fn animated_xforms_above_the_skeleton_become_root_motion() {
    let Some(py) = python() else {
        return;
    };
    let dir = scratch();
    let out = Command::new(&py)
        .arg(repo().join("tests/cli/usd_root_motion.py"))
        .arg(dir.path())
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let source = dir.path().join("moving.usda");

    // .usda: exact at every frame (time code) up to SkelAnimation's float3/quatf storage
    // (the character is 80 cm from the origin, 8 cm tall: about 1e-6 of its diagonal).
    let usda = dir.path().join("moving_out.usda");
    let stderr = rigport_ok(&["convert", s(&source), "-o", s(&usda)]);
    assert!(stderr.contains("root motion"), "{stderr}");
    let (ok, report) = check_usd(&py, &usda, None);
    assert!(ok, "{report}");
    let frames: Vec<f64> = (0..=24).map(|k| f64::from(k) / 24.0).collect();
    let want = usd_world(&py, &source, Some(&frames), None);
    let got = usd_world(&py, &usda, Some(&frames), None);
    let dev = worst(&got, &want);
    eprintln!("moving.usda -> .usda under UsdSkel, every frame: {dev:e} of the diagonal");
    assert!(dev <= 1e-5, "{dev:e}");

    // .glb: rigport's evaluation of the glTF (Y-up metres) at its key times.
    let glb = dir.path().join("moving.glb");
    rigport_ok(&["convert", s(&source), "-o", s(&glb), "--quiet"]);
    assert_valid(&glb);
    let npz = dir.path().join("moving.npz");
    rigport_ok(&["eval", s(&glb), "--out", s(&npz), "--quiet"]);
    let dump = read_npz(&npz);
    let times = dump["times"].numbers.clone();
    let pos = &dump["positions"];
    let (n_frames, v) = (pos.shape[0], pos.shape[1]);
    let want = usd_world(&py, &source, Some(&times), None);
    let mut dev = 0.0f64;
    for f in 0..n_frames {
        let got: Vec<[f64; 3]> = (0..v)
            .map(|i| [0, 1, 2].map(|k| pos.numbers[(f * v + i) * 3 + k]))
            .collect();
        dev = dev.max(deviation(&got, &want[f].points));
    }
    eprintln!("moving.usda -> .glb vs UsdSkel in Y-up metres: {dev:e} of the diagonal");
    assert!(dev <= 1e-5, "{dev:e}");
}
