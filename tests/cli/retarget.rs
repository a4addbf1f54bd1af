//! `rigport retarget` (issue 19): a corpus clip onto its own skeleton gives the same motion;
//! a BVH walk and an ASF/AMC walk onto the Pinocchio `human_model1` rig and the demo
//! character validate clean, play in three.js without NaN, keep their feet planted and
//! their limbs' end-effector paths within 10% of the limb length of the source's, scaled;
//! bad maps exit 1 with the JSON path and write nothing.

use std::path::{Path, PathBuf};

use rigport_model::glam::Vec3;

use crate::common::*;
use crate::gltf_read::{self, GltfScene};
use crate::motion::gltf_pose;
use crate::three::three_eval;

const WALK_BVH: &str = "4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh";
const WALK_ASF: (&str, &str) = (
    "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf",
    "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07_05-walk.amc",
);
const BANDAI_WALK: &str = "4_bvh/bandai_namco_ds1/dataset-1_walk_normal_002.bvh";
const HUMAN_MODEL1: &str = "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1";

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The corpus paths of the two walks, as rigport arguments.
fn walks() -> Option<Vec<(&'static str, Vec<PathBuf>)>> {
    Some(vec![
        ("cgspeed BVH walk", vec![corpus(WALK_BVH)?]),
        (
            "CMU ASF/AMC walk",
            vec![corpus(WALK_ASF.0)?, corpus(WALK_ASF.1)?],
        ),
    ])
}

/// Per key time of the first animation, every node's world position by node name order.
fn frames(scene: &GltfScene) -> Vec<Vec<Vec3>> {
    let times = scene.animations[0]
        .channels
        .iter()
        .map(|c| &c.times)
        .max_by_key(|t| t.len())
        .unwrap()
        .clone();
    times.iter().map(|&t| gltf_pose(scene, 0, t)).collect()
}

#[test]
fn identity_returns_the_same_motion() {
    let (Some(mut walks), Some(bandai)) = (walks(), corpus(BANDAI_WALK)) else {
        return;
    };
    walks.push(("Bandai Namco BVH walk", vec![bandai]));
    for (label, motion) in walks {
        let dir = scratch();
        let (src, out) = (dir.path().join("src.glb"), dir.path().join("out.glb"));
        let mut convert = vec!["convert"];
        convert.extend(motion.iter().map(|p| s(p)));
        convert.extend(["-o", s(&src), "--quiet"]);
        rigport_ok(&convert);
        // The skeleton file is the rig: an .asf alone, the .bvh itself.
        let mut args = vec!["retarget"];
        args.extend(motion.iter().map(|p| s(p)));
        args.extend(["--onto", s(&motion[0]), "-o", s(&out), "--quiet"]);
        rigport_ok(&args);
        assert_valid(&out);
        let (a, b) = (gltf_read::read(&src), gltf_read::read(&out));
        assert_eq!(a.node_names, b.node_names, "{label}: same skeleton");
        let (fa, fb) = (frames(&a), frames(&b));
        assert_eq!(fa.len(), fb.len(), "{label}: frame count");
        let (lo, hi) = fa[0].iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
        let height = (hi - lo).max_element();
        let worst = fa
            .iter()
            .zip(&fb)
            .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| p.distance(*q)))
            .fold(0.0f32, f32::max);
        eprintln!(
            "{label} onto itself: {} frames, worst joint {:.2e} of the height",
            fa.len(),
            worst / height
        );
        assert!(worst < 1e-5 * height, "{label}: {worst} of height {height}");
    }
}

#[test]
fn cross_rig_walks_plant_feet_and_follow_limbs() {
    let (Some(walks), Some(model1)) = (walks(), corpus(HUMAN_MODEL1)) else {
        return;
    };
    let dir = scratch();
    let demo = demo_outputs().join("demo.glb");
    for (label, motion) in walks {
        for (rig_label, rig) in [("human_model1", &model1), ("demo", &demo)] {
            let out = dir.path().join(format!("{}_{rig_label}.glb", motion.len()));
            let mut args = vec!["retarget"];
            args.extend(motion.iter().map(|p| s(p)));
            args.extend([
                "--onto",
                s(rig),
                "-o",
                s(&out),
                "--plant-feet",
                "--json",
                "--quiet",
            ]);
            let run = rigport(&args);
            let stderr = String::from_utf8_lossy(&run.stderr);
            assert!(run.status.success(), "{label} onto {rig_label}: {stderr}");
            let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
            assert_valid(&out);
            let limbs = report["limbs"].as_array().unwrap();
            assert!(
                limbs.len() >= 4,
                "{label} onto {rig_label}: limbs {limbs:?}"
            );
            let mut figures = Vec::new();
            for l in limbs {
                let max = l["max_error"].as_f64().unwrap();
                figures.push(format!("{} {max:.3}", l["limb"].as_str().unwrap()));
                assert!(max < 0.1, "{label} onto {rig_label}: {l}");
            }
            let feet = report["feet"].as_array().unwrap();
            assert_eq!(feet.len(), 2, "{label} onto {rig_label}: feet");
            for f in feet {
                assert!(f["contacts"].as_u64().unwrap() > 0, "{f}");
                let slide = f["slide_after"]["max"].as_f64().unwrap();
                figures.push(format!(
                    "foot {} slide {slide:.1e}",
                    f["label"].as_str().unwrap()
                ));
                assert!(slide < 1e-3, "{label} onto {rig_label}: {f}");
            }
            eprintln!("{label} onto {rig_label}: {}", figures.join(", "));
            if let Some((_, positions)) = three_eval(&out, &["--clip-index", "0", "--fps", "10"]) {
                assert!(!positions.numbers.is_empty());
                assert!(
                    positions.numbers.iter().all(|v| v.is_finite()),
                    "{label} onto {rig_label}: NaN in three.js"
                );
            }
        }
    }
}

#[test]
fn bad_maps_exit_1_with_the_json_path() {
    let (Some(bvh), Some(model1)) = (corpus(WALK_BVH), corpus(HUMAN_MODEL1)) else {
        return;
    };
    let dir = scratch();
    for (name, text, expected) in [
        (
            "unknown",
            r#"{"joints": {"Hips": "root", "LeftArm": "no_such_bone"}}"#,
            "at /joints/LeftArm: the target has no joint named \"no_such_bone\"",
        ),
        (
            "unknown_source",
            r#"{"joints": {"Hipz": "root"}}"#,
            "at /joints/Hipz: the source has no joint named \"Hipz\"",
        ),
        (
            "cycle",
            r#"{"joints": {"Hips": "bone_1", "Spine": "root"}}"#,
            "at /joints/Spine: a cycle:",
        ),
        (
            "twice",
            r#"{"joints": {"Hips": "root", "Spine": ["bone_1", "root"]}}"#,
            "at /joints/Spine/1: two source joints onto one target",
        ),
    ] {
        let map = dir.path().join(format!("{name}.json"));
        std::fs::write(&map, text).unwrap();
        let out = dir.path().join(format!("{name}.glb"));
        let run = rigport(&[
            "retarget",
            s(&bvh),
            "--onto",
            s(&model1),
            "--map",
            s(&map),
            "-o",
            s(&out),
        ]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{name}: {stderr}");
        assert!(stderr.contains(expected), "{name}: {stderr}");
        assert!(!out.exists(), "{name}: no output");
    }
    // A well-formed map file that moves one leg only leaves the other limbs of the motion
    // unmapped: exit 1 naming each, nothing written (issue 28; until then it wrote a rig
    // whose arms, head and right leg kept their rest pose, with exit 0).
    let map = dir.path().join("one_leg.json");
    std::fs::write(&map, r#"{"joints": {"Hips": "root", "LeftUpLeg": "bone_9", "LeftLeg": "bone_10", "LeftFoot": "bone_11"}, "pelvis": {"source": "Hips", "target": "bone_4"}}"#).unwrap();
    let out = dir.path().join("one_leg.glb");
    let args = [
        "retarget",
        s(&bvh),
        "--onto",
        s(&model1),
        "--map",
        s(&map),
        "-o",
        s(&out),
    ];
    let run = rigport(&args);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    for limb in [
        "the source's right leg (RightUpLeg, RightLeg) drives no target joint",
        "the source's left arm (LeftArm, LeftForeArm)",
        "the source's right arm (RightArm, RightForeArm)",
        "the source's head (Neck, Neck1, Head)",
        "--allow-partial",
    ] {
        assert!(stderr.contains(limb), "{limb}: {stderr}");
    }
    assert!(!stderr.contains("left leg"), "{stderr}");
    assert!(!out.exists(), "no output");
    // With --allow-partial it is written, with a coded warning naming the limbs.
    let mut partial = args.to_vec();
    partial.push("--allow-partial");
    let run = rigport(&partial);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning[W004]: retarget map (file): the map is partial")
            && stderr.contains("right leg (RightUpLeg, RightLeg)"),
        "{stderr}"
    );
    assert_valid(&out);
}

/// `walk.bvh` with the joint names of cgspeed's first release of the CMU database:
/// `LeftHip` is the upper leg, `LeftShoulder` the upper arm, `LeftCollar` the clavicle.
fn cgspeed_original_names(bvh: &str) -> String {
    let rename = |name: &str| -> String {
        let (side, part) = match name.strip_prefix("Left") {
            Some(p) => ("Left", p),
            None => match name.strip_prefix("Right") {
                Some(p) => ("Right", p),
                None => {
                    return if name == "Spine1" {
                        "Chest".into()
                    } else {
                        name.into()
                    }
                }
            },
        };
        let part = match part {
            "UpLeg" => "Hip",
            "Leg" => "Knee",
            "Foot" => "Ankle",
            "ToeBase" => "Toe",
            "Shoulder" => "Collar",
            "Arm" => "Shoulder",
            "ForeArm" => "Elbow",
            "Hand" => "Wrist",
            p => p,
        };
        format!("{side}{part}")
    };
    bvh.lines()
        .map(|line| {
            let trimmed = line.trim_start();
            match trimmed.split_once(' ') {
                Some((kw @ ("JOINT" | "ROOT"), name)) => {
                    let indent = &line[..line.len() - trimmed.len()];
                    format!("{indent}{kw} {}", rename(name.trim()))
                }
                _ => line.to_string(),
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

/// Issue 28: cgspeed's original names matched 5 of 18 joints of the built-in maps, put
/// `RightShoulder` (the upper arm) on the clavicle and left the legs and arms frozen, with
/// exit 0. The structure finds every limb, and the report lists each role's joints.
#[test]
fn cgspeed_original_names_move_every_limb() {
    let (Some(bvh), Some(model1)) = (corpus(WALK_BVH), corpus(HUMAN_MODEL1)) else {
        return;
    };
    let dir = scratch();
    let renamed = dir.path().join("walk_cgspeed.bvh");
    let text = std::fs::read_to_string(&bvh).unwrap();
    std::fs::write(&renamed, cgspeed_original_names(&text)).unwrap();
    let out = dir.path().join("walk.glb");
    let run = rigport(&[
        "retarget",
        s(&renamed),
        "--onto",
        s(&model1),
        "-o",
        s(&out),
        "--json",
        "--quiet",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert_valid(&out);
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    let roles = report["roles"].as_array().unwrap();
    let row = |role: &str| roles.iter().find(|r| r["role"] == role).unwrap();
    for (role, source) in [
        ("LeftUpperLeg", "LeftHip"),
        ("LeftLowerLeg", "LeftKnee"),
        ("LeftFoot", "LeftAnkle"),
        ("RightUpperLeg", "RightHip"),
        ("RightLowerLeg", "RightKnee"),
        ("RightFoot", "RightAnkle"),
        ("LeftShoulder", "LeftCollar"),
        ("LeftUpperArm", "LeftShoulder"),
        ("LeftLowerArm", "LeftElbow"),
        ("RightShoulder", "RightCollar"),
        ("RightUpperArm", "RightShoulder"),
        ("RightLowerArm", "RightElbow"),
        ("Chest", "Chest"),
        ("Neck", "Neck"),
    ] {
        let r = row(role);
        assert_eq!(r["source"], source, "{r}");
        assert_eq!(r["driven_by"], source, "{r}");
        assert!(
            r["target"].as_str().is_some_and(|t| t.starts_with("bone_")),
            "{r}"
        );
    }
    let limbs = report["limbs"].as_array().unwrap();
    assert!(limbs.len() >= 4, "{limbs:?}");
    for l in limbs {
        assert!(l["max_error"].as_f64().unwrap() < 0.1, "{l}");
    }
}

#[test]
fn usd_output_and_matched_hands() {
    let (Some(asf), Some(amc), Some(model1)) =
        (corpus(WALK_ASF.0), corpus(WALK_ASF.1), corpus(HUMAN_MODEL1))
    else {
        return;
    };
    let dir = scratch();
    let usda = dir.path().join("walk.usda");
    rigport_ok(&[
        "retarget",
        s(&asf),
        s(&amc),
        "--onto",
        s(&model1),
        "-o",
        s(&usda),
        "--plant-feet",
        "--quiet",
    ]);
    if let Some(python) = crate::usd::python() {
        let (ok, log) = crate::usd::check_usd(&python, &usda, None);
        assert!(ok, "{log}");
    }
    // The demo has hand joints: --match-hands puts its wrists on the source's, scaled.
    let out = dir.path().join("hands.glb");
    let run = rigport(&[
        "retarget",
        s(&asf),
        s(&amc),
        "--onto",
        s(&demo_outputs().join("demo.glb")),
        "-o",
        s(&out),
        "--match-hands",
        "--json",
        "--quiet",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert_valid(&out);
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    let hands = report["hands"].as_array().unwrap();
    assert_eq!(hands.len(), 2, "{report}");
    for h in hands {
        // Within reach the wrist lands on its goal; the demo's arm is short of the CMU
        // actor's scaled reach on a few frames by about 2% of the height.
        let e = h["max_error"].as_f64().unwrap();
        eprintln!("hand {}: {e:.2e} of the height", h["label"]);
        assert!(e < 0.05, "{h}");
    }
}
