//! Tests of the USD exporter: text assertions on the sample assets, determinism, rejected
//! assets, and round trips through usd-core (`tools/check_usd.py`), including a comparison
//! of UsdSkel's evaluation with a naive reference evaluation of the model written here.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{DMat4, DQuat, DVec3};
use rigport_model::glam::{Mat4, Quat, Vec3};
use rigport_model::{
    Asset, AssetError, Clip, Interpolation, Joint, JointIndex, Mesh, MeshIndex, Skeleton, Track,
    TrackTarget, Transform, Warning,
};

use super::anim::frame_rate;
use super::sampler::Sampler;
use super::*;
use crate::labels::fallback_palette_index;
use crate::{test_assets, Problem};

fn usda(asset: &Asset, skinning: SkinningMethod) -> ExportedUsd {
    to_usda(
        asset,
        &UsdOptions {
            skinning: Some(skinning),
            ..Default::default()
        },
    )
    .expect("export")
}

/// The block of text from the line containing `start` to the next line equal to `end`
/// at the same indentation.
fn block<'a>(text: &'a str, start: &str) -> &'a str {
    let from = text
        .find(start)
        .unwrap_or_else(|| panic!("{start:?} not in the text"));
    let line_start = text[..from].rfind('\n').map_or(0, |i| i + 1);
    let line = &text[line_start..];
    let indent = &line[..line.len() - line.trim_start().len()];
    let close = format!("\n{indent}}}\n");
    let to = text[from..]
        .find(&close)
        .map_or(text.len(), |i| from + i + close.len());
    &text[from..to]
}

/// The numbers of a line `decl = [...]` inside `text`.
fn numbers(text: &str, decl: &str) -> Vec<f64> {
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with(decl))
        .unwrap_or_else(|| panic!("{decl:?} not found"));
    let value = &line[line.find('=').expect("=") + 1..];
    value
        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<f64>().expect("number"))
        .collect()
}

#[test]
fn rig_text_has_the_usdskel_layout() {
    let asset = test_assets::rig();
    let out = usda(&asset, SkinningMethod::Lbs);
    let text = &out.text;
    assert!(text
        .starts_with("#usda 1.0\n(\n    defaultPrim = \"rig\"\n    doc = \"Written by rigport "));
    // Keys at 0, 0.5, 1, 1.5, 2 s: a 24 fps stage (2 fps fits but plays badly), ending
    // at the longest clip's last key.
    for line in [
        "    endTimeCode = 48\n",
        "    metersPerUnit = 1\n",
        "    startTimeCode = 0\n",
        "    timeCodesPerSecond = 24\n",
        "    upAxis = \"Y\"\n)\n",
    ] {
        assert!(text.contains(line), "{line:?}");
    }
    assert!(text.contains(
        "def SkelRoot \"rig\" (\n    variants = {\n        string clip = \"wave\"\n    }\n    prepend variantSets = \"clip\"\n)\n"
    ));
    let skel = block(text, "def Skeleton \"Skeleton\"");
    assert!(skel.contains("prepend apiSchemas = [\"SkelBindingAPI\"]"));
    assert!(skel.contains("uniform token[] joints = [\"root\", \"root/mid\", \"root/mid/tip\"]\n"));
    // Rest transforms: local, row-vector convention (translation in the last row).
    let rest = numbers(skel, "uniform matrix4d[] restTransforms");
    assert_eq!(rest.len(), 48);
    assert_eq!(&rest[28..32], &[0.0, 1.0, 0.0, 1.0]); // mid: one unit up its parent
    assert!((rest[16] - 0.1_f64.cos()).abs() < 1e-7 && (rest[17] - 0.1_f64.sin()).abs() < 1e-7);
    // Bind transforms: model space, the inverse of the inverse bind matrices.
    let bind = numbers(skel, "uniform matrix4d[] bindTransforms");
    let model = asset.skeleton.model_rest_matrices();
    for j in 0..3 {
        let cols = model[j].to_cols_array();
        for k in 0..16 {
            assert!(
                (bind[16 * j + k] - f64::from(cols[k])).abs() < 1e-6,
                "joint {j} element {k}"
            );
        }
    }
    assert!(
        !skel.contains("animationSource"),
        "clips are bound in the variants only"
    );

    // Animations: every key time and every 1/24 s (cubic and step tracks), all three
    // attributes, quaternions w first.
    let wave = block(text, "def SkelAnimation \"wave\"");
    assert!(wave.contains("uniform token[] joints = [\"root\", \"root/mid\", \"root/mid/tip\"]\n"));
    for attr in ["rotations", "scales", "translations", "blendShapeWeights"] {
        let samples = block(wave, &format!("{attr}.timeSamples = {{"));
        assert_eq!(samples.lines().count(), 49 + 2, "{attr}: {samples}");
        assert!(samples.contains("    48: ["), "{attr}");
    }
    let rest_rot = numbers(wave, "quatf[] rotations =");
    let q = Quat::from_rotation_z(0.1);
    assert_eq!(rest_rot.len(), 12);
    assert!(
        (rest_rot[4] - f64::from(q.w)).abs() < 1e-7 && (rest_rot[7] - f64::from(q.z)).abs() < 1e-7
    );
    // The STEP scale of `tip` holds 1.2 (half: 1.2001953) from 0.5 s to 1 s.
    let scales = block(wave, "half3[] scales.timeSamples");
    assert!(scales.contains("    12: [(1, 1, 1), (1, 1, 1), (1.2001953, 0.89990234, 1.2001953)],"));
    assert!(scales.contains("    23: [(1, 1, 1), (1, 1, 1), (1.2001953, 0.89990234, 1.2001953)],"));
    assert!(scales.contains("    24: [(1, 1, 1), (1, 1, 1), (1, 1, 1)],"));
    assert!(wave.contains("uniform token[] blendShapes = [\"bulge\", \"pinch\"]"));
    assert!(wave.contains("float[] blendShapeWeights = [0, 0.25]\n"));
    let idle = block(text, "def SkelAnimation \"idle\"");
    assert!(idle.contains("uniform token[] joints = [\"root\", \"root/mid\"]\n"));
    assert!(text.contains(
        "        \"idle\" {\n            over \"Skeleton\"\n            {\n                rel skel:animationSource = </rig/Animations/idle>\n            }\n        }\n"
    ));

    // The skinned mesh: 1-8 raw entries over a 3-joint palette merge to at most 3.
    let body = block(text, "def Mesh \"body\"");
    assert!(body.contains("prepend apiSchemas = [\"SkelBindingAPI\"]"));
    assert!(body.contains("int[] faceVertexIndices = [0, 20, 1, 1, 20, 21, "));
    assert!(body.contains("int[] faceVertexCounts = [3, 3, "));
    assert!(body.contains(
        "] (\n            elementSize = 3\n            interpolation = \"vertex\"\n        )\n"
    ));
    assert!(
        body.contains("texCoord2f[] primvars:st = [(0, 0), (0.05, 0), "),
        "v flipped"
    );
    assert!(body.contains("matrix4d primvars:skel:geomBindTransform = ( (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1) )"));
    assert!(body.contains("rel skel:skeleton = </rig/Skeleton>"));
    assert!(body.contains("rel skel:blendShapeTargets = [</rig/body/bulge>, </rig/body/pinch>]"));
    assert!(body.contains("uniform token subdivisionScheme = \"none\""));
    assert!(!body.contains("skinningMethod"));
    assert!(
        !body.contains("rigport:sourceVertex"),
        "identity source map"
    );
    // Skeleton joint indices, palette (tip-first) mapped to skeleton order; vertex 0 has no
    // influence and goes to the root; every row sums to 1.
    let indices = numbers(body, "int[] primvars:skel:jointIndices");
    let weights = numbers(body, "float[] primvars:skel:jointWeights");
    assert_eq!(indices.len(), 600);
    assert_eq!(
        (&indices[..3], &weights[..3]),
        (&[0.0, 0.0, 0.0][..], &[1.0, 0.0, 0.0][..])
    );
    for row in weights.chunks(3) {
        assert!((row.iter().sum::<f64>() - 1.0).abs() < 1e-6, "{row:?}");
        assert!(row.windows(2).all(|w| w[0] >= w[1]), "sorted {row:?}");
    }
    assert!(indices.iter().all(|&j| (0.0..3.0).contains(&j)));
    let bulge = block(body, "def BlendShape \"bulge\"");
    assert!(
        bulge.contains("uniform int[] pointIndices = [20, 21, "),
        "sparse: ring 0 and 9 do not move"
    );
    assert!(bulge.contains("uniform vector3f[] normalOffsets = "));

    // The hat rides on `tip` rigidly: points in the joint's space, geomBindTransform = bind.
    let hat = block(text, "def Mesh \"hat\"");
    assert!(hat.contains("int[] primvars:skel:jointIndices = [2] (\n            elementSize = 1\n            interpolation = \"constant\"\n        )"));
    assert!(hat.contains("float[] primvars:skel:jointWeights = [1] ("));
    let geom = numbers(hat, "matrix4d primvars:skel:geomBindTransform");
    assert!(
        (geom[12] + 0.1_f64.sin()).abs() < 1e-6 && (geom[13] - 1.0 - 0.1_f64.cos()).abs() < 1e-6,
        "{geom:?}"
    );

    // The lossy steps are reported.
    let has = |f: &dyn Fn(&Warning) -> bool| out.warnings.iter().any(f);
    assert!(has(&|w| matches!(w, Warning::WeightsRenormalized { .. })));
    assert!(has(
        &|w| matches!(w, Warning::Repaired { message, .. } if message.contains("1 vertex had no influence"))
    ));
    assert!(has(
        &|w| matches!(w, Warning::Repaired { location, message } if location == "clip \"wave\"" && message.contains("half precision"))
    ));
    assert!(has(
        &|w| matches!(w, Warning::Repaired { message, .. } if message.contains("sampled at 24 fps"))
    ));

    let dqs = usda(&asset, SkinningMethod::Dqs).text;
    assert_eq!(
        dqs.matches("uniform token primvars:skel:skinningMethod = \"dualQuaternion\"")
            .count(),
        1
    );
    assert_eq!(
        dqs.replace(
            "        uniform token primvars:skel:skinningMethod = \"dualQuaternion\"\n",
            ""
        ),
        *text
    );
}

#[test]
fn other_samples() {
    // Several roots in one Skeleton.
    let text = usda(&test_assets::two_roots(), SkinningMethod::Lbs).text;
    assert!(text.contains(
        "uniform token[] joints = [\"left\", \"left/left_end\", \"right\", \"right/right_end\"]"
    ));
    assert!(text.contains("timeCodesPerSecond = 24\n"));
    // Tracks holding the rest value leave their joint to restTransforms.
    let mut asset = test_assets::two_roots();
    asset.clips[0].tracks.push(Track {
        target: TrackTarget::Translation(JointIndex(0)),
        interpolation: Interpolation::Linear,
        times: vec![0.0, 2.0],
        values: vec![-1.0, 0.0, 0.0, -1.0, 0.0, 0.0],
    });
    asset.clips[0].tracks.push(Track {
        target: TrackTarget::Rotation(JointIndex(1)),
        interpolation: Interpolation::Step,
        times: vec![0.0],
        values: vec![0.0, 0.0, 0.0, -1.0],
    });
    let text = usda(&asset, SkinningMethod::Lbs).text;
    assert!(text.contains("uniform token[] joints = [\"right\"]\n"));
    assert!(
        text.contains("endTimeCode = 48\n"),
        "their keys still count"
    );
    asset.clips[0].tracks[1].values[0] = -0.999;
    let text = usda(&asset, SkinningMethod::Lbs).text;
    assert!(text.contains("uniform token[] joints = [\"left\", \"right\"]\n"));

    // No clips, but a default morph weight: a `rest` animation carries it.
    let text = usda(&test_assets::wide_rig(), SkinningMethod::Lbs).text;
    assert!(text.contains("rel skel:animationSource = </wide/Animations/rest>"));
    assert!(!text.contains("variantSet"));
    assert!(
        text.contains("elementSize = 8\n"),
        "1-8 distinct influences, no limit"
    );
    // Unskinned meshes only: an empty Skeleton drives the blend shapes; the grid is plain.
    let text = usda(&test_assets::static_props(), SkinningMethod::Lbs).text;
    assert!(text.contains("uniform token[] joints = []\n"));
    let grid = block(&text, "def Mesh \"grid\"");
    assert!(grid.starts_with("def Mesh \"grid\"\n"), "no SkelBindingAPI");
    assert!(!grid.contains("skel:"));
    let hat = block(&text, "def Mesh \"hat\"");
    assert!(hat.contains("uniform token[] skel:blendShapes = [\"squash\"]"));
    assert!(!hat.contains("jointIndices"));
    // Big palettes are no problem for int indices.
    let text = usda(&test_assets::big_palette(), SkinningMethod::Lbs).text;
    assert!(text.contains("elementSize = 2\n"));
    // Bones only: no animation, no time metadata.
    let text = usda(&test_assets::bones_only(), SkinningMethod::Lbs).text;
    assert!(!text.contains("timeCodesPerSecond"));
    assert!(
        text.contains("metersPerUnit = 1\n"),
        "unknown units are written as metres"
    );
}

#[test]
fn output_is_deterministic() {
    for asset in [
        test_assets::rig(),
        test_assets::two_roots(),
        test_assets::wide_rig(),
    ] {
        let a = usda(&asset, SkinningMethod::Dqs);
        let b = usda(&asset.clone(), SkinningMethod::Dqs);
        assert_eq!(a, b);
    }
}

fn joint(name: &str, parent: Option<u32>) -> Joint {
    Joint {
        name: name.into(),
        parent: parent.map(JointIndex),
        rest_local: Transform::from_translation(Vec3::Y),
    }
}

#[test]
fn joint_names_become_unique_identifiers() {
    let skeleton = Skeleton::new(vec![
        joint("Hips", None),
        joint("Left Arm", Some(0)),
        joint("Left_Arm", Some(0)),
        joint("1st", Some(1)),
        joint("腕", Some(0)),
        joint("Left Arm.001", None),
    ])
    .unwrap();
    let asset = Asset {
        name: "my rig".into(),
        skeleton,
        ..Default::default()
    };
    let out = usda(&asset, SkinningMethod::Lbs);
    assert!(out.text.contains(
        "uniform token[] joints = [\"Hips\", \"Hips/Left_Arm\", \"Hips/Left_Arm_1\", \"Hips/Left_Arm/_1st\", \"Hips/_u8155\", \"Left_Arm_001\"]"
    ));
    assert!(out.text.contains("def SkelRoot \"my_rig\""));
    assert!(out.text.contains("defaultPrim = \"my_rig\""));
    let Some(Warning::Repaired { location, message }) = out.warnings.first() else {
        panic!("{:?}", out.warnings);
    };
    assert_eq!(location, "skeleton");
    assert!(message.starts_with("5 joint names renamed"), "{message}");
    assert!(
        message.contains("\"Left_Arm\" -> \"Left_Arm_1\""),
        "{message}"
    );
}

#[test]
fn invalid_assets_are_rejected_and_usd_only_limits_lifted() {
    let mut asset = test_assets::rig();
    asset.meshes[1].triangles.push([0, 1, 99]);
    let Err(ExportError::Invalid { problems }) = to_usda(&asset, &UsdOptions::default()) else {
        panic!("expected Invalid");
    };
    assert!(
        problems.contains(&Problem::Asset(AssetError::TriangleIndex {
            mesh: 1,
            triangle: 12,
            vertex: 99,
            count: 24
        }))
    );
    let mut asset = test_assets::rig();
    asset.skins.push(asset.skins[0].clone());
    let Err(ExportError::Invalid { problems }) = to_usda(&asset, &UsdOptions::default()) else {
        panic!("expected Invalid");
    };
    assert_eq!(
        problems,
        vec![Problem::SharedSkinMesh {
            mesh: 0,
            first_skin: 0,
            second_skin: 1
        }]
    );
    // An empty mesh is a valid USD Mesh (glTF needs an accessor element).
    let mut asset = test_assets::bones_only();
    asset.meshes.push(Mesh {
        name: "empty".into(),
        ..Default::default()
    });
    let text = usda(&asset, SkinningMethod::Lbs).text;
    assert!(text.contains("int[] faceVertexCounts = []\n"));
}

#[test]
fn frame_rates() {
    let at = |rate: f64, n: usize| -> Vec<f64> {
        (0..n)
            .map(|k| f64::from((k as f64 / rate) as f32))
            .collect()
    };
    assert_eq!(frame_rate(&at(30.0, 100)), Some(30.0));
    assert_eq!(
        frame_rate(&at(120.0, 200_000)),
        Some(120.0),
        "f32 times, 27 minutes"
    );
    // BVH `Frame Time: 0.0333333`: keys are evenly spaced at 30.00003 per second.
    let bvh: Vec<f64> = (0..300)
        .map(|k| f64::from(k as f32 * 0.033_333_3_f32))
        .collect();
    let rate = frame_rate(&bvh).unwrap();
    assert!(
        (rate - 1.0 / 0.033_333_3).abs() < 1e-3 && rate != 30.0,
        "{rate}"
    );
    assert_eq!(frame_rate(&[0.0, 0.5, 1.0, 2.0]), Some(24.0));
    assert_eq!(frame_rate(&[0.0, 1.0 / 7.0, 1.0]), Some(28.0));
    assert_eq!(frame_rate(&[0.0, 0.0123, 0.5]), None);
    assert_eq!(frame_rate(&[0.25]), None);
    // An irregular first clip gets millisecond time codes.
    let mut asset = test_assets::two_roots();
    asset.clips[0].tracks[0].times = vec![0.0, 0.0123];
    let text = usda(&asset, SkinningMethod::Lbs).text;
    assert!(text.contains("timeCodesPerSecond = 1000\n"));
    let code = f64::from(0.0123_f32) * 1000.0;
    assert!(
        text.contains(&format!(" {code}: [")),
        "non-integral codes kept exact"
    );
}

#[test]
fn bind_pose_mismatches_use_geom_bind_or_a_second_skeleton() {
    // Two skinned copies of the body on the same chain: the second bound 2 units to the
    // left (its inverse binds carry the offset), the third with an unrelated bind pose.
    let mut asset = test_assets::rig();
    let mut moved = asset.skins[0].clone();
    moved.mesh = MeshIndex(2);
    let offset = Mat4::from_translation(Vec3::new(2.0, 0.0, 0.0));
    for ib in &mut moved.inv_bind {
        *ib *= offset;
    }
    let mut odd = asset.skins[0].clone();
    odd.mesh = MeshIndex(3);
    odd.inv_bind[0] = Mat4::from_rotation_x(1.0) * odd.inv_bind[0];
    asset.meshes.push(asset.meshes[0].clone());
    asset.meshes.push(asset.meshes[0].clone());
    asset.skins.push(moved);
    asset.skins.push(odd);
    let out = usda(&asset, SkinningMethod::Lbs);
    let second = block(&out.text, "def Mesh \"body_1\"");
    let g = numbers(second, "matrix4d primvars:skel:geomBindTransform");
    assert!((g[12] - 2.0).abs() < 1e-6 && g[13].abs() < 1e-6, "{g:?}");
    assert!(second.contains("rel skel:skeleton = </rig/Skeleton>"));
    let third = block(&out.text, "def Mesh \"body_2\"");
    assert!(third.contains("rel skel:skeleton = </rig/Skeleton_1>"));
    assert!(out.text.contains("def Skeleton \"Skeleton_1\""));
    assert!(out.text.contains("            over \"Skeleton_1\"\n            {\n                rel skel:animationSource = </rig/Animations/wave>"));
    assert!(out
        .warnings
        .iter()
        .any(|w| matches!(w, Warning::Note { message, .. } if message.contains("Skeleton_1"))));
    assert!(out.warnings.iter().any(|w| matches!(w, Warning::Repaired { location, message } if location == "meshes" && message.contains("\"body\" -> \"body_1\""))));
}

#[test]
fn dropped_tracks_are_reported() {
    let mut asset = test_assets::rig();
    let clip = &mut asset.clips[0];
    clip.tracks.push(clip.tracks[0].clone());
    clip.tracks.push(Track {
        target: TrackTarget::MorphWeights(MeshIndex(1)),
        interpolation: Interpolation::Linear,
        times: vec![0.0],
        values: vec![1.0],
    });
    let out = usda(&asset, SkinningMethod::Lbs);
    let dropped: Vec<&str> = out
        .warnings
        .iter()
        .filter_map(|w| match w {
            Warning::Repaired { location, message } if message.starts_with("track dropped") => {
                Some(location.as_str())
            }
            _ => None,
        })
        .collect();
    assert_eq!(
        dropped,
        vec!["clip \"wave\" track 5", "clip \"wave\" track 6"]
    );
}

#[test]
fn prepare_and_write() {
    let dir = tempfile::tempdir().unwrap();
    let asset = test_assets::two_roots();
    let err = prepare_usd(&asset, &dir.path().join("x.glb"), &UsdOptions::default()).unwrap_err();
    assert!(matches!(err, ExportError::UnsupportedExtension { .. }));
    let path = dir.path().join("out.USDA");
    let prepared = prepare_usd(&asset, &path, &UsdOptions::default()).unwrap();
    assert!(prepared.warnings().is_empty(), "{:?}", prepared.warnings());
    assert_eq!(prepared.path(), path);
    let text = prepared
        .text()
        .expect("a short text is in memory")
        .to_owned();
    prepared.write().unwrap();
    assert_eq!(std::fs::read_to_string(&path).unwrap(), text);
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 1, "no temporary file left: {names:?}");
    let missing = prepare_usd(
        &asset,
        &dir.path().join("no/such/dir/a.usda"),
        &UsdOptions::default(),
    )
    .unwrap();
    assert!(matches!(missing.write(), Err(ExportError::Io { .. })));
}

/// A text longer than the spill size is staged in a temporary file as it is built: the
/// same bytes as in memory, nothing at the output before `write`, no temporary file left
/// after it or after a drop.
#[test]
fn a_long_text_is_streamed_to_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let asset = test_assets::two_roots();
    assert!(!asset.clips.is_empty(), "the sample has a clip to stream");
    let expected = to_usda(&asset, &UsdOptions::default()).unwrap().text;
    let names = |dir: &Path| -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    let path = dir.path().join("two_roots.usda");
    let prepared =
        super::prepare_usd_spilling_at(&asset, &path, &UsdOptions::default(), 256).unwrap();
    assert_eq!(prepared.text(), None, "spilled past 256 bytes");
    let staged = names(dir.path());
    assert_eq!(staged.len(), 1, "{staged:?}");
    assert!(staged[0].starts_with(".two_roots.usda.") && staged[0].ends_with(".tmp"));
    prepared.write().unwrap();
    assert_eq!(std::fs::read_to_string(&path).unwrap(), expected);
    assert_eq!(names(dir.path()), ["two_roots.usda"]);
    // Dropped (say, refused under --deny-warnings): the old file stays, the staged one goes.
    let dropped =
        super::prepare_usd_spilling_at(&asset, &path, &UsdOptions::default(), 256).unwrap();
    drop(dropped);
    assert_eq!(names(dir.path()), ["two_roots.usda"]);
    // A folder that does not exist: an I/O error naming the output, at prepare time.
    let missing = super::prepare_usd_spilling_at(
        &asset,
        &dir.path().join("no/such/dir/a.usda"),
        &UsdOptions::default(),
        256,
    )
    .unwrap_err();
    match missing {
        ExportError::Io { path, .. } => assert!(path.ends_with("no/such/dir/a.usda")),
        other => panic!("{other:?}"),
    }
}

// ------------------------------------------------------------------ usd-core round trips

/// The venv's Python (`RIGPORT_PYTHON`, else `tools/.venv/bin/python`), or `None` when
/// absent; absent tools fail the test when `CI` is set.
fn python() -> Option<PathBuf> {
    let path = std::env::var_os("RIGPORT_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/.venv/bin/python")
        });
    if path.exists() {
        return Some(path);
    }
    if std::env::var("CI").is_ok_and(|v| !v.is_empty()) {
        panic!(
            "{} is missing and CI is set: run bash tools/setup.sh",
            path.display()
        );
    }
    println!(
        "SKIPPED: {} not found (run bash tools/setup.sh)",
        path.display()
    );
    None
}

fn checker() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/check_usd.py")
}

/// Runs the checker; returns its exit code and output.
fn check(python: &Path, args: &[&Path], extra: &[&str]) -> (i32, String) {
    let out = Command::new(python)
        .arg(checker())
        .args(args)
        .args(extra)
        .output()
        .expect("run check_usd.py");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.code().unwrap_or(-1), text)
}

#[test]
fn every_sample_passes_usd_validation() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("rig", test_assets::rig(), SkinningMethod::Lbs),
        ("rig_dqs", test_assets::rig(), SkinningMethod::Dqs),
        ("wide", test_assets::wide_rig(), SkinningMethod::Dqs),
        ("two_roots", test_assets::two_roots(), SkinningMethod::Lbs),
        (
            "big_palette",
            test_assets::big_palette(),
            SkinningMethod::Lbs,
        ),
        ("props", test_assets::static_props(), SkinningMethod::Lbs),
        ("bones", test_assets::bones_only(), SkinningMethod::Lbs),
    ];
    for (name, asset, skinning) in cases {
        let path = dir.path().join(format!("{name}.usda"));
        prepare_usd(
            &asset,
            &path,
            &UsdOptions {
                skinning: Some(skinning),
                ..Default::default()
            },
        )
        .unwrap()
        .write()
        .unwrap();
        let (code, out) = check(&python, &[&path], &["--strict"]);
        assert_eq!(code, 0, "{name}:\n{out}");
        assert!(
            out.contains("validators: UsdValidation ran"),
            "{name}:\n{out}"
        );
        assert!(
            out.contains("check_usd: OK: 0 errors, 0 warnings"),
            "{name}:\n{out}"
        );
    }
}

#[test]
fn checker_rejects_broken_bindings() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let good = usda(&test_assets::two_roots(), SkinningMethod::Lbs).text;
    let body = block(&good, "def Mesh \"body\"");
    let cases: [(&str, String, &str); 4] = [
        (
            "element_size",
            good.replacen("elementSize = 2", "elementSize = 3", 1),
            "jointIndices elementSize 3 != jointWeights elementSize 2",
        ),
        (
            "index_range",
            good.replacen(
                "int[] primvars:skel:jointIndices = [3, 1,",
                "int[] primvars:skel:jointIndices = [4, 1,",
                1,
            ),
            "joint index 4 at entry 0 out of range for 4 joints",
        ),
        (
            "weights",
            {
                // The first row's two weights become 0.5, 0.25 (sum 0.75).
                let line = body.lines().find(|l| l.contains("jointWeights")).unwrap();
                let (head, tail) = line.split_once(" = [").unwrap();
                let rest: Vec<&str> = tail.splitn(3, ", ").collect();
                good.replacen(line, &format!("{head} = [0.5, 0.25, {}", rest[2]), 1)
            },
            "joint weights of point 0 sum to 0.75",
        ),
        (
            "skeleton",
            good.replace(
                "rel skel:skeleton = </two_roots/Skeleton>",
                "rel skel:skeleton = </two_roots/Nowhere>",
            ),
            "does not resolve to one Skeleton",
        ),
    ];
    assert!(
        body.contains("int[] primvars:skel:jointIndices = [3, 1,"),
        "fixture assumption"
    );
    for (name, text, expect) in cases {
        assert_ne!(text, good, "{name}: the edit applied");
        let path = dir.path().join(format!("{name}.usda"));
        std::fs::write(&path, text).unwrap();
        let (code, out) = check(&python, &[&path], &[]);
        assert_eq!(code, 1, "{name}:\n{out}");
        assert!(
            out.contains(expect),
            "{name}: expected {expect:?} in\n{out}"
        );
    }
}

/// A naive evaluation of `asset` at `t` seconds of `clip` (`None`: the rest pose), in
/// `f64`: joint model matrices, and points mesh by mesh in source-vertex order (the first
/// vertex of each source vertex), morph targets applied before skinning, weights
/// normalized, vertices without influence bound to the skin's root (the exporter's rule).
fn reference(asset: &Asset, clip: Option<&Clip>, t: f64) -> (Vec<DMat4>, Vec<DVec3>) {
    let joints = asset.skeleton.joints();
    let mut local: Vec<(DVec3, DQuat, DVec3)> = joints
        .iter()
        .map(|j| {
            let r = j.rest_local;
            (
                r.translation.as_dvec3(),
                r.rotation.as_dquat().normalize(),
                r.scale.as_dvec3(),
            )
        })
        .collect();
    let mut weights: Vec<Vec<f64>> = asset
        .meshes
        .iter()
        .map(|m| {
            (0..m.morph_targets.len())
                .map(|k| m.morph_weights.get(k).map_or(0.0, |&w| f64::from(w)))
                .collect()
        })
        .collect();
    let mut seen = std::collections::BTreeSet::new();
    for track in clip.map_or(&[][..], |c| &c.tracks[..]) {
        if !seen.insert(track.target) {
            continue;
        }
        let s = Sampler::new(track);
        let mut v = vec![0.0; track.components()];
        s.sample(t, &mut v);
        match track.target {
            TrackTarget::Translation(j) => local[j.get()].0 = DVec3::new(v[0], v[1], v[2]),
            TrackTarget::Rotation(j) => {
                local[j.get()].1 = DQuat::from_xyzw(v[0], v[1], v[2], v[3]).normalize()
            }
            // SkelAnimation scales are half3[]: the documented (and reported) loss.
            TrackTarget::Scale(j) => {
                let h = |x: f64| f64::from(super::values::to_half(x as f32));
                local[j.get()].2 = DVec3::new(h(v[0]), h(v[1]), h(v[2]));
            }
            TrackTarget::MorphWeights(m) => weights[m.get()] = v,
        }
    }
    let mut model: Vec<DMat4> = Vec::new();
    for (j, joint) in joints.iter().enumerate() {
        let (tr, r, s) = local[j];
        let m = DMat4::from_scale_rotation_translation(s, r, tr);
        model.push(joint.parent.map_or(m, |p| model[p.get()] * m));
    }
    let mut points = Vec::new();
    for (mi, mesh) in asset.meshes.iter().enumerate() {
        let skin = asset.skins.iter().find(|s| s.mesh.get() == mi);
        for &v in &mesh.first_vertex_of_source() {
            let v = v as usize;
            let mut p = mesh.positions[v].as_dvec3();
            for (target, w) in mesh.morph_targets.iter().zip(&weights[mi]) {
                p += target.position_deltas[v].as_dvec3() * *w;
            }
            points.push(match (skin, mesh.attached_to) {
                (Some(skin), _) => {
                    let row = skin.influences.vertex(v);
                    let total: f64 = row.iter().map(|i| f64::from(i.weight)).sum();
                    if total > 0.0 {
                        row.iter().fold(DVec3::ZERO, |acc, i| {
                            let k = i.joint as usize;
                            let m = model[skin.joints[k].get()] * skin.inv_bind[k].as_dmat4();
                            acc + m.transform_point3(p) * (f64::from(i.weight) / total)
                        })
                    } else {
                        let k = fallback_palette_index(&asset.skeleton, &skin.joints);
                        (model[skin.joints[k].get()] * skin.inv_bind[k].as_dmat4())
                            .transform_point3(p)
                    }
                }
                (None, Some(j)) => model[j.get()].transform_point3(p),
                (None, None) => p,
            });
        }
    }
    (model, points)
}

/// A `.npy` file (format 1.0) of little-endian `f32`s, or of fixed-width UTF-32 strings.
fn npy(shape: &[usize], descr: &str, data: &[u8]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    let shape = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

fn f32_bytes(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
    values.into_iter().flat_map(f32::to_le_bytes).collect()
}

/// CRC-32 (IEEE), bitwise: test data is small.
fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0_u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// An uncompressed zip of `name.npy` entries: what `numpy.savez` writes.
fn npz(entries: &[(&str, Vec<u8>)]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut central = Vec::new();
    for (name, data) in entries {
        let name = format!("{name}.npy");
        let offset = out.len() as u32;
        let crc = crc32(data);
        let fixed = |v: &mut Vec<u8>| {
            v.extend_from_slice(&20_u16.to_le_bytes()); // version needed
            v.extend_from_slice(&0_u16.to_le_bytes()); // flags
            v.extend_from_slice(&0_u16.to_le_bytes()); // stored
            v.extend_from_slice(&0_u16.to_le_bytes()); // time
            v.extend_from_slice(&0x21_u16.to_le_bytes()); // date 1980-01-01
            v.extend_from_slice(&crc.to_le_bytes());
            v.extend_from_slice(&(data.len() as u32).to_le_bytes());
            v.extend_from_slice(&(data.len() as u32).to_le_bytes());
            v.extend_from_slice(&(name.len() as u16).to_le_bytes());
            v.extend_from_slice(&0_u16.to_le_bytes()); // extra
        };
        out.extend_from_slice(&0x0403_4b50_u32.to_le_bytes());
        fixed(&mut out);
        out.extend_from_slice(name.as_bytes());
        out.extend_from_slice(data);
        central.extend_from_slice(&0x0201_4b50_u32.to_le_bytes());
        central.extend_from_slice(&20_u16.to_le_bytes()); // made by
        fixed(&mut central);
        central.extend_from_slice(&[0; 6]); // comment length, disk, internal attributes
        central.extend_from_slice(&0_u32.to_le_bytes()); // external attr
        central.extend_from_slice(&offset.to_le_bytes());
        central.extend_from_slice(name.as_bytes());
    }
    let cd_offset = out.len() as u32;
    out.extend_from_slice(&central);
    out.extend_from_slice(&0x0605_4b50_u32.to_le_bytes());
    out.extend_from_slice(&[0; 4]);
    for _ in 0..2 {
        out.extend_from_slice(&(entries.len() as u16).to_le_bytes());
    }
    out.extend_from_slice(&(central.len() as u32).to_le_bytes());
    out.extend_from_slice(&cd_offset.to_le_bytes());
    out.extend_from_slice(&0_u16.to_le_bytes());
    out
}

/// A dump like `rigport eval`'s, of the reference at `times` (`None`: one rest pose).
fn dump(asset: &Asset, clip: Option<&Clip>, times: Option<&[f32]>) -> Vec<u8> {
    let frames: Vec<f64> = times.map_or(vec![0.0], |t| t.iter().map(|&x| f64::from(x)).collect());
    let mut world = Vec::new();
    let mut positions = Vec::new();
    let mut v = 0;
    for &t in &frames {
        let (model, points) = reference(asset, clip, t);
        // Row-major storage of column-vector matrices.
        world.extend(
            model
                .iter()
                .flat_map(|m| m.transpose().to_cols_array().map(|x| x as f32)),
        );
        positions.extend(points.iter().flat_map(|p| p.to_array().map(|x| x as f32)));
        v = points.len();
    }
    let j = asset.skeleton.len();
    let width = asset
        .skeleton
        .joints()
        .iter()
        .map(|x| x.name.chars().count())
        .max()
        .unwrap_or(1)
        .max(1);
    let names: Vec<u8> = asset
        .skeleton
        .joints()
        .iter()
        .flat_map(|x| {
            let mut c: Vec<u32> = x.name.chars().map(u32::from).collect();
            c.resize(width, 0);
            c.into_iter().flat_map(u32::to_le_bytes)
        })
        .collect();
    let f = frames.len();
    let lbs: Vec<u8> = "lbs"
        .chars()
        .flat_map(|c| u32::from(c).to_le_bytes())
        .collect();
    let mut entries = vec![
        ("joint_names", npy(&[j], &format!("<U{width}"), &names)),
        ("skinning", npy(&[1], "<U3", &lbs)),
    ];
    match times {
        Some(times) => {
            entries.push(("times", npy(&[f], "<f4", &f32_bytes(times.iter().copied()))));
            entries.push(("joint_world", npy(&[f, j, 4, 4], "<f4", &f32_bytes(world))));
            entries.push(("positions", npy(&[f, v, 3], "<f4", &f32_bytes(positions))));
        }
        None => {
            entries.push(("joint_world", npy(&[j, 4, 4], "<f4", &f32_bytes(world))));
            entries.push(("positions", npy(&[v, 3], "<f4", &f32_bytes(positions))));
        }
    }
    npz(&entries)
}

/// The rig with a seam: the hat's corners shared by three faces become one source vertex
/// each (8 source vertices for 24 points), so the dump lists fewer points than the Mesh.
fn rig_with_seams() -> Asset {
    let mut asset = test_assets::rig();
    let hat = &mut asset.meshes[1];
    let mut firsts: Vec<Vec3> = Vec::new();
    hat.source_vertex = hat
        .positions
        .iter()
        .map(|p| match firsts.iter().position(|q| q == p) {
            Some(s) => s as u32,
            None => {
                firsts.push(*p);
                firsts.len() as u32 - 1
            }
        })
        .collect();
    assert_eq!(hat.source_vertex_count(), 8);
    asset
}

#[test]
fn usd_evaluation_matches_the_reference() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let frames = |seconds: f32| -> Vec<f32> {
        (0..=(seconds * 24.0).round() as u32)
            .map(|k| k as f32 / 24.0)
            .collect()
    };
    let rig = rig_with_seams();
    // The seams' copies agree on position, influences and morph deltas, so they merge back
    // into the source's points (no source map needed; normals and st go face-varying).
    let text = usda(&rig, SkinningMethod::Lbs).text;
    assert!(
        !text.contains("primvars:rigport:sourceVertex"),
        "seams merged back"
    );
    assert!(text.contains("interpolation = \"faceVarying\""), "{text}");
    // (name, asset, clip, dump times; no clip and no times: the rest pose)
    type Case = (&'static str, Asset, Option<usize>, Option<Vec<f32>>);
    let cases: Vec<Case> = vec![
        ("rig_wave", rig.clone(), Some(0), Some(frames(2.0))),
        // A cubic-spline clip: exact at frames (between frames USD interpolates linearly;
        // at 0.3 s the deviation was measured at 9.7e-6 of the diagonal).
        (
            "rig_idle",
            rig.clone(),
            Some(1),
            Some(vec![0.0, 7.0 / 24.0, 1.0, 2.0]),
        ),
        ("rig_rest", rig, None, None),
        // A LINEAR clip matches between frames too.
        (
            "two_roots",
            test_assets::two_roots(),
            Some(0),
            Some(vec![0.0, 0.1, 0.5, 0.77, 1.0]),
        ),
        ("wide_rest", test_assets::wide_rig(), None, None),
        (
            "props",
            test_assets::static_props(),
            Some(0),
            Some(frames(0.5)),
        ),
    ];
    for (name, asset, clip, times) in cases {
        let usd = dir.path().join(format!("{name}.usda"));
        prepare_usd(&asset, &usd, &UsdOptions::default())
            .unwrap()
            .write()
            .unwrap();
        let clip_ref = clip.map(|c| &asset.clips[c]);
        let npz_path = dir.path().join(format!("{name}.npz"));
        std::fs::write(&npz_path, dump(&asset, clip_ref, times.as_deref())).unwrap();
        let mut extra = vec!["--against".to_string(), npz_path.display().to_string()];
        if let Some(c) = clip_ref {
            extra.extend(["--clip".to_string(), c.name.clone()]);
        }
        let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
        let (code, out) = check(&python, &[&usd], &extra);
        assert_eq!(code, 0, "{name}:\n{out}");
        println!(
            "{name}: {}",
            out.lines()
                .find(|l| l.starts_with("compare: largest"))
                .unwrap_or("")
        );
        let frames_printed = out.lines().filter(|l| l.starts_with("frame ")).count();
        assert_eq!(
            frames_printed,
            times.as_ref().map_or(1, Vec::len),
            "{name}:\n{out}"
        );
        assert!(out.contains("points max"), "{name}:\n{out}");
        if name != "props" {
            assert!(out.contains("joints translation max"), "{name}:\n{out}");
        }
    }

    // The comparison can fail: a dump of another clip is far off.
    let asset = test_assets::rig();
    let usd = dir.path().join("mismatch.usda");
    prepare_usd(&asset, &usd, &UsdOptions::default())
        .unwrap()
        .write()
        .unwrap();
    let npz_path = dir.path().join("mismatch.npz");
    std::fs::write(
        &npz_path,
        dump(&asset, Some(&asset.clips[1]), Some(&[0.5, 1.0])),
    )
    .unwrap();
    let (code, out) = check(&python, &[&usd], &["--against", npz_path.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("off by"), "{out}");

    // The skinning method is honoured: the DQS file's joints match the LBS reference, its
    // blended points do not.
    let usd = dir.path().join("dqs.usda");
    let asset = rig_with_seams();
    prepare_usd(
        &asset,
        &usd,
        &UsdOptions {
            skinning: Some(SkinningMethod::Dqs),
            ..Default::default()
        },
    )
    .unwrap()
    .write()
    .unwrap();
    let npz_path = dir.path().join("lbs.npz");
    std::fs::write(
        &npz_path,
        dump(&asset, Some(&asset.clips[0]), Some(&[1.0, 1.5])),
    )
    .unwrap();
    let (code, out) = check(&python, &[&usd], &["--against", npz_path.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains(": point "), "{out}");
    assert!(!out.contains(": joint "), "{out}");
    assert!(
        out.contains(
            "/rig/body skins with dualQuaternion but the dump was made with classicLinear"
        ),
        "{out}"
    );
}

#[test]
fn reference_helpers_are_sane() {
    // The reference's rigid attachment and skinning agree with the model's rules.
    let mut asset = test_assets::two_roots();
    asset.meshes[0].morph_weights.clear();
    let (model, points) = reference(&asset, None, 0.0);
    assert_eq!(model.len(), 4);
    assert_eq!(points.len(), asset.meshes[0].vertex_count());
    for (p, q) in points.iter().zip(&asset.meshes[0].positions) {
        assert!(
            (*p - q.as_dvec3()).length() < 1e-6,
            "rest pose skins to the bind shape"
        );
    }
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
}

#[test]
fn a_rate_of_37_5_with_uneven_keys_is_found_exactly() {
    // 1300 keys at 37.5 per second, some dropped (a key reducer's output): the gaps are
    // uneven, but every key is on a frame of 37.5.
    let times: Vec<f64> = (0..1300)
        .filter(|k| k % 7 != 3)
        .map(|k| f64::from((k as f64 / 37.5) as f32))
        .collect();
    assert_eq!(frame_rate(&times), Some(37.5));
}

#[test]
fn each_clip_variant_has_its_own_time_range() {
    let mut asset = test_assets::two_roots();
    let mut long = asset.clips[0].clone();
    long.name = "long".into();
    for t in &mut long.tracks {
        t.times.iter_mut().for_each(|x| *x *= 2.0);
    }
    asset.clips.push(long);
    let text = usda(&asset, SkinningMethod::Lbs).text;
    assert!(
        text.contains("endTimeCode = 24\n"),
        "the stage: the selected clip"
    );
    let variant = |name: &str| block(&text, &format!("\"{name}\" (")).to_string();
    let first = &asset.clips[0].name;
    assert!(
        variant(first).contains("double endTimeCode = 24\n"),
        "{}",
        variant(first)
    );
    assert!(
        variant("long").contains("double endTimeCode = 48\n"),
        "{}",
        variant("long")
    );
    assert!(variant("long").contains("double startTimeCode = 0\n"));
}

#[test]
fn the_scene_frame_is_written_as_authored_or_converted() {
    use rigport_model::{SceneFrame, UpAxis};
    let mut asset = test_assets::rig();
    let place = DMat4::from_scale_rotation_translation(
        DVec3::splat(100.0),
        DQuat::from_rotation_z(0.5),
        DVec3::new(1.0, 2.0, 3.0),
    );
    asset.frame = SceneFrame {
        up_axis: UpAxis::Z,
        model_to_scene: place,
    };
    asset.meters_per_unit = Some(0.01);
    let text = usda(&asset, SkinningMethod::Lbs).text;
    assert!(text.contains("upAxis = \"Z\"\n"), "kept");
    assert!(text.contains("metersPerUnit = 0.01\n"), "kept");
    let xform = numbers(&text, "matrix4d xformOp:transform");
    // Written row by row in USD's row-vector form: the column-vector matrix's columns.
    let want = place.to_cols_array();
    assert!(
        xform.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-9),
        "{xform:?}"
    );
    assert!(text.contains("uniform token[] xformOpOrder = [\"xformOp:transform\"]"));
    // Asked for Y-up metres: the root's transform converts.
    let out = to_usda(
        &asset,
        &UsdOptions {
            up_axis: Some(UpAxis::Y),
            meters_per_unit: Some(1.0),
            ..Default::default()
        },
    )
    .unwrap()
    .text;
    assert!(out.contains("upAxis = \"Y\"\n") && out.contains("metersPerUnit = 1\n"));
    let xform = numbers(&out, "matrix4d xformOp:transform");
    let want = (DMat4::from_scale(DVec3::splat(0.01)) * UpAxis::Z.conversion_to(UpAxis::Y) * place)
        .to_cols_array();
    assert!(
        xform.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-9),
        "{xform:?}"
    );
    // An identity frame authors no transform.
    assert!(!usda(&test_assets::rig(), SkinningMethod::Lbs)
        .text
        .contains("xformOp"));
}
