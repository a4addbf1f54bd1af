use std::path::PathBuf;

use ::gltf::json::Value;
use rigport_model::glam::{Mat4, Quat, Vec2, Vec3};
use rigport_model::{Asset, Clip, Interpolation, JointIndex, MeshIndex, TrackTarget, Warning};

use super::container::{decode_base64, json_pointer, percent_decode};
use super::mesh::{fan_triangles, strip_triangles};
use super::*;
use crate::{ImportError, Imported, Problem};

const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/gltf/");

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(FIXTURES).join(name)
}

fn import_fixture(name: &str) -> Imported {
    match import(&fixture(name)) {
        Ok(imported) => imported,
        Err(e) => panic!("{name}: {e}"),
    }
}

/// Imports a fixture after editing its JSON.
fn import_edited(name: &str, edit: impl FnOnce(&mut Value)) -> Result<Imported, ImportError> {
    let path = fixture(name);
    let mut json: Value =
        ::gltf::json::deserialize::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    edit(&mut json);
    import_slice(&::gltf::json::serialize::to_vec(&json).unwrap(), &path)
}

/// A GLB container around `json` and `bin`.
fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// One triangle whose positions are `positions` (9 floats), in a GLB.
fn triangle_glb(positions: &[f32]) -> Vec<u8> {
    let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
            "nodes":[{"name":"T","mesh":0}],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
            "buffers":[{"byteLength":36}],
            "bufferViews":[{"buffer":0,"byteLength":36}],
            "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
                          "min":[0,0,0],"max":[1,1,0]}]}"#;
    glb(json, &floats(positions))
}

fn json_path(e: &ImportError) -> &str {
    e.location.json_path.as_deref().unwrap_or("")
}

fn names(asset: &Asset) -> Vec<&str> {
    asset
        .skeleton
        .joints()
        .iter()
        .map(|j| j.name.as_str())
        .collect()
}

fn has_warning(warnings: &[Warning], location_part: &str, message_part: &str) -> bool {
    warnings.iter().any(|w| match w {
        Warning::Note { location, message } | Warning::Repaired { location, message } => {
            location.contains(location_part) && message.contains(message_part)
        }
        other => {
            let text = other.to_string();
            text.contains(location_part) && text.contains(message_part)
        }
    })
}

fn assert_close(a: &[f32], b: &[f32]) {
    assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() < 1e-5, "{a:?} vs {b:?}: {x} != {y}");
    }
}

/// `model_rest(joint) * inv_bind` when it is the same matrix for every palette joint of
/// every skin (the rest pose is the bind pose up to that transform of the mesh), else
/// `None`.
fn rest_times_inv_bind(asset: &Asset) -> Option<Mat4> {
    let model = asset.skeleton.model_rest_matrices();
    let mut all = asset.skins.iter().flat_map(|skin| {
        skin.joints
            .iter()
            .zip(&skin.inv_bind)
            .map(|(j, ib)| model[j.get()] * *ib)
    });
    let first = all.next()?;
    all.all(|m| m.abs_diff_eq(first, 1e-4)).then_some(first)
}

fn bind_pose_is_rest_pose(asset: &Asset) -> bool {
    rest_times_inv_bind(asset).is_some_and(|m| m.abs_diff_eq(Mat4::IDENTITY, 1e-4))
}

// --- fixtures -----------------------------------------------------------------------

#[test]
fn skin_basic_maps_nodes_mesh_skin_and_clips() {
    let Imported { asset, warnings } = import_fixture("skin_basic.gltf");
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(asset.name, "skin_basic");
    assert_eq!(asset.meters_per_unit, Some(1.0));
    // Nodes are stored child-before-parent (Spine = node 0); the skeleton is sorted.
    assert_eq!(
        names(&asset),
        ["Hips", "Spine"],
        "the skinned mesh node Body is no joint"
    );
    let parents: Vec<_> = asset.skeleton.parents().collect();
    assert_eq!(parents, [None, Some(JointIndex(0))]);
    assert_eq!(
        asset.skeleton.joint(JointIndex(1)).rest_local.translation,
        Vec3::Y
    );

    assert_eq!(asset.meshes.len(), 1);
    let mesh = &asset.meshes[0];
    assert_eq!(mesh.name, "Body");
    assert_eq!(mesh.vertex_count(), 6);
    assert_eq!(mesh.triangles, [[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]]);
    assert_eq!(mesh.source_vertex, [0, 1, 2, 3, 4, 5]);
    assert_eq!(mesh.normals.as_ref().unwrap()[0], Vec3::Z);
    // As stored in glTF: no V flip.
    assert_eq!(mesh.uvs.as_ref().unwrap()[0], Vec2::new(0.0, 1.0));
    assert_eq!(mesh.attached_to, None, "skinned meshes are in bind space");

    assert_eq!(asset.skins.len(), 1);
    let skin = &asset.skins[0];
    assert_eq!(skin.mesh, MeshIndex(0));
    assert_eq!(skin.joints, [JointIndex(0), JointIndex(1)]);
    assert!(bind_pose_is_rest_pose(&asset));
    let row = |v| {
        skin.influences
            .vertex(v)
            .iter()
            .map(|i| (i.joint, i.weight))
            .collect::<Vec<_>>()
    };
    assert_eq!(row(0), [(0, 1.0)]);
    assert_eq!(row(2), [(0, 0.5), (1, 0.5)]);
    assert_eq!(row(5), [(1, 1.0)]);

    assert_eq!(asset.clips.len(), 2);
    let bend = &asset.clips[0];
    assert_eq!(bend.name, "bend");
    assert_eq!(bend.tracks.len(), 3);
    let rot = &bend.tracks[0];
    assert_eq!(rot.target, TrackTarget::Rotation(JointIndex(1)));
    assert_eq!(rot.interpolation, Interpolation::Linear);
    assert_eq!(rot.times, [0.0, 1.0]);
    let s = 0.5f32.sqrt();
    assert_close(&rot.values, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, s, s]);
    let step = &bend.tracks[1];
    assert_eq!(step.target, TrackTarget::Translation(JointIndex(0)));
    assert_eq!(step.interpolation, Interpolation::Step);
    assert_eq!(step.times, [0.0, 0.5, 1.0]);
    assert_close(&step.values, &[0.0, 1.0, 0.0, 0.0, 1.5, 0.0, 0.0, 1.0, 0.0]);
    let cubic = &bend.tracks[2];
    assert_eq!(cubic.target, TrackTarget::Scale(JointIndex(1)));
    assert_eq!(cubic.interpolation, Interpolation::CubicSpline);
    assert_eq!(cubic.values.len(), 2 * 3 * 3, "[in, value, out] per key");
    assert_eq!(cubic.key_value(1), [1.0, 2.0, 1.0]);
    assert_eq!(asset.clips[1].name, "animation_1");
    assert_eq!(
        asset.clips[1].tracks[0].target,
        TrackTarget::Rotation(JointIndex(0))
    );
}

#[test]
fn glb_imports_like_the_gltf() {
    let gltf = import_fixture("skin_basic.gltf");
    let glb = import_fixture("skin_basic.glb");
    assert_eq!(glb.asset, gltf.asset);
    assert!(glb.warnings.is_empty(), "{:?}", glb.warnings);
}

#[test]
fn weights_from_all_sets_merged_and_renormalized() {
    let Imported { asset, warnings } = import_fixture("skin_weights.gltf");
    assert_eq!(
        names(&asset),
        ["A", "B", "C"],
        "the skinned mesh node is no joint"
    );
    let skin = &asset.skins[0];
    assert_eq!(skin.joints, [JointIndex(0), JointIndex(1), JointIndex(2)]);
    assert_eq!(
        skin.inv_bind,
        vec![Mat4::IDENTITY; 3],
        "identity when absent"
    );
    let rows: Vec<Vec<(u32, f32)>> = skin
        .influences
        .rows()
        .map(|r| r.iter().map(|i| (i.joint, i.weight)).collect())
        .collect();
    // Vertex 0: 0.5 on joint 0, 0.25 (set 0) + 51/255 (set 1, normalized u8) on joint 1,
    // a zero weight on joint 2 dropped; the row (sum 0.95) rescaled to sum 1.
    assert_eq!(rows[0].len(), 2);
    assert_eq!(rows[0][0].0, 0);
    assert!((rows[0][0].1 - 0.5 / 0.95).abs() < 1e-6, "{rows:?}");
    assert_eq!(rows[0][1].0, 1);
    assert!((rows[0][1].1 - 0.45 / 0.95).abs() < 1e-6, "{rows:?}");
    assert_eq!(rows[1], [(2, 1.0)]);
    // Vertex 2 names joint 0 twice in one set.
    assert_eq!(rows[2].len(), 1);
    assert!((rows[2][0].1 - 1.0).abs() < 1e-6);
    assert!(
        has_warning(
            &warnings,
            "/meshes/0/primitives/0/attributes",
            "2 vertices list the same joint"
        ),
        "{warnings:?}"
    );
    assert!(
        warnings.iter().any(|w| matches!(
            w,
            Warning::WeightsRenormalized { source, rows: 1, max_row_sum_error }
                if source.contains("WEIGHTS_0") && (max_row_sum_error - 0.05).abs() < 1e-6
        )),
        "{warnings:?}"
    );
    assert_eq!(asset.meshes[0].triangles, [[0, 1, 2]], "implicit indices");
}

#[test]
fn morph_targets_sparse_accessors_and_weight_tracks_per_primitive() {
    let Imported { asset, warnings } = import_fixture("morph_sparse.gltf");
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(asset.meshes.len(), 2);
    for (k, mesh) in asset.meshes.iter().enumerate() {
        assert_eq!(mesh.name, format!("Face_{k}"));
        assert_eq!(mesh.attached_to, Some(JointIndex(0)));
        assert_eq!(mesh.morph_weights, [0.25, 0.0]);
        let target_names: Vec<_> = mesh.morph_targets.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(target_names, ["smile", "blink"]);
        assert_eq!(
            mesh.morph_targets[0].position_deltas[2],
            Vec3::new(0.0, 0.3, 0.0)
        );
        assert!(mesh.morph_targets[0].normal_deltas.is_some());
        // Sparse, no bufferView: zeros except vertex 2.
        assert_eq!(
            mesh.morph_targets[1].position_deltas,
            [Vec3::ZERO, Vec3::ZERO, Vec3::Z]
        );
        assert!(mesh.morph_targets[1].normal_deltas.is_none());
    }
    assert_eq!(asset.meshes[0].positions[0], Vec3::ZERO);
    // Sparse over a base view: vertex 0 replaced.
    assert_eq!(asset.meshes[1].positions, [-Vec3::Z, Vec3::X, Vec3::Y]);
    let clip = &asset.clips[0];
    assert_eq!(clip.name, "talk");
    let targets: Vec<_> = clip.tracks.iter().map(|t| t.target).collect();
    assert_eq!(
        targets,
        [
            TrackTarget::MorphWeights(MeshIndex(0)),
            TrackTarget::MorphWeights(MeshIndex(1))
        ]
    );
    for t in &clip.tracks {
        assert_eq!(t.times, [0.0, 2.0]);
        assert_eq!(t.values, [0.0, 1.0, 1.0, 0.5]);
        assert_eq!(t.components(), 2);
    }
}

#[test]
fn strips_and_fans_become_triangles_lines_are_skipped() {
    let Imported { asset, warnings } = import_fixture("primitive_modes.gltf");
    assert_eq!(asset.meshes.len(), 2);
    assert_eq!(asset.meshes[0].name, "Modes_0");
    assert_eq!(asset.meshes[0].triangles, [[0, 1, 2], [1, 3, 2], [2, 3, 4]]);
    assert_eq!(asset.meshes[1].name, "Modes_1");
    assert_eq!(asset.meshes[1].triangles, [[1, 2, 0], [2, 3, 0], [3, 4, 0]]);
    assert!(
        has_warning(
            &warnings,
            "/meshes/0/primitives/2/mode",
            "Lines primitive skipped"
        ),
        "{warnings:?}"
    );
}

#[test]
fn strip_and_fan_helpers() {
    assert_eq!(strip_triangles(&[0, 1]), Vec::<[u32; 3]>::new());
    // A restart by repeated indices makes degenerate triangles, which are dropped.
    assert_eq!(strip_triangles(&[0, 1, 2, 3]), [[0, 1, 2], [1, 3, 2]]);
    // A restart by repeated indices makes degenerate triangles, which are dropped; the
    // winding still alternates with the position in the strip.
    assert_eq!(
        strip_triangles(&[0, 1, 2, 2, 3, 4, 5]),
        [[0, 1, 2], [2, 4, 3], [3, 4, 5]]
    );
    assert_eq!(fan_triangles(&[]), Vec::<[u32; 3]>::new());
    assert_eq!(fan_triangles(&[7, 8, 9]), [[8, 9, 7]]);
}

#[test]
fn node_matrices_decompose_and_shear_is_reported() {
    let Imported { asset, warnings } = import_fixture("node_matrix.gltf");
    assert_eq!(names(&asset), ["Rotated", "Sheared", "Quat"]);
    let rotated = asset.skeleton.joint(JointIndex(0)).rest_local;
    assert_eq!(rotated.translation, Vec3::new(1.0, 2.0, 3.0));
    let expect = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
    assert!(
        rotated.rotation.abs_diff_eq(expect, 1e-6),
        "{:?}",
        rotated.rotation
    );
    assert!(rotated.scale.abs_diff_eq(Vec3::ONE, 1e-6));
    assert!(!has_warning(&warnings, "/nodes/0/", ""), "{warnings:?}");
    assert!(
        has_warning(&warnings, "/nodes/1/matrix", "not a TRS"),
        "{warnings:?}"
    );
    let quat = asset.skeleton.joint(JointIndex(2)).rest_local.rotation;
    assert_eq!(quat, Quat::IDENTITY);
    assert!(
        has_warning(&warnings, "/nodes/2/rotation", "length 2; normalized"),
        "{warnings:?}"
    );
}

#[test]
fn node_names_made_unique_and_non_empty() {
    let Imported { asset, warnings } = import_fixture("node_names.gltf");
    assert_eq!(
        names(&asset),
        ["node_0_1", "arm", "arm_2", "node_0", "node_4"]
    );
    assert!(
        has_warning(&warnings, "/nodes/2/name", r#"duplicate node name "arm""#),
        "{warnings:?}"
    );
    assert!(
        has_warning(&warnings, "/nodes/0/name", "taken"),
        "{warnings:?}"
    );
    assert!(
        has_warning(&warnings, "/nodes", "2 unnamed node(s)"),
        "{warnings:?}"
    );
}

#[test]
fn external_bin_is_read_relative_to_the_file() {
    let Imported { asset, .. } = import_fixture("external_bin.gltf");
    assert_eq!(asset.meshes[0].positions, [Vec3::ZERO, Vec3::X, Vec3::Y]);
    assert_eq!(asset.meshes[0].attached_to, Some(JointIndex(0)));
}

#[test]
fn missing_bin_names_the_file() {
    let e = import(&fixture("missing_bin.gltf")).unwrap_err();
    assert_eq!(json_path(&e), "/buffers/0/uri");
    let text = e.to_string();
    assert!(
        text.contains("missing.bin") && text.contains("cannot read"),
        "{text}"
    );
}

#[test]
fn data_uris_need_no_file_system() {
    let bytes = std::fs::read(fixture("morph_sparse.gltf")).unwrap();
    let imported = import_slice(&bytes, Path::new("/nonexistent/dir/face.gltf")).unwrap();
    assert_eq!(imported.asset.name, "face");
    assert_eq!(imported.asset.meshes.len(), 2);
}

// --- errors -------------------------------------------------------------------------

#[test]
fn empty_input() {
    let e = import_slice(b"  \n", Path::new("e.gltf")).unwrap_err();
    assert!(matches!(e.problem, Problem::Empty), "{e}");
}

#[test]
fn json_syntax_error_has_line_and_column() {
    let text = b"{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [ }\n}\n";
    let e = import_slice(text, Path::new("bad.gltf")).unwrap_err();
    assert_eq!(e.location.line, Some(3), "{e}");
    assert!(e.location.column.is_some(), "{e}");
    assert!(e.to_string().starts_with("bad.gltf:3:"), "{e}");
    let e = import_slice(b"{\"asset\": {", Path::new("cut.gltf")).unwrap_err();
    assert!(matches!(e.problem, Problem::Truncated(_)), "{e}");
}

#[test]
fn schema_error_has_json_pointer() {
    let e = import_edited("skin_basic.gltf", |j| j["nodes"][1]["mesh"] = 7.into()).unwrap_err();
    assert_eq!(json_path(&e), "/nodes/1/mesh", "{e}");
    assert!(e.to_string().contains("index out of range"), "{e}");
    assert_eq!(
        json_pointer(r#"meshes[0].primitives[1].attributes["JOINTS_0"]"#),
        "/meshes/0/primitives/1/attributes/JOINTS_0"
    );
    let e = import_edited("skin_basic.gltf", |j| {
        j["extensionsRequired"] = vec!["KHR_draco_mesh_compression"].into();
        j["extensionsUsed"] = vec!["KHR_draco_mesh_compression"].into();
    })
    .unwrap_err();
    assert_eq!(json_path(&e), "/extensionsRequired/0", "{e}");
    assert!(
        e.to_string()
            .contains("required extension KHR_draco_mesh_compression is not supported"),
        "{e}"
    );
    let ok = import_edited("skin_basic.gltf", |j| {
        j["extensionsRequired"] = vec!["KHR_texture_transform"].into();
        j["extensionsUsed"] = vec!["KHR_texture_transform"].into();
    })
    .unwrap();
    assert!(has_warning(
        &ok.warnings,
        "/extensionsRequired/0",
        "only affects materials"
    ));
}

#[test]
fn truncated_glb_is_reported_not_panicked() {
    let bytes = std::fs::read(fixture("skin_basic.glb")).unwrap();
    let e = import_slice(&bytes[..100], Path::new("cut.glb")).unwrap_err();
    assert!(matches!(e.problem, Problem::Truncated(_)), "{e}");
    assert_eq!(e.location.byte_offset, Some(8));
    assert!(e.to_string().contains("truncated"), "{e}");
    for len in 0..bytes.len() {
        if let Ok(i) = import_slice(&bytes[..len], Path::new("cut.glb")) {
            panic!("prefix of {len} bytes imported: {:?}", i.asset.name);
        }
    }
}

#[test]
fn glb_header_and_chunk_errors_have_byte_offsets() {
    let good = std::fs::read(fixture("skin_basic.glb")).unwrap();
    let mut v1 = good.clone();
    v1[4] = 1;
    let e = import_slice(&v1, Path::new("v1.glb")).unwrap_err();
    assert_eq!(e.location.byte_offset, Some(4), "{e}");
    let mut bin_first = good.clone();
    bin_first[16..20].copy_from_slice(b"BIN\0");
    let e = import_slice(&bin_first, Path::new("b.glb")).unwrap_err();
    assert_eq!(e.location.byte_offset, Some(16), "{e}");
    let e = import_slice(b"glTF\x02\0\0\0", Path::new("h.glb")).unwrap_err();
    assert!(matches!(e.problem, Problem::Truncated(_)), "{e}");
}

#[test]
fn glb_byte_flips_never_panic() {
    let good = std::fs::read(fixture("skin_basic.glb")).unwrap();
    for i in 0..good.len() {
        for value in [0x00, 0xff, b'9'] {
            let mut bytes = good.clone();
            bytes[i] = value;
            let _ = import_slice(&bytes, Path::new("flip.glb"));
        }
    }
}

#[test]
fn joint_index_out_of_range_names_the_joints_attribute() {
    let e = import_edited("skin_weights.gltf", |j| {
        j["skins"][0]["joints"] = vec![1, 2].into()
    })
    .unwrap_err();
    assert_eq!(
        json_path(&e),
        "/meshes/0/primitives/0/attributes/JOINTS_0",
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("names joint 2, but skin 0 has 2 joints"),
        "{e}"
    );
}

#[test]
fn nan_position_is_an_error() {
    let e = import_slice(
        &triangle_glb(&[0.0, 0.0, 0.0, 1.0, f32::NAN, 0.0, 0.0, 1.0, 0.0]),
        Path::new("nan.glb"),
    )
    .unwrap_err();
    assert_eq!(json_path(&e), "/meshes/0/primitives/0/attributes/POSITION");
    assert!(e.to_string().contains("element 1 is not finite"), "{e}");
    let ok = import_slice(
        &triangle_glb(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
        Path::new("ok.glb"),
    )
    .unwrap();
    assert_eq!(ok.asset.meshes[0].positions.len(), 3);
}

#[test]
fn accessor_without_buffer_view_is_zeros() {
    // glTF 2.0 §3.6.2.1; gltf-json 1.4 alone would reject it as missing bufferView.
    let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
            "nodes":[{"mesh":0}],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
            "accessors":[{"componentType":5126,"count":3,"type":"VEC3",
                          "min":[0,0,0],"max":[0,0,0]}]}"#;
    let ok = import_slice(json.as_bytes(), Path::new("zeros.gltf")).unwrap();
    assert_eq!(ok.asset.meshes[0].positions, [Vec3::ZERO; 3]);
    let huge = json.replace(r#""count":3"#, r#""count":100000000"#);
    let e = import_slice(huge.as_bytes(), Path::new("huge.gltf")).unwrap_err();
    assert!(e.to_string().contains("no bufferView"), "{e}");
}

#[test]
fn accessor_data_out_of_range_is_an_error() {
    let e = import_edited("skin_basic.gltf", |j| {
        j["accessors"][0]["byteOffset"] = 4.into()
    })
    .unwrap_err();
    assert_eq!(
        json_path(&e),
        "/meshes/0/primitives/0/attributes/POSITION",
        "{e}"
    );
    assert!(e.to_string().contains("which holds 72 bytes"), "{e}");
    let e = import_edited("skin_basic.gltf", |j| {
        j["bufferViews"][4]["byteLength"] = 100_000.into()
    })
    .unwrap_err();
    assert_eq!(
        json_path(&e),
        "/meshes/0/primitives/0/attributes/JOINTS_0",
        "{e}"
    );
    assert!(e.to_string().contains("buffer view 4 spans"), "{e}");
    let e =
        import_edited("skin_basic.gltf", |j| j["accessors"][0]["count"] = 0.into()).unwrap_err();
    assert!(e.to_string().contains("count 0"), "{e}");
    let e = import_edited("skin_basic.gltf", |j| {
        j["accessors"][0]["type"] = "VEC2".into()
    })
    .unwrap_err();
    assert!(
        e.to_string()
            .contains("is VEC2 of FLOAT; expected VEC3 of FLOAT"),
        "{e}"
    );
    let e = import_edited("skin_basic.gltf", |j| {
        j["buffers"][0]["byteLength"] = 5000.into()
    })
    .unwrap_err();
    assert!(matches!(e.problem, Problem::Truncated(_)), "{e}");
    assert_eq!(json_path(&e), "/buffers/0");
}

#[test]
fn node_hierarchy_errors_name_the_children_entry() {
    let doc =
        |nodes: &str| format!(r#"{{"asset":{{"version":"2.0"}},"nodes":{nodes}}}"#).into_bytes();
    let e = import_slice(
        &doc(r#"[{"children":[2]},{"children":[2]},{}]"#),
        Path::new("p.gltf"),
    )
    .unwrap_err();
    assert_eq!(json_path(&e), "/nodes/1/children/0", "{e}");
    assert!(e.to_string().contains("already a child of node 0"), "{e}");
    let e = import_slice(
        &doc(r#"[{"children":[1]},{"children":[0]}]"#),
        Path::new("c.gltf"),
    )
    .unwrap_err();
    assert!(e.to_string().contains("cycle"), "{e}");
    assert!(json_path(&e).ends_with("/children"), "{e}");
    let e = import_slice(&doc(r#"[{"children":[0]}]"#), Path::new("s.gltf")).unwrap_err();
    assert_eq!(json_path(&e), "/nodes/0/children/0", "{e}");
    // No scenes: every node, with a note.
    let ok = import_slice(
        &doc(r#"[{"children":[1]},{"name":"b"}]"#),
        Path::new("n.gltf"),
    )
    .unwrap();
    assert_eq!(names(&ok.asset), ["node_0", "b"]);
    assert!(has_warning(&ok.warnings, "/nodes", "no scenes"));
}

#[test]
fn bad_key_times_are_errors() {
    let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
            "nodes":[{"name":"J"}],
            "animations":[{"samplers":[{"input":0,"output":1}],
                           "channels":[{"sampler":0,"target":{"node":0,"path":"translation"}}]}],
            "buffers":[{"byteLength":32}],
            "bufferViews":[{"buffer":0,"byteLength":8},{"buffer":0,"byteOffset":8,"byteLength":24}],
            "accessors":[{"bufferView":0,"componentType":5126,"count":2,"type":"SCALAR",
                          "min":[0],"max":[1]},
                         {"bufferView":1,"componentType":5126,"count":2,"type":"VEC3"}]}"#;
    let bin = |t0: f32, t1: f32| floats(&[t0, t1, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
    let ok = import_slice(&glb(json, &bin(0.0, 1.0)), Path::new("t.glb")).unwrap();
    assert_eq!(ok.asset.clips[0].tracks[0].times, [0.0, 1.0]);
    let e = import_slice(&glb(json, &bin(1.0, 1.0)), Path::new("t.glb")).unwrap_err();
    assert_eq!(json_path(&e), "/animations/0/samplers/0/input", "{e}");
    assert!(e.to_string().contains("increase strictly"), "{e}");
    let e = import_slice(&glb(json, &bin(-1.0, 1.0)), Path::new("t.glb")).unwrap_err();
    assert!(e.to_string().contains("negative"), "{e}");
}

#[test]
fn base64_and_percent_decoding() {
    assert_eq!(decode_base64("TWFu").unwrap(), b"Man");
    assert_eq!(decode_base64("TWE=").unwrap(), b"Ma");
    assert_eq!(decode_base64("TQ==").unwrap(), b"M");
    assert_eq!(decode_base64("").unwrap(), b"");
    assert!(decode_base64("T").is_none());
    assert!(decode_base64("TW!u").is_none());
    assert_eq!(percent_decode("a%20b%2").unwrap(), "a b%2");
    assert!(percent_decode("%ff").is_none());
}

// --- corpus -------------------------------------------------------------------------

/// A corpus file, or `None` (with a message) when the corpus is absent; on CI a missing
/// corpus is a failure.
fn corpus(rel: &str) -> Option<PathBuf> {
    rigport_testkit::corpus(&format!("5_gltf/{rel}"))
}

fn import_corpus(rel: &str) -> Option<Imported> {
    let path = corpus(rel)?;
    Some(import(&path).unwrap_or_else(|e| panic!("{e}")))
}

/// Every track of every clip has `keys` keys from `first` to `last` seconds.
fn assert_keys(clip: &Clip, tracks: usize, keys: usize, first: f32, last: f32) {
    assert_eq!(clip.tracks.len(), tracks, "{}", clip.name);
    for t in &clip.tracks {
        assert_eq!(t.times.len(), keys, "{:?}", t.target);
        assert!((t.times[0] - first).abs() < 1e-4, "{:?}", t.times);
        assert!((t.times[keys - 1] - last).abs() < 1e-4, "{:?}", t.times);
    }
}

#[test]
fn corpus_rigged_simple() {
    let Some(Imported { asset, warnings }) =
        import_corpus("khronos_samples__nobuyuki83_delfem2/RiggedSimple.glb")
    else {
        return;
    };
    assert_eq!(
        asset.skeleton.len(),
        4,
        "5 nodes less the skinned mesh node"
    );
    assert_eq!(asset.meshes.len(), 1);
    assert_eq!(asset.meshes[0].name, "Cylinder");
    assert_eq!(asset.meshes[0].vertex_count(), 96);
    assert_eq!(asset.meshes[0].triangles.len(), 564 / 3);
    assert_eq!(asset.skins[0].joints.len(), 2);
    // COLLADA2GLTF: rest * inverse bind is the root node's Z-up to Y-up matrix for
    // every joint (bind pose = rest pose seen through the root).
    let root = asset.skeleton.joint(JointIndex(0)).rest_local.to_mat4();
    assert!(rest_times_inv_bind(&asset).is_some_and(|m| m.abs_diff_eq(root, 1e-4)));
    assert!(root.abs_diff_eq(Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2), 1e-6));
    assert_eq!(asset.clips.len(), 1);
    assert_eq!(asset.clips[0].name, "animation_0");
    assert_keys(&asset.clips[0], 6, 3, 0.041_666, 2.083_333);
    // The skinned mesh node sits under the Z-up-to-Y-up root matrix.
    assert!(has_warning(
        &warnings,
        "/nodes/1",
        "skinned mesh node has a transform"
    ));
    assert!(has_warning(&warnings, "/nodes", "4 unnamed node(s)"));
}

#[test]
fn corpus_rigged_figure() {
    let Some(Imported { asset, warnings }) =
        import_corpus("khronos_samples__nobuyuki83_delfem2/RiggedFigure.glb")
    else {
        return;
    };
    assert_eq!(
        asset.skeleton.len(),
        21,
        "22 nodes less the skinned mesh node"
    );
    assert_eq!(asset.meshes.len(), 1);
    assert_eq!(asset.meshes[0].name, "Proxy");
    assert_eq!(asset.meshes[0].vertex_count(), 370);
    assert_eq!(asset.meshes[0].triangles.len(), 768 / 3);
    assert_eq!(asset.skins[0].joints.len(), 19);
    // COLLADA2GLTF: rest * inverse bind is the root node's Z-up to Y-up matrix for
    // every joint (bind pose = rest pose seen through the root).
    let root = asset.skeleton.joint(JointIndex(0)).rest_local.to_mat4();
    assert!(rest_times_inv_bind(&asset).is_some_and(|m| m.abs_diff_eq(root, 1e-4)));
    assert!(root.abs_diff_eq(Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2), 1e-6));
    assert_eq!(asset.clips.len(), 1);
    assert_keys(&asset.clips[0], 57, 2, 0.0, 1.25);
    assert!(
        has_warning(&warnings, "WEIGHTS_0", "renormalized 31 weight rows"),
        "{warnings:?}"
    );
}

#[test]
fn corpus_cesium_man() {
    let Some(Imported { asset, warnings }) =
        import_corpus("khronos_samples__nobuyuki83_delfem2/CesiumMan.glb")
    else {
        return;
    };
    assert_eq!(
        asset.skeleton.len(),
        21,
        "22 nodes less the skinned mesh node"
    );
    assert_eq!(asset.meshes.len(), 1);
    let mesh = &asset.meshes[0];
    assert_eq!(mesh.name, "Cesium_Man");
    assert_eq!(mesh.vertex_count(), 3273);
    assert_eq!(mesh.triangles.len(), 14016 / 3);
    assert!(mesh.uvs.is_some() && mesh.normals.is_some());
    assert_eq!(asset.skins[0].joints.len(), 19);
    assert!(asset.skins[0].influences.max_per_vertex() <= 4);
    // COLLADA2GLTF: rest * inverse bind is the root node's Z-up to Y-up matrix for
    // every joint (bind pose = rest pose seen through the root).
    let root = asset.skeleton.joint(JointIndex(0)).rest_local.to_mat4();
    assert!(rest_times_inv_bind(&asset).is_some_and(|m| m.abs_diff_eq(root, 1e-4)));
    assert!(root.abs_diff_eq(Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2), 1e-6));
    assert_eq!(asset.clips.len(), 1);
    assert_keys(&asset.clips[0], 57, 49, 0.0, 2.0);
    assert!(
        has_warning(&warnings, "WEIGHTS_0", "renormalized 210 weight rows"),
        "{warnings:?}"
    );
}

#[test]
fn corpus_simple_skin() {
    let Some(Imported { asset, warnings }) =
        import_corpus("bevy_assets__bevyengine_bevy/SimpleSkin.gltf")
    else {
        return;
    };
    assert_eq!(asset.skeleton.len(), 3);
    // The skinned mesh node is the parent of the joints.
    let parents: Vec<_> = asset.skeleton.parents().collect();
    assert_eq!(parents, [None, Some(JointIndex(0)), Some(JointIndex(1))]);
    assert_eq!(asset.meshes[0].name, "mesh_0");
    assert_eq!(asset.meshes[0].vertex_count(), 10);
    assert_eq!(asset.meshes[0].triangles.len(), 8);
    assert_eq!(asset.skins[0].joints, [JointIndex(1), JointIndex(2)]);
    // The inverse binds place the mesh 0.5 to the -X of the rest pose.
    let offset = rest_times_inv_bind(&asset).unwrap();
    assert!(offset.abs_diff_eq(Mat4::from_translation(Vec3::new(-0.5, 0.0, 0.0)), 1e-6));
    assert_eq!(asset.clips.len(), 1);
    assert_keys(&asset.clips[0], 1, 12, 0.0, 5.5);
    // Keys are up to 2.3e-4 off unit length: normalized silently (within tolerance).
    for q in asset.clips[0].tracks[0].values.chunks_exact(4) {
        let len = q.iter().map(|c| c * c).sum::<f32>().sqrt();
        assert!((len - 1.0).abs() < 1e-6, "{q:?}");
    }
    assert!(
        has_warning(&warnings, "/scenes", "no default scene"),
        "{warnings:?}"
    );
}

#[test]
fn corpus_blender_skinned_cylinder() {
    let Some(Imported { asset, warnings }) =
        import_corpus("blender_io_roundtrip__KhronosGroup/03_skinned_cylinder.gltf")
    else {
        return;
    };
    // Nodes are stored children first; the skeleton is parents first.
    assert_eq!(
        names(&asset),
        [
            "Root",
            "Cylinder",
            "Root.001",
            "Joint_One",
            "Joint_Two",
            "Joint_Three",
            "Joint_Four",
            "Camera"
        ]
    );
    assert_eq!(asset.meshes[0].name, "Cylinder");
    assert_eq!(asset.meshes[0].vertex_count(), 750);
    assert_eq!(asset.meshes[0].triangles.len(), 948 / 3);
    assert!(asset.meshes[0].uvs.is_some());
    let palette: Vec<&str> = asset.skins[0]
        .joints
        .iter()
        .map(|j| asset.skeleton.joint(*j).name.as_str())
        .collect();
    assert_eq!(
        palette,
        ["Joint_One", "Joint_Two", "Joint_Three", "Joint_Four"]
    );
    // The rest pose is bent (Joint_Three 30 degrees, Joint_Four 15 more about X), the
    // bind pose straight: rest * inverse bind is the identity for the first two only.
    let model = asset.skeleton.model_rest_matrices();
    let skin = &asset.skins[0];
    let offsets: Vec<bool> = skin
        .joints
        .iter()
        .zip(&skin.inv_bind)
        .map(|(j, ib)| (model[j.get()] * *ib).abs_diff_eq(Mat4::IDENTITY, 1e-4))
        .collect();
    assert_eq!(offsets, [true, true, false, false]);
    assert_eq!(asset.clips.len(), 1);
    assert_eq!(asset.clips[0].name, "SkeletonAnimation_Root.001");
    assert_keys(&asset.clips[0], 12, 49, 0.0, 2.0);
    assert!(warnings.is_empty(), "{warnings:?}");
}

/// The Khronos validator's negative tests: each may import or fail, never panic.
#[test]
fn corpus_validator_negative_tests_never_panic() {
    let Some(dir) = corpus("validator_negative_tests__KhronosGroup") else {
        return;
    };
    let mut files = Vec::new();
    let mut stack = vec![dir];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|e| e == "gltf" || e == "glb") {
                files.push(p);
            }
        }
    }
    files.sort();
    assert!(!files.is_empty());
    for file in &files {
        let result = std::panic::catch_unwind(|| import(file));
        match result {
            Ok(Ok(i)) => eprintln!("ok   {}: {} warnings", file.display(), i.warnings.len()),
            Ok(Err(e)) => eprintln!("err  {e}"),
            Err(_) => panic!("{} panicked", file.display()),
        }
    }
}

#[test]
fn extensions_used_but_not_read_are_a_coded_warning() {
    let imported = import_edited("skin_basic.gltf", |j| {
        j["extensionsUsed"] = vec!["KHR_materials_emissive_strength", "KHR_lights_punctual"].into();
    })
    .unwrap();
    let lost: Vec<_> = imported
        .warnings
        .iter()
        .filter(|w| w.to_string().contains("extensions not imported"))
        .collect();
    assert_eq!(lost.len(), 1, "{:?}", imported.warnings);
    assert_eq!(lost[0].code(), "W004");
    assert!(lost[0].to_string().contains("KHR_lights_punctual"));
}
