//! `--root-motion` (issue 30) on the corpus walks: `in-place` holds the hips over one point
//! with their up motion unchanged; `extract` puts the travel on a root joint whose track
//! with the hips' gives the original hips at every key, on a skinned rig whose vertices
//! stay where they were (rigport eval, three.js); `keep` writes today's bytes; the files
//! pass glTF-Validator and usd-core.

use std::path::{Path, PathBuf};

use rigport_model::glam::Vec3;

use crate::common::*;
use crate::gltf_read::{self, GltfScene};
use crate::motion::gltf_pose;
use crate::three::three_eval;

const CMU_WALK: (&str, &str) = (
    "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf",
    "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07_05-walk.amc",
);
const CGSPEED_WALK: &str = "4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh";
const BANDAI_WALK: &str = "4_bvh/bandai_namco_ds1/dataset-1_walk_normal_002.bvh";
const HUMAN_MODEL1: &str = "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1";

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The walks: label, rigport arguments, hips joint, leg joints (hip, knee, ankle).
fn walks() -> Vec<(&'static str, Vec<PathBuf>, &'static str, [&'static str; 3])> {
    let mut out = Vec::new();
    if let (Some(asf), Some(amc)) = (corpus(CMU_WALK.0), corpus(CMU_WALK.1)) {
        out.push((
            "CMU 07_05",
            vec![asf, amc],
            "root",
            ["lfemur", "ltibia", "lfoot"],
        ));
    }
    if let Some(bvh) = corpus(CGSPEED_WALK) {
        let leg = ["LeftUpLeg", "LeftLeg", "LeftFoot"];
        out.push(("cgspeed walk", vec![bvh], "Hips", leg));
    }
    out
}

/// Converts `inputs` to `out` with `extra` flags; returns stderr.
fn convert(inputs: &[PathBuf], out: &Path, extra: &[&str]) -> String {
    let mut args = vec!["convert"];
    args.extend(inputs.iter().map(|p| s(p)));
    args.extend(["-o", s(out)]);
    args.extend(extra);
    rigport_ok(&args)
}

/// Every node's world position at every key of the first animation.
fn frames(scene: &GltfScene) -> Vec<Vec<Vec3>> {
    let times = (scene.animations[0].channels.iter())
        .map(|c| &c.times)
        .max_by_key(|t| t.len())
        .unwrap()
        .clone();
    times.iter().map(|&t| gltf_pose(scene, 0, t)).collect()
}

fn node(scene: &GltfScene, name: &str) -> usize {
    (scene.node_names.iter().position(|n| n == name)).unwrap_or_else(|| panic!("no node {name}"))
}

/// The largest distance between the same-named nodes of two scenes over all keys, but for
/// the node named `except`.
fn worst_node_distance(a: &GltfScene, b: &GltfScene, except: &str) -> f32 {
    let (fa, fb) = (frames(a), frames(b));
    assert_eq!(fa.len(), fb.len(), "key count");
    let pairs: Vec<(usize, usize)> = (a.node_names.iter().enumerate())
        .filter(|(_, n)| *n != except)
        .map(|(i, n)| (i, node(b, n)))
        .collect();
    let mut worst: f32 = 0.0;
    for (x, y) in fa.iter().zip(&fb) {
        for &(i, j) in &pairs {
            worst = worst.max(x[i].distance(y[j]));
        }
    }
    worst
}

#[test]
fn in_place_holds_the_hips_over_one_point_and_keeps_their_height() {
    for (label, inputs, hips, leg) in walks() {
        let dir = scratch();
        let keep = dir.path().join("keep.glb");
        convert(&inputs, &keep, &["-q"]);
        let kept = gltf_read::read(&keep);
        let fk = frames(&kept);
        let h = node(&kept, hips);
        let [a, b, c] = leg.map(|n| node(&kept, n));
        let leg_length = fk[0][a].distance(fk[0][b]) + fk[0][b].distance(fk[0][c]);
        // By default the hips stay within 1% of the leg length of one point; a 1 s window
        // keeps their sway about the smoothed path (2-5% on these walks).
        for (window, bound) in [("default", 0.01), ("1", 0.10)] {
            let out = dir.path().join(format!("in_place_{window}.glb"));
            let mut args = vec!["--root-motion", "in-place"];
            if window != "default" {
                args.extend(["--root-window", window]);
            }
            let log = convert(&inputs, &out, &args);
            assert!(log.contains("root motion in place: hips"), "{label}: {log}");
            assert_valid(&out);
            let fo = frames(&gltf_read::read(&out));
            let ground: Vec<Vec3> = fo.iter().map(|f| Vec3::new(f[h].x, 0.0, f[h].z)).collect();
            let (lo, hi) = (ground.iter()).fold((Vec3::MAX, Vec3::MIN), |(lo, hi), g| {
                (lo.min(*g), hi.max(*g))
            });
            let centre = (lo + hi) / 2.0;
            let drift = ground
                .iter()
                .map(|g| g.distance(centre))
                .fold(0.0, f32::max);
            let up = (fk.iter().zip(&fo))
                .map(|(k, o)| (k[h].y - o[h].y).abs())
                .fold(0.0, f32::max);
            let travel = fk[0][h].distance(fk[fk.len() - 1][h]);
            eprintln!(
                "{label} in place, window {window} s: hips within {:.2}% of the leg length \
                 ({leg_length:.3} m) of one point (travel was {travel:.2} m), up changed by {up:.1e} m",
                100.0 * drift / leg_length
            );
            assert!(
                drift < bound * leg_length,
                "{label}: {drift} of {leg_length}"
            );
            assert!(up < 1e-6, "{label}: up changed by {up}");
        }
    }
}

#[test]
fn extract_keeps_every_joint_and_vertex_on_a_skinned_rig() {
    let (Some(bvh), Some(rig)) = (corpus(CGSPEED_WALK), corpus(HUMAN_MODEL1)) else {
        return;
    };
    let dir = scratch();
    let retarget = |mode: &str, out: &Path, extra: &[&str]| {
        let mut args = vec!["retarget", s(&bvh), "--onto", s(&rig), "-o", s(out)];
        args.extend(["--root-motion", mode, "--root-yaw", "--json", "-q"]);
        args.extend(extra);
        let run = rigport(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{mode}: {stderr}");
        serde_json::from_slice::<serde_json::Value>(&run.stdout).unwrap()
    };
    let (keep, extract) = (dir.path().join("keep.glb"), dir.path().join("extract.glb"));
    retarget("keep", &keep, &[]);
    let report = retarget("extract", &extract, &[]);
    let moved = &report["root_motion"];
    assert_eq!(moved["mode"], "extract", "{report}");
    assert_eq!(moved["added_joint"], true, "{report}");
    let clip = &moved["clips"][0];
    eprintln!(
        "cgspeed walk onto human_model1: root {} carries {:.3} units in {:.2} s, turn {:.1} deg",
        moved["root"], clip["distance"], clip["duration_s"], clip["turn_deg"]
    );
    assert!(clip["distance"].as_f64().unwrap() > 0.0, "{report}");
    assert_valid(&extract);
    let (a, b) = (gltf_read::read(&keep), gltf_read::read(&extract));
    assert_eq!(b.node_names.len(), a.node_names.len() + 1);
    // Joint positions are the product of the root's track and every local track below it.
    let worst = worst_node_distance(&a, &b, "");
    eprintln!("extract: every joint within {worst:.1e} of the original (all keys)");
    assert!(worst < 1e-6, "{worst}");

    // The vertices: rigport eval of both files, and three.js playing the extracted file.
    let eval = |glb: &Path, name: &str| {
        let npz = dir.path().join(name);
        let args = ["eval", s(glb), "--fps", "10", "--max-influences", "4"];
        rigport_ok(&[&args[..], &["--out", s(&npz), "-q"]].concat());
        read_npz(&npz).remove("positions").unwrap()
    };
    let (ours_keep, ours_extract) = (eval(&keep, "keep.npz"), eval(&extract, "extract.npz"));
    let diagonal = diagonal(&ours_keep.numbers[..ours_keep.shape[1] * 3]);
    let worst = max_deviation(&ours_keep.numbers, &ours_extract.numbers);
    eprintln!(
        "extract: rigport eval vertices within {:.1e} of the diagonal",
        worst / diagonal
    );
    assert!(worst < 1e-6 * diagonal, "{worst} of {diagonal}");
    if let Some((_, three)) = three_eval(&extract, &["--clip-index", "0", "--fps", "10"]) {
        assert_eq!(three.shape, ours_keep.shape);
        let worst = max_deviation(&three.numbers, &ours_keep.numbers);
        eprintln!(
            "extract: three.js vertices within {:.1e} of the diagonal",
            worst / diagonal
        );
        assert!(worst < 1e-5 * diagonal, "{worst} of {diagonal}");
    }
    // The same rig as USD passes usd-core's checks.
    let usda = dir.path().join("extract.usda");
    retarget("extract", &usda, &[]);
    if let Some(python) = crate::usd::python() {
        let (ok, text) = crate::usd::check_usd(&python, &usda, None);
        assert!(ok, "{text}");
    }
}

fn diagonal(points: &[f64]) -> f64 {
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in points.chunks_exact(3) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
}

fn max_deviation(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn extract_puts_the_travel_on_an_existing_top_joint() {
    let Some(bvh) = corpus(BANDAI_WALK) else {
        return;
    };
    let dir = scratch();
    let (keep, extract) = (dir.path().join("keep.glb"), dir.path().join("extract.glb"));
    convert(
        std::slice::from_ref(&bvh),
        &keep,
        &["-q", "--input-units", "cm"],
    );
    let log = convert(
        &[bvh],
        &extract,
        &[
            "--input-units",
            "cm",
            "--root-motion",
            "extract",
            "--root-yaw",
        ],
    );
    assert!(
        log.contains("travel on joint_Root (existing top joint)"),
        "{log}"
    );
    assert_valid(&extract);
    let (a, b) = (gltf_read::read(&keep), gltf_read::read(&extract));
    assert_eq!(a.node_names, b.node_names);
    // Every joint below joint_Root is where it was; joint_Root itself now travels.
    let worst = worst_node_distance(&a, &b, "joint_Root");
    eprintln!("Bandai walk, extract onto joint_Root: every joint within {worst:.1e} m");
    assert!(worst < 1e-5, "{worst}");
    let (fb, root) = (frames(&b), node(&b, "joint_Root"));
    let moved = fb[0][root].distance(fb[fb.len() - 1][root]);
    assert!(moved > 1.0, "joint_Root travels: {moved} m");
}

#[test]
fn keep_writes_the_bytes_of_a_run_without_the_flag() {
    let (Some(bvh), Some(rig)) = (corpus(CGSPEED_WALK), corpus(HUMAN_MODEL1)) else {
        return;
    };
    let dir = scratch();
    let runs: [(&str, Vec<&str>); 3] = [
        ("convert", vec!["convert", s(&bvh)]),
        ("retime", vec!["retime", s(&bvh), "--speed", "0.5"]),
        ("retarget", vec!["retarget", s(&bvh), "--onto", s(&rig)]),
    ];
    for (label, args) in runs {
        let mut bytes = Vec::new();
        for (k, extra) in [&[][..], &["--root-motion", "keep"][..]].iter().enumerate() {
            let out = dir.path().join(format!("{label}_{k}.glb"));
            rigport_ok(&[&args[..], &["-o", s(&out), "-q"], extra].concat());
            bytes.push(std::fs::read(&out).unwrap());
        }
        assert!(bytes[0] == bytes[1], "{label}: keep changed the bytes");
    }
}

#[test]
fn retime_then_in_place_reports_each_clip() {
    let Some(bvh) = corpus(CGSPEED_WALK) else {
        return;
    };
    let dir = scratch();
    let out = dir.path().join("slow.usda");
    let log = rigport_ok(&[
        "retime",
        s(&bvh),
        "--speed",
        "0.5",
        "--root-motion",
        "in-place",
        "--root-yaw",
        "-o",
        s(&out),
    ]);
    let line = log
        .lines()
        .find(|l| l.starts_with("clip \"walk\": travel"))
        .unwrap();
    eprintln!("{line}");
    assert!(line.contains("units/s"), "{line}");
    if let Some(python) = crate::usd::python() {
        let (ok, text) = crate::usd::check_usd(&python, &out, None);
        assert!(ok, "{text}");
    }
}
