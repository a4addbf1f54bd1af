//! The CSCI 520 issue's acceptance on the corpus rigs, against a test-only reference that
//! implements the course's formulas straight from the files.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use rigport_model::glam::{DMat3, DMat4, DQuat, DVec3, Quat};

use crate::common::*;
use crate::gltf_read;

const RIGS: [&str; 3] = [
    "2_csci520_ik_skinning/tydia/armadillo",
    "2_csci520_ik_skinning/tydia/hand",
    "2_csci520_ik_skinning/shreyabhaumik/star",
];

/// The rig as the files say, in the files' own joint numbering.
struct Course {
    parents: Vec<Option<usize>>,
    translate: Vec<DVec3>,
    rest_deg: Vec<DVec3>,
    orient_deg: Vec<DVec3>,
    orders: Vec<String>,
    vertices: Vec<DVec3>,
    /// (vertex, joint, weight)
    weights: Vec<(usize, usize, f64)>,
}

fn numbers(text: &str) -> Vec<f64> {
    text.split_ascii_whitespace()
        .filter_map(|t| t.parse().ok())
        .collect()
}

fn read_course(dir: &Path) -> Course {
    let config = std::fs::read_to_string(dir.join("skin.config")).unwrap();
    let mut options = HashMap::new();
    let mut lines = config
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'));
    while let Some(l) = lines.next() {
        if let Some(name) = l.strip_prefix('*') {
            options.insert(
                name.to_ascii_lowercase(),
                lines.next().unwrap_or("").to_string(),
            );
        }
    }
    let file = |k: &str| dir.join(&options[k]);
    let parents: Vec<Option<usize>> =
        numbers(&std::fs::read_to_string(file("jointhierarchyfilename")).unwrap())
            .iter()
            .map(|&p| (p >= 0.0).then_some(p as usize))
            .collect();
    let j = parents.len();
    let rest_text = std::fs::read_to_string(file("jointresttransformsfilename")).unwrap();
    let nums = numbers(&rest_text);
    let triple = |k: usize, i: usize| {
        DVec3::new(
            nums[3 * (k * j + i)],
            nums[3 * (k * j + i) + 1],
            nums[3 * (k * j + i) + 2],
        )
    };
    let orders: Vec<String> = rest_text
        .split_ascii_whitespace()
        .filter(|t| t.parse::<f64>().is_err())
        .map(str::to_ascii_lowercase)
        .collect();
    let vertices = std::fs::read_to_string(file("meshfilename"))
        .unwrap()
        .lines()
        .filter_map(|l| l.trim().strip_prefix("v "))
        .map(|l| {
            let n = numbers(l);
            DVec3::new(n[0], n[1], n[2])
        })
        .collect();
    let w = numbers(&std::fs::read_to_string(file("jointweightsfilename")).unwrap());
    let weights = w[2..]
        .chunks(3)
        .map(|c| (c[0] as usize, c[1] as usize, c[2]))
        .collect();
    Course {
        parents,
        translate: (0..j).map(|i| triple(0, i)).collect(),
        rest_deg: (0..j).map(|i| triple(1, i)).collect(),
        orient_deg: (0..j).map(|i| triple(2, i)).collect(),
        orders: if orders.len() == j {
            orders
        } else {
            vec!["xyz".into(); j]
        },
        vertices,
        weights,
    }
}

/// R_order(angles): the first letter's rotation is applied first (right-most).
fn euler(order: &str, deg: DVec3) -> DMat3 {
    let r = deg * (std::f64::consts::PI / 180.0);
    let m = |c: char| match c {
        'x' => DMat3::from_rotation_x(r.x),
        'y' => DMat3::from_rotation_y(r.y),
        _ => DMat3::from_rotation_z(r.z),
    };
    order.chars().fold(DMat3::IDENTITY, |acc, c| m(c) * acc)
}

/// global(i) for the given per-joint angles (course formula).
fn globals(c: &Course, angles: &[DVec3]) -> Vec<DMat4> {
    fn rec(c: &Course, a: &[DVec3], i: usize, memo: &mut Vec<Option<DMat4>>) -> DMat4 {
        if let Some(m) = memo[i] {
            return m;
        }
        let local = DMat4::from_translation(c.translate[i])
            * DMat4::from_mat3(euler("xyz", c.orient_deg[i]))
            * DMat4::from_mat3(euler(&c.orders[i], a[i]));
        let g = match c.parents[i] {
            Some(p) => rec(c, a, p, memo) * local,
            None => local,
        };
        memo[i] = Some(g);
        g
    }
    let mut memo = vec![None; c.parents.len()];
    (0..c.parents.len())
        .map(|i| rec(c, angles, i, &mut memo))
        .collect()
}

fn course_skin(c: &Course, pose: &[DVec3]) -> Vec<DVec3> {
    let rest = globals(c, &c.rest_deg);
    let posed = globals(c, pose);
    let skin: Vec<DMat4> = posed
        .iter()
        .zip(&rest)
        .map(|(p, r)| *p * r.inverse())
        .collect();
    let mut out = vec![DVec3::ZERO; c.vertices.len()];
    for &(v, j, w) in &c.weights {
        out[v] += skin[j].transform_point3(c.vertices[v]) * w;
    }
    out
}

fn diag(points: &[DVec3]) -> f64 {
    let lo = points.iter().fold(DVec3::splat(f64::MAX), |a, b| a.min(*b));
    let hi = points.iter().fold(DVec3::splat(f64::MIN), |a, b| a.max(*b));
    (hi - lo).length()
}

fn rig_dir(rel: &str) -> Option<PathBuf> {
    corpus(rel)
}

#[test]
fn csci520_rigs_convert_clean_with_bind_pose_equal_to_the_obj() {
    for rel in RIGS {
        let Some(dir) = rig_dir(rel) else { continue };
        let course = read_course(&dir);
        let out_dir = scratch();
        for max in ["4", "8"] {
            let out = out_dir.path().join(format!("rig{max}.glb"));
            let stderr = rigport_ok(&[
                "convert",
                dir.to_str().unwrap(),
                "--max-influences",
                max,
                "-o",
                out.to_str().unwrap(),
            ]);
            let most = course
                .weights
                .iter()
                .fold(HashMap::new(), |mut m, &(v, _, _)| {
                    *m.entry(v).or_insert(0) += 1;
                    m
                });
            let most = most.values().copied().max().unwrap_or(0);
            if max == "4" && most > 4 {
                assert!(
                    stderr.contains("lost weight to the limit of 4"),
                    "{rel}: no loss warning:\n{stderr}"
                );
            }
            assert_valid(&out);
            let scene = gltf_read::read(&out);
            let skin = &scene.skins[0];
            // Output vertex i is `v` line i (UV splits come after).
            for (v, p) in course.vertices.iter().enumerate() {
                assert!(
                    (skin.positions[v].as_dvec3() - *p).length() <= 1e-6,
                    "{rel} vertex {v}"
                );
            }
            // Rest pose through the file's own IBMs and node transforms, in f64.
            let world: Vec<DMat4> = {
                let w = scene.world(&HashMap::new());
                w.iter().map(|m| m.as_dmat4()).collect()
            };
            for (v, (p, infl)) in skin.positions.iter().zip(&skin.influences).enumerate() {
                let ibm: HashMap<usize, DMat4> = skin
                    .joints
                    .iter()
                    .zip(&skin.inverse_bind)
                    .map(|(j, m)| (*j, m.as_dmat4()))
                    .collect();
                let moved: DVec3 = infl
                    .iter()
                    .map(|(n, w)| {
                        (world[*n] * ibm[n]).transform_point3(p.as_dvec3()) * f64::from(*w)
                    })
                    .sum();
                assert!(
                    (moved - p.as_dvec3()).length() <= 1e-5 * diag(&course.vertices),
                    "{rel} vertex {v}: {moved} vs {p}"
                );
            }
        }
    }
}

#[test]
fn csci520_eval_matches_the_course_formula_and_the_gltf() {
    for rel in RIGS {
        let Some(dir) = rig_dir(rel) else { continue };
        let course = read_course(&dir);
        let j = course.parents.len();
        // Pose angles: the rest angles plus a change on several joints, each in its own
        // rotate order (the armadillo's zxy joints 2, 6, 14 and 18 included).
        let mut pose = course.rest_deg.clone();
        let mut picked: Vec<usize> = vec![1, 2, j / 2, j - 1];
        picked.extend([6, 14, 18].iter().filter(|&&k| k < j));
        for (n, &k) in picked.iter().enumerate() {
            pose[k] += DVec3::new(20.0 + 5.0 * n as f64, -15.0, 25.0 - 3.0 * n as f64);
        }
        let reference = course_skin(&course, &pose);
        // The pose file: joints whose rest angles are zero get Euler angles in their own
        // order; the others the equivalent change of rotation, R_order(rest)^-1 R_order(pose).
        let mut entries = Vec::new();
        for &k in &picked {
            let name = format!("joint_{k}");
            if course.rest_deg[k] == DVec3::ZERO {
                let a = pose[k];
                entries.push(format!(
                    "\"{name}\": {{\"euler_deg\": [{}, {}, {}], \"order\": \"{}\"}}",
                    a.x, a.y, a.z, course.orders[k]
                ));
            } else {
                let rest = euler(&course.orders[k], course.rest_deg[k]);
                let posed = euler(&course.orders[k], pose[k]);
                let q = DQuat::from_mat3(&(rest.transpose() * posed)).normalize();
                entries.push(format!(
                    "\"{name}\": {{\"quat\": [{}, {}, {}, {}]}}",
                    q.x, q.y, q.z, q.w
                ));
            }
        }
        entries.sort();
        entries.dedup();
        let work = scratch();
        let pose_file = work.path().join("pose.json");
        std::fs::write(&pose_file, format!("{{{}}}", entries.join(", "))).unwrap();
        let dump = work.path().join("dump.npz");
        rigport_ok(&[
            "eval",
            dir.to_str().unwrap(),
            "--pose",
            pose_file.to_str().unwrap(),
            "-o",
            dump.to_str().unwrap(),
        ]);
        let npz = read_npz(&dump);
        let got = &npz["positions"].numbers;
        let tol = 1e-5 * diag(&course.vertices);
        let mut max_dev = 0.0f64;
        let mut moved = 0;
        for (v, r) in reference.iter().enumerate() {
            let p = DVec3::new(got[3 * v], got[3 * v + 1], got[3 * v + 2]);
            max_dev = max_dev.max((p - *r).length());
            if (*r - course.vertices[v]).length() > 100.0 * tol {
                moved += 1;
            }
        }
        assert!(moved > 0, "{rel}: the pose moved nothing");
        assert!(
            max_dev <= tol,
            "{rel}: eval deviates {max_dev} > {tol} from the course formula"
        );
        eprintln!("{rel}: eval vs course formula: max deviation {max_dev:.3e} (tolerance {tol:.3e}), {moved} vertices moved");

        // The exported glTF, skinned by the test-only evaluator from its own IBMs and node
        // transforms, with the same pose applied to the named nodes.
        let glb = work.path().join("rig.glb");
        rigport_ok(&[
            "convert",
            dir.to_str().unwrap(),
            "--max-influences",
            "8",
            "-o",
            glb.to_str().unwrap(),
        ]);
        let scene = gltf_read::read(&glb);
        let names = scene.node_by_name();
        let pose_json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&pose_file).unwrap()).unwrap();
        let mut deltas = HashMap::new();
        for (name, entry) in pose_json.as_object().unwrap() {
            let q = if let Some(q) = entry.get("quat") {
                let q: Vec<f32> = q
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap() as f32)
                    .collect();
                Quat::from_slice(&q)
            } else {
                let k: usize = name["joint_".len()..].parse().unwrap();
                Quat::from_mat3(&euler(&course.orders[k], pose[k]).as_mat3())
            };
            deltas.insert(names[name.as_str()], q);
        }
        let world = scene.world(&deltas);
        let skinned = scene.skin_positions(0, &world);
        let mut max_dev = 0.0f64;
        for (v, r) in reference.iter().enumerate() {
            max_dev = max_dev.max((skinned[v].as_dvec3() - *r).length());
        }
        assert!(
            max_dev <= tol,
            "{rel}: glTF skinning deviates {max_dev} > {tol}"
        );
    }
}

/// Copies the chain fixture into a scratch folder, with one file replaced.
fn chain_with(dir: &Path, file: &str, text: &str) -> PathBuf {
    let src = repo().join("fixtures/csci520/chain");
    for entry in std::fs::read_dir(&src).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), dir.join(entry.file_name())).unwrap();
    }
    std::fs::write(dir.join(file), text).unwrap();
    dir.join("skin.config")
}

#[test]
fn csci520_malformed_folders_are_rejected_with_file_and_line() {
    let chain = repo().join("fixtures/csci520/chain");
    let config = std::fs::read_to_string(chain.join("skin.config")).unwrap();
    let cases: Vec<(&str, String, Vec<&str>)> = vec![
        (
            "skin.config",
            config.replace("jointRestTransforms.txt", "missing.txt"),
            vec!["skin.config:", "missing.txt"],
        ),
        (
            "jointWeights.txt",
            "8 5\n0 2 1.0\n".into(),
            vec!["jointWeights.txt:1"],
        ),
        (
            "jointWeights.txt",
            std::fs::read_to_string(chain.join("jointWeights.txt"))
                .unwrap()
                .replace("7 0 1.0", "9 0 1.0"),
            vec!["jointWeights.txt:13"],
        ),
        (
            "jointRestTransforms.txt",
            std::fs::read_to_string(chain.join("jointRestTransforms.txt"))
                .unwrap()
                .replace("zxy", "zqy"),
            vec!["jointRestTransforms.txt:4", "zqy"],
        ),
        (
            "jointHierarchy.txt",
            "1 3 3 2\n".into(),
            vec!["jointHierarchy.txt:1", "cycle"],
        ),
    ];
    for (file, text, needles) in cases {
        let dir = scratch();
        let cfg = chain_with(dir.path(), file, &text);
        let out_dir = scratch();
        let out = out_dir.path().join("out.glb");
        let r = rigport(&[
            "convert",
            cfg.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "{file}: {stderr}");
        for n in needles {
            assert!(stderr.contains(n), "{file}: {n:?} not in {stderr}");
        }
        assert_eq!(
            std::fs::read_dir(out_dir.path()).unwrap().count(),
            0,
            "{file}: output left behind"
        );
    }
}

#[test]
fn csci520_rig_without_weights_converts_with_a_warning_and_eval_refuses() {
    let dir = scratch();
    let cfg = chain_with(
        dir.path(),
        "skin.config",
        &std::fs::read_to_string(repo().join("fixtures/csci520/chain/skin.config"))
            .unwrap()
            .replace("jointWeights.txt", "gone.txt"),
    );
    let out = dir.path().join("out.glb");
    let stderr = rigport_ok(&[
        "convert",
        cfg.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        stderr.contains("warning[W004]:") && stderr.contains("no skin weights"),
        "{stderr}"
    );
    assert_valid(&out);
    let r = rigport(&[
        "eval",
        cfg.to_str().unwrap(),
        "-o",
        dir.path().join("d.npz").to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&r.stderr).contains("nothing to skin"));
    let r = rigport(&[
        "--deny-warnings",
        "convert",
        cfg.to_str().unwrap(),
        "-o",
        dir.path().join("x.glb").to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(4));
}
