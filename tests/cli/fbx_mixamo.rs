//! Mixamo conventions (issue 29) on a Mixamo-like character made with Blender's exporter
//! (tools/blender/mixamo.py: the 65 `mixamorig:` bones, ~20k vertices, centimetres, +Y up,
//! one clip; and the same armature and clip with no mesh, as Mixamo's animation-only
//! downloads): the `.glb` stands at its height in the file's unit times metres per unit
//! (1.5-2 m), keeps the `mixamorig:` names, and the animation-only file retargets onto the
//! corpus's Pinocchio `human_model1` with both legs, both arms, the spine and the head
//! mapped and its feet planted. The corpus has no Mixamo file. Skips without bpy
//! (tests/cli/fbx_blender.rs).

use std::path::Path;

use crate::common::*;
use crate::fbx::{glb_height, source_height};
use crate::fbx_blender::{blender_python, make_fbx};

const HUMAN_MODEL1: &str = "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1";

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn mixamo_character_stands_at_human_height_with_its_names() {
    let Some(bpy) = blender_python() else {
        return;
    };
    let dir = scratch();
    let fbx = &make_fbx(&bpy, dir.path(), &["mixamo"])[0];
    let glb = dir.path().join("mixamo.glb");
    rigport_ok(&["convert", "-q", s(fbx), "-o", s(&glb)]);
    assert_valid(&glb);
    let (height, meters_per_unit) = source_height(fbx);
    assert!(
        (meters_per_unit - 0.01).abs() < 1e-12,
        "Mixamo files are centimetres"
    );
    let expected = height * meters_per_unit;
    let got = glb_height(&glb);
    eprintln!("mixamo: {height} cm in the file, {got} m in the glb");
    assert!(
        ((got - expected) / expected).abs() < 1e-5,
        "{got} vs {expected}"
    );
    assert!((1.5..=2.0).contains(&got), "{got} m");
    let scene = crate::gltf_read::read(&glb);
    let bones = scene
        .node_names
        .iter()
        .filter(|n| n.starts_with("mixamorig:"))
        .count();
    assert_eq!(bones, 65, "{:?}", scene.node_names);
    assert!(scene
        .node_names
        .iter()
        .any(|n| n == "mixamorig:LeftHandPinky4"));
}

#[test]
fn mixamo_animation_retargets_onto_pinocchio_with_planted_feet() {
    let (Some(bpy), Some(rig)) = (blender_python(), corpus(HUMAN_MODEL1)) else {
        return;
    };
    let dir = scratch();
    let fbx = &make_fbx(&bpy, dir.path(), &["mixamo_anim"])[0];
    let out = dir.path().join("retargeted.glb");
    let (mesh, skel, att) = (
        rig.join("Model1.obj"),
        rig.join("skeleton.out"),
        rig.join("attachment.out"),
    );
    let json = rigport(&[
        "retarget",
        s(fbx),
        "--onto",
        s(&mesh),
        s(&skel),
        s(&att),
        "--plant-feet",
        "--json",
        "-o",
        s(&out),
    ]);
    assert!(
        json.status.success(),
        "{}",
        String::from_utf8_lossy(&json.stderr)
    );
    assert_valid(&out);
    let report: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    let map = report["map"].as_str().unwrap();
    assert!(map.contains("Mixamo names agree"), "{map}");
    // Every limb drives the target: legs, arms, spine and head.
    let roles = report["roles"].as_array().unwrap();
    for limb in [
        "left leg",
        "right leg",
        "left arm",
        "right arm",
        "spine",
        "head",
    ] {
        let words: Vec<&str> = limb.split(' ').collect();
        let driven = roles.iter().any(|r| {
            let l = r["limb"].as_str().unwrap_or("").to_lowercase();
            words.iter().all(|w| l.contains(w)) && !r["driven_by"].is_null()
        });
        assert!(driven, "no {limb} role driven: {roles:?}");
    }
    assert_eq!(report["planted"], true);
    let feet = report["feet"].as_array().unwrap();
    assert_eq!(feet.len(), 2);
    for foot in feet {
        assert!(foot["contacts"].as_u64().unwrap() >= 1, "{foot}");
        let after = foot["slide_after"]["max"].as_f64().unwrap();
        let before = foot["slide_before"]["max"].as_f64().unwrap();
        assert!(
            after < 1e-4 * report["height"].as_f64().unwrap().max(1.0),
            "{foot}"
        );
        assert!(after < before, "{foot}");
    }
}
