//! Skin influences: more than four per vertex, palettes that need an extra root or
//! `UNSIGNED_SHORT` joints, and unskinned meshes.

//! Round trips through an independent reader (the `gltf` crate), layout rules read from the
//! JSON, determinism and atomic writing.

use std::collections::BTreeMap;

use rigport_model::glam::Mat4;
use rigport_model::{Influence, Warning};

use super::*;
use crate::test_assets;

#[test]
fn eight_influences_use_a_second_set_and_four_report_drops() {
    let asset = test_assets::wide_rig();
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
    let out = glb(&test_assets::two_roots(), 4);
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
    let json = glb_json(&glb(&test_assets::wide_rig(), 4).glb);
    assert_eq!(json["skins"][0]["skeleton"], 0);
    assert!(json["nodes"]
        .as_array()
        .expect("nodes")
        .iter()
        .all(|n| n["name"] != "rigport_root"));
}

#[test]
fn large_palettes_use_unsigned_short_joints() {
    let asset = test_assets::big_palette();
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
    let (doc, _) = import(&glb(&test_assets::rig(), 4).glb);
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
fn unskinned_meshes_sit_at_the_root_and_large_ones_use_u32_indices() {
    let asset = test_assets::static_props();
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
