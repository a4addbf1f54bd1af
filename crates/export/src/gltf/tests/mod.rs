//! Round trips through an independent reader (the `gltf` crate), layout rules read from the
//! JSON, determinism and validation. Skinning, animation and file-writing tests are in the
//! submodules.

use std::collections::BTreeMap;
use std::path::Path;

use gltf::animation::util::ReadOutputs;
use rigport_model::conventions::WEIGHT_EPSILON;
use rigport_model::glam::{Mat4, Vec3, Vec4};
use rigport_model::{
    Asset, AssetError, Influence, Influences, Interpolation, JointIndex, Track, TrackTarget,
    Warning,
};
use serde_json::Value;

use super::*;
use crate::test_assets;
use crate::Problem;

mod animation;
mod compression;
mod files;
mod skin;

/// Tolerance for values that went through `f32` arithmetic once (normalization); values
/// copied verbatim are compared exactly.
const EPS: f32 = 1e-6;

fn assert_close(a: &[f32], b: &[f32], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths differ");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= EPS,
            "{what}[{i}]: {x} vs {y} (diff {})",
            (x - y).abs()
        );
    }
}

fn glb(asset: &Asset, max_influences: usize) -> Exported {
    to_glb(
        asset,
        &GltfOptions {
            max_influences,
            ..Default::default()
        },
    )
    .expect("export")
}

/// The JSON chunk of a GLB, parsed.
fn glb_json(glb: &[u8]) -> Value {
    let len = u32::from_le_bytes(glb[12..16].try_into().expect("4 bytes")) as usize;
    serde_json::from_slice(&glb[20..20 + len]).expect("json chunk")
}

/// Reads a GLB with the `gltf` crate (which validates the document on load).
fn import(glb: &[u8]) -> (gltf::Document, Vec<gltf::buffer::Data>) {
    let (doc, buffers, _) = gltf::import_slice(glb).expect("gltf crate reads the export");
    (doc, buffers)
}

/// The expected (palette joint, weight) pairs of a raw row: merged, tiny dropped, the
/// `max` largest kept (ties by palette index), renormalized.
fn expected_row(row: &[Influence], max: usize) -> BTreeMap<u16, f32> {
    let mut merged: BTreeMap<u32, f64> = BTreeMap::new();
    for i in row {
        *merged.entry(i.joint).or_default() += f64::from(i.weight);
    }
    let merged_total: f64 = merged.values().sum();
    let mut v: Vec<(u32, f64)> = merged
        .into_iter()
        .filter(|&(_, w)| w / merged_total >= f64::from(WEIGHT_EPSILON))
        .collect();
    v.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    v.truncate(max);
    let total: f64 = v.iter().map(|&(_, w)| w).sum();
    v.into_iter()
        .map(|(j, w)| (j as u16, (w / total) as f32))
        .collect()
}

#[test]
fn glb_round_trips_through_the_gltf_crate() {
    let asset = test_assets::rig();
    let out = glb(&asset, 4);
    let (doc, buffers) = import(&out.glb);
    let data = |b: gltf::Buffer| Some(&*buffers[b.index()]);

    // Header and asset.
    assert_eq!(&out.glb[..4], b"glTF");
    assert_eq!(u32::from_le_bytes(out.glb[4..8].try_into().expect("4")), 2);
    assert_eq!(
        u32::from_le_bytes(out.glb[8..12].try_into().expect("4")) as usize,
        out.glb.len()
    );
    let json = glb_json(&out.glb);
    assert_eq!(json["asset"]["version"], "2.0");
    assert_eq!(
        json["asset"]["generator"],
        format!("rigport {}", env!("CARGO_PKG_VERSION"))
    );

    // Nodes: joints first, hierarchy from the parent links, identity TRS omitted.
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    assert_eq!(nodes.len(), 5, "3 joints + body + hat");
    let names: Vec<_> = nodes.iter().map(|n| n.name().unwrap_or("")).collect();
    assert_eq!(names, ["root", "mid", "tip", "body", "hat"]);
    let kids = |i: usize| nodes[i].children().map(|c| c.index()).collect::<Vec<_>>();
    assert_eq!(kids(0), [1]);
    assert_eq!(kids(1), [2]);
    assert_eq!(kids(2), [4], "the hat hangs under its joint");
    let scene = doc.default_scene().expect("default scene");
    assert_eq!(scene.nodes().map(|n| n.index()).collect::<Vec<_>>(), [0, 3]);
    for (i, joint) in asset.skeleton.joints().iter().enumerate() {
        let (t, r, s) = nodes[i].transform().decomposed();
        assert_eq!(Vec3::from(t), joint.rest_local.translation);
        assert_close(
            &r,
            &joint.rest_local.rotation.normalize().to_array(),
            "rotation",
        );
        assert_eq!(Vec3::from(s), joint.rest_local.scale);
    }
    let jn = json["nodes"].as_array().expect("nodes");
    assert!(
        jn[0].get("translation").is_none()
            && jn[0].get("rotation").is_none()
            && jn[0].get("scale").is_none()
    );
    assert!(jn[1].get("rotation").is_some() && jn[1].get("scale").is_none());
    for k in [3, 4] {
        let node = &jn[k];
        assert!(
            node.get("translation").is_none()
                && node.get("rotation").is_none()
                && node.get("matrix").is_none()
        );
    }
    assert_eq!(jn[3]["skin"], 0);
    assert!(jn[4].get("skin").is_none());

    // The skinned body.
    let body = &asset.meshes[0];
    let mesh = nodes[3].mesh().expect("body mesh");
    let prim = mesh.primitives().next().expect("one primitive");
    assert_eq!(prim.mode(), gltf::mesh::Mode::Triangles);
    let reader = prim.reader(data);
    let positions: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
    assert_eq!(
        positions,
        body.positions
            .iter()
            .map(|p| p.to_array())
            .collect::<Vec<_>>()
    );
    let bb = prim.bounding_box();
    let (lo, hi) = body.bounds().expect("bounds");
    assert_eq!((Vec3::from(bb.min), Vec3::from(bb.max)), (lo, hi));
    let normals: Vec<[f32; 3]> = reader.read_normals().expect("normals").collect();
    let computed = body.compute_normals();
    for (n, c) in normals.iter().zip(&computed) {
        assert_close(n, &c.to_array(), "normal");
        assert!((Vec3::from(*n).length() - 1.0).abs() < EPS);
    }
    let uvs: Vec<[f32; 2]> = reader.read_tex_coords(0).expect("uvs").into_f32().collect();
    assert_eq!(
        uvs,
        body.uvs
            .as_ref()
            .expect("uvs")
            .iter()
            .map(|t| t.to_array())
            .collect::<Vec<_>>()
    );
    let indices: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
    assert_eq!(
        indices,
        body.triangles.iter().flatten().copied().collect::<Vec<_>>()
    );
    assert!(matches!(
        reader.read_indices(),
        Some(gltf::mesh::util::ReadIndices::U16(_))
    ));

    // Joints and weights against the rules, vertex by vertex.
    assert!(
        reader.read_joints(1).is_none(),
        "3 joints never need a second set"
    );
    let joints: Vec<[u16; 4]> = reader.read_joints(0).expect("joints").into_u16().collect();
    let weights: Vec<[f32; 4]> = reader
        .read_weights(0)
        .expect("weights")
        .into_f32()
        .collect();
    let skin = &asset.skins[0];
    for (v, row) in skin.influences.rows().enumerate() {
        let got: BTreeMap<u16, f32> = (0..4)
            .filter(|&k| weights[v][k] != 0.0)
            .map(|k| (joints[v][k], weights[v][k]))
            .collect();
        let expect = if v == 0 {
            // No influence: bound to the skin's root (palette index 2 = joint `root`).
            BTreeMap::from([(2, 1.0)])
        } else {
            expected_row(row, 4)
        };
        assert_eq!(
            got.keys().collect::<Vec<_>>(),
            expect.keys().collect::<Vec<_>>(),
            "vertex {v}"
        );
        for (j, w) in &expect {
            assert!(
                (got[j] - w).abs() <= EPS,
                "vertex {v} joint {j}: {} vs {w}",
                got[j]
            );
        }
        for k in 0..4 {
            if weights[v][k] == 0.0 {
                assert_eq!(joints[v][k], 0, "vertex {v}: unused slot names joint 0");
            }
        }
        assert!(
            weights[v].windows(2).all(|w| w[0] >= w[1]),
            "vertex {v} sorted"
        );
    }

    // Skin: palette, inverse bind matrices (last row exact), skeleton root.
    let gskin = doc.skins().next().expect("skin");
    assert_eq!(
        gskin.joints().map(|n| n.index()).collect::<Vec<_>>(),
        [2, 1, 0]
    );
    assert_eq!(gskin.skeleton().map(|n| n.index()), Some(0));
    let ibms: Vec<[[f32; 4]; 4]> = gskin
        .reader(data)
        .read_inverse_bind_matrices()
        .expect("ibm")
        .collect();
    for (m, want) in ibms.iter().zip(&skin.inv_bind) {
        assert_close(
            &Mat4::from_cols_array_2d(m).to_cols_array(),
            &want.to_cols_array(),
            "ibm",
        );
        assert_eq!([m[0][3], m[1][3], m[2][3], m[3][3]], [0.0, 0.0, 0.0, 1.0]);
    }

    // Morph targets: deltas, names, default weights.
    let targets: Vec<_> = reader.read_morph_targets().collect();
    assert_eq!(targets.len(), 2);
    for (t, (pos, nrm, _)) in body.morph_targets.iter().zip(targets) {
        let pos: Vec<[f32; 3]> = pos.expect("position deltas").collect();
        assert_eq!(
            pos,
            t.position_deltas
                .iter()
                .map(|d| d.to_array())
                .collect::<Vec<_>>()
        );
        let nrm: Vec<[f32; 3]> = nrm.expect("normal deltas for every target").collect();
        match &t.normal_deltas {
            Some(d) => assert_eq!(nrm, d.iter().map(|d| d.to_array()).collect::<Vec<_>>()),
            None => assert!(nrm.iter().all(|d| *d == [0.0; 3])),
        }
    }
    assert_eq!(mesh.weights(), Some(&[0.0, 0.25][..]));
    let extras: Value =
        serde_json::from_str(mesh.extras().as_ref().expect("extras").get()).expect("json");
    assert_eq!(
        extras,
        serde_json::json!({ "targetNames": ["bulge", "pinch"] })
    );
    let tgt = &json["meshes"][0]["primitives"][0]["targets"];
    assert!(tgt[0]["POSITION"].is_u64());
    let acc = &json["accessors"][tgt[1]["POSITION"].as_u64().expect("index") as usize];
    assert!(
        acc["min"].is_array() && acc["max"].is_array(),
        "morph POSITION needs bounds"
    );

    // The attached hat keeps its own normals.
    let hat = nodes[4].mesh().expect("hat");
    let hat_prim = hat.primitives().next().expect("primitive");
    let hat_normals: Vec<[f32; 3]> = hat_prim
        .reader(data)
        .read_normals()
        .expect("normals")
        .collect();
    assert_eq!(
        hat_normals,
        asset.meshes[1]
            .normals
            .as_ref()
            .expect("normals")
            .iter()
            .map(|n| n.to_array())
            .collect::<Vec<_>>()
    );
    assert!(hat_prim.reader(data).read_joints(0).is_none());

    // Animations: times exact, values equal (rotations up to normalization and sign).
    let anims: Vec<_> = doc.animations().collect();
    assert_eq!(
        anims
            .iter()
            .map(|a| a.name().unwrap_or(""))
            .collect::<Vec<_>>(),
        ["wave", "idle"]
    );
    for (anim, clip) in anims.iter().zip(&asset.clips) {
        assert_eq!(anim.channels().count(), clip.tracks.len());
        for (channel, track) in anim.channels().zip(&clip.tracks) {
            check_channel(&channel, track, &data, &nodes);
        }
    }

    // Warnings: unnormalized source rows, the one empty row; nothing dropped (3 joints < 4).
    let off_rows = skin
        .influences
        .rows()
        .filter(|r| {
            let mut m: BTreeMap<u32, f64> = BTreeMap::new();
            for i in r.iter() {
                *m.entry(i.joint).or_default() += f64::from(i.weight);
            }
            let merged_total: f64 = m.values().sum();
            let total: f64 = m
                .values()
                .filter(|&&w| w / merged_total >= f64::from(WEIGHT_EPSILON))
                .sum();
            !m.is_empty() && (total - 1.0).abs() > 1e-5
        })
        .count();
    assert!(off_rows > 100);
    assert_eq!(out.warnings.len(), 2, "{:?}", out.warnings);
    assert!(
        matches!(&out.warnings[0], Warning::WeightsRenormalized { source, rows, .. }
            if source == "mesh \"body\" (skin 0)" && *rows == off_rows),
        "{:?}",
        out.warnings[0]
    );
    assert_eq!(
        out.warnings[1].to_string(),
        "mesh \"body\" (skin 0): repaired: 1 vertex had no influence; bound with weight 1 to the skin's root joint \"root\""
    );
}

/// Checks one channel against its track.
fn check_channel<'a>(
    channel: &gltf::animation::Channel<'a>,
    track: &Track,
    data: &dyn Fn(gltf::Buffer<'a>) -> Option<&'a [u8]>,
    nodes: &[gltf::Node],
) {
    use gltf::animation::{Interpolation as I, Property};
    let target = channel.target();
    let (node, property) = match track.target {
        TrackTarget::Translation(j) => (j.get(), Property::Translation),
        TrackTarget::Rotation(j) => (j.get(), Property::Rotation),
        TrackTarget::Scale(j) => (j.get(), Property::Scale),
        TrackTarget::MorphWeights(_) => (3, Property::MorphTargetWeights),
    };
    assert_eq!(target.node().index(), node);
    assert_eq!(target.property(), property);
    assert!(nodes.len() > node);
    let sampler = channel.sampler();
    let cubic = track.interpolation == Interpolation::CubicSpline;
    let want = match track.interpolation {
        Interpolation::Linear => I::Linear,
        Interpolation::Step => I::Step,
        Interpolation::CubicSpline => I::CubicSpline,
    };
    assert_eq!(sampler.interpolation(), want);
    let reader = channel.reader(data);
    let times: Vec<f32> = reader.read_inputs().expect("inputs").collect();
    assert_eq!(times, track.times);
    let values: Vec<f32> = match reader.read_outputs().expect("outputs") {
        ReadOutputs::Translations(t) | ReadOutputs::Scales(t) => t.flatten().collect(),
        ReadOutputs::Rotations(r) => r.into_f32().flatten().collect(),
        ReadOutputs::MorphTargetWeights(w) => w.into_f32().collect(),
    };
    if property != Property::Rotation {
        assert_eq!(values, track.values);
        return;
    }
    let (stride, offset) = if cubic { (12, 4) } else { (4, 0) };
    let mut previous: Option<Vec4> = None;
    for (got, src) in values
        .chunks_exact(stride)
        .zip(track.values.chunks_exact(stride))
    {
        let q = Vec4::from_slice(&got[offset..offset + 4]);
        let s = Vec4::from_slice(&src[offset..offset + 4]);
        assert!((q.length() - 1.0).abs() <= EPS, "unit rotation {q}");
        let sign = if q.dot(s) < 0.0 { -1.0 } else { 1.0 };
        assert_close(
            &q.to_array(),
            &(s.normalize() * sign).to_array(),
            "rotation key",
        );
        if cubic {
            // Tangents copied, flipped with their value.
            assert_close(
                &got[0..4],
                &(Vec4::from_slice(&src[0..4]) * sign).to_array(),
                "in tangent",
            );
            assert_close(
                &got[8..12],
                &(Vec4::from_slice(&src[8..12]) * sign).to_array(),
                "out tangent",
            );
        }
        if let Some(p) = previous {
            assert!(p.dot(q) >= 0.0, "sign-continuous");
        }
        previous = Some(q);
    }
}

#[test]
fn gltf_split_matches_glb() {
    let asset = test_assets::rig();
    let glb_out = glb(&asset, 4);
    let split = to_gltf(&asset, &GltfOptions::default(), "rig%20data.bin").expect("export");
    assert_eq!(glb_out.warnings, split.warnings);
    let json: Value = serde_json::from_slice(&split.json).expect("json");
    assert_eq!(json["buffers"][0]["uri"], "rig%20data.bin");
    assert_eq!(json["buffers"][0]["byteLength"], split.bin.len());
    // Same document apart from the uri; the GLB's BIN chunk is the .bin.
    let mut from_glb = glb_json(&glb_out.glb);
    from_glb["buffers"][0]["uri"] = "rig%20data.bin".into();
    assert_eq!(from_glb, json);
    let json_len = u32::from_le_bytes(glb_out.glb[12..16].try_into().expect("4")) as usize;
    let bin_at = 20 + json_len;
    assert_eq!(&glb_out.glb[bin_at + 4..bin_at + 8], b"BIN\0");
    assert_eq!(&glb_out.glb[bin_at + 8..], &split.bin[..]);
    // The gltf crate reads the split form too.
    let gltf = gltf::Gltf::from_slice(&split.json).expect("gltf crate reads the json");
    assert_eq!(gltf.document.meshes().count(), 2);
}

#[test]
fn exports_are_deterministic() {
    for asset in [
        test_assets::rig(),
        test_assets::wide_rig(),
        test_assets::two_roots(),
        test_assets::big_palette(),
        test_assets::static_props(),
        test_assets::bones_only(),
    ] {
        let a = glb(&asset, 8);
        let b = glb(&asset.clone(), 8);
        assert_eq!(a.glb, b.glb, "{}", asset.name);
        let c = to_gltf(&asset, &GltfOptions::default(), "x.bin").expect("export");
        let d = to_gltf(&asset, &GltfOptions::default(), "x.bin").expect("export");
        assert_eq!((c.json, c.bin), (d.json, d.bin), "{}", asset.name);
    }
}

#[test]
fn buffer_layout_follows_the_rules() {
    for asset in [
        test_assets::rig(),
        test_assets::big_palette(),
        test_assets::wide_rig(),
        test_assets::static_props(),
    ] {
        let out = glb(&asset, 8);
        let json = glb_json(&out.glb);
        let views = json["bufferViews"].as_array().expect("views");
        let accessors = json["accessors"].as_array().expect("accessors");
        // Which accessors are vertex data, indices, or other (IBM, animation).
        let mut role: BTreeMap<u64, &str> = BTreeMap::new();
        for mesh in json["meshes"].as_array().expect("meshes") {
            for prim in mesh["primitives"].as_array().expect("primitives") {
                for (_, a) in prim["attributes"].as_object().expect("attributes") {
                    role.insert(a.as_u64().expect("index"), "vertex");
                }
                for t in prim["targets"].as_array().into_iter().flatten() {
                    for (_, a) in t.as_object().expect("target") {
                        role.insert(a.as_u64().expect("index"), "vertex");
                    }
                }
                role.insert(prim["indices"].as_u64().expect("indices"), "index");
            }
        }
        for skin in json["skins"].as_array().into_iter().flatten() {
            role.insert(skin["inverseBindMatrices"].as_u64().expect("ibm"), "other");
        }
        for anim in json["animations"].as_array().into_iter().flatten() {
            for s in anim["samplers"].as_array().expect("samplers") {
                role.insert(s["input"].as_u64().expect("input"), "other");
                role.insert(s["output"].as_u64().expect("output"), "other");
            }
        }
        assert_eq!(
            role.len(),
            accessors.len(),
            "{}: every accessor used",
            asset.name
        );
        assert_eq!(views.len(), accessors.len(), "one view per accessor");
        for (i, acc) in accessors.iter().enumerate() {
            assert!(acc.get("byteOffset").is_none());
            let view = &views[acc["bufferView"].as_u64().expect("view") as usize];
            assert_eq!(view["byteOffset"].as_u64().unwrap_or(0) % 4, 0);
            assert!(view.get("byteStride").is_none());
            let target = view.get("target").and_then(Value::as_u64);
            match role[&(i as u64)] {
                "vertex" => assert_eq!(target, Some(34962)),
                "index" => assert_eq!(target, Some(34963)),
                _ => assert_eq!(target, None),
            }
        }
        // Chunk padding: JSON with spaces, lengths multiples of 4.
        let json_len = u32::from_le_bytes(out.glb[12..16].try_into().expect("4")) as usize;
        assert_eq!(json_len % 4, 0);
        assert_eq!(out.glb.len() % 4, 0);
        let bin_len =
            u32::from_le_bytes(out.glb[20 + json_len..24 + json_len].try_into().expect("4"));
        assert_eq!(json["buffers"][0]["byteLength"], bin_len);
    }
}

#[test]
fn invalid_assets_and_options_are_rejected() {
    let mut asset = test_assets::rig();
    asset.meshes[0].triangles[5] = [0, 1, 999];
    asset.skins[0].inv_bind.pop();
    asset.meshes[1].morph_weights = vec![1.0];
    asset.skins.push(asset.skins[0].clone());
    let err = to_glb(&asset, &GltfOptions::default()).unwrap_err();
    let ExportError::Invalid { problems } = &err else {
        panic!("expected Invalid, got {err:?}");
    };
    assert!(
        problems.contains(&Problem::Asset(AssetError::TriangleIndex {
            mesh: 0,
            triangle: 5,
            vertex: 999,
            count: 200
        }))
    );
    assert!(problems.contains(&Problem::MorphWeightCount {
        mesh: 1,
        found: 1,
        expected: 0
    }));
    assert!(problems.contains(&Problem::SharedSkinMesh {
        mesh: 0,
        first_skin: 0,
        second_skin: 1
    }));
    assert!(problems
        .iter()
        .any(|p| matches!(p, Problem::Asset(AssetError::BadReference { .. }))));
    assert!(
        err.to_string()
            .starts_with("the asset cannot be exported: "),
        "{err}"
    );

    let mut asset = test_assets::rig();
    asset.skins[0].joints[1] = JointIndex(2);
    asset.clips[0].tracks[1].values[4..8].copy_from_slice(&[0.0; 4]);
    asset.meshes[0].morph_targets[0].normal_deltas = Some(vec![Vec3::ZERO; 3]);
    let ExportError::Invalid { problems } = to_glb(&asset, &GltfOptions::default()).unwrap_err()
    else {
        panic!("expected Invalid");
    };
    assert_eq!(
        problems,
        [
            Problem::Asset(AssetError::AttributeLength {
                mesh: 0,
                attribute: "morph target normals",
                found: 3,
                expected: 200
            }),
            Problem::DuplicatePaletteJoint {
                skin: 0,
                joint: JointIndex(2)
            },
            Problem::DegenerateRotationKey {
                clip: "wave".into(),
                track: 1,
                key: 1
            },
        ]
    );

    let mut empty = test_assets::rig();
    empty.meshes[1].triangles.clear();
    empty.skins[0].joints.clear();
    empty.skins[0].inv_bind.clear();
    empty.skins[0].influences = Influences::from_rows(vec![Vec::<Influence>::new(); 200]);
    let ExportError::Invalid { problems } = to_glb(&empty, &GltfOptions::default()).unwrap_err()
    else {
        panic!("expected Invalid");
    };
    assert_eq!(
        problems,
        [
            Problem::EmptyMesh {
                mesh: 1,
                vertices: 24,
                triangles: 0
            },
            Problem::EmptyPalette { skin: 0 }
        ]
    );

    for max_influences in [0, 9] {
        let err = to_glb(
            &test_assets::rig(),
            &GltfOptions {
                max_influences,
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(
            matches!(err, ExportError::MaxInfluences { max_influences: m } if m == max_influences)
        );
    }
}

/// Prints why a test is skipped, or fails when the environment variable `CI` is set.
fn skip_or_fail(why: &str) {
    if std::env::var("CI").is_ok_and(|v| !v.is_empty()) {
        panic!("{why}");
    }
    println!("SKIPPED: {why}");
}

/// Khronos glTF-Validator's JSON report on a GLB (tools/validate_gltf.mjs); `None` when node
/// or the validator is missing (`bash tools/setup.sh` installs it).
fn khronos_report(glb: &[u8]) -> Option<Value> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    if !root.join("tools/node_modules/gltf-validator").exists() {
        skip_or_fail("glTF-Validator is not installed in tools/node_modules");
        return None;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("constant.glb");
    std::fs::write(&file, glb).expect("write");
    let out = match std::process::Command::new("node")
        .arg(root.join("tools/validate_gltf.mjs"))
        .arg("--json")
        .arg(&file)
        .output()
    {
        Ok(out) => out,
        Err(e) => {
            skip_or_fail(&format!("cannot run node: {e}"));
            return None;
        }
    };
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().next().unwrap_or_else(|| {
        panic!(
            "validator printed nothing: {}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    Some(serde_json::from_str(line).expect("validator JSON"))
}

fn assert_khronos_valid(glb: &[u8]) {
    if let Some(report) = khronos_report(glb) {
        assert_eq!(
            (report["errors"].as_u64(), report["warnings"].as_u64()),
            (Some(0), Some(0)),
            "{:#}",
            report["messages"]
        );
    }
}

#[test]
fn exported_samples_still_validate() {
    for asset in [
        test_assets::rig(),
        test_assets::two_roots(),
        test_assets::static_props(),
    ] {
        assert_khronos_valid(&glb(&asset, 4).glb);
    }
}
