//! Absurd frame rates fail at once with a message naming the rate and the limit (issue 14:
//! `--fps 1e9` used to allocate until the process died).

use std::time::{Duration, Instant};

use crate::common::{repo, rigport, scratch};

/// Runs rigport with `args` and checks it exits 1 quickly, naming the rate and the limit,
/// and writes nothing at `out`.
fn fails_fast(args: &[&str], out: &std::path::Path) {
    let started = Instant::now();
    let r = rigport(args);
    let elapsed = started.elapsed();
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{args:?}: {stderr}");
    assert!(
        stderr.contains("frame rate 1000000000 fps") && stderr.contains("the limit is 1000000"),
        "{args:?}: {stderr}"
    );
    // Generous for a debug build on a loaded machine; the old behaviour never finished.
    assert!(
        elapsed < Duration::from_secs(20),
        "{args:?}: took {elapsed:?}"
    );
    assert!(!out.exists(), "{args:?}: wrote {}", out.display());
}

fn fixture(rel: &str) -> String {
    repo().join("fixtures").join(rel).display().to_string()
}

#[test]
fn eval_with_an_absurd_fps_exits_1_at_once() {
    let dir = scratch();
    let out = dir.path().join("a.npz");
    let bvh = fixture("bvh/end_sites.bvh");
    fails_fast(
        &["eval", &bvh, "--fps", "1e9", "-o", out.to_str().unwrap()],
        &out,
    );
}

#[test]
fn render_with_an_absurd_fps_exits_1_at_once() {
    let dir = scratch();
    let out = dir.path().join("a.png");
    let bvh = fixture("bvh/end_sites.bvh");
    fails_fast(
        &["render", &bvh, "--fps", "1e9", "-o", out.to_str().unwrap()],
        &out,
    );
}

#[test]
fn bake_with_an_absurd_fps_exits_1_at_once() {
    let dir = scratch();
    let out = dir.path().join("a.glb");
    let rig = fixture("usda/skinned_arm.usda");
    fails_fast(
        &[
            "bake",
            &rig,
            "--skinning",
            "dqs",
            "--fps",
            "1e9",
            "-o",
            out.to_str().unwrap(),
        ],
        &out,
    );
}

#[test]
fn ik_with_an_absurd_fps_exits_1_at_once() {
    let dir = scratch();
    let out = dir.path().join("a.glb");
    let handles = dir.path().join("h.json");
    std::fs::write(
        &handles,
        r#"{"handles": [{"joint": "Head_end", "keys": [{"time": 0, "position": [0, 13, 0]}, {"time": 1, "position": [1, 12, 0]}]}]}"#,
    )
    .unwrap();
    let bvh = fixture("bvh/end_sites.bvh");
    fails_fast(
        &[
            "ik",
            &bvh,
            "--handles",
            handles.to_str().unwrap(),
            "--fps",
            "1e9",
            "-o",
            out.to_str().unwrap(),
        ],
        &out,
    );
}
