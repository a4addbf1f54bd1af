//! IK end to end: handle tracks solved per frame, baked into a clip, checked by an
//! independent evaluation of the written glTF (test-only sampler in motion.rs).

use std::path::{Path, PathBuf};

use rigport_model::glam::Vec3;

use crate::common::*;
use crate::gltf_read;
use crate::motion::gltf_pose;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// (joint, relative, key times, key positions) of a handles file, read by the test.
fn read_handles(path: &Path) -> (f64, Vec<(String, bool, Vec<f32>, Vec<Vec3>)>) {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let fps = v["fps"].as_f64().unwrap_or(30.0);
    let handles = v["handles"]
        .as_array()
        .unwrap()
        .iter()
        .map(|h| {
            let keys = h["keys"].as_array().unwrap();
            (
                h["joint"].as_str().unwrap().to_string(),
                h["relative"].as_bool().unwrap_or(false),
                keys.iter()
                    .map(|k| k["time"].as_f64().unwrap() as f32)
                    .collect(),
                keys.iter()
                    .map(|k| {
                        let p: Vec<f32> = k["position"]
                            .as_array()
                            .unwrap()
                            .iter()
                            .map(|x| x.as_f64().unwrap() as f32)
                            .collect();
                        Vec3::from_slice(&p)
                    })
                    .collect(),
            )
        })
        .collect();
    (fps, handles)
}

fn lerp_keys(times: &[f32], pos: &[Vec3], t: f32) -> Vec3 {
    if t <= times[0] {
        return pos[0];
    }
    if t >= *times.last().unwrap() {
        return *pos.last().unwrap();
    }
    let k = times.partition_point(|&x| x <= t) - 1;
    let u = (t - times[k]) / (times[k + 1] - times[k]);
    pos[k].lerp(pos[k + 1], u)
}

/// Bakes `handles` on the rig to a .glb, validates it, and checks every handle joint of the
/// file's own animation against its target at every frame; returns the worst miss.
fn bake_and_check(rig: &[PathBuf], handles: &Path, dir: &Path) -> f32 {
    let glb = dir.join("ik.glb");
    let mut args: Vec<&str> = vec!["ik"];
    args.extend(rig.iter().map(|p| s(p)));
    args.extend(["--handles", s(handles), "-o", s(&glb), "--quiet"]);
    rigport_ok(&args);
    assert_valid(&glb);
    let scene = gltf_read::read(&glb);
    let by_name = scene.node_by_name();
    let rest = gltf_pose(&scene, 0, 0.0); // frame 0 of the clip
    let rest_world = scene.world(&Default::default());
    let (fps, tracks) = read_handles(handles);
    let anim = &scene.animations[0];
    let frames = anim.channels.iter().map(|c| c.times.len()).max().unwrap();
    let heights: Vec<Vec3> = rest_world.iter().map(|m| m.w_axis.truncate()).collect();
    let lo = heights.iter().fold(Vec3::splat(f32::MAX), |a, b| a.min(*b));
    let hi = heights.iter().fold(Vec3::splat(f32::MIN), |a, b| a.max(*b));
    let tolerance = 1e-4 * (hi - lo).max_element();
    let mut worst = 0.0f32;
    for f in 0..frames {
        let t = (f as f64 / fps) as f32;
        let world = gltf_pose(&scene, 0, t);
        for (joint, relative, times, pos) in &tracks {
            let node = by_name[joint.as_str()];
            let p = lerp_keys(times, pos, t);
            let target = if *relative {
                rest_world[node].w_axis.truncate() + p
            } else {
                p
            };
            let miss = (world[node] - target).length();
            worst = worst.max(miss);
            assert!(
                miss <= 2.0 * tolerance,
                "{}: frame {f} handle {joint}: {miss:e} from its target (tolerance {tolerance:e})",
                handles.display()
            );
        }
    }
    assert!(rest.len() == rest_world.len());
    worst
}

#[test]
fn baked_reach_clips_put_handles_on_their_targets() {
    let model1 = PINOCCHIO_RIGS.iter().find(|r| r.0 == "model1").unwrap();
    let (Some(m), Some(sk), Some(a)) = (corpus(model1.1), corpus(model1.2), corpus(model1.3))
    else {
        return;
    };
    let Some(armadillo) = corpus("2_csci520_ik_skinning/tydia/armadillo") else {
        return;
    };
    let fixtures = repo().join("fixtures/ik");
    for (rig, file) in [
        (
            vec![m.clone(), sk.clone(), a.clone()],
            "pinocchio_one_hand_reach.json",
        ),
        (vec![m, sk, a], "pinocchio_two_hand_reach.json"),
        (vec![armadillo], "armadillo_four_handles.json"),
    ] {
        let dir = scratch();
        let worst = bake_and_check(&rig, &fixtures.join(file), dir.path());
        eprintln!("{file}: worst handle miss in the glTF {worst:.3e}");
    }
}

#[test]
fn unreachable_and_bad_handles() {
    let Some(armadillo) = corpus("2_csci520_ik_skinning/tydia/armadillo") else {
        return;
    };
    let dir = scratch();
    let p = |n: &str| dir.path().join(n);
    // Unreachable: 100 units away. Best effort, a warning, finite and valid output, exit 0
    // (exit 4 with --deny-warnings).
    std::fs::write(
        p("far.json"),
        r#"{"handles": [{"joint": "joint_15", "keys": [{"time": 0, "position": [100, 0, 0]}, {"time": 1, "position": [0, 100, 0]}]}]}"#,
    )
    .unwrap();
    let out = rigport(&[
        "ik",
        s(&armadillo),
        "--handles",
        s(&p("far.json")),
        "-o",
        s(&p("far.glb")),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let max = report["handles"][0]["max_residual"].as_f64().unwrap();
    assert!(max.is_finite() && max > 90.0, "residual {max}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("farther than the tolerance"));
    assert_valid(&p("far.glb"));
    let out = rigport(&[
        "ik",
        s(&armadillo),
        "--handles",
        s(&p("far.json")),
        "-o",
        s(&p("deny.glb")),
        "--deny-warnings",
    ]);
    assert_eq!(out.status.code(), Some(4));
    assert!(!p("deny.glb").exists());
    // A target on the handle joint's parent (degenerate): finite, valid.
    std::fs::write(
        p("at_joint.json"),
        r#"{"handles": [{"joint": "joint_15", "relative": true, "keys": [{"time": 0, "position": [0, 0, 0]}]}]}"#,
    )
    .unwrap();
    rigport_ok(&[
        "ik",
        s(&armadillo),
        "--handles",
        s(&p("at_joint.json")),
        "-o",
        s(&p("at.glb")),
        "--quiet",
    ]);
    assert_valid(&p("at.glb"));
    // Bad input: NaN (not JSON), unknown joint, keys out of order: exit 1, file and place named.
    for (name, text, needle) in [
        (
            "nan.json",
            r#"{"handles": [{"joint": "joint_15", "keys": [{"time": 0, "position": [NaN, 0, 0]}]}]}"#,
            "nan.json:1:",
        ),
        (
            "joint.json",
            r#"{"handles": [{"joint": "nope", "keys": [{"time": 0, "position": [0, 0, 0]}]}]}"#,
            "/handles/0/joint",
        ),
        (
            "order.json",
            r#"{"handles": [{"joint": "joint_15", "keys": [{"time": 1, "position": [0, 0, 0]}, {"time": 0.5, "position": [0, 0, 0]}]}]}"#,
            "/handles/0/keys/1/time",
        ),
    ] {
        std::fs::write(p(name), text).unwrap();
        let out_file = p(&format!("{name}.glb"));
        let out = rigport(&[
            "ik",
            s(&armadillo),
            "--handles",
            s(&p(name)),
            "-o",
            s(&out_file),
        ]);
        assert_eq!(out.status.code(), Some(1), "{name}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{name}: {err}");
        assert!(!out_file.exists());
    }
}

#[test]
fn substeps_reduce_residual_on_a_far_jump() {
    let Some(armadillo) = corpus("2_csci520_ik_skinning/tydia/armadillo") else {
        return;
    };
    let dir = scratch();
    let p = |n: &str| dir.path().join(n);
    // The hand jumps far between two frames; with 3 iterations a frame, sub-steps help.
    std::fs::write(
        p("jump.json"),
        r#"{"fps": 2, "handles": [{"joint": "joint_15", "relative": true, "keys": [{"time": 0, "position": [0, 0, 0]}, {"time": 0.5, "position": [-0.25, 0.35, 0.2]}]}]}"#,
    )
    .unwrap();
    let jump = p("jump.json");
    let run = |extra: &[&str], out: &str| -> f64 {
        let mut args = vec![
            "ik",
            s(&armadillo),
            "--handles",
            s(&jump),
            "-o",
            out,
            "--json",
            "--max-iterations",
            "3",
        ];
        args.extend_from_slice(extra);
        let o = rigport(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v["handles"][0]["max_residual"].as_f64().unwrap()
    };
    let plain = run(&[], s(&p("plain.glb")));
    let sub = run(&["--substep", "0.02"], s(&p("sub.glb")));
    eprintln!("far jump: residual {plain:.3e} without sub-steps, {sub:.3e} with");
    assert!(sub <= plain, "sub-steps {sub} vs none {plain}");
}
