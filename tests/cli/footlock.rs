//! `rigport footlock` on every corpus BVH and ASF/AMC clip (issues 16 and 28): during the
//! contacts it reports, the feet hold still to 1e-3 of the skeleton's height; the output
//! validates clean; every joint outside the legs is where the source puts it; the knee
//! angle changes per frame by at most 15° at 120 fps (scaled by 120/fps at other rates)
//! beyond the source's own change; no leg is more than 2% longer than the source's.
//! Measured on the written glTF with the test-only reader and sampler, against `rigport
//! convert` of the same input. A corpus AMC played at twice its rate gets warning W006,
//! which `--deny-warnings` refuses, from `footlock` and `retarget --plant-feet` alike.

use std::collections::HashSet;
use std::path::Path;

use rigport_model::glam::Vec3;

use crate::common::*;
use crate::gltf_read::{self, GltfScene};
use crate::motion::{gltf_pose, ASF_AMC, BVH};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Per frame (the animation's key times), every node's world position.
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

/// The nodes below (and at) each leg's hip: the ankle's grandparent.
fn leg_nodes(scene: &GltfScene, ankles: &[String]) -> HashSet<usize> {
    let by_name = scene.node_by_name();
    let hips: Vec<usize> = ankles
        .iter()
        .map(|a| {
            let ankle = by_name[a.as_str()];
            let knee = scene.parents[ankle].unwrap();
            scene.parents[knee].unwrap()
        })
        .collect();
    (0..scene.parents.len())
        .filter(|&n| {
            let mut cur = Some(n);
            while let Some(c) = cur {
                if hips.contains(&c) {
                    return true;
                }
                cur = scene.parents[c];
            }
            false
        })
        .collect()
}

/// Runs footlock and convert on `input`, checks the three acceptance points and prints the
/// slides.
fn check(label: &str, input: &[&str]) {
    let dir = scratch();
    let (src, out) = (dir.path().join("src.glb"), dir.path().join("out.glb"));
    let mut args = vec!["footlock"];
    args.extend_from_slice(input);
    args.extend_from_slice(&["-o", s(&out), "--json", "--quiet"]);
    let run = rigport(&args);
    assert!(
        run.status.success(),
        "{label}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    let mut convert = vec!["convert"];
    convert.extend_from_slice(input);
    convert.extend_from_slice(&["-o", s(&src), "--quiet"]);
    rigport_ok(&convert);
    assert_valid(&out);

    let (a, b) = (gltf_read::read(&src), gltf_read::read(&out));
    let (before, after) = (frames(&a), frames(&b));
    assert_eq!(before.len(), after.len(), "{label}: frame count");
    assert_eq!(before.len() as u64, report["frames"].as_u64().unwrap());
    let lo = before[0].iter().fold(Vec3::MAX, |m, p| m.min(*p));
    let hi = before[0].iter().fold(Vec3::MIN, |m, p| m.max(*p));
    let height = f64::from((hi - lo).max_element());
    let by_name = b.node_by_name();

    let feet = report["feet"].as_array().unwrap();
    let ankles: Vec<String> = feet
        .iter()
        .map(|f| f["ankle"].as_str().unwrap().to_string())
        .collect();
    let legs = leg_nodes(&b, &ankles);
    let fps = report["fps"].as_f64().unwrap();
    knees_and_stretch(label, &b, &ankles, &before, &after, fps);
    let mut outside = 0.0f64;
    for (fa, fb) in before.iter().zip(&after) {
        for (n, (pa, pb)) in fa.iter().zip(fb).enumerate() {
            if !legs.contains(&n) {
                outside = outside.max(f64::from((*pa - *pb).length()));
            }
        }
    }
    assert!(
        outside <= 1e-5 * height,
        "{label}: a joint outside the legs moved {:.3e} of the height",
        outside / height
    );

    let mut contacts = 0;
    for foot in feet {
        let (mut src_max, mut out_max) = (0.0f64, 0.0f64);
        for c in foot["contacts"].as_array().unwrap() {
            let node = by_name[c["joint"].as_str().unwrap()];
            let (start, end) = (
                c["start_frame"].as_u64().unwrap() as usize,
                c["end_frame"].as_u64().unwrap() as usize,
            );
            for f in start..=end {
                let d = |fr: &[Vec<Vec3>]| f64::from((fr[f][node] - fr[start][node]).length());
                src_max = src_max.max(d(&before) / height);
                out_max = out_max.max(d(&after) / height);
            }
            contacts += 1;
        }
        eprintln!(
            "{label}: foot {}: {} contacts, slide before {src_max:.3e}, after {out_max:.3e} of the height (report: {:.3e} -> {:.3e}, stretch {:.2}%)",
            foot["label"].as_str().unwrap(),
            foot["contacts"].as_array().unwrap().len(),
            foot["slide_before"]["max"].as_f64().unwrap(),
            foot["slide_after"]["max"].as_f64().unwrap(),
            100.0 * foot["stretch"].as_f64().unwrap(),
        );
        assert!(
            out_max <= 1e-3,
            "{label}: foot {} slides {out_max:.3e} of the height during its contacts",
            foot["label"]
        );
    }
    assert!(contacts > 0, "{label}: no contact detected");
    eprintln!(
        "{label}: joints outside the legs moved at most {:.1e} of the height",
        outside / height
    );
}

/// Acceptance of issue 28 per leg: the knee angle's change per frame beyond the source's,
/// and the leg's length against the source's.
fn knees_and_stretch(
    label: &str,
    scene: &GltfScene,
    ankles: &[String],
    before: &[Vec<Vec3>],
    after: &[Vec<Vec3>],
    fps: f64,
) {
    let limit_deg = 15.0 * 120.0 / fps;
    let by_name = scene.node_by_name();
    for ankle_name in ankles {
        let ankle = by_name[ankle_name.as_str()];
        let knee = scene.parents[ankle].unwrap();
        let hip = scene.parents[knee].unwrap();
        let angle = |p: &[Vec3]| {
            f64::from(
                (p[hip] - p[knee])
                    .angle_between(p[ankle] - p[knee])
                    .to_degrees(),
            )
        };
        let length =
            |p: &[Vec3]| f64::from((p[knee] - p[hip]).length() + (p[ankle] - p[knee]).length());
        let (mut worst_step, mut worst_stretch, mut straightest) = (0.0f64, 0.0f64, 0.0f64);
        for f in 0..before.len() {
            worst_stretch = worst_stretch.max(length(&after[f]) / length(&before[f]) - 1.0);
            straightest = straightest.max(angle(&after[f]));
            if f > 0 {
                let step = (angle(&after[f]) - angle(&after[f - 1]))
                    - (angle(&before[f]) - angle(&before[f - 1]));
                worst_step = worst_step.max(step.abs());
            }
        }
        eprintln!(
            "{label}: {ankle_name}: knee step beyond the source {worst_step:.2}° (limit {limit_deg:.0}° at {fps:.0} fps), stretch {:.3}%, straightest knee {straightest:.1}°",
            100.0 * worst_stretch
        );
        assert!(
            worst_step <= limit_deg,
            "{label}: {ankle_name}: the knee turns {worst_step:.2}° in a frame beyond the source"
        );
        assert!(
            worst_stretch <= 0.02 + 1e-4,
            "{label}: {ankle_name}: the leg stretches {:.3}%",
            100.0 * worst_stretch
        );
    }
}

#[test]
fn footlock_holds_the_feet_of_every_corpus_asf_amc_clip() {
    for (asf, amc) in ASF_AMC {
        let (Some(asf), Some(amc)) = (corpus(asf), corpus(amc)) else {
            return;
        };
        let label = amc.file_name().unwrap().to_string_lossy().into_owned();
        check(&label, &[s(&asf), "--motion", s(&amc)]);
    }
}

#[test]
fn footlock_holds_the_feet_of_every_corpus_bvh_clip() {
    for rel in BVH {
        let Some(path) = corpus(rel) else {
            return;
        };
        let label = path.file_name().unwrap().to_string_lossy().into_owned();
        check(&label, &[s(&path)]);
    }
}

#[test]
fn footlock_rejects_unknown_feet_and_rigs_without_feet() {
    let dir = scratch();
    let out = dir.path().join("out.glb");
    // Two joints and no leg: no foot by any known name.
    let bvh = dir.path().join("arm.bvh");
    std::fs::write(
        &bvh,
        "HIERARCHY\nROOT Shoulder\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n  JOINT Elbow\n  {\n    OFFSET 1 0 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n    End Site\n    {\n      OFFSET 1 0 0\n    }\n  }\n}\nMOTION\nFrames: 3\nFrame Time: 0.1\n0 0 0 0 0 0 0 0 0\n0 0 0 10 0 0 5 0 0\n0 0 0 20 0 0 10 0 0\n",
    )
    .unwrap();
    let cases: [(&[&str], &str); 3] = [
        (&[s(&bvh)], "no feet found"),
        (
            &[s(&bvh), "--foot", "Ankle,Toe"],
            "no joint named \"Ankle\"",
        ),
        (&[s(&bvh), "--foot", "Elbow"], "\"Elbow\" cannot be a foot"),
    ];
    for (input, message) in cases {
        let mut args = vec!["footlock"];
        args.extend_from_slice(input);
        args.extend_from_slice(&["-o", s(&out)]);
        let run = rigport(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{input:?}: {stderr}");
        assert!(stderr.contains(message), "{input:?}: {stderr}");
        assert!(!out.exists(), "{input:?}: no output on failure");
    }
}

#[test]
fn a_corpus_amc_played_at_the_wrong_rate_gets_the_no_contact_warning() {
    let (asf, amc) = ASF_AMC[1]; // CMU 09_06 run, recorded at 120 fps
    let (Some(asf), Some(amc)) = (corpus(asf), corpus(amc)) else {
        return;
    };
    let dir = scratch();
    let (rig, out) = (dir.path().join("rig.glb"), dir.path().join("out.glb"));
    rigport_ok(&["convert", s(&asf), "-o", s(&rig), "--quiet"]);
    let footlock = [
        "footlock",
        s(&asf),
        "--motion",
        s(&amc),
        "--amc-fps",
        "240",
        "-o",
        s(&out),
    ];
    let retarget = [
        "retarget",
        s(&asf),
        "--motion",
        s(&amc),
        "--amc-fps",
        "240",
        "--onto",
        s(&rig),
        "--plant-feet",
        "-o",
        s(&out),
    ];
    for command in [&footlock[..], &retarget[..]] {
        let mut args = command.to_vec();
        args.extend(["--quiet", "--deny-warnings"]);
        let run = rigport(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(4), "{}: {stderr}", command[0]);
        for needle in [
            "warning[W006]",
            "no foot stays under the contact speed",
            "2.0x too fast",
            "--amc-fps 120",
        ] {
            assert!(
                stderr.contains(needle),
                "{}: {needle:?} in {stderr}",
                command[0]
            );
        }
        assert!(
            !out.exists(),
            "{}: no output when warnings are refused",
            command[0]
        );
    }
    // Without --deny-warnings it is written, unchanged, and the warning is still printed;
    // at the right rate there are contacts and no warning.
    let run = rigport(&footlock);
    assert!(run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("warning[W006]"));
    let right = rigport(&[
        "footlock",
        s(&asf),
        "--motion",
        s(&amc),
        "-o",
        s(&out),
        "--deny-warnings",
        "--quiet",
    ]);
    assert!(
        right.status.success(),
        "{}",
        String::from_utf8_lossy(&right.stderr)
    );
}

#[test]
fn footlock_reports_one_row_per_contact() {
    let Some(walk) = corpus(BVH[3]) else {
        return;
    };
    let dir = scratch();
    let out = dir.path().join("out.glb");
    let run = rigport(&["footlock", s(&walk), "-o", s(&out)]);
    assert!(run.status.success());
    let stdout = String::from_utf8_lossy(&run.stdout);
    let json = rigport(&["footlock", s(&walk), "-o", s(&out), "--json", "--quiet"]);
    let report: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    let contacts: Vec<&serde_json::Value> = report["feet"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|f| f["contacts"].as_array().unwrap())
        .collect();
    assert!(contacts.len() >= 4, "{report}");
    assert!(
        stdout.contains("| foot | joint | start s | end s | frames | slide before | after |"),
        "{stdout}"
    );
    // One table row per contact, each in its own row with its frame count.
    for c in &contacts {
        let row = format!(
            "| {} | {:.3} | {:.3} | {} |",
            c["joint"].as_str().unwrap(),
            c["start_time"].as_f64().unwrap(),
            c["end_time"].as_f64().unwrap(),
            c["frames"].as_u64().unwrap()
        );
        assert_eq!(stdout.matches(&row).count(), 1, "{row} in {stdout}");
    }
}
