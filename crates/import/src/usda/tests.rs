//! Tests of the `.usda` importer on the fixtures in `fixtures/usda/` and the corpus.

use std::path::{Path, PathBuf};

use rigport_model::glam::{Mat4, Quat, Vec2, Vec3};
use rigport_model::{
    Clip, Influence, Interpolation, JointIndex, MeshIndex, Track, TrackTarget, Warning,
};

use super::*;

const ARM: &str = include_str!("../../../../fixtures/usda/skinned_arm.usda");
const RIGID: &str = include_str!("../../../../fixtures/usda/rigid_subset.usda");
const VARIANTS: &str = include_str!("../../../../fixtures/usda/clip_variants.usda");
const BAD_ELEMENT_SIZE: &str = include_str!("../../../../fixtures/usda/bad_element_size.usda");
const BAD_INDEX: &str = include_str!("../../../../fixtures/usda/joint_index_out_of_range.usda");
const NO_SKELETON: &str = include_str!("../../../../fixtures/usda/missing_skeleton.usda");

fn import_text(text: &str, name: &str) -> Result<Imported, ImportError> {
    import_slice(text.as_bytes(), Path::new(name))
}

fn ok(text: &str, name: &str) -> Imported {
    import_text(text, name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn err(text: &str) -> String {
    match import_text(text, "bad.usda") {
        Ok(_) => panic!("imported, expected an error"),
        Err(e) => e.to_string(),
    }
}

/// `text` with `from` replaced by `to` (which must occur).
fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "{from:?} not in the fixture");
    text.replacen(from, to, 1)
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-6
}

fn track(clip: &Clip, target: TrackTarget) -> &Track {
    clip.tracks
        .iter()
        .find(|t| t.target == target)
        .unwrap_or_else(|| panic!("no track {target:?}"))
}

#[test]
fn skinned_arm_maps_every_feature() {
    let imported = ok(ARM, "skinned_arm.usda");
    assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
    let a = &imported.asset;
    assert_eq!(a.name, "skinned_arm");
    assert_eq!(a.meters_per_unit, Some(1.0));

    let names: Vec<&str> = a
        .skeleton
        .joints()
        .iter()
        .map(|j| j.name.as_str())
        .collect();
    assert_eq!(names, ["Shoulder", "Elbow", "Hand"]);
    let parents: Vec<_> = a.skeleton.parents().collect();
    assert_eq!(parents, [None, Some(JointIndex(0)), Some(JointIndex(1))]);
    // Row-vector restTransforms: the translation is the last row.
    assert_eq!(
        a.skeleton.joints()[2].rest_local.translation,
        Vec3::new(0.0, 2.0, 0.0)
    );

    let mesh = &a.meshes[0];
    assert_eq!(mesh.name, "Sleeve");
    // 7 points, and 2 more where face 1's UVs differ from face 0's (points 2 and 3).
    assert_eq!(mesh.source_vertex, [0, 1, 2, 3, 4, 5, 6, 2, 3]);
    // geomBindTransform moves the points by +1 in z.
    assert_eq!(mesh.positions[0], Vec3::new(0.0, 0.0, 1.0));
    assert_eq!(mesh.positions[7], mesh.positions[2]);
    // Fans: the quad gives 2 triangles, the pentagon 3, on the split vertices 7 and 8.
    assert_eq!(
        mesh.triangles,
        [[0, 1, 3], [0, 3, 2], [7, 8, 5], [7, 5, 6], [7, 6, 4]]
    );
    let normals = mesh.normals.as_ref().unwrap();
    assert!(close(normals[6], Vec3::Z), "normalized: {:?}", normals[6]);
    let uvs = mesh.uvs.as_ref().unwrap();
    // USD's v points up, glTF's down.
    assert_eq!(uvs[0], Vec2::new(0.0, 1.0));
    assert_eq!(uvs[2], Vec2::new(0.0, 0.5));
    assert!(
        (uvs[7] - Vec2::new(0.0, 0.4)).length() < 1e-6,
        "{:?}",
        uvs[7]
    );

    let skin = &a.skins[0];
    assert_eq!(skin.joints, [JointIndex(0), JointIndex(1), JointIndex(2)]);
    assert!(skin.inv_bind[1].abs_diff_eq(Mat4::from_translation(Vec3::new(0.0, -2.0, 0.0)), 1e-6));
    let inf = |joint, weight| Influence { joint, weight };
    assert_eq!(
        skin.influences.vertex(0),
        [inf(0, 1.0)],
        "zero weights dropped"
    );
    assert_eq!(skin.influences.vertex(3), [inf(1, 0.5), inf(0, 0.5)]);
    assert_eq!(
        skin.influences.vertex(6),
        [inf(2, 1.0)],
        "a joint listed twice is merged"
    );
    assert_eq!(
        skin.influences.vertex(8),
        skin.influences.vertex(3),
        "splits share their point's row"
    );

    assert_eq!(a.clips.len(), 1);
    let clip = &a.clips[0];
    assert_eq!(clip.name, "Bend");
    // Animation joint 0 is "Shoulder/Elbow", skeleton joint 1.
    let rot = track(clip, TrackTarget::Rotation(JointIndex(1)));
    assert_eq!(rot.interpolation, Interpolation::Linear);
    assert_eq!(rot.times, [0.0, 1.0 / 30.0, 2.0 / 30.0]);
    let q1 = Quat::from_slice(rot.key_value(1));
    let q2 = Quat::from_slice(rot.key_value(2));
    assert!(q1.abs_diff_eq(Quat::from_rotation_z(std::f32::consts::FRAC_PI_2), 1e-6));
    assert_eq!(q1, q2, "the sign flip of the last key is undone");
    let tr = track(clip, TrackTarget::Translation(JointIndex(1)));
    assert_eq!(
        (tr.times.as_slice(), tr.values.as_slice()),
        (&[0.0][..], &[0.0, 2.0, 0.0][..])
    );
    // half3 1.1 is stored as the nearest binary16, 1 + 102/1024.
    let sc = track(clip, TrackTarget::Scale(JointIndex(0)));
    assert_eq!(sc.values, [1.0996094; 3]);
    assert!(clip
        .tracks
        .iter()
        .all(|t| t.target != TrackTarget::Rotation(JointIndex(2))));
}

#[test]
fn rigid_binding_rest_from_bind_and_shifted_times() {
    let imported = ok(RIGID, "rigid_subset.usda");
    let a = &imported.asset;
    assert_eq!(a.meters_per_unit, Some(DEFAULT_METERS_PER_UNIT));
    let tip = &a.skeleton.joints()[1].rest_local;
    // Bind (1, 3, 0) with a 90-degree turn about Z, relative to the parent's bind (1, 0, 0).
    assert!(close(tip.translation, Vec3::new(0.0, 3.0, 0.0)), "{tip:?}");
    assert!(tip
        .rotation
        .abs_diff_eq(Quat::from_rotation_z(std::f32::consts::FRAC_PI_2), 1e-6));
    let box_skin = &a.skins[0];
    assert_eq!(box_skin.mesh, MeshIndex(0));
    assert_eq!(
        box_skin.joints,
        [JointIndex(1)],
        "skel:joints maps index 0 to Base/Tip"
    );
    assert!(box_skin.influences.rows().all(|r| r
        == [Influence {
            joint: 0,
            weight: 1.0
        }]));
    let model = a.skeleton.model_rest_matrices();
    assert!((box_skin.inv_bind[0] * model[1]).abs_diff_eq(Mat4::IDENTITY, 1e-6));
    let ground = &a.meshes[1];
    assert_eq!(
        ground.triangles,
        [[0, 2, 1]],
        "left-handed winding is flipped"
    );
    assert!(a.skins.len() == 1, "the ground is static");
    let clip = &a.clips[0];
    let tr = track(clip, TrackTarget::Translation(JointIndex(1)));
    assert_eq!(
        tr.times,
        [0.0, 1.0],
        "time codes -12 and 12 at 24 per second, shifted"
    );
    assert_eq!(tr.values, [0.0, 3.0, 0.0, 0.0, 4.0, 0.0]);
    assert_eq!(
        track(clip, TrackTarget::Rotation(JointIndex(1))).times,
        [0.0]
    );
    let text: Vec<String> = imported.warnings.iter().map(ToString::to_string).collect();
    let has = |needle: &str| text.iter().any(|w| w.contains(needle));
    assert!(!has("Z-up"), "the up axis is in the frame: {text:?}");
    assert_eq!(a.frame.up_axis, rigport_model::UpAxis::Z);
    assert!(has("</Root/Prop>: references not resolved"), "{text:?}");
    assert!(has("no restTransforms"), "{text:?}");
    assert!(has("shifted by 0.5 s"), "{text:?}");
    assert!(matches!(
        imported
            .warnings
            .iter()
            .find(|w| w.to_string().contains("references")),
        Some(Warning::Incomplete { .. })
    ));
}

#[test]
fn variants_give_the_selected_clip_first_and_the_others_after() {
    let a = ok(VARIANTS, "clip_variants.usda").asset;
    let names: Vec<&str> = a.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["Run", "Idle", "Walk"]);
    assert_eq!(a.clips[0].duration(), 0.5);
    assert_eq!(a.clips[2].duration(), 1.0);
    // Selecting "walk" makes Walk the bound clip.
    let walk = edit(VARIANTS, "string clip = \"run\"", "string clip = \"walk\"");
    let a = ok(&walk, "w.usda").asset;
    let names: Vec<&str> = a.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["Walk", "Idle", "Run"]);
}

#[test]
fn stage_rates_and_units() {
    let fps = edit(ARM, "timeCodesPerSecond = 30", "framesPerSecond = 10");
    let a = ok(&fps, "f.usda").asset;
    let rot = track(&a.clips[0], TrackTarget::Rotation(JointIndex(1)));
    assert_eq!(
        rot.times,
        [0.0, 0.1, 0.2],
        "framesPerSecond is the fallback rate"
    );
    let none = edit(ARM, "timeCodesPerSecond = 30", "");
    let a = ok(&none, "n.usda").asset;
    let rot = track(&a.clips[0], TrackTarget::Rotation(JointIndex(1)));
    assert_eq!(rot.times[1], 1.0 / 24.0, "24 per second by default");
    let bad = edit(ARM, "timeCodesPerSecond = 30", "timeCodesPerSecond = 0");
    assert!(err(&bad).contains("bad.usda:9: timeCodesPerSecond must be a positive number"));
}

// ---------------------------------------------------------------------------------------
// One negative test per error kind; each names the prim.
// ---------------------------------------------------------------------------------------

#[test]
fn bad_element_size_names_the_mesh() {
    assert_eq!(
        err(BAD_ELEMENT_SIZE),
        "bad.usda: </Root/Arm/Mesh>: primvars:skel:jointIndices has elementSize 3 but 7 values \
         for 3 points"
    );
    let zero = edit(ARM, "elementSize = 2", "elementSize = 0");
    assert!(err(&zero).contains("</Arm/Sleeve>: primvars:skel:jointIndices has elementSize"));
    // The number as written, not `Number(2147483647.0)` (issue 15).
    let huge = edit(ARM, "elementSize = 2", "elementSize = 2147483647");
    assert!(
        err(&huge).contains("has elementSize 2147483647; it must be a positive integer"),
        "{}",
        err(&huge)
    );
    let differ = edit(
        ARM,
        "elementSize = 2\n        )\n        float",
        "elementSize = 1\n        )\n        float",
    );
    assert!(err(&differ).contains("</Arm/Sleeve>: "), "{}", err(&differ));
}

#[test]
fn joint_index_out_of_range_names_the_mesh() {
    assert_eq!(
        err(BAD_INDEX),
        "bad.usda: </Root/Arm/Mesh>: primvars:skel:jointIndices[1] = 5 is out of range: the \
         Skeleton </Root/Skel> has 1 joint(s)"
    );
    let negative = edit(ARM, "[0, 1,  0, 1,", "[0, -1,  0, 1,");
    assert!(err(&negative)
        .contains("</Arm/Sleeve>: primvars:skel:jointIndices[1] = -1 is out of range"));
}

#[test]
fn missing_skeleton_names_the_mesh() {
    let e = err(NO_SKELETON);
    assert!(
        e.starts_with("bad.usda: </Root/Arm/Mesh>: has joint influences"),
        "{e}"
    );
    let dangling = edit(
        ARM,
        "rel skel:skeleton = </Arm/Skel>",
        "rel skel:skeleton = </Arm/Nope>",
    );
    let e = err(&dangling);
    assert!(
        e.contains("</Arm>: skel:skeleton targets </Arm/Nope>, which does not exist"),
        "{e}"
    );
    assert!(e.contains("</Arm/Sleeve>"), "{e}");
    let not_skel = edit(
        ARM,
        "rel skel:skeleton = </Arm/Skel>",
        "rel skel:skeleton = </Arm/Sleeve>",
    );
    assert!(err(&not_skel).contains("which is not a defined Skeleton (Mesh)"));
}

#[test]
fn weights_and_indices_of_different_lengths() {
    let text = edit(ARM, "0.5, 0.5] (", "0.5, 0.5, 1] (");
    assert!(err(&text).contains(
        "</Arm/Sleeve>: primvars:skel:jointIndices has 14 values but primvars:skel:jointWeights has 15"
    ));
    let no_weights = edit(
        ARM,
        "float[] primvars:skel:jointWeights",
        "float[] primvars:skel:otherWeights",
    );
    assert!(err(&no_weights).contains(
        "</Arm/Sleeve>: has primvars:skel:jointIndices but no primvars:skel:jointWeights"
    ));
}

#[test]
fn non_finite_values_are_rejected() {
    let cases = [
        (edit(ARM, "(0.5, 5, 0)]", "(0.5, nan, 0)]"), "</Arm/Sleeve>: points holds a non-finite value"),
        (edit(ARM, "0.75, 0.25,  0.5", "0.75, inf,  0.5"), "</Arm/Sleeve>: primvars:skel:jointWeights[11] is not finite"),
        (edit(ARM, "(0, 0, 1, 0), (0, 2, 0, 1)),\n            ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 2, 0, 1))\n        ]", "(0, 0, 1, 0), (0, 2, 0, 1)),\n            ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, -inf, 0, 1))\n        ]"), "</Arm/Skel>: restTransforms[2] is not finite"),
        (edit(ARM, "float3[] translations = [(0, 2, 0)", "float3[] translations = [(0, nan, 0)"), "</Arm/Skel/Bend>: translations holds a non-finite value"),
        (edit(ARM, "(0, 0, 1), (0, 0, 2)]", "(0, 0, 1), (0, 0, inf)]"), "</Arm/Sleeve>: normals holds a non-finite value"),
    ];
    for (text, needle) in cases {
        let e = err(&text);
        assert!(e.contains(needle), "{needle:?} not in {e}");
    }
    let negative = edit(ARM, "0.75, 0.25,  0.5", "0.75, -0.25,  0.5");
    assert!(err(&negative).contains("</Arm/Sleeve>: primvars:skel:jointWeights[11] is negative"));
}

#[test]
fn joints_not_parents_first_are_rejected() {
    let text = edit(
        ARM,
        "[\"Shoulder\", \"Shoulder/Elbow\", \"Shoulder/Elbow/Hand\"]",
        "[\"Shoulder\", \"Shoulder/Elbow/Hand\", \"Shoulder/Elbow\"]",
    );
    let e = err(&text);
    assert!(
        e.contains("</Arm/Skel>: joints are not parents-first"),
        "{e}"
    );
    let dup = edit(ARM, "\"Shoulder/Elbow/Hand\"]", "\"Shoulder/Elbow\"]");
    assert!(err(&dup).contains("</Arm/Skel>: joints 1 and 2 are both \"Shoulder/Elbow\""));
}

#[test]
fn other_usdskel_errors_name_the_prim() {
    let cases = [
        (edit(ARM, "[(0, 2, 0), (0, 0, 0)]", "[(0, 2, 0)]"), "</Arm/Skel/Bend>: translations has 1 values for 2 joints"),
        (edit(ARM, "interpolation = \"vertex\"\n            elementSize = 2\n        )\n        float", "interpolation = \"uniform\"\n            elementSize = 2\n        )\n        float"), "</Arm/Sleeve>: primvars:skel:jointIndices has interpolation \"uniform\""),
        (edit(ARM, "int[] faceVertexIndices = [0, 1, 3, 2,", "int[] faceVertexIndices = [0, 1, 9, 2,"), "</Arm/Sleeve>: faceVertexIndices[2] = 9 is out of range for 7 points"),
        (edit(ARM, "int[] faceVertexCounts = [4, 5]", "int[] faceVertexCounts = [4, 4]"), "</Arm/Sleeve>: faceVertexCounts add up to 8 but faceVertexIndices has 9 entries"),
        (edit(ARM, "(0, 0, 1), (0, 0, 2)]", "(0, 0, 1)]"), "</Arm/Sleeve>: normals has 6 elements for 7 points"),
        (edit(ARM, "rel skel:animationSource = <Bend>", "rel skel:animationSource = <Nope>"), "</Arm/Skel>: skel:animationSource targets </Arm/Skel/Nope>, which does not exist"),
        (edit(ARM, "uniform matrix4d[] bindTransforms = [\n            ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)),\n", "uniform matrix4d[] bindTransforms = [\n"), "</Arm/Skel>: bindTransforms has 2 matrices for 3 joints"),
        (edit(ARM, "point3f[] points = [", "point3f[] points = [1, "), "bad.usda:58: </Arm/Sleeve>: points must be a point3f[]"),
    ];
    for (text, needle) in cases {
        let e = err(&text);
        assert!(e.contains(needle), "{needle:?} not in {e}");
    }
    let skel_joints = edit(
        RIGID,
        "skel:joints = [\"Base/Tip\"]",
        "skel:joints = [\"Base/Nope\"]",
    );
    assert!(err(&skel_joints).contains("</Root/Box>: skel:joints names \"Base/Nope\", which the Skeleton </Root/Skel> does not have"));
    // A skeleton whose joints would come from a reference rigport does not read.
    let behind = edit(
        RIGID,
        "def Skeleton \"Skel\" (\n        prepend apiSchemas = [\"SkelBindingAPI\"]\n    )\n    {\n        uniform token[] joints = [\"Base\", \"Base/Tip\"]",
        "def Skeleton \"Skel\" (\n        prepend references = @skel.usda@\n    )\n    {",
    );
    let e = err(&behind);
    assert!(e.contains("</Root/Skel>: the Skeleton has no joints (it may come from the references on </Root/Skel>"), "{e}");
}

#[test]
fn syntax_errors_carry_line_and_column() {
    let text = edit(
        ARM,
        "int[] faceVertexCounts = [4, 5]",
        "int[] faceVertexCounts = [4 5]",
    );
    assert_eq!(
        err(&text),
        "bad.usda:56:37: expected ',' or ']', found \"5\""
    );
    let e = err("not usd\n");
    assert!(
        e.starts_with("bad.usda:1:1: expected the header #usda 1.0"),
        "{e}"
    );
}

// ---------------------------------------------------------------------------------------
// The corpus (skipped when absent, required in CI).
// ---------------------------------------------------------------------------------------

fn corpus(rel: &str) -> Option<PathBuf> {
    rigport_testkit::corpus(&format!("6_usd/{rel}"))
}

#[test]
fn corpus_arms_import() {
    for rel in [
        "ustc_cg_24_hw10__USTC-CG/arm.usda",
        "openusd_usdskel__PixarAnimationStudios/skinnedArm.usda",
    ] {
        let Some(path) = corpus(rel) else { continue };
        let imported = import(&path).unwrap();
        assert!(
            imported.warnings.is_empty(),
            "{rel}: {:?}",
            imported.warnings
        );
        let a = imported.asset;
        assert_eq!(a.skeleton.len(), 3);
        assert_eq!(a.meters_per_unit, Some(0.01));
        assert_eq!(a.meshes[0].vertex_count(), 12);
        assert_eq!(a.meshes[0].triangles.len(), 20);
        // Points 0..4 are bound to the hand (index 2), whose bind is at z = 4.
        let skin = &a.skins[0];
        let row = skin.influences.vertex(0);
        assert_eq!(skin.joints[row[0].joint as usize], JointIndex(2));
        assert!(skin.inv_bind[row[0].joint as usize]
            .abs_diff_eq(Mat4::from_translation(Vec3::new(0.0, 0.0, -4.0)), 1e-6));
        let clip = &a.clips[0];
        assert_eq!(clip.name, "Anim");
        let rot = track(clip, TrackTarget::Rotation(JointIndex(1)));
        assert_eq!(rot.times, [1.0 / 24.0, 10.0 / 24.0]);
        let q = Quat::from_slice(rot.key_value(1));
        assert!(q.abs_diff_eq(Quat::from_rotation_x(std::f32::consts::FRAC_PI_2), 1e-4));
    }
}

#[test]
fn corpus_bake_inputs_import() {
    for rel in ["lbs.usda", "dqs.usda"] {
        let Some(path) = corpus(&format!(
            "openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning/{rel}"
        )) else {
            continue;
        };
        let imported = import(&path).unwrap();
        let a = &imported.asset;
        let names: Vec<&str> = a.meshes.iter().map(|m| m.name.as_str()).collect();
        // The implicit Sphere, Cube and Cylinder arrive tessellated, after the Meshes.
        assert_eq!(
            names,
            [
                "Mesh",
                "MeshWithFaceVaryingNormals",
                "MeshWithNormals",
                "Sphere",
                "Cube",
                "Cylinder"
            ]
        );
        // Face-varying normals split the 12 points of the second mesh.
        assert_eq!(a.meshes[1].source_vertex_count(), 12);
        assert!(a.meshes[1].vertex_count() > 12);
        // MeshWithNormals writes its points twice; the second statement wins (x = 0.45 ..
        // 0.55 before the geomBindTransform, which maps x to z).
        let b = a.meshes[2].bounds().unwrap();
        assert!(
            (b.0.z - 0.45).abs() < 1e-6 && (b.1.z - 0.55).abs() < 1e-6,
            "{b:?}"
        );
        assert_eq!(a.clips[0].name, "Animation");
        assert_eq!(a.clips[0].duration(), 30.0 / 24.0);
        let skipped = imported
            .warnings
            .iter()
            .filter(|w| w.to_string().contains("has no surface rigport imports"))
            .count();
        assert_eq!(skipped, 1, "the curves");
        let want = if rel == "dqs.usda" {
            rigport_model::SkinningMethod::Dqs
        } else {
            rigport_model::SkinningMethod::Lbs
        };
        assert!(a.skins.iter().all(|s| s.method == want), "{rel}");
    }
}

#[test]
fn every_corpus_usda_imports_or_fails_cleanly() {
    let Some(root) = corpus("") else { return };
    let mut stack = vec![root];
    let mut seen = 0;
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|e| e == "usda") {
                seen += 1;
                if let Err(e) = import(&p) {
                    // Only the deliberately broken test inputs may fail, with a prim path.
                    let msg = e.to_string();
                    assert!(msg.contains(": </"), "{}: {msg}", p.display());
                }
            }
        }
    }
    assert!(seen >= 10, "{seen} files");
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]
    #[test]
    fn never_panics_on_edited_fixtures(
        which in 0_usize..3,
        edits in proptest::collection::vec(
            (proptest::num::usize::ANY, 0_u8..3, proptest::sample::select(
                b"0123456789 .-+eE()[]{}<>@\"'#/\n=,:;xyzdefovrclassMeshSkeleton".to_vec()
            )),
            0..8,
        ),
        cut in proptest::num::usize::ANY,
    ) {
        let sources = [ARM, RIGID, VARIANTS];
        let mut bytes = sources[which].as_bytes().to_vec();
        for (at, op, byte) in edits {
            let i = at % (bytes.len() + 1);
            match op {
                0 if i < bytes.len() => bytes[i] = byte,
                1 => bytes.insert(i, byte),
                _ if i < bytes.len() => {
                    bytes.remove(i);
                }
                _ => {}
            }
        }
        bytes.truncate(cut % (bytes.len() + 1));
        let _ = import_slice(&bytes, Path::new("p.usda"));
    }
}

#[test]
fn transforms_above_the_skeleton_become_the_scene_frame() {
    use glam::{DMat4, DQuat, DVec3};
    let text = include_str!("../../../../fixtures/usda/blender_frame.usda");
    let imported = ok(text, "blender_frame.usda");
    let a = &imported.asset;
    let text: Vec<String> = imported.warnings.iter().map(ToString::to_string).collect();
    assert!(
        !text.iter().any(|w| w.contains("xformOp")),
        "transforms are applied, not reported: {text:?}"
    );
    assert_eq!(a.frame.up_axis, rigport_model::UpAxis::Z);
    assert_eq!(a.meters_per_unit, Some(0.01));
    let deg = f64::to_radians;
    // rotateXYZ: X first, then Y, then Z.
    let rot = DQuat::from_rotation_z(deg(30.0)) * DQuat::from_rotation_x(deg(90.0));
    // `orient` as USD evaluates it (`GfRotation(quat)`): the angle 2 acos(w) about the
    // imaginary part's direction; the f32 value 0.70710677 is not exactly sqrt(1/2), so it
    // turns 3.4e-8 rad more than the normalized quaternion does (usd-core agrees).
    let orient = DQuat::from_axis_angle(DVec3::Y, 2.0 * f64::from(0.70710677_f32).acos());
    let expect = DMat4::from_scale(DVec3::splat(100.0))
        * DMat4::from_translation(DVec3::new(0.5, 0.0, 0.0))
        * DMat4::from_quat(rot)
        * DMat4::from_quat(orient);
    assert!(
        a.frame.model_to_scene.abs_diff_eq(expect, 1e-9),
        "{} vs {expect}",
        a.frame.model_to_scene
    );
    // The static prop's points are in model space: the frame maps them to the stage.
    let prop = &a.meshes[1];
    let stage_of = |p: Vec3| a.frame.model_to_scene.transform_point3(p.as_dvec3());
    let want = DMat4::from_scale(DVec3::splat(100.0)) * DMat4::from_translation(DVec3::Z);
    for (p, src) in prop.positions.iter().zip([DVec3::ZERO, DVec3::X, DVec3::Y]) {
        assert!(
            (stage_of(*p) - want.transform_point3(src)).length() < 1e-4,
            "{p} -> {} vs {}",
            stage_of(*p),
            want.transform_point3(src)
        );
    }
}

#[test]
fn xform_op_orders_and_reset_stack() {
    let text = r#"#usda 1.0
def Xform "A"
{
    double3 xformOp:translate = (1, 2, 3)
    uniform token[] xformOpOrder = ["xformOp:translate"]
    def Xform "B"
    {
        double3 xformOp:translate:pivot = (0, 1, 0)
        float xformOp:rotateZ = 90
        matrix4d xformOp:transform = ((2,0,0,0),(0,2,0,0),(0,0,2,0),(0,0,5,1))
        uniform token[] xformOpOrder = ["xformOp:transform", "xformOp:translate:pivot", "xformOp:rotateZ", "!invert!xformOp:translate:pivot"]
        def Mesh "M"
        {
            int[] faceVertexCounts = [3]
            int[] faceVertexIndices = [0, 1, 2]
            point3f[] points = [(1, 1, 0), (0, 0, 0), (0, 1, 0)]
        }
    }
    def Xform "C"
    {
        uniform token[] xformOpOrder = ["!resetXformStack!"]
        def Mesh "N"
        {
            int[] faceVertexCounts = [3]
            int[] faceVertexIndices = [0, 1, 2]
            point3f[] points = [(1, 1, 0), (0, 0, 0), (0, 1, 0)]
        }
    }
}
"#;
    let a = ok(text, "ops.usda").asset;
    // (1,1,0): about the pivot (0,1,0) by 90° about Z -> (0,2,0); x2 and +(0,0,5) -> (0,4,5);
    // + (1,2,3) -> (1,6,8).
    assert!(
        close(a.meshes[0].positions[0], Vec3::new(1.0, 6.0, 8.0)),
        "{}",
        a.meshes[0].positions[0]
    );
    assert!(
        close(a.meshes[1].positions[0], Vec3::new(1.0, 1.0, 0.0)),
        "reset: {}",
        a.meshes[1].positions[0]
    );
}

#[test]
fn results_that_differ_from_usdskel_are_warnings_not_notes() {
    // Without SkelBindingAPI, usd-core ignores the mesh's skinning primvars; rigport skins
    // it: `--deny-warnings` must catch that.
    let text = ARM.replace(
        "    def Mesh \"Sleeve\" (\n        prepend apiSchemas = [\"SkelBindingAPI\"]\n    )",
        "    def Mesh \"Sleeve\"",
    );
    assert_ne!(text, ARM, "the fixture changed");
    let imported = ok(&text, "no_api.usda");
    assert!(
        imported
            .warnings
            .iter()
            .any(|w| matches!(w, Warning::Repaired { message, .. }
            if message.contains("SkelBindingAPI"))),
        "{:?}",
        imported.warnings
    );
}

#[test]
fn a_static_mesh_under_animated_transforms_rides_a_joint_of_its_own() {
    // Reality Converter's AnimatedTriangle: a non-unit orient (0.707, 0, 0, 0.707)
    // time-sampled on the mesh itself. usd-core (26.x) gives, at time code 3, the slerp
    // (0.92385066, 0, 0, 0.38263762) and a matrix whose first row is (0.707, 0.707213, 0):
    // GfSlerp on the components as authored, then GfRotation's angle 2 acos(w).
    let text = r#"#usda 1.0
(
    timeCodesPerSecond = 24
    upAxis = "Y"
    metersPerUnit = 1
)
def Xform "Root"
{
    def Mesh "Tri"
    {
        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 2]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
        quatf xformOp:orient.timeSamples = {
            0: (1, 0, 0, 0),
            6: (0.707, 0, 0, 0.707),
        }
        uniform token[] xformOpOrder = ["xformOp:orient"]
    }
}
"#;
    let imported = ok(text, "tri.usda");
    let a = &imported.asset;
    assert_eq!(a.skeleton.len(), 1, "one joint carries the mesh's motion");
    assert_eq!(a.skeleton.joints()[0].name, "Tri");
    assert_eq!(a.meshes[0].attached_to, Some(JointIndex(0)));
    assert_eq!(
        a.meshes[0].positions[1],
        Vec3::X,
        "points stay in the prim's space"
    );
    let clip = &a.clips[0];
    let rot = clip
        .tracks
        .iter()
        .find(|t| t.target == rigport_model::TrackTarget::Rotation(JointIndex(0)))
        .unwrap();
    // Keys at every time code 0..=6.
    assert_eq!(rot.times.len(), 7);
    assert!((rot.times[3] - 3.0 / 24.0).abs() < 1e-7);
    let q = Quat::from_slice(rot.key_value(3));
    let m = glam::Mat3::from_quat(q);
    // USD's row 0 is the image of +X: (0.707, 0.707213, 0).
    assert!((m.x_axis.x - 0.707).abs() < 1e-6, "{m}");
    assert!((m.x_axis.y - 0.707213).abs() < 1e-6, "{m}");
    let text: Vec<String> = imported.warnings.iter().map(ToString::to_string).collect();
    assert!(
        !text.iter().any(|w| w.contains("default time")),
        "the motion is kept: {text:?}"
    );
}

#[test]
fn a_second_uv_set_left_out_is_a_coded_warning() {
    let text = r#"#usda 1.0
def Mesh "M"
{
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(1, 1, 0), (0, 0, 0), (0, 1, 0)]
    texCoord2f[] primvars:st = [(0, 0), (1, 0), (0, 1)] (
        interpolation = "vertex"
    )
    texCoord2f[] primvars:st1 = [(0, 0), (1, 1), (1, 0)] (
        interpolation = "vertex"
    )
}
"#;
    let imported = ok(text, "uvs.usda");
    assert!(imported.asset.meshes[0].uvs.is_some());
    let lost: Vec<_> = imported
        .warnings
        .iter()
        .filter(|w| w.to_string().contains("primvars:st1"))
        .collect();
    assert_eq!(lost.len(), 1, "{:?}", imported.warnings);
    assert_eq!(lost[0].code(), "W004");
}

#[test]
fn display_colour_left_out_is_a_coded_warning() {
    let text = r#"#usda 1.0
def Mesh "M"
{
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(1, 1, 0), (0, 0, 0), (0, 1, 0)]
    color3f[] primvars:displayColor = [(1, 0, 0)]
}
"#;
    let imported = ok(text, "red.usda");
    let shown: Vec<String> = imported
        .warnings
        .iter()
        .map(|w| format!("{}: {w}", w.code()))
        .collect();
    assert_eq!(shown.len(), 1, "{shown:?}");
    assert!(
        shown[0].starts_with("W004")
            && shown[0].contains("</M>: primvars:displayColor not imported"),
        "{shown:?}"
    );
}
