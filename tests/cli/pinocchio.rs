//! Acceptance 1 and 2 of the foundation issue on the corpus' Pinocchio rigs.

use std::collections::HashMap;
use std::path::Path;

use rigport_model::glam::{DVec3, Mat4, Quat, Vec3};

use crate::common::*;
use crate::gltf_read;

/// The raw rig, read straight from the files by test-only code.
struct RawRig {
    joints: Vec<DVec3>,
    parents: Vec<Option<usize>>,
    vertices: Vec<DVec3>,
    /// Per vertex, one weight per bone (column k-1 = bone ending at joint k), as written.
    rows: Vec<Vec<f64>>,
}

fn numbers(line: &str) -> Vec<f64> {
    line.split_ascii_whitespace()
        .map(|t| t.parse::<f64>().expect("number"))
        .collect()
}

fn read_raw(mesh: &Path, skeleton: &Path, attachment: &Path) -> RawRig {
    let mut joints = Vec::new();
    let mut parents = Vec::new();
    for line in std::fs::read_to_string(skeleton).unwrap().lines() {
        let f = numbers(line);
        if f.len() == 5 {
            joints.push(DVec3::new(f[1], f[2], f[3]));
            parents.push((f[4] >= 0.0).then_some(f[4] as usize));
        }
    }
    let vertices = std::fs::read_to_string(mesh)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let f = numbers(l);
            DVec3::new(f[0], f[1], f[2])
        })
        .collect();
    let rows = std::fs::read_to_string(attachment)
        .unwrap()
        .lines()
        .map(numbers)
        .filter(|r| !r.is_empty())
        .collect();
    RawRig {
        joints,
        parents,
        vertices,
        rows,
    }
}

/// Pinocchio's deformation, from the raw data: bone k rotates its vertices by `R_k` about
/// its head (the position of its parent joint), composed down the chain; a vertex moves by
/// the weight-averaged bone transforms (rows renormalized, as Pinocchio's are meant to sum
/// to 1).
fn pinocchio_reference(rig: &RawRig, rotations: &HashMap<usize, Quat>) -> Vec<DVec3> {
    let n = rig.joints.len();
    // Per bone k: rigid transform p -> r * p + t, composed from the root down.
    let mut bone: Vec<Option<(rigport_model::glam::DQuat, DVec3)>> = vec![None; n];
    fn solve(
        k: usize,
        rig: &RawRig,
        rot: &HashMap<usize, Quat>,
        bone: &mut Vec<Option<(rigport_model::glam::DQuat, DVec3)>>,
    ) -> (rigport_model::glam::DQuat, DVec3) {
        use rigport_model::glam::DQuat;
        if let Some(b) = bone[k] {
            return b;
        }
        let parent = rig.parents[k].expect("bones have parents");
        let (pr, pt) = if rig.parents[parent].is_some() {
            solve(parent, rig, rot, bone)
        } else {
            (DQuat::IDENTITY, DVec3::ZERO)
        };
        let r = rot.get(&k).map_or(DQuat::IDENTITY, |q| q.as_dquat());
        let head = rig.joints[parent];
        // rotate about head: p -> r (p - head) + head, then the parent bone's transform.
        let local_t = head - r * head;
        let out = (pr * r, pr * local_t + pt);
        bone[k] = Some(out);
        out
    }
    for k in 1..n {
        solve(k, rig, rotations, &mut bone);
    }
    rig.vertices
        .iter()
        .zip(&rig.rows)
        .map(|(p, row)| {
            let sum: f64 = row.iter().sum();
            let first_bone = row.len() + 1 - n; // 0 for J-1 columns, 1 with a leading root column
            let mut out = DVec3::ZERO;
            if first_bone == 1 {
                out += *p * row[0] / sum;
            }
            for (c, w) in row[first_bone..].iter().enumerate() {
                let (r, t) = bone[c + 1].expect("bone");
                out += (r * *p + t) * (*w / sum);
            }
            out
        })
        .collect()
}

fn bbox_diagonal(points: &[DVec3]) -> f64 {
    let lo = points.iter().fold(DVec3::splat(f64::MAX), |a, b| a.min(*b));
    let hi = points.iter().fold(DVec3::splat(f64::MIN), |a, b| a.max(*b));
    (hi - lo).length()
}

/// A pose that rotates several bones at once, some along one chain.
fn test_pose(joint_count: usize) -> HashMap<usize, Quat> {
    let mut pose = HashMap::new();
    let picks = [1, 2, joint_count / 2, joint_count - 1];
    for (i, &k) in picks.iter().enumerate() {
        if k >= 1 && k < joint_count {
            let axis = Vec3::new(1.0, 0.5 * i as f32, -0.3).normalize();
            pose.insert(k, Quat::from_axis_angle(axis, 0.35 + 0.2 * i as f32));
        }
    }
    pose
}

fn pose_json(pose: &HashMap<usize, Quat>) -> String {
    let mut entries: Vec<String> = pose
        .iter()
        .map(|(k, q)| format!("\"bone_{k}\": {{\"quat\": {:?}}}", q.to_array()))
        .collect();
    entries.sort();
    format!("{{{}}}", entries.join(", "))
}

/// Top-N of a renormalized row, renormalized again (ties: lower joint first).
fn top_n(row: &[f64], n: usize) -> Vec<(usize, f64)> {
    let sum: f64 = row.iter().sum();
    let mut w: Vec<(usize, f64)> = row
        .iter()
        .enumerate()
        .filter(|(_, w)| **w > 0.0)
        .map(|(c, w)| (c + 1, w / sum))
        .collect();
    w.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    w.truncate(n);
    let s: f64 = w.iter().map(|x| x.1).sum();
    w.iter().map(|(j, x)| (*j, x / s)).collect()
}

fn rig_paths(rig: &(&str, &str, &str, &str)) -> Option<[std::path::PathBuf; 3]> {
    Some([corpus(rig.1)?, corpus(rig.2)?, corpus(rig.3)?])
}

#[test]
fn pinocchio_rigs_convert_validate_and_read_back() {
    for rig in &PINOCCHIO_RIGS {
        let Some([mesh, skel, att]) = rig_paths(rig) else {
            continue;
        };
        let raw = read_raw(&mesh, &skel, &att);
        let dir = scratch();
        for (ext, max) in [("glb", 4usize), ("gltf", 4), ("glb", 8)] {
            let out = dir.path().join(format!("{}_{max}.{ext}", rig.0));
            rigport_ok(&[
                "convert",
                "--mesh",
                mesh.to_str().unwrap(),
                "--skeleton",
                skel.to_str().unwrap(),
                "--attachment",
                att.to_str().unwrap(),
                "--max-influences",
                &max.to_string(),
                "-o",
                out.to_str().unwrap(),
            ]);
            assert_valid(&out);
            let scene = gltf_read::read(&out);
            assert_eq!(scene.skins.len(), 1, "{}", rig.0);
            let skin = &scene.skins[0];
            // Bind pose == rest pose: positions are the OBJ's, and world * IBM == identity.
            assert_eq!(skin.positions.len(), raw.vertices.len(), "{}", rig.0);
            for (v, (a, b)) in skin.positions.iter().zip(&raw.vertices).enumerate() {
                assert!(
                    (a.as_dvec3() - *b).abs().max_element() <= 1e-6 * (1.0 + b.abs().max_element()),
                    "{} vertex {v}: {a} vs {b}",
                    rig.0
                );
            }
            let world = scene.world(&HashMap::new());
            for (j, ibm) in skin.joints.iter().zip(&skin.inverse_bind) {
                let m = world[*j] * *ibm;
                assert!(
                    m.abs_diff_eq(Mat4::IDENTITY, 1e-5),
                    "{} joint {j}: {m}",
                    rig.0
                );
            }
            // Weights: the renormalized top-N of each row, on the joint named bone_<k>.
            for (v, (infl, row)) in skin.influences.iter().zip(&raw.rows).enumerate() {
                let expect = top_n(row, max);
                let mut got: Vec<(usize, f64)> = infl
                    .iter()
                    .map(|(node, w)| {
                        let name = &scene.node_names[*node];
                        let k = name
                            .strip_prefix("bone_")
                            .expect("bone joint")
                            .parse()
                            .unwrap();
                        (k, *w as f64)
                    })
                    .collect();
                got.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
                assert_eq!(
                    got.len(),
                    expect.len(),
                    "{} vertex {v}: {got:?} vs {expect:?}",
                    rig.0
                );
                for (g, e) in got.iter().zip(&expect) {
                    assert!(
                        g.0 == e.0 && (g.1 - e.1).abs() < 1e-6,
                        "{} vertex {v}: {got:?} vs {expect:?}",
                        rig.0
                    );
                }
            }
        }
    }
}

#[test]
fn pinocchio_eval_matches_reference_and_gltf() {
    for rig in &PINOCCHIO_RIGS {
        let Some([mesh, skel, att]) = rig_paths(rig) else {
            continue;
        };
        let raw = read_raw(&mesh, &skel, &att);
        let pose = test_pose(raw.joints.len());
        let dir = scratch();
        let pose_file = dir.path().join("pose.json");
        std::fs::write(&pose_file, pose_json(&pose)).unwrap();
        let inputs = [
            mesh.to_str().unwrap(),
            skel.to_str().unwrap(),
            att.to_str().unwrap(),
        ];
        let dump = dir.path().join("dump.npz");
        let mut args = vec!["eval"];
        args.extend(inputs);
        args.extend([
            "--pose",
            pose_file.to_str().unwrap(),
            "--out",
            dump.to_str().unwrap(),
        ]);
        rigport_ok(&args);
        let npz = read_npz(&dump);
        let positions = &npz["positions"];
        assert_eq!(positions.shape, vec![raw.vertices.len(), 3]);
        let reference = pinocchio_reference(&raw, &pose);
        let tol = 1e-5 * bbox_diagonal(&raw.vertices);
        let mut max_dev = 0.0f64;
        let mut moved = 0;
        for (v, r) in reference.iter().enumerate() {
            let p = DVec3::new(
                positions.numbers[3 * v],
                positions.numbers[3 * v + 1],
                positions.numbers[3 * v + 2],
            );
            max_dev = max_dev.max((p - *r).length());
            if (*r - raw.vertices[v]).length() > 100.0 * tol {
                moved += 1;
            }
        }
        assert!(
            moved > raw.vertices.len() / 20,
            "{}: the pose moved only {moved} vertices",
            rig.0
        );
        assert!(max_dev <= tol, "{}: max deviation {max_dev} > {tol}", rig.0);
        eprintln!(
            "{}: eval vs Pinocchio reference: max deviation {max_dev:.3e} (tolerance {tol:.3e})",
            rig.0
        );

        // Second reference: the exported glTF's own IBMs and node transforms, with the same
        // influence limit applied by eval.
        for max in ["4", "8"] {
            let glb = dir.path().join(format!("rig{max}.glb"));
            let mut args = vec!["convert"];
            args.extend(inputs);
            args.extend(["--max-influences", max, "-o", glb.to_str().unwrap()]);
            rigport_ok(&args);
            let dump_n = dir.path().join(format!("dump{max}.npz"));
            let mut args = vec!["eval"];
            args.extend(inputs);
            args.extend([
                "--max-influences",
                max,
                "--pose",
                pose_file.to_str().unwrap(),
                "--out",
                dump_n.to_str().unwrap(),
            ]);
            rigport_ok(&args);
            let npz = read_npz(&dump_n);
            let scene = gltf_read::read(&glb);
            let names = scene.node_by_name();
            let deltas: HashMap<usize, Quat> = pose
                .iter()
                .map(|(k, q)| (names[format!("bone_{k}").as_str()], *q))
                .collect();
            let world = scene.world(&deltas);
            let skinned = scene.skin_positions(0, &world);
            let mut max_dev = 0.0f64;
            for (v, s) in skinned.iter().enumerate() {
                let p = DVec3::new(
                    npz["positions"].numbers[3 * v],
                    npz["positions"].numbers[3 * v + 1],
                    npz["positions"].numbers[3 * v + 2],
                );
                max_dev = max_dev.max((p - s.as_dvec3()).length());
            }
            assert!(
                max_dev <= tol,
                "{} (max {max}): glTF reference deviates {max_dev} > {tol}",
                rig.0
            );
        }
    }
}
