//! Scene frames and units at the format boundaries (issue 22): glTF is +Y up in metres,
//! USD keeps the source's frame; UsdSkel's evaluation (usd-core) is the reference.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::*;
use crate::gltf_read;
use crate::motion::ASF_AMC;
use crate::usd::python;

/// One evaluated frame, +Y up, metres.
pub struct Frame {
    pub joints: Vec<[f64; 3]>,
    pub points: Vec<[f64; 3]>,
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn triples(v: &serde_json::Value) -> Vec<[f64; 3]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let a = p.as_array().unwrap();
            [0, 1, 2].map(|k| a[k].as_f64().unwrap())
        })
        .collect()
}

/// UsdSkel's evaluation of `stage` at `seconds` (None: the default time), in +Y-up metres
/// (tests/cli/usd_world.py).
pub fn usd_world(
    py: &Path,
    stage: &Path,
    seconds: Option<&[f64]>,
    clip: Option<&str>,
) -> Vec<Frame> {
    run_usd_world(py, stage, seconds, clip, &[])
}

/// Runs tests/cli/usd_world.py on `stage` with `extra` flags (`--model-space`): its frames.
pub fn run_usd_world(
    py: &Path,
    stage: &Path,
    seconds: Option<&[f64]>,
    clip: Option<&str>,
    extra: &[&str],
) -> Vec<Frame> {
    let mut cmd = Command::new(py);
    cmd.arg(repo().join("tests/cli/usd_world.py"))
        .arg(stage)
        .arg(repo().join("tools"))
        .arg(serde_json::to_string(&seconds).unwrap())
        .args(extra);
    if let Some(c) = clip {
        cmd.args(["--clip", c]);
    }
    let out = cmd.output().expect("python runs");
    assert!(
        out.status.success(),
        "usd_world.py {}: {}",
        stage.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| Frame {
            joints: triples(&f["joints"]),
            points: triples(&f["points"]),
        })
        .collect()
}

/// The bounding-box diagonal of `points`.
pub fn diagonal(points: &[[f64; 3]]) -> f64 {
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// Largest `|a - b|` over matching entries, relative to the diagonal of `b`.
pub fn deviation(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    assert_eq!(a.len(), b.len(), "point counts differ");
    let d = diagonal(b).max(1e-30);
    a.iter().zip(b).map(|(p, q)| dist(p, q)).fold(0.0, f64::max) / d
}

#[test]
fn asf_to_glb_is_in_metres_like_the_usda() {
    let (asf, amc) = ASF_AMC[0];
    let (Some(asf), Some(amc)) = (corpus(asf), corpus(amc)) else {
        return;
    };
    let dir = scratch();
    let glb = dir.path().join("walk.glb");
    let usda = dir.path().join("walk.usda");
    for out in [&glb, &usda] {
        rigport_ok(&["convert", s(&asf), s(&amc), "-o", s(out), "--quiet"]);
    }
    let scene = gltf_read::read(&glb);
    let world = scene.world(&Default::default());
    // Joints are the first nodes; the bone mesh's node comes last.
    let joints: Vec<[f64; 3]> = world
        .iter()
        .zip(&scene.node_names)
        .filter(|(_, n)| n.as_str() != "bones")
        .map(|(m, _)| m.w_axis.truncate().as_dvec3().to_array())
        .collect();
    let height = joints.iter().map(|p| p[1]).fold(f64::MIN, f64::max)
        - joints.iter().map(|p| p[1]).fold(f64::MAX, f64::min);
    assert!(
        (1.3..2.0).contains(&height),
        "a CMU figure is a person's height in glTF metres, got {height}"
    );
    let Some(py) = python() else {
        return;
    };
    let usd = usd_world(&py, &usda, None, None);
    let n = usd[0].joints.len();
    let dev = deviation(&joints[..n], &usd[0].joints);
    eprintln!("ASF .glb joints vs UsdSkel of the .usda in metres: {dev:e} of the diagonal");
    assert!(dev <= 1e-5, "{dev:e}");
}

/// Pixar's bake inputs, the Blender-exported arms, and the Blender-like fixture.
fn usd_sources() -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = [
        "6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning/lbs.usda",
        "6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning/dqs.usda",
        "6_usd/ustc_cg_24_hw10__USTC-CG/arm.usda",
        "6_usd/ustc_cg_24_hw10__USTC-CG/arm_with_cloth.usda",
    ]
    .iter()
    .filter_map(|r| corpus(r))
    .collect();
    out.push(repo().join("fixtures/usda/blender_frame.usda"));
    out
}

/// `source`, or a copy in `dir` with its implicit surfaces (Cube, Sphere, ...) deactivated:
/// usd_world.py evaluates Meshes only, while rigport tessellates those prims into meshes
/// (checked against UsdSkel in usd_topology.rs).
fn meshes_only(py: &Path, source: &Path, dir: &Path) -> PathBuf {
    const SCRIPT: &str = r#"
import sys
from pxr import Usd
s = Usd.Stage.Open(sys.argv[1])
n = 0
for p in list(s.Traverse()):
    if p.GetTypeName() in ("Cube", "Sphere", "Cylinder", "Capsule", "Cone"):
        p.SetActive(False)
        n += 1
if n:
    s.GetRootLayer().Export(sys.argv[2])
print(n)
"#;
    let name = source.file_name().unwrap().to_string_lossy().into_owned();
    let copy = dir.join(format!("meshes_only_{name}"));
    let out = Command::new(py)
        .args(["-c", SCRIPT])
        .arg(source)
        .arg(&copy)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    if String::from_utf8_lossy(&out.stdout).trim() == "0" {
        source.to_path_buf()
    } else {
        copy
    }
}

/// The key times (seconds) rigport samples a source's first clip at.
fn key_times(source: &Path, dir: &Path) -> Vec<f64> {
    let npz = dir.join("keys.npz");
    rigport_ok(&["eval", s(source), "--out", s(&npz), "--quiet"]);
    read_npz(&npz)["times"].numbers.clone()
}

/// Largest deviation over frames, points relative to each frame's diagonal.
fn worst(a: &[Frame], b: &[Frame]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| deviation(&x.points, &y.points))
        .fold(0.0, f64::max)
}

/// Tolerance of a USD -> USD round trip: 1e-6 of the diagonal, except arm.usda, whose
/// 4-digit quaternions ((0.7071, 0.7071, 0, 0)) rigport normalizes (with a warning),
/// which moves it by about 1.1e-5 of the diagonal: that difference is expected.
fn round_trip_tolerance(source: &Path) -> f64 {
    if source.ends_with("ustc_cg_24_hw10__USTC-CG/arm.usda") {
        2e-5
    } else {
        1e-6
    }
}

#[test]
fn usd_to_usda_evaluates_like_the_source_in_usdskel() {
    let Some(py) = python() else {
        return;
    };
    let dir = scratch();
    let mut report = Vec::new();
    for source in usd_sources() {
        let name = source.file_stem().unwrap().to_string_lossy().into_owned();
        let source = meshes_only(&py, &source, dir.path());
        let out = dir.path().join(format!("{name}.usda"));
        rigport_ok(&["convert", s(&source), "-o", s(&out), "--quiet"]);
        let times = key_times(&source, dir.path());
        let want = usd_world(&py, &source, Some(&times), None);
        let got = usd_world(&py, &out, Some(&times), None);
        let dev = worst(&got, &want);
        eprintln!("{name}: .usda vs source under UsdSkel: {dev:e} of the diagonal");
        if dev > round_trip_tolerance(&source) {
            report.push(format!("{name}: {dev:e}"));
        }
    }
    assert!(report.is_empty(), "{report:?}");
}

#[test]
fn usd_to_glb_plays_like_the_source_in_y_up_metres() {
    let Some(py) = python() else {
        return;
    };
    let dir = scratch();
    let mut report = Vec::new();
    for source in usd_sources() {
        let name = source.file_stem().unwrap().to_string_lossy().into_owned();
        let source = meshes_only(&py, &source, dir.path());
        let glb = dir.path().join(format!("{name}.glb"));
        rigport_ok(&["convert", s(&source), "-o", s(&glb), "--quiet"]);
        if name == "dqs" {
            // glTF is LBS only: compare the LBS source.
            continue;
        }
        let npz = dir.path().join(format!("{name}.npz"));
        rigport_ok(&["eval", s(&glb), "--out", s(&npz), "--quiet"]);
        let dump = read_npz(&npz);
        let times = dump["times"].numbers.clone();
        let pos = &dump["positions"];
        let (frames, v) = (pos.shape[0], pos.shape[1]);
        let glb_frames: Vec<Vec<[f64; 3]>> = (0..frames)
            .map(|f| {
                (0..v)
                    .map(|i| [0, 1, 2].map(|k| pos.numbers[(f * v + i) * 3 + k]))
                    .collect()
            })
            .collect();
        let want = usd_world(&py, &source, Some(&times), None);
        // glTF splits points on seams: each glTF vertex is matched with the source point
        // whose trajectory is nearest (points of two meshes may coincide in one frame).
        let n = want[0].points.len();
        let map: Vec<usize> = (0..v)
            .map(|i| {
                let cost = |a: usize| -> f64 {
                    glb_frames
                        .iter()
                        .zip(&want)
                        .map(|(g, w)| dist(&g[i], &w.points[a]))
                        .sum()
                };
                (0..n).min_by(|&a, &b| cost(a).total_cmp(&cost(b))).unwrap()
            })
            .collect();
        let mut dev = 0.0f64;
        for (f, frame) in glb_frames.iter().enumerate() {
            let expect: Vec<[f64; 3]> = map.iter().map(|&i| want[f].points[i]).collect();
            let d = diagonal(&want[f].points);
            let e = frame
                .iter()
                .zip(&expect)
                .map(|(a, b)| dist(a, b))
                .fold(0.0, f64::max)
                / d;
            dev = dev.max(e);
        }
        eprintln!("{name}: .glb vs UsdSkel of the source in Y-up metres: {dev:e} of the diagonal");
        // arm.usda: its 4-digit quaternions are normalized (see round_trip_tolerance).
        if dev > round_trip_tolerance(&source).max(1e-5) {
            report.push(format!("{name}: {dev:e}"));
        }
    }
    assert!(report.is_empty(), "{report:?}");
}

#[test]
fn dqs_usda_round_trip_keeps_dual_quaternion_skinning() {
    let Some(dqs) =
        corpus("6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning/dqs.usda")
    else {
        return;
    };
    let dir = scratch();
    let out = dir.path().join("dqs.usda");
    rigport_ok(&["convert", s(&dqs), "-o", s(&out), "--quiet"]);
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("uniform token primvars:skel:skinningMethod = \"dualQuaternion\""),
        "the source's method is kept"
    );
    // --skinning overrides it.
    rigport_ok(&[
        "convert",
        s(&dqs),
        "-o",
        s(&out),
        "--skinning",
        "lbs",
        "--quiet",
    ]);
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(!text.contains("dualQuaternion"));
    // glTF cannot carry it: a warning says the file deforms differently.
    let glb = dir.path().join("dqs.glb");
    let stderr = rigport_ok(&["convert", s(&dqs), "-o", s(&glb)]);
    assert!(stderr.contains("dual quaternions"), "{stderr}");
}
