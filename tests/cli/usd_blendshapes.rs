//! UsdSkel blend shapes (issue 22): BlendShape prims with inbetweens and the
//! SkelAnimation's weights become morph targets and weight tracks; UsdSkel's evaluation
//! (usd-core) of the source is the reference for the `.usda` rigport writes, and a glTF
//! player written here from the spec (morph targets, then skinning) for the `.glb`.

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use rigport_model::glam::{Mat4, Quat, Vec3};

use crate::common::*;
use crate::frames::{deviation, usd_world};
use crate::gltf_read::{self, GltfScene};
use crate::motion::sample_channel;
use crate::usd::{check_usd, python};

const SCRIPT: &str = "tests/cli/usd_blendshapes.py";
const PIXAR: &str = "6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning";

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The usd-core fixture (tests/cli/usd_blendshapes.py `make`): `shapes.usda`, `shapes.usdc`.
fn make_fixture(py: &Path, dir: &Path) {
    let out = Command::new(py)
        .arg(repo().join(SCRIPT))
        .arg("make")
        .arg(dir)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

type Frames = Vec<(Vec<[f64; 3]>, Vec<[f64; 3]>)>;

fn triples(v: &serde_json::Value) -> Vec<[f64; 3]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|p| [0, 1, 2].map(|k| p[k].as_f64().unwrap()))
        .collect()
}

/// Points and normals after UsdSkel's blend shapes (`normals` mode of the script), or, for
/// `baked`, the authored points and normals of every Mesh at each time code.
fn shaped(py: &Path, mode: &str, stage: &Path, time_codes: &[f64]) -> Frames {
    let out = Command::new(py)
        .arg(repo().join(SCRIPT))
        .arg(mode)
        .arg(stage)
        .arg(serde_json::to_string(time_codes).unwrap())
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{mode} {}: {}",
        stage.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| (triples(&f["points"]), triples(&f["normals"])))
        .collect()
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    assert_eq!(a.len(), b.len(), "point counts differ");
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn pixar_blend_shapes_with_normals_match_the_baseline() {
    let (Some(source), Some(baseline)) = (
        corpus(&format!("{PIXAR}/blendshapesWithNormals.usda")),
        corpus(&format!(
            "{PIXAR}/baseline/blendshapesWithNormals.baked.usda"
        )),
    ) else {
        return;
    };
    let Some(py) = python() else {
        return;
    };
    let dir = scratch();
    let out = dir.path().join("blendshapesWithNormals.usda");
    rigport_ok(&["convert", s(&source), "-o", s(&out), "--quiet"]);
    let (ok, report) = check_usd(&py, &out, None);
    assert!(ok, "{report}");
    // The baseline at its time codes; source and output also between them (the inbetweens'
    // kinks fall between samples).
    let whole: Vec<f64> = (1..=17).map(f64::from).collect();
    let want = shaped(&py, "baked", &baseline, &whole);
    let got = shaped(&py, "normals", &out, &whole);
    let mut dev = 0.0f64;
    for ((gp, gn), (wp, wn)) in got.iter().zip(&want) {
        dev = dev.max(max_diff(gp, wp)).max(max_diff(gn, wn));
    }
    let quarters: Vec<f64> = (4..=68).map(|k| f64::from(k) / 4.0).collect();
    let src = shaped(&py, "normals", &source, &quarters);
    let ours = shaped(&py, "normals", &out, &quarters);
    let mut between = 0.0f64;
    for ((gp, gn), (wp, wn)) in ours.iter().zip(&src) {
        between = between.max(max_diff(gp, wp)).max(max_diff(gn, wn));
    }
    // The plane's diagonal is sqrt(2): absolute differences are within 1e-6 of it.
    eprintln!(
        "blendshapesWithNormals: .usda vs Pixar's baseline {dev:e}, vs the source at quarter \
         time codes {between:e} (points and unit normals)"
    );
    assert!(dev <= 1e-6 && between <= 1e-6, "{dev:e} {between:e}");
}

#[test]
fn blend_shapes_with_inbetweens_round_trip_through_usda_and_usdc() {
    let Some(py) = python() else {
        return;
    };
    let dir = scratch();
    make_fixture(&py, dir.path());
    // Every quarter frame of the 24 fps clip, so the kinks between samples are covered.
    let seconds: Vec<f64> = (0..=120).map(|k| f64::from(k) / 96.0).collect();
    let want = usd_world(&py, &dir.path().join("shapes.usda"), Some(&seconds), None);
    for ext in ["usda", "usdc"] {
        let source = dir.path().join(format!("shapes.{ext}"));
        let out = dir.path().join(format!("from_{ext}.usda"));
        let stderr = rigport_ok(&["convert", s(&source), "-o", s(&out)]);
        assert!(
            !stderr.contains("blend shape"),
            "no blend-shape warning: {stderr}"
        );
        let (ok, report) = check_usd(&py, &out, None);
        assert!(ok, "{report}");
        let got = usd_world(&py, &out, Some(&seconds), None);
        let dev = got
            .iter()
            .zip(&want)
            .map(|(g, w)| deviation(&g.points, &w.points))
            .fold(0.0, f64::max);
        eprintln!("shapes.{ext} -> .usda under UsdSkel: {dev:e} of the diagonal");
        assert!(dev <= 1e-6, "{ext}: {dev:e}");
    }
}

/// A mesh node of a glTF file: base positions, POSITION morph deltas, skin.
struct MorphMesh {
    node: usize,
    positions: Vec<Vec3>,
    targets: Vec<Vec<Vec3>>,
    /// (joint nodes, inverse bind matrices, per vertex (joint slot, weight)).
    skin: Option<(Vec<usize>, Vec<Mat4>, Vec<Vec<(usize, f32)>>)>,
}

fn morph_meshes(path: &Path) -> Vec<MorphMesh> {
    let (doc, buffers, _) = gltf::import(path).unwrap();
    let mut out = Vec::new();
    for node in doc.nodes() {
        let Some(mesh) = node.mesh() else {
            continue;
        };
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            let positions: Vec<Vec3> = reader.read_positions().unwrap().map(Vec3::from).collect();
            let targets = reader
                .read_morph_targets()
                .map(|(p, _, _)| match p {
                    Some(p) => p.map(Vec3::from).collect(),
                    None => vec![Vec3::ZERO; positions.len()],
                })
                .collect();
            let skin = node.skin().map(|skin| {
                let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
                let ibm = skin
                    .reader(|b| Some(&buffers[b.index()]))
                    .read_inverse_bind_matrices()
                    .unwrap()
                    .map(|m| Mat4::from_cols_array_2d(&m))
                    .collect();
                let mut infl = vec![Vec::new(); positions.len()];
                let mut set = 0;
                while let (Some(js), Some(ws)) = (reader.read_joints(set), reader.read_weights(set))
                {
                    for (v, (j, w)) in js.into_u16().zip(ws.into_f32()).enumerate() {
                        for k in 0..4 {
                            if w[k] > 0.0 {
                                infl[v].push((j[k] as usize, w[k]));
                            }
                        }
                    }
                    set += 1;
                }
                (joints, ibm, infl)
            });
            out.push(MorphMesh {
                node: node.index(),
                positions,
                targets,
                skin,
            });
        }
    }
    out
}

/// World positions of every mesh vertex at `t` (glTF 2.0 §3.7.2.2 morph targets, then
/// §3.7.3 skinning; unskinned meshes by their node's world matrix).
fn play(scene: &GltfScene, meshes: &[MorphMesh], t: f32) -> Vec<[f64; 3]> {
    let mut local = scene.local.clone();
    let mut weights: HashMap<usize, Vec<f32>> = HashMap::new();
    for ch in &scene.animations[0].channels {
        let v = sample_channel(ch, t);
        match ch.path.as_str() {
            "Translation" => local[ch.node].0 = Vec3::from_slice(&v),
            "Rotation" => local[ch.node].1 = Quat::from_slice(&v),
            "Scale" => local[ch.node].2 = Vec3::from_slice(&v),
            "MorphTargetWeights" => {
                weights.insert(ch.node, v);
            }
            other => panic!("channel {other}"),
        }
    }
    let mut world = vec![Mat4::IDENTITY; local.len()];
    // glTF nodes need not be parents-first: resolve by walking up.
    for i in 0..local.len() {
        let mut m = Mat4::IDENTITY;
        let mut cur = Some(i);
        while let Some(c) = cur {
            let (tr, r, sc) = local[c];
            m = Mat4::from_scale_rotation_translation(sc, r, tr) * m;
            cur = scene.parents[c];
        }
        world[i] = m;
    }
    let mut out = Vec::new();
    for mesh in meshes {
        let w = weights.get(&mesh.node).cloned().unwrap_or_default();
        for (v, p) in mesh.positions.iter().enumerate() {
            let mut q = *p;
            for (k, target) in mesh.targets.iter().enumerate() {
                q += target[v] * w.get(k).copied().unwrap_or(0.0);
            }
            let q = match &mesh.skin {
                Some((joints, ibm, infl)) => {
                    let mut m = Mat4::ZERO;
                    for &(slot, wt) in &infl[v] {
                        m += (world[joints[slot]] * ibm[slot]) * wt;
                    }
                    m.transform_point3(q)
                }
                None => world[mesh.node].transform_point3(q),
            };
            out.push(q.as_dvec3().to_array());
        }
    }
    out
}

#[test]
fn blend_shapes_become_gltf_morph_targets_that_play_like_usdskel() {
    let Some(py) = python() else {
        return;
    };
    let dir = scratch();
    make_fixture(&py, dir.path());
    let source = dir.path().join("shapes.usda");
    let glb = dir.path().join("shapes.glb");
    rigport_ok(&["convert", s(&source), "-o", s(&glb), "--quiet"]);
    assert_valid(&glb);
    let scene = gltf_read::read(&glb);
    let meshes = morph_meshes(&glb);
    // Body: primary + 3 inbetweens of smile, primary + 1 of puff; Lid: primary + 1.
    let counts: Vec<usize> = meshes.iter().map(|m| m.targets.len()).collect();
    assert_eq!(counts, vec![6, 2]);
    let seconds: Vec<f64> = (0..=120).map(|k| f64::from(k) / 96.0).collect();
    let want = usd_world(&py, &source, Some(&seconds), None);
    let mut dev = 0.0f64;
    for (t, w) in seconds.iter().zip(&want) {
        let got = play(&scene, &meshes, *t as f32);
        dev = dev.max(deviation(&got, &w.points));
    }
    eprintln!("shapes.usda -> .glb (morph, then skin) vs UsdSkel: {dev:e} of the diagonal");
    assert!(dev <= 1e-5, "{dev:e}");
}
