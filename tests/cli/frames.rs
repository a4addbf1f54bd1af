//! Scene frames and units at the format boundaries (issue 22): glTF is +Y up in metres,
//! USD keeps the source's frame; UsdSkel's evaluation (usd-core) is the reference.

use std::path::Path;
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
    let mut cmd = Command::new(py);
    cmd.arg(repo().join("tests/cli/usd_world.py"))
        .arg(stage)
        .arg(repo().join("tools"))
        .arg(serde_json::to_string(&seconds).unwrap());
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
