//! Round trips through an independent reader (the `gltf` crate), layout rules read from the
//! JSON, determinism and atomic writing.

use std::collections::BTreeMap;
use std::path::Path;

use gltf::animation::util::ReadOutputs;
use rigport_model::conventions::WEIGHT_EPSILON;
use rigport_model::glam::{Mat4, Vec3, Vec4};
use rigport_model::{
    Asset, AssetError, Influence, Influences, Interpolation, JointIndex, MeshIndex, Track,
    TrackTarget, Warning,
};
use serde_json::Value;

use super::*;
use crate::sample;
use crate::Problem;

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
    to_glb(asset, &GltfOptions { max_influences }).expect("export")
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
    let asset = sample::rig();
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
    let asset = sample::rig();
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
        sample::rig(),
        sample::wide_rig(),
        sample::two_roots(),
        sample::big_palette(),
        sample::static_props(),
        sample::bones_only(),
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
        sample::rig(),
        sample::big_palette(),
        sample::wide_rig(),
        sample::static_props(),
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
fn eight_influences_use_a_second_set_and_four_report_drops() {
    let asset = sample::wide_rig();
    let skin = &asset.skins[0];
    let rows: Vec<&[Influence]> = skin.influences.rows().collect();

    let out8 = glb(&asset, 8);
    let (doc, buffers) = import(&out8.glb);
    let data = |b: gltf::Buffer| Some(&*buffers[b.index()]);
    let prim = doc
        .meshes()
        .next()
        .expect("mesh")
        .primitives()
        .next()
        .expect("primitive");
    let reader = prim.reader(data);
    let j0: Vec<[u16; 4]> = reader.read_joints(0).expect("set 0").into_u16().collect();
    let j1: Vec<[u16; 4]> = reader.read_joints(1).expect("set 1").into_u16().collect();
    let w0: Vec<[f32; 4]> = reader.read_weights(0).expect("set 0").into_f32().collect();
    let w1: Vec<[f32; 4]> = reader.read_weights(1).expect("set 1").into_f32().collect();
    for v in 1..rows.len() {
        let got: BTreeMap<u16, f32> = (0..8)
            .map(|k| {
                if k < 4 {
                    (j0[v][k], w0[v][k])
                } else {
                    (j1[v][k - 4], w1[v][k - 4])
                }
            })
            .filter(|&(_, w)| w != 0.0)
            .collect();
        let expect = expected_row(rows[v], 8);
        assert_eq!(got.len(), expect.len(), "vertex {v}");
        for (j, w) in &expect {
            assert!((got[j] - w).abs() <= EPS, "vertex {v}");
        }
        // Set 0 holds the 4 largest.
        let min0 = w0[v]
            .iter()
            .copied()
            .filter(|&w| w != 0.0)
            .fold(f32::INFINITY, f32::min);
        assert!(w1[v].iter().all(|&w| w <= min0));
    }
    assert!(!out8
        .warnings
        .iter()
        .any(|w| matches!(w, Warning::InfluencesDropped { .. })));

    let out4 = glb(&asset, 4);
    let limited = rows.iter().filter(|r| r.len() > 4).count();
    let dropped: Vec<_> = out4
        .warnings
        .iter()
        .filter_map(|w| match w {
            Warning::InfluencesDropped {
                mesh,
                max_influences,
                vertices,
                max_dropped_weight,
            } => Some((
                mesh.clone(),
                *max_influences,
                *vertices,
                *max_dropped_weight,
            )),
            _ => None,
        })
        .collect();
    assert_eq!(dropped.len(), 1, "one warning per mesh");
    assert_eq!(
        (dropped[0].0.as_str(), dropped[0].1, dropped[0].2),
        ("body", 4, limited)
    );
    let largest = rows
        .iter()
        .filter(|r| r.len() > 4)
        .map(|r| {
            let total: f64 = r.iter().map(|i| f64::from(i.weight)).sum();
            let mut w: Vec<f64> = r.iter().map(|i| f64::from(i.weight)).collect();
            w.sort_by(|a, b| b.total_cmp(a));
            (w[4] / total) as f32
        })
        .fold(0.0, f32::max);
    assert_eq!(dropped[0].3, largest);
    let (doc, _) = import(&out4.glb);
    let prim = doc
        .meshes()
        .next()
        .expect("mesh")
        .primitives()
        .next()
        .expect("primitive");
    assert!(prim.get(&gltf::Semantic::Joints(1)).is_none());
}

#[test]
fn disjoint_palette_gets_an_extra_root() {
    let out = glb(&sample::two_roots(), 4);
    let (doc, _) = import(&out.glb);
    let root = doc.nodes().nth(4).expect("extra root");
    assert_eq!(root.name(), Some("rigport_root"));
    assert_eq!(root.transform().matrix(), Mat4::IDENTITY.to_cols_array_2d());
    assert_eq!(
        root.children().map(|c| c.index()).collect::<Vec<_>>(),
        [0, 2]
    );
    let scene = doc.default_scene().expect("scene");
    assert_eq!(scene.nodes().map(|n| n.index()).collect::<Vec<_>>(), [4, 5]);
    let skin = doc.skins().next().expect("skin");
    assert_eq!(skin.skeleton().map(|n| n.index()), Some(4));
    // A palette under one root needs none, and its skeleton is the nearest common ancestor.
    let json = glb_json(&glb(&sample::wide_rig(), 4).glb);
    assert_eq!(json["skins"][0]["skeleton"], 0);
    assert!(json["nodes"]
        .as_array()
        .expect("nodes")
        .iter()
        .all(|n| n["name"] != "rigport_root"));
}

#[test]
fn large_palettes_use_unsigned_short_joints() {
    let asset = sample::big_palette();
    let out = glb(&asset, 4);
    let (doc, buffers) = import(&out.glb);
    let data = |b: gltf::Buffer| Some(&*buffers[b.index()]);
    let prim = doc
        .meshes()
        .next()
        .expect("mesh")
        .primitives()
        .next()
        .expect("primitive");
    assert_eq!(
        prim.get(&gltf::Semantic::Joints(0))
            .expect("joints")
            .data_type(),
        gltf::accessor::DataType::U16
    );
    let joints: Vec<[u16; 4]> = prim
        .reader(data)
        .read_joints(0)
        .expect("joints")
        .into_u16()
        .collect();
    assert_eq!(
        joints[0],
        [299, 0, 0, 0],
        "v0: 299 (0.75) then 0 (0.25): joint 0 second"
    );
    assert_eq!(joints[1], [298, 7, 0, 0]);
    // The small rig's palette fits in bytes.
    let (doc, _) = import(&glb(&sample::rig(), 4).glb);
    let prim = doc
        .meshes()
        .next()
        .expect("mesh")
        .primitives()
        .next()
        .expect("primitive");
    assert_eq!(
        prim.get(&gltf::Semantic::Joints(0))
            .expect("joints")
            .data_type(),
        gltf::accessor::DataType::U8
    );
}

#[test]
fn tracks_gltf_cannot_hold_are_dropped_with_warnings() {
    let mut asset = sample::rig();
    let clip = &mut asset.clips[0];
    let morph_on_hat = Track {
        target: TrackTarget::MorphWeights(MeshIndex(1)),
        interpolation: Interpolation::Linear,
        times: vec![0.0],
        values: vec![1.0],
    };
    let wrong_count = Track {
        target: TrackTarget::MorphWeights(MeshIndex(0)),
        interpolation: Interpolation::Linear,
        times: vec![0.0],
        values: vec![1.0, 0.0, 0.0],
    };
    let duplicate = clip.tracks[0].clone();
    clip.tracks.extend([morph_on_hat, wrong_count, duplicate]);
    let mut one_key_cubic = clip.tracks[3].clone();
    one_key_cubic.times.truncate(1);
    one_key_cubic.values.truncate(12);
    asset.clips[1].tracks[0] = Track {
        target: TrackTarget::Rotation(JointIndex(1)),
        ..one_key_cubic
    };
    asset.clips.push(rigport_model::Clip {
        name: "empty".into(),
        tracks: Vec::new(),
    });
    let out = glb(&asset, 4);
    let messages: Vec<String> = out.warnings.iter().map(ToString::to_string).collect();
    let has = |s: &str| messages.iter().any(|m| m.contains(s));
    assert!(
        has("clip \"wave\" track 5: repaired: track dropped: mesh \"hat\" has no morph targets"),
        "{messages:#?}"
    );
    assert!(has(
        "clip \"wave\" track 6: repaired: track dropped: 3 weights per key for the 2 morph targets"
    ));
    assert!(has(
        "clip \"wave\" track 7: repaired: track dropped: an earlier track"
    ));
    assert!(has(
        "clip \"idle\" track 0: one-key cubic spline written as STEP"
    ));
    assert!(has(
        "clip \"empty\": repaired: clip has no exportable track"
    ));
    let (doc, buffers) = import(&out.glb);
    let data = |b: gltf::Buffer| Some(&*buffers[b.index()]);
    assert_eq!(doc.animations().count(), 2);
    let idle = doc.animations().nth(1).expect("idle");
    let ch = idle.channels().next().expect("channel");
    assert_eq!(
        ch.sampler().interpolation(),
        gltf::animation::Interpolation::Step
    );
    let ReadOutputs::Rotations(r) = ch.reader(data).read_outputs().expect("outputs") else {
        panic!("rotation outputs expected");
    };
    let r: Vec<[f32; 4]> = r.into_f32().collect();
    assert_eq!(r, [rigport_model::glam::Quat::IDENTITY.to_array()]);
}

#[test]
fn invalid_assets_and_options_are_rejected() {
    let mut asset = sample::rig();
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

    let mut asset = sample::rig();
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

    let mut empty = sample::rig();
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
        let err = to_glb(&sample::rig(), &GltfOptions { max_influences }).unwrap_err();
        assert!(
            matches!(err, ExportError::MaxInfluences { max_influences: m } if m == max_influences)
        );
    }
}

fn dir_names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("read dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn write_gltf_is_atomic_and_leaves_nothing_on_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let asset = sample::rig();
    let opts = GltfOptions::default();

    let mut bad = asset.clone();
    bad.meshes[0].positions[3].x = f32::NAN;
    for name in ["bad.glb", "bad.gltf", "bad.GLTF"] {
        let err = write_gltf(&bad, &dir.path().join(name), &opts).unwrap_err();
        assert!(matches!(err, ExportError::Invalid { .. }), "{err:?}");
    }
    let err = write_gltf(&asset, &dir.path().join("rig.obj"), &opts).unwrap_err();
    assert!(matches!(err, ExportError::UnsupportedExtension { .. }));
    let err = write_gltf(&asset, &dir.path().join("rig"), &opts).unwrap_err();
    assert!(matches!(err, ExportError::UnsupportedExtension { .. }));
    assert_eq!(
        dir_names(dir.path()),
        Vec::<String>::new(),
        "no file after failures"
    );

    let warnings = write_gltf(&asset, &dir.path().join("my rig.gltf"), &opts).expect("gltf");
    let w2 = write_gltf(&asset, &dir.path().join("rig.glb"), &opts).expect("glb");
    assert_eq!(warnings, w2);
    assert_eq!(
        dir_names(dir.path()),
        ["my rig.bin", "my rig.gltf", "rig.glb"]
    );
    let json: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("my rig.gltf")).expect("read"))
            .expect("json");
    assert_eq!(json["buffers"][0]["uri"], "my%20rig.bin");
    assert_eq!(
        std::fs::read(dir.path().join("rig.glb")).expect("read"),
        glb(&asset, 4).glb
    );
    // Overwriting keeps the directory clean; a failure leaves the previous files intact.
    write_gltf(&asset, &dir.path().join("rig.glb"), &opts).expect("overwrite");
    assert!(write_gltf(&bad, &dir.path().join("rig.glb"), &opts).is_err());
    assert_eq!(
        std::fs::read(dir.path().join("rig.glb")).expect("read"),
        glb(&asset, 4).glb
    );
    assert_eq!(
        dir_names(dir.path()),
        ["my rig.bin", "my rig.gltf", "rig.glb"]
    );

    // Prepared exports write nothing until asked.
    let prepared = prepare_gltf(&asset, &dir.path().join("later.gltf"), &opts).expect("prepare");
    assert_eq!(prepared.warnings(), &warnings[..]);
    assert_eq!(prepared.path(), dir.path().join("later.gltf"));
    assert_eq!(
        dir_names(dir.path()),
        ["my rig.bin", "my rig.gltf", "rig.glb"]
    );
    prepared.write().expect("write");
    assert_eq!(
        dir_names(dir.path()),
        [
            "later.bin",
            "later.gltf",
            "my rig.bin",
            "my rig.gltf",
            "rig.glb"
        ]
    );
    std::fs::remove_file(dir.path().join("later.bin")).expect("rm");
    std::fs::remove_file(dir.path().join("later.gltf")).expect("rm");

    // An unwritable target (a directory in the way) is an Io error and leaves no temp files.
    std::fs::create_dir(dir.path().join("taken.gltf")).expect("mkdir");
    std::fs::write(dir.path().join("taken.gltf").join("x"), b"x").expect("write");
    let err = write_gltf(&asset, &dir.path().join("taken.gltf"), &opts).unwrap_err();
    assert!(
        matches!(&err, ExportError::Io { path, .. } if path.ends_with("taken.gltf")),
        "{err:?}"
    );
    assert_eq!(
        dir_names(dir.path()),
        ["my rig.bin", "my rig.gltf", "rig.glb", "taken.gltf"]
    );
}

#[test]
fn percent_encoding_keeps_safe_characters() {
    assert_eq!(percent_encode("walk_01-a.bin"), "walk_01-a.bin");
    assert_eq!(percent_encode("my rig#2?.bin"), "my%20rig%232%3F.bin");
    assert_eq!(percent_encode("c:ü%.bin"), "c%3A%C3%BC%25.bin");
}

#[test]
fn an_asset_without_binary_data_has_no_buffer() {
    let asset = sample::bones_only();
    let split = to_gltf(&asset, &GltfOptions::default(), "x.bin").expect("export");
    assert!(split.bin.is_empty());
    let json: Value = serde_json::from_slice(&split.json).expect("json");
    assert!(json.get("buffers").is_none());
    let out = to_glb(&asset, &GltfOptions::default()).expect("export");
    assert_eq!(
        out.glb.len(),
        20 + u32::from_le_bytes(out.glb[12..16].try_into().expect("4")) as usize
    );
    let dir = tempfile::tempdir().expect("tempdir");
    write_gltf(
        &asset,
        &dir.path().join("bones.gltf"),
        &GltfOptions::default(),
    )
    .expect("write");
    assert_eq!(dir_names(dir.path()), ["bones.gltf"]);
    import(&out.glb);
}

#[test]
fn unskinned_meshes_sit_at_the_root_and_large_ones_use_u32_indices() {
    let asset = sample::static_props();
    let out = glb(&asset, 4);
    assert!(out.warnings.is_empty(), "{:?}", out.warnings);
    let (doc, buffers) = import(&out.glb);
    let data = |b: gltf::Buffer| Some(&*buffers[b.index()]);
    let scene = doc.default_scene().expect("scene");
    assert_eq!(scene.nodes().map(|n| n.index()).collect::<Vec<_>>(), [0, 1]);
    let grid = doc
        .meshes()
        .next()
        .expect("grid")
        .primitives()
        .next()
        .expect("primitive");
    let reader = grid.reader(data);
    assert!(matches!(
        reader.read_indices(),
        Some(gltf::mesh::util::ReadIndices::U32(_))
    ));
    let indices: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
    assert_eq!(
        indices,
        asset.meshes[0]
            .triangles
            .iter()
            .flatten()
            .copied()
            .collect::<Vec<_>>()
    );
    let anim = doc.animations().next().expect("animation");
    let channel = anim.channels().next().expect("channel");
    assert_eq!(channel.target().node().index(), 1);
    assert_eq!(
        channel.target().property(),
        gltf::animation::Property::MorphTargetWeights
    );
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

fn keys(n: usize, step: f32) -> Vec<f32> {
    (0..n).map(|k| k as f32 * step).collect()
}

fn repeat(value: &[f32], n: usize) -> Vec<f32> {
    value.repeat(n)
}

/// One channel as read back: (node, property, interpolation, times, flat outputs).
type ReadChannel = (
    usize,
    gltf::animation::Property,
    gltf::animation::Interpolation,
    Vec<f32>,
    Vec<f32>,
);

fn read_channels(glb: &[u8], animation: usize) -> Vec<ReadChannel> {
    let (doc, buffers) = import(glb);
    let data = |b: gltf::Buffer| Some(&*buffers[b.index()]);
    let anim = doc.animations().nth(animation).expect("animation");
    anim.channels()
        .map(|ch| {
            let reader = ch.reader(data);
            let times: Vec<f32> = reader.read_inputs().expect("inputs").collect();
            let values: Vec<f32> = match reader.read_outputs().expect("outputs") {
                ReadOutputs::Translations(t) | ReadOutputs::Scales(t) => t.flatten().collect(),
                ReadOutputs::Rotations(r) => r.into_f32().flatten().collect(),
                ReadOutputs::MorphTargetWeights(w) => w.into_f32().collect(),
            };
            (
                ch.target().node().index(),
                ch.target().property(),
                ch.sampler().interpolation(),
                times,
                values,
            )
        })
        .collect()
}

#[test]
fn constant_tracks_are_dropped_at_rest_and_reduced_to_two_keys_elsewhere() {
    use gltf::animation::{Interpolation as I, Property as P};
    use rigport_model::glam::Quat;
    let mut asset = sample::rig();
    let rest_rot = asset.skeleton.joints()[1].rest_local.rotation;
    let t5 = keys(5, 0.25);
    let track = |target, interpolation, times: &[f32], values: Vec<f32>| Track {
        target,
        interpolation,
        times: times.to_vec(),
        values,
    };
    let tip_rest = asset.skeleton.joints()[2].rest_local.translation;
    asset.clips = vec![rigport_model::Clip {
        name: "still".into(),
        tracks: vec![
            // 0: joint 1's rest translation: dropped.
            track(
                TrackTarget::Translation(JointIndex(1)),
                Interpolation::Linear,
                &t5,
                repeat(&[0.0, 1.0, 0.0], 5),
            ),
            // 1: joint 1's rest rotation, stored as q, -q and 2q: dropped.
            track(
                TrackTarget::Rotation(JointIndex(1)),
                Interpolation::Linear,
                &t5,
                [1.0f32, -1.0, 2.0, 1.0, -2.0]
                    .iter()
                    .flat_map(|s| (rest_rot * *s).to_array())
                    .collect(),
            ),
            // 2: constant 1.5 scale (one key off by 1e-7 relative): two STEP keys.
            track(
                TrackTarget::Scale(JointIndex(2)),
                Interpolation::Step,
                &t5,
                [
                    repeat(&[1.5; 3], 3),
                    vec![1.5, 1.5 * (1.0 + 1e-7), 1.5],
                    repeat(&[1.5; 3], 1),
                ]
                .concat(),
            ),
            // 3: varying rotation: written as it is.
            track(
                TrackTarget::Rotation(JointIndex(0)),
                Interpolation::Linear,
                &t5,
                (0..5)
                    .flat_map(|k| Quat::from_rotation_y(0.3 * k as f32).to_array())
                    .collect(),
            ),
            // 4: the mesh's default morph weights [0, 0.25]: dropped.
            track(
                TrackTarget::MorphWeights(MeshIndex(0)),
                Interpolation::Linear,
                &t5,
                repeat(&[0.0, 0.25], 5),
            ),
            // 5: constant cubic spline with zero tangents, not at rest: two cubic keys.
            track(
                TrackTarget::Translation(JointIndex(0)),
                Interpolation::CubicSpline,
                &[0.0, 0.5, 1.0],
                repeat(&[0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0], 3),
            ),
            // 6: 2e-6 (relative) from joint 2's rest translation: not at rest, two keys.
            track(
                TrackTarget::Translation(JointIndex(2)),
                Interpolation::Linear,
                &t5,
                repeat(&(tip_rest * (1.0 + 2e-6)).to_array(), 5),
            ),
            // 7: 1e-7 (relative) from joint 0's unit scale: at rest, dropped.
            track(
                TrackTarget::Scale(JointIndex(0)),
                Interpolation::Linear,
                &t5,
                repeat(&[1.0 + 1e-7; 3], 5),
            ),
            // 8: joint 2's rest rotation (identity) turned by 2e-3 rad (|dot| = 1 - 5e-7):
            // not at rest, two keys.
            track(
                TrackTarget::Rotation(JointIndex(2)),
                Interpolation::Linear,
                &t5,
                repeat(&Quat::from_rotation_x(2e-3).to_array(), 5),
            ),
        ],
    }];
    let out = glb(&asset, 4);
    assert_eq!(
        out.warnings,
        glb(&sample::rig(), 4).warnings,
        "dropping constant tracks is lossless: no new warning"
    );
    let channels = read_channels(&out.glb, 0);
    let summary: Vec<(usize, P, I, Vec<f32>)> = channels
        .iter()
        .map(|(n, p, i, t, _)| (*n, *p, *i, t.clone()))
        .collect();
    assert_eq!(
        summary,
        [
            (2, P::Scale, I::Step, vec![0.0, 1.0]),
            (0, P::Rotation, I::Linear, t5.clone()),
            (0, P::Translation, I::CubicSpline, vec![0.0, 1.0]),
            (2, P::Translation, I::Linear, vec![0.0, 1.0]),
            (2, P::Rotation, I::Linear, vec![0.0, 1.0]),
        ]
    );
    assert_eq!(channels[0].4, repeat(&[1.5; 3], 2));
    assert_close(
        &channels[1].4,
        &asset.clips[0].tracks[3].values,
        "varying rotation",
    );
    assert_eq!(
        channels[2].4,
        repeat(&[0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0], 2)
    );
    assert_eq!(
        channels[3].4,
        repeat(&(tip_rest * (1.0 + 2e-6)).to_array(), 2)
    );
    assert_close(
        &channels[4].4,
        &repeat(&Quat::from_rotation_x(2e-3).to_array(), 2),
        "constant rotation",
    );
    assert_khronos_valid(&out.glb);
}

#[test]
fn an_animation_keeps_its_clip_duration_when_tracks_are_dropped() {
    use gltf::animation::{Interpolation as I, Property as P};
    use rigport_model::glam::Quat;
    let mut asset = sample::rig();
    let rest_rot = asset.skeleton.joints()[1].rest_local.rotation.to_array();
    let at_rest = |target, times: Vec<f32>, value: &[f32]| Track {
        target,
        interpolation: Interpolation::Linear,
        values: repeat(value, times.len()),
        times,
    };
    asset.clips = vec![
        rigport_model::Clip {
            name: "rest_only".into(),
            tracks: vec![
                at_rest(
                    TrackTarget::Rotation(JointIndex(1)),
                    vec![0.0, 0.5, 2.0],
                    &rest_rot,
                ),
                at_rest(
                    TrackTarget::Translation(JointIndex(1)),
                    vec![0.0, 0.5, 2.0],
                    &[0.0, 1.0, 0.0],
                ),
            ],
        },
        rigport_model::Clip {
            name: "short_motion".into(),
            tracks: vec![
                Track {
                    target: TrackTarget::Rotation(JointIndex(0)),
                    interpolation: Interpolation::Linear,
                    times: vec![0.5, 1.0],
                    values: [Quat::IDENTITY, Quat::from_rotation_y(1.0)]
                        .iter()
                        .flat_map(|q| q.to_array())
                        .collect(),
                },
                at_rest(TrackTarget::Scale(JointIndex(1)), keys(3, 1.0), &[1.0; 3]),
                at_rest(
                    TrackTarget::Scale(JointIndex(2)),
                    vec![1.0, 2.0, 3.0],
                    &[1.0; 3],
                ),
                at_rest(TrackTarget::Scale(JointIndex(0)), keys(5, 0.5), &[1.0; 3]),
                at_rest(
                    TrackTarget::Translation(JointIndex(2)),
                    vec![0.25, 3.0],
                    &[0.0, 1.0, 0.0],
                ),
            ],
        },
    ];
    let out = glb(&asset, 4);
    assert!(
        !out.warnings.iter().any(|w| w.to_string().contains("clip")),
        "{:?}",
        out.warnings
    );
    let json = glb_json(&out.glb);
    assert_eq!(json["animations"].as_array().expect("animations").len(), 2);

    // Every track at rest: the first stays, with its first and last key.
    let rest_only = read_channels(&out.glb, 0);
    assert_eq!(rest_only.len(), 1);
    let (node, property, interpolation, times, values) = &rest_only[0];
    assert_eq!(
        (*node, *property, *interpolation),
        (1, P::Rotation, I::Linear)
    );
    assert_eq!(times, &[0.0, 2.0]);
    assert_close(values, &repeat(&rest_rot, 2), "rest rotation");

    // The motion ends at 1 s, the clip at 3 s and starts at 0: the first at-rest track
    // reaching 3 s (scale of joint 2; not the later translation) and then the first
    // reaching 0 (scale of joint 1) stay, with two keys each.
    let short = read_channels(&out.glb, 1);
    let summary: Vec<(usize, P, Vec<f32>)> = short
        .iter()
        .map(|(n, p, _, t, _)| (*n, *p, t.clone()))
        .collect();
    assert_eq!(
        summary,
        [
            (0, P::Rotation, vec![0.5, 1.0]),
            (1, P::Scale, vec![0.0, 2.0]),
            (2, P::Scale, vec![1.0, 3.0]),
        ]
    );
    for (anim, clip) in json["animations"]
        .as_array()
        .expect("animations")
        .iter()
        .zip(&asset.clips)
    {
        let inputs = anim["samplers"]
            .as_array()
            .expect("samplers")
            .iter()
            .map(|s| &json["accessors"][s["input"].as_u64().expect("input") as usize]);
        let (lo, hi) = inputs.fold((f64::INFINITY, 0.0f64), |(lo, hi), acc| {
            (
                lo.min(acc["min"][0].as_f64().expect("min")),
                hi.max(acc["max"][0].as_f64().expect("max")),
            )
        });
        assert_eq!((lo, hi as f32), (0.0, clip.duration()), "{}", clip.name);
    }
    assert_khronos_valid(&out.glb);
}

#[test]
fn exported_samples_still_validate() {
    for asset in [sample::rig(), sample::two_roots(), sample::static_props()] {
        assert_khronos_valid(&glb(&asset, 4).glb);
    }
}

#[cfg(unix)]
#[test]
fn symlinked_gltf_is_refused_and_a_bin_directory_too() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("model.gltf"), b"old").expect("write");
    let link = dir.path().join("link.gltf");
    std::os::unix::fs::symlink("model.gltf", &link).expect("symlink");
    let err = write_gltf(&sample::rig(), &link, &GltfOptions::default()).unwrap_err();
    assert!(matches!(err, ExportError::Io { .. }), "{err:?}");
    assert_eq!(dir_names(dir.path()), ["link.gltf", "model.gltf"]);
    assert_eq!(
        std::fs::read(dir.path().join("model.gltf")).expect("read"),
        b"old"
    );
    // A directory where the .bin goes is refused before anything is written.
    std::fs::create_dir(dir.path().join("x.bin")).expect("mkdir");
    let err = write_gltf(
        &sample::rig(),
        &dir.path().join("x.gltf"),
        &GltfOptions::default(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("x.bin"), "{err}");
    assert_eq!(dir_names(dir.path()), ["link.gltf", "model.gltf", "x.bin"]);
}
