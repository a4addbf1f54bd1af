//! Skinning acceptance (issue 5): LBS/DQS against usd-core on every shared rig, and DQS
//! baked into glTF as corrective morph targets, checked by an independent glTF sampler.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use rigport_model::glam::{Mat4, Quat, Vec3};

use crate::common::*;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

// ---------------------------------------------------------------------------------------
// An independent glTF sampler: the `gltf` crate parses the document; accessors (sparse
// included), animation sampling, morphing and skinning are written here from the spec.

/// Reads `count` VEC3 floats of an accessor: the base view (or zeros when it has none,
/// glTF 2.0 §3.6.2.3), then the sparse substitution.
fn read_vec3(acc: &gltf::Accessor<'_>, buffers: &[gltf::buffer::Data]) -> Vec<Vec3> {
    assert_eq!(acc.data_type(), gltf::accessor::DataType::F32);
    assert_eq!(acc.dimensions(), gltf::accessor::Dimensions::Vec3);
    let bytes = |view: &gltf::buffer::View<'_>| -> &[u8] {
        let b = &buffers[view.buffer().index()];
        &b[view.offset()..view.offset() + view.length()]
    };
    let f32_at = |data: &[u8], at: usize| f32::from_le_bytes(data[at..at + 4].try_into().unwrap());
    let mut out = vec![Vec3::ZERO; acc.count()];
    if let Some(view) = acc.view() {
        let data = bytes(&view);
        let stride = view.stride().unwrap_or(12);
        for (i, o) in out.iter_mut().enumerate() {
            let at = acc.offset() + i * stride;
            *o = Vec3::new(f32_at(data, at), f32_at(data, at + 4), f32_at(data, at + 8));
        }
    }
    if let Some(sparse) = acc.sparse() {
        let idx = sparse.indices();
        let idata = &bytes(&idx.view())[idx.offset()..];
        let vdata = &bytes(&sparse.values().view())[sparse.values().offset()..];
        let mut last = None;
        for k in 0..sparse.count() {
            let i = match idx.index_type() {
                gltf::accessor::sparse::IndexType::U8 => idata[k] as usize,
                gltf::accessor::sparse::IndexType::U16 => {
                    u16::from_le_bytes([idata[2 * k], idata[2 * k + 1]]) as usize
                }
                gltf::accessor::sparse::IndexType::U32 => {
                    u32::from_le_bytes(idata[4 * k..4 * k + 4].try_into().unwrap()) as usize
                }
            };
            assert!(last.is_none_or(|l| i > l), "sparse indices must increase");
            last = Some(i);
            out[i] = Vec3::new(
                f32_at(vdata, 12 * k),
                f32_at(vdata, 12 * k + 4),
                f32_at(vdata, 12 * k + 8),
            );
        }
    }
    out
}

/// The skinned primitive of a baked file, with its morph targets.
struct Baked {
    scene: crate::gltf_read::GltfScene,
    mesh_node: usize,
    targets: Vec<Vec<Vec3>>,
    target_names: Vec<String>,
}

fn read_baked(path: &Path) -> Baked {
    let scene = crate::gltf_read::read(path);
    assert_eq!(scene.skins.len(), 1, "one skinned primitive");
    let (doc, buffers, _) = gltf::import(path).unwrap();
    let node = doc
        .nodes()
        .find(|n| n.skin().is_some() && n.mesh().is_some())
        .unwrap();
    let mesh = node.mesh().unwrap();
    let prim = mesh.primitives().next().unwrap();
    let targets: Vec<Vec<Vec3>> = prim
        .morph_targets()
        .map(|t| read_vec3(&t.positions().expect("POSITION target"), &buffers))
        .collect();
    let extras: serde_json::Value =
        serde_json::from_str(mesh.extras().as_ref().expect("mesh extras").get()).unwrap();
    let target_names = extras["targetNames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_string())
        .collect();
    Baked {
        scene,
        mesh_node: node.index(),
        targets,
        target_names,
    }
}

/// glTF 2.0 §3.11: LINEAR is lerp (slerp for rotations), STEP holds, clamped at the ends.
fn sample(ch: &crate::gltf_read::GltfChannel, t: f32) -> Vec<f32> {
    let n = ch.times.len();
    if n == 1 || t <= ch.times[0] {
        return ch.values[0].clone();
    }
    if t >= ch.times[n - 1] {
        return ch.values[n - 1].clone();
    }
    let k = ch.times.partition_point(|&x| x <= t) - 1;
    let u = (t - ch.times[k]) / (ch.times[k + 1] - ch.times[k]);
    let (a, b) = (&ch.values[k], &ch.values[k + 1]);
    match (ch.interpolation.as_str(), ch.path.as_str()) {
        ("Step", _) => a.clone(),
        ("Linear", "Rotation") => Quat::from_slice(a)
            .slerp(Quat::from_slice(b), u)
            .to_array()
            .to_vec(),
        ("Linear", _) => a.iter().zip(b).map(|(x, y)| x + (y - x) * u).collect(),
        (other, _) => panic!("interpolation {other} not expected"),
    }
}

/// What a glTF viewer shows at time `t`: morph targets with the animated weights, then
/// linear blend skinning (glTF 2.0 §3.7.2.2 before §3.7.3).
fn viewer_positions(b: &Baked, t: f32) -> Vec<Vec3> {
    let scene = &b.scene;
    let anim = &scene.animations[0];
    let mut local = scene.local.clone();
    let mut weights = vec![0.0; b.targets.len()];
    for ch in &anim.channels {
        let v = sample(ch, t);
        match ch.path.as_str() {
            "Translation" => local[ch.node].0 = Vec3::from_slice(&v),
            "Rotation" => local[ch.node].1 = Quat::from_slice(&v),
            "Scale" => local[ch.node].2 = Vec3::from_slice(&v),
            "MorphTargetWeights" => {
                assert_eq!(ch.node, b.mesh_node);
                weights = v;
            }
            other => panic!("{other}"),
        }
    }
    let mut world: Vec<Option<Mat4>> = vec![None; local.len()];
    fn rec(
        i: usize,
        sc: &crate::gltf_read::GltfScene,
        l: &[(Vec3, Quat, Vec3)],
        w: &mut [Option<Mat4>],
    ) -> Mat4 {
        if let Some(m) = w[i] {
            return m;
        }
        let (tr, r, s) = l[i];
        let m = Mat4::from_scale_rotation_translation(s, r, tr);
        let m = match sc.parents[i] {
            Some(p) => rec(p, sc, l, w) * m,
            None => m,
        };
        w[i] = Some(m);
        m
    }
    let world: Vec<Mat4> = (0..local.len())
        .map(|i| rec(i, scene, &local, &mut world))
        .collect();
    let skin = &scene.skins[0];
    let ibm: HashMap<usize, Mat4> = skin
        .joints
        .iter()
        .zip(&skin.inverse_bind)
        .map(|(j, m)| (*j, *m))
        .collect();
    (0..skin.positions.len())
        .map(|v| {
            let mut p = skin.positions[v];
            for (t, w) in b.targets.iter().zip(&weights) {
                p += t[v] * *w;
            }
            let mut m = Mat4::ZERO;
            for (node, w) in &skin.influences[v] {
                m += (world[*node] * ibm[node]) * *w;
            }
            m.transform_point3(p)
        })
        .collect()
}

fn diagonal(points: &[Vec3]) -> f32 {
    let lo = points.iter().fold(Vec3::splat(f32::MAX), |a, b| a.min(*b));
    let hi = points.iter().fold(Vec3::splat(f32::MIN), |a, b| a.max(*b));
    (hi - lo).length()
}

fn vec3s(numbers: &[f64]) -> Vec<Vec3> {
    numbers
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
        .collect()
}

/// Bakes `input` with `bake_args`, validates it, and compares the viewer's result with
/// `rigport eval --skinning dqs` (same frames and influence limit) at every frame; returns
/// the worst deviation relative to the frame's bounding-box diagonal, and bake's stderr.
fn bake_and_compare(
    input: &[&str],
    frame_args: &[&str],
    extra_bake: &[&str],
    dir: &Path,
    tag: &str,
) -> (f32, String) {
    let glb = dir.join(format!("{tag}.glb"));
    let dump = dir.join(format!("{tag}.npz"));
    let mut args = vec!["bake"];
    args.extend_from_slice(input);
    args.extend_from_slice(&["--skinning", "dqs", "--max-influences", "4", "-o", s(&glb)]);
    args.extend_from_slice(frame_args);
    args.extend_from_slice(extra_bake);
    let stderr = rigport_ok(&args);
    assert!(stderr.contains("file size:"), "{stderr}");
    assert_valid(&glb);
    let mut args = vec!["eval"];
    args.extend_from_slice(input);
    args.extend_from_slice(&[
        "--skinning",
        "dqs",
        "--max-influences",
        "4",
        "-o",
        s(&dump),
        "--quiet",
    ]);
    args.extend_from_slice(frame_args);
    rigport_ok(&args);
    let npz = read_npz(&dump);
    let times: Vec<f32> = npz["times"].numbers.iter().map(|&t| t as f32).collect();
    let rest = vec3s(&npz["rest_positions"].numbers);
    let v = rest.len();
    let baked = read_baked(&glb);
    if extra_bake.is_empty() {
        assert_eq!(baked.targets.len(), times.len(), "one target per frame");
        let names: Vec<String> = (0..times.len()).map(|k| format!("frame_{k}")).collect();
        assert_eq!(baked.target_names, names);
    }
    // Dump vertex -> glTF vertex, by identical rest position.
    let mut by_rest = HashMap::new();
    for (i, p) in baked.scene.skins[0].positions.iter().enumerate() {
        by_rest.entry(p.to_array().map(f32::to_bits)).or_insert(i);
    }
    let map: Vec<usize> = rest
        .iter()
        .map(|p| by_rest[&p.to_array().map(f32::to_bits)])
        .collect();
    let dqs = vec3s(&npz["positions"].numbers);
    let mut worst = 0.0f32;
    for (f, &t) in times.iter().enumerate() {
        let want = &dqs[f * v..(f + 1) * v];
        let got = viewer_positions(&baked, t);
        let diag = diagonal(want);
        for (vi, w) in want.iter().enumerate() {
            let d = (got[map[vi]] - *w).length() / diag;
            assert!(
                d <= 1e-4,
                "{tag} frame {f} (t = {t}) vertex {vi}: viewer {} vs DQS {w}: {d:e} of the diagonal",
                got[map[vi]]
            );
            worst = worst.max(d);
        }
    }
    eprintln!(
        "{tag}: {} frames, worst {worst:e} of the diagonal",
        times.len()
    );
    (worst, stderr)
}

/// A Pinocchio rig with a keyed clip twisting and bending limbs (`rigport animate`).
fn twisting_pinocchio(dir: &Path) -> Option<PathBuf> {
    let rig = PINOCCHIO_RIGS.iter().find(|r| r.0 == "model1")?;
    let (mesh, skel, att) = (corpus(rig.1)?, corpus(rig.2)?, corpus(rig.3)?);
    let keys = dir.join("twist.keys.json");
    std::fs::write(
        &keys,
        r#"{"name": "twist", "keys": [
            {"time": 0, "pose": {}},
            {"time": 0.5, "pose": {"bone_3": {"euler_deg": [0, 90, 0]}, "bone_7": {"euler_deg": [100, 0, 30]}}},
            {"time": 1.0, "pose": {"bone_3": {"euler_deg": [0, 150, 40]}, "bone_7": {"euler_deg": [160, 20, 0]}, "bone_12": {"euler_deg": [0, 0, 70]}}}
        ]}"#,
    )
    .unwrap();
    let glb = dir.join("twist_source.glb");
    rigport_ok(&[
        "animate",
        s(&mesh),
        s(&skel),
        s(&att),
        "--keys",
        s(&keys),
        "-o",
        s(&glb),
        "--quiet",
    ]);
    Some(glb)
}

#[test]
fn baked_dqs_glb_validates_and_a_viewer_lands_on_dqs() {
    let dir = scratch();
    if let Some(walk) = corpus("4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh") {
        bake_and_compare(&[s(&walk)], &["--fps", "10"], &[], dir.path(), "walk");
    }
    let Some(twist) = twisting_pinocchio(dir.path()) else {
        return;
    };
    let (_, stderr) = bake_and_compare(&[s(&twist)], &[], &[], dir.path(), "twist");
    // The twist needs real corrections: LBS and DQS differ there.
    let line = stderr
        .lines()
        .find(|l| l.contains("vertices corrected"))
        .unwrap();
    let max: usize = line
        .split("max ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .unwrap()
        .parse()
        .unwrap();
    assert!(max > 100, "{line}");
    // `--skinning lbs` writes the plain file: no targets.
    let plain = dir.path().join("plain.glb");
    rigport_ok(&[
        "bake",
        s(&twist),
        "--skinning",
        "lbs",
        "-o",
        s(&plain),
        "--quiet",
    ]);
    assert_valid(&plain);
    assert!(read_baked_targets_empty(&plain));
    // K shared targets: as many as frames is lossless; fewer reports its error.
    bake_and_compare(&[s(&twist)], &[], &["--correctives", "3"], dir.path(), "k3");
    let k1 = dir.path().join("k1.glb");
    let stderr = rigport_ok(&[
        "bake",
        s(&twist),
        "--skinning",
        "dqs",
        "--fps",
        "8",
        "--correctives",
        "1",
        "-o",
        s(&k1),
    ]);
    assert_valid(&k1);
    assert!(stderr.contains("1 targets"), "{stderr}");
    let baked = read_baked(&k1);
    assert_eq!(baked.target_names, ["corrective_0"]);
}

fn read_baked_targets_empty(path: &Path) -> bool {
    let (doc, _, _) = gltf::import(path).unwrap();
    doc.meshes()
        .all(|m| m.primitives().all(|p| p.morph_targets().next().is_none()))
}

#[test]
fn near_singular_blends_fall_back_with_a_warning_naming_the_frame() {
    let dir = scratch();
    let p = |n: &str| dir.path().join(n);
    // Source vertex 4 of the chain is weighted 0.5/0.5 to joint_3 and its child joint_1:
    // turning joint_1 by 180° makes the blend I + R of rank 1 at the last key.
    std::fs::write(
        p("flip.json"),
        r#"{"name": "flip", "keys": [{"time": 0, "pose": {}}, {"time": 1, "pose": {"joint_1": {"quat": [1, 0, 0, 0]}}}]}"#,
    )
    .unwrap();
    let chain = repo().join("fixtures/csci520/chain");
    rigport_ok(&[
        "animate",
        s(&chain),
        "--keys",
        s(&p("flip.json")),
        "-o",
        s(&p("flip.glb")),
        "--quiet",
    ]);
    let out = p("baked.glb");
    let stderr = rigport_ok(&[
        "bake",
        s(&p("flip.glb")),
        "--skinning",
        "dqs",
        "--fps",
        "4",
        "-o",
        s(&out),
    ]);
    assert!(
        stderr.contains("near-singular") && stderr.contains("in frames 4 (2 vertices)"),
        "{stderr}"
    );
    assert_valid(&out);
    let denied = rigport(&[
        "--deny-warnings",
        "bake",
        s(&p("flip.glb")),
        "--skinning",
        "dqs",
        "--fps",
        "4",
        "-o",
        s(&p("denied.glb")),
    ]);
    assert!(!denied.status.success());
    assert!(!p("denied.glb").exists());
}

#[test]
fn bake_rejects_what_it_cannot_do() {
    let dir = scratch();
    let fixture = repo().join("fixtures/csci520/chain");
    // A rig without a clip.
    let out = rigport(&[
        "bake",
        s(&fixture),
        "--skinning",
        "dqs",
        "-o",
        s(&dir.path().join("x.glb")),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no clip"), "{err}");
    // USD declares DQS itself.
    let out = rigport(&[
        "bake",
        s(&fixture),
        "--skinning",
        "dqs",
        "-o",
        s(&dir.path().join("x.usda")),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--skinning dqs"));
}

// ---------------------------------------------------------------------------------------
// Acceptance 1: rigport's LBS and DQS against usd-core's UsdSkel.SkinPoints.

fn python() -> Option<PathBuf> {
    let p = std::env::var_os("RIGPORT_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join("tools/.venv/bin/python"));
    require(
        "Python with usd-core (RIGPORT_PYTHON or tools/.venv, bash tools/setup.sh)",
        (p.exists() || std::env::var_os("RIGPORT_PYTHON").is_some()).then_some(p),
    )
}

/// A small seeded generator (SplitMix64), so poses are the same on every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [-1, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

fn joint_names(input: &[&str]) -> Vec<String> {
    let mut args = vec!["inspect", "--json"];
    args.extend_from_slice(input);
    let out = rigport(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    json[0]["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["name"].as_str().unwrap().to_string())
        .collect()
}

/// Evaluates `input` under a random pose (from `seed`) with LBS and with DQS into `dir`;
/// returns the two dumps.
fn posed_dumps(input: &[&str], seed: u64, dir: &Path, tag: &str) -> Vec<PathBuf> {
    let names = joint_names(input);
    let mut rng = Rng(seed);
    let mut pose = serde_json::Map::new();
    for _ in 0..4.min(names.len()) {
        let j = &names[(rng.next() % names.len() as u64) as usize];
        let e: Vec<f64> = (0..3).map(|_| (rng.unit() * 60.0).round()).collect();
        pose.insert(j.clone(), serde_json::json!({ "euler_deg": e }));
    }
    let pose_path = dir.join(format!("{tag}.pose.json"));
    std::fs::write(&pose_path, serde_json::Value::Object(pose).to_string()).unwrap();
    let mut dumps = Vec::new();
    for method in ["lbs", "dqs"] {
        let dump = dir.join(format!("{tag}.{method}.npz"));
        let mut args = vec!["eval"];
        args.extend_from_slice(input);
        args.extend_from_slice(&[
            "--pose",
            s(&pose_path),
            "--skinning",
            method,
            "-o",
            s(&dump),
            "--quiet",
        ]);
        rigport_ok(&args);
        dumps.push(dump);
    }
    dumps
}

/// Runs tools/check_skinning.py on every dump in one call (usd-core loads once): each
/// dump's summary must say OK.
fn check_dumps(py: &Path, dumps: &[PathBuf]) {
    let out = Command::new(py)
        .arg(repo().join("tools/check_skinning.py"))
        .args(dumps)
        .arg("--quiet")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "check_skinning.py exit {:?}\n{text}\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    let ok = text
        .lines()
        .filter(|l| l.starts_with("max deviation") && l.ends_with(": OK"))
        .count();
    assert_eq!(ok, dumps.len(), "{text}");
}

#[test]
fn lbs_and_dqs_match_usdskel_on_every_shared_rig_under_random_poses() {
    let Some(py) = python() else {
        return;
    };
    let dir = scratch();
    let mut dumps = Vec::new();
    let mut seed = 520;
    for (label, mesh, skel, att) in PINOCCHIO_RIGS {
        seed += 1;
        let (Some(mesh), Some(skel), Some(att)) = (corpus(mesh), corpus(skel), corpus(att)) else {
            continue;
        };
        let input = [s(&mesh), s(&skel), s(&att)];
        dumps.extend(posed_dumps(&input, seed, dir.path(), label));
    }
    for rel in [
        "2_csci520_ik_skinning/tydia/armadillo",
        "2_csci520_ik_skinning/tydia/hand",
        "2_csci520_ik_skinning/shreyabhaumik/star",
    ] {
        seed += 1;
        let Some(folder) = corpus(rel) else {
            continue;
        };
        let tag = rel.replace('/', "_");
        dumps.extend(posed_dumps(&[s(&folder)], seed, dir.path(), &tag));
    }
    let demo = crate::common::demo_outputs();
    let glb = demo.join("demo.glb");
    dumps.extend(posed_dumps(&[s(&glb)], seed + 1, dir.path(), "demo"));
    check_dumps(&py, &dumps);
}
