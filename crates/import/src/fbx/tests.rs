//! FBX importer tests: error classes on bytes made here, and the corpus's files.

use std::path::Path;

use rigport_model::glam::Vec3;
use rigport_testkit::corpus;

use super::*;

const FBX: &str = "7_fbx/assimp_test_models__assimp";

fn error_of(bytes: &[u8]) -> ImportError {
    match import_slice(bytes, Path::new("x.fbx")) {
        Ok(_) => panic!("imported a broken file"),
        Err(e) => e,
    }
}

#[test]
fn garbage_after_the_binary_magic_is_an_unsupported_version_at_byte_23() {
    let mut bytes = b"Kaydara FBX Binary  \0\x1a\0".to_vec();
    bytes.extend((0..600u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8 | 0x80));
    let e = error_of(&bytes);
    assert_eq!(e.location.to_string(), "x.fbx: at byte 23", "{e}");
    assert!(e.to_string().contains("unsupported FBX version"), "{e}");
}

#[test]
fn a_binary_record_past_the_end_is_truncated_at_its_offset() {
    let mut bytes = b"Kaydara FBX Binary  \0\x1a\0".to_vec();
    bytes.extend(7400u32.to_le_bytes());
    // One record that claims to end at byte 5000 of a file of 60 bytes.
    bytes.extend(5000u32.to_le_bytes());
    bytes.extend(0u32.to_le_bytes());
    bytes.extend(0u32.to_le_bytes());
    bytes.push(18);
    bytes.extend(b"FBXHeaderExtension");
    let e = error_of(&bytes);
    assert_eq!(e.location.to_string(), "x.fbx: at byte 27", "{e}");
    assert!(matches!(e.problem, Problem::Truncated(_)), "{e}");
    assert!(e.to_string().contains("\"FBXHeaderExtension\""), "{e}");
}

#[test]
fn an_ascii_file_cut_inside_a_block_is_truncated_at_its_last_line() {
    let text = "; FBX 7.3.0 project file\nFBXHeaderExtension:  {\n\tFBXHeaderVersion: 1003\n\tFBXVersion: 7300\nObjects:  {\n\tModel: 1, \"Model::a\", \"Mesh\" {\n\t\tVersion: 2";
    let e = error_of(text.as_bytes());
    assert_eq!(e.location.to_string(), "x.fbx:7", "{e}");
    assert!(e.to_string().contains("opened on line 6"), "{e}");
}

#[test]
fn empty_input_is_empty() {
    assert!(matches!(error_of(b"  \n").problem, Problem::Empty));
}

#[test]
fn skinned_corpus_file_keeps_bones_clusters_and_every_influence() {
    let Some(path) = corpus(&format!("{FBX}/huesitos.fbx")) else {
        return;
    };
    let imported = import(&path).expect("imports");
    let asset = &imported.asset;
    assert!(asset.meters_per_unit.is_some_and(|m| m > 0.0));
    assert_eq!(asset.skins.len(), 1);
    let skin = &asset.skins[0];
    assert_eq!(skin.joints.len(), skin.inv_bind.len());
    // Every joint of the palette is a bone or lies above one; parents come first.
    for (k, joint) in asset.skeleton.joints().iter().enumerate() {
        assert!(joint.parent.is_none_or(|p| (p.0 as usize) < k));
    }
    // The clusters' weights reach the mesh: every vertex has at least one influence.
    assert!(skin.influences.rows().all(|row| !row.is_empty()));
    assert_eq!(asset.clips.len(), 1);
}

#[test]
fn every_animation_stack_is_a_named_clip() {
    let Some(path) = corpus(&format!("{FBX}/multiple_animations_test.fbx")) else {
        return;
    };
    let asset = import(&path).expect("imports").asset;
    let names: Vec<&str> = asset.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["anim 1", "anim 2", "spin"]);
    for clip in &asset.clips {
        assert!(clip.tracks.iter().all(|t| t.times.first() >= Some(&0.0)));
        assert!(clip.duration() > 0.0);
    }
}

#[test]
fn a_file_without_bones_or_animation_is_static_meshes() {
    let Some(path) = corpus(&format!("{FBX}/spider.fbx")) else {
        return;
    };
    let imported = import(&path).expect("imports");
    let asset = &imported.asset;
    assert!(asset.skeleton.is_empty());
    assert!(asset.skins.is_empty() && asset.clips.is_empty());
    assert!(!asset.meshes.is_empty());
    assert!(asset.meshes.iter().all(|m| m.material.is_some()));
    // Its textures are paths on the author's disk: warnings, not errors.
    assert!(imported
        .warnings
        .iter()
        .any(|w| matches!(w, Warning::Incomplete { message, .. } if message.contains("texture"))));
}

/// A triangle with a Phong material: a base colour texture, a normal map, a bump map, an
/// emissive colour and a transparency (ASCII FBX 7.4; textures beside it).
const PHONG: &str = r#"; FBX 7.4.0 project file
FBXHeaderExtension:  {
	FBXHeaderVersion: 1003
	FBXVersion: 7400
}
Objects:  {
	Geometry: 10, "Geometry::tri", "Mesh" {
		Vertices: *9 {
			a: 0,0,0,1,0,0,0,1,0
		}
		PolygonVertexIndex: *3 {
			a: 0,1,-3
		}
		GeometryVersion: 124
		LayerElementUV: 0 {
			Version: 101
			Name: "map1"
			MappingInformationType: "ByPolygonVertex"
			ReferenceInformationType: "Direct"
			UV: *6 {
				a: 0,0,1,0,0,1
			}
		}
		LayerElementMaterial: 0 {
			Version: 101
			Name: ""
			MappingInformationType: "AllSame"
			ReferenceInformationType: "IndexToDirect"
			Materials: *1 {
				a: 0
			}
		}
		Layer: 0 {
			Version: 100
			LayerElement:  {
				Type: "LayerElementUV"
				TypedIndex: 0
			}
			LayerElement:  {
				Type: "LayerElementMaterial"
				TypedIndex: 0
			}
		}
	}
	Model: 20, "Model::tri", "Mesh" {
		Version: 232
	}
	Material: 30, "Material::shiny", "" {
		Version: 102
		ShadingModel: "phong"
		Properties70:  {
			P: "DiffuseColor", "Color", "", "A",0.5,0.25,1
			P: "EmissiveColor", "Color", "", "A",1,0.5,0
			P: "EmissiveFactor", "Number", "", "A",0.5
			P: "TransparentColor", "Color", "", "A",1,1,1
			P: "TransparencyFactor", "Number", "", "A",0.25
		}
	}
	Texture: 40, "Texture::base", "" {
		Type: "TextureVideoClip"
		FileName: "base.png"
		RelativeFilename: "base.png"
	}
	Texture: 41, "Texture::normals", "" {
		Type: "TextureVideoClip"
		FileName: "normals.png"
		RelativeFilename: "normals.png"
	}
	Texture: 42, "Texture::bumps", "" {
		Type: "TextureVideoClip"
		FileName: "bumps.png"
		RelativeFilename: "bumps.png"
	}
}
Connections:  {
	C: "OO",20,0
	C: "OO",10,20
	C: "OO",30,20
	C: "OP",40,30, "DiffuseColor"
	C: "OP",41,30, "NormalMap"
	C: "OP",42,30, "Bump"
}
"#;

#[test]
fn phong_keeps_emission_normal_map_and_transparency_and_names_the_bump_it_loses() {
    let dir = tempfile::tempdir().unwrap();
    // The importer keeps an image's bytes as they are; any bytes do.
    for (name, byte) in [("base.png", 1u8), ("normals.png", 2), ("bumps.png", 3)] {
        let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
        png.push(byte);
        std::fs::write(dir.path().join(name), png).unwrap();
    }
    let path = dir.path().join("phong.fbx");
    std::fs::write(&path, PHONG).unwrap();
    let imported = import(&path).unwrap();
    let m = &imported.asset.materials[0];
    let image = |t: &Option<rigport_model::TextureRef>| {
        imported.asset.images[t.as_ref().expect("a texture").image.get()]
            .name
            .clone()
    };
    assert_eq!(image(&m.base_color_texture), "base.png");
    assert_eq!(image(&m.normal_texture), "normals.png");
    assert_eq!(m.emissive_factor, [0.5, 0.25, 0.0]);
    // Opacity 1 - 0.25 x TransparentColor (white).
    assert!((m.base_color_factor[3] - 0.75).abs() < 1e-6, "{m:?}");
    assert_eq!(m.alpha_mode, rigport_model::AlphaMode::Blend);
    assert_eq!((m.metallic_factor, m.roughness_factor), (0.0, 1.0));
    let lost: Vec<String> = imported.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(lost.len(), 1, "{lost:?}");
    assert!(
        lost[0].contains("shiny") && lost[0].contains("textures on Bump are not kept"),
        "{lost:?}"
    );
    assert_eq!(imported.warnings[0].code(), "W004");
}

/// A triangle bound to one bone whose `Lcl` pose (x + 5) is not its bind pose (the
/// identity `TransformLink`), as Blender writes a file at a frame other than the rest.
const POSED_BONE: &str = "; FBX 7.4.0 project file
FBXHeaderExtension:  {
\tFBXHeaderVersion: 1003
\tFBXVersion: 7400
}
Objects:  {
\tGeometry: 10, \"Geometry::tri\", \"Mesh\" {
\t\tVertices: *9 {
\t\t\ta: 0,0,0,1,0,0,0,1,0
\t\t}
\t\tPolygonVertexIndex: *3 {
\t\t\ta: 0,1,-3
\t\t}
\t}
\tModel: 20, \"Model::tri\", \"Mesh\" {
\t}
\tModel: 30, \"Model::bone\", \"LimbNode\" {
\t\tProperties70:  {
\t\t\tP: \"Lcl Translation\", \"Lcl Translation\", \"\", \"A\",5,0,0
\t\t}
\t}
\tDeformer: 40, \"Deformer::skin\", \"Skin\" {
\t}
\tDeformer: 50, \"SubDeformer::cluster\", \"Cluster\" {
\t\tIndexes: *3 {
\t\t\ta: 0,1,2
\t\t}
\t\tWeights: *3 {
\t\t\ta: 1,1,1
\t\t}
\t\tTransform: *16 {
\t\t\ta: 1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1
\t\t}
\t\tTransformLink: *16 {
\t\t\ta: 1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1
\t\t}
\t}
}
Connections:  {
\tC: \"OO\",20,0
\tC: \"OO\",10,20
\tC: \"OO\",30,0
\tC: \"OO\",40,10
\tC: \"OO\",50,40
\tC: \"OO\",30,50
}
";

#[test]
fn skinned_points_sit_at_the_bind_pose_not_the_loaded_pose() {
    // FBX SDK: the cluster's TransformLink is the bone at bind time; the mesh's points at
    // bind time are TransformLink x Transform x point, whatever pose the bone's Lcl
    // properties hold (ufbx's `geometry_to_world` would put them at x + 5).
    let imported = import_slice(POSED_BONE.as_bytes(), Path::new("x.fbx")).expect("imports");
    let mesh = &imported.asset.meshes[0];
    let xs: Vec<f32> = mesh.positions.iter().map(|p| p.x).collect();
    let lo = xs.iter().copied().fold(f32::MAX, f32::min);
    let hi = xs.iter().copied().fold(f32::MIN, f32::max);
    assert!(
        lo.abs() < 1e-6 && (hi - 1.0).abs() < 1e-6,
        "{:?}",
        mesh.positions
    );
}

/// A triangle with one blend channel holding an in-between shape at 50% (vertex 1 moved
/// up by one unit) and its full shape at 100% (up by one and out by two): the channel is
/// piecewise linear in its weight. `DEFORM` is replaced by the channel's `DeformPercent`.
const IN_BETWEEN: &str = "; FBX 7.4.0 project file
FBXHeaderExtension:  {
\tFBXHeaderVersion: 1003
\tFBXVersion: 7400
}
Objects:  {
\tGeometry: 10, \"Geometry::tri\", \"Mesh\" {
\t\tVertices: *9 {
\t\t\ta: 0,0,0,1,0,0,0,1,0
\t\t}
\t\tPolygonVertexIndex: *3 {
\t\t\ta: 0,1,-3
\t\t}
\t}
\tModel: 20, \"Model::tri\", \"Mesh\" {
\t}
\tGeometry: 60, \"Geometry::half\", \"Shape\" {
\t\tVersion: 100
\t\tIndexes: *1 {
\t\t\ta: 1
\t\t}
\t\tVertices: *3 {
\t\t\ta: 0,1,0
\t\t}
\t}
\tGeometry: 61, \"Geometry::full\", \"Shape\" {
\t\tVersion: 100
\t\tIndexes: *1 {
\t\t\ta: 1
\t\t}
\t\tVertices: *3 {
\t\t\ta: 2,1,0
\t\t}
\t}
\tDeformer: 70, \"Deformer::blend\", \"BlendShape\" {
\t\tVersion: 100
\t}
\tDeformer: 80, \"SubDeformer::smile\", \"BlendShapeChannel\" {
\t\tVersion: 100
\t\tDeformPercent: DEFORM
\t\tFullWeights: *2 {
\t\t\ta: 50,100
\t\t}
\t\tProperties70:  {
\t\t\tP: \"DeformPercent\", \"Number\", \"\", \"A\",DEFORM
\t\t}
\t}
}
Connections:  {
\tC: \"OO\",20,0
\tC: \"OO\",10,20
\tC: \"OO\",70,10
\tC: \"OO\",80,70
\tC: \"OO\",60,80
\tC: \"OO\",61,80
}
";

#[test]
fn in_between_shapes_blend_as_ufbx_evaluates_them() {
    for percent in ["0", "25", "50", "75", "100", "130", "-20"] {
        let text = IN_BETWEEN.replace("DEFORM", percent);
        let imported = import_slice(text.as_bytes(), Path::new("x.fbx")).expect("imports");
        assert!(
            imported.warnings.iter().all(|w| w.code() != "W004"),
            "{:?}",
            imported.warnings
        );
        let mesh = &imported.asset.meshes[0];
        assert_eq!(mesh.morph_targets.len(), 2, "one target per shape");
        // The reference: ufbx's own blend of the channel at this weight.
        let scene = ufbx::load_memory(text.as_bytes(), ufbx::LoadOpts::default()).unwrap();
        let blend = &scene.blend_deformers[0];
        for (v, &point) in mesh.source_vertex.iter().enumerate() {
            let o = ufbx::get_blend_vertex_offset(blend, point as usize);
            let expected = Vec3::new(o.x as f32, o.y as f32, o.z as f32);
            let ours: Vec3 = (mesh.morph_targets.iter())
                .zip(&mesh.morph_weights)
                .map(|(t, &w)| t.position_deltas[v] * w)
                .sum();
            assert!(
                ours.distance(expected) < 1e-5,
                "{percent}%: vertex {v}: {ours} vs ufbx {expected}"
            );
            if percent == "75" && point == 1 {
                // Halfway from the in-between (0, 1, 0) to the full shape (2, 1, 0).
                assert!(ours.distance(Vec3::new(1.0, 1.0, 0.0)) < 1e-5, "{ours}");
            }
        }
    }
}

/// A three-bone chain with what Maya and 3ds Max write beyond plain TRS: a rotation pivot
/// and scaling pivot, pre- and post-rotation, a rotation offset, a parent scaled by 2, and
/// the child's `InheritType` (`INHERIT`: 0 RrSs, 1 RSrs, 2 Rrs, Maya's segment scale
/// compensate: the child ignores its parent's scale).
///
/// Not exact, and warned about instead: a *non-uniform* parent scale with a scaling pivot
/// or a child's rotation offset. ufbx then adds a scale helper node (its inherit-mode
/// compensation is exact for uniform scale only), and the helper drops those offsets: the
/// child lands up to 0.15 units (5% of the bone) from where ufbx's own evaluation without
/// compensation puts it (`a_non_uniform_scale_over_segment_scale_compensate_is_warned`).
const PIVOTS: &str = "; FBX 7.4.0 project file
FBXHeaderExtension:  {
\tFBXHeaderVersion: 1003
\tFBXVersion: 7400
}
Objects:  {
\tNodeAttribute: 130, \"NodeAttribute::\", \"LimbNode\" {
\t\tTypeFlags: \"Skeleton\"
\t}
\tNodeAttribute: 131, \"NodeAttribute::\", \"LimbNode\" {
\t\tTypeFlags: \"Skeleton\"
\t}
\tNodeAttribute: 132, \"NodeAttribute::\", \"LimbNode\" {
\t\tTypeFlags: \"Skeleton\"
\t}
\tModel: 30, \"Model::root\", \"LimbNode\" {
\t\tProperties70:  {
\t\t\tP: \"RotationActive\", \"bool\", \"\", \"\",1
\t\t\tP: \"PreRotation\", \"Vector3D\", \"Vector\", \"\",90,0,0
\t\t\tP: \"RotationPivot\", \"Vector3D\", \"Vector\", \"\",0.5,0,0
\t\t\tP: \"ScalingPivot\", \"Vector3D\", \"Vector\", \"\",0,0.25,0
\t\t\tP: \"Lcl Translation\", \"Lcl Translation\", \"\", \"A\",1,2,3
\t\t\tP: \"Lcl Rotation\", \"Lcl Rotation\", \"\", \"A\",0,0,30
\t\t\tP: \"Lcl Scaling\", \"Lcl Scaling\", \"\", \"A\",2,2,2
\t\t}
\t}
\tModel: 31, \"Model::mid\", \"LimbNode\" {
\t\tProperties70:  {
\t\t\tP: \"RotationActive\", \"bool\", \"\", \"\",1
\t\t\tP: \"InheritType\", \"enum\", \"\", \"\",INHERIT
\t\t\tP: \"PostRotation\", \"Vector3D\", \"Vector\", \"\",0,0,20
\t\t\tP: \"RotationOffset\", \"Vector3D\", \"Vector\", \"\",0.1,0,0
\t\t\tP: \"Lcl Translation\", \"Lcl Translation\", \"\", \"A\",0,3,0
\t\t\tP: \"Lcl Rotation\", \"Lcl Rotation\", \"\", \"A\",0,45,0
\t\t\tP: \"Lcl Scaling\", \"Lcl Scaling\", \"\", \"A\",1,0.5,1
\t\t}
\t}
\tModel: 32, \"Model::tip\", \"LimbNode\" {
\t\tProperties70:  {
\t\t\tP: \"Lcl Translation\", \"Lcl Translation\", \"\", \"A\",0,2,0
\t\t}
\t}
}
Connections:  {
\tC: \"OO\",30,0
\tC: \"OO\",31,30
\tC: \"OO\",32,31
\tC: \"OO\",130,30
\tC: \"OO\",131,31
\tC: \"OO\",132,32
}
";

#[test]
fn pivots_pre_post_rotation_and_segment_scale_compensate_place_joints_as_ufbx_does() {
    for inherit in ["0", "1", "2"] {
        let text = PIVOTS.replace("INHERIT", inherit);
        let imported = import_slice(text.as_bytes(), Path::new("x.fbx")).expect("imports");
        let skeleton = &imported.asset.skeleton;
        let world = skeleton.model_rest_matrices();
        let scene = ufbx::load_memory(text.as_bytes(), ufbx::LoadOpts::default()).unwrap();
        let checked =
            assert_joints_at_nodes(skeleton, &world, &scene, &format!("InheritType {inherit}"));
        assert_eq!(checked, 3);
    }
}

/// Asserts that every named node of `scene` (not its root) is a joint of `skeleton` whose
/// model matrix in `world` puts the origin and a point one unit along each axis where the
/// node's `node_to_world` does, within 1e-4 (`label` in messages); returns how many.
fn assert_joints_at_nodes(
    skeleton: &rigport_model::Skeleton,
    world: &[rigport_model::glam::Mat4],
    scene: &ufbx::Scene,
    label: &str,
) -> usize {
    let nodes = scene
        .nodes
        .iter()
        .filter(|n| !n.is_root && !n.element.name.is_empty());
    let mut checked = 0;
    for node in nodes {
        let names: Vec<&str> = skeleton.joints().iter().map(|j| j.name.as_str()).collect();
        let j = (skeleton.find(&node.element.name))
            .unwrap_or_else(|| panic!("{label}: {:?} not among {names:?}", node.element.name));
        let expected = super::skeleton::mat(&node.node_to_world).as_mat4();
        for p in [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z] {
            let (ours, theirs) = (
                world[j.get()].transform_point3(p),
                expected.transform_point3(p),
            );
            assert!(
                ours.distance(theirs) < 1e-4,
                "{label}: {}: {p} -> {ours} vs ufbx {theirs}",
                node.element.name
            );
        }
        checked += 1;
    }
    checked
}

#[test]
fn a_non_uniform_scale_over_segment_scale_compensate_is_warned() {
    let drift_warnings = |inherit: &str, scale: &str| {
        let text = PIVOTS
            .replace("INHERIT", inherit)
            .replace("\"A\",2,2,2", &format!("\"A\",{scale}"));
        let imported = import_slice(text.as_bytes(), Path::new("x.fbx")).expect("imports");
        (imported.warnings.iter())
            .filter(|w| w.to_string().contains("has no exact joint transform"))
            .map(ToString::to_string)
            .collect::<Vec<_>>()
    };
    // RrSs (0) and Rrs (2, segment scale compensate) under a parent scaled 2, 1, 1: the
    // helper drops mid's rotation offset (0.1 units, 2.5% of the skeleton).
    for inherit in ["0", "2"] {
        let warned = drift_warnings(inherit, "2,1,1");
        assert_eq!(warned.len(), 1, "InheritType {inherit}: {warned:?}");
        assert!(
            warned[0].contains("x.fbx: mid: placed 1.000e-1 units (2.52%"),
            "{}",
            warned[0]
        );
        // Uniform scale is compensated exactly: no warning.
        assert!(
            drift_warnings(inherit, "2,2,2").is_empty(),
            "InheritType {inherit}"
        );
    }
    // The standard inherit type (RSrs) needs no helper.
    assert!(drift_warnings("1", "2,1,1").is_empty());
}

/// [`PIVOTS`] with Rrs (segment scale compensate) on `mid` and one stack that scales the
/// root's X from 2 to 3 over a second: the only curve is on the root, yet ufbx bakes `mid`
/// too (its inherit type makes its own transform follow the parent's scale). Without the
/// scaling pivot and rotation offset, which ufbx's scale helper cannot carry under a
/// non-uniform scale (see [`PIVOTS`]).
fn animated_pivots() -> String {
    let anim = "\tAnimationStack: 900, \"AnimStack::grow\", \"\" {
\t}
\tAnimationLayer: 901, \"AnimLayer::BaseLayer\", \"\" {
\t}
\tAnimationCurveNode: 902, \"AnimCurveNode::S\", \"\" {
\t\tProperties70:  {
\t\t\tP: \"d|X\", \"Number\", \"\", \"A\",2
\t\t\tP: \"d|Y\", \"Number\", \"\", \"A\",2
\t\t\tP: \"d|Z\", \"Number\", \"\", \"A\",2
\t\t}
\t}
\tAnimationCurve: 903, \"AnimCurve::\", \"\" {
\t\tDefault: 2
\t\tKeyVer: 4009
\t\tKeyTime: *2 {
\t\t\ta: 0,46186158000
\t\t}
\t\tKeyValueFloat: *2 {
\t\t\ta: 2,3
\t\t}
\t\tKeyAttrFlags: *1 {
\t\t\ta: 4
\t\t}
\t\tKeyAttrDataFloat: *4 {
\t\t\ta: 0,0,0,0
\t\t}
\t\tKeyAttrRefCount: *1 {
\t\t\ta: 2
\t\t}
\t}
}
Connections:  {
\tC: \"OO\",901,900
\tC: \"OO\",902,901
\tC: \"OP\",902,30, \"Lcl Scaling\"
\tC: \"OP\",903,902, \"d|X\"
";
    PIVOTS
        .replace("INHERIT", "2")
        .replace(
            "\t\t\tP: \"ScalingPivot\", \"Vector3D\", \"Vector\", \"\",0,0.25,0\n",
            "",
        )
        .replace(
            "\t\t\tP: \"RotationOffset\", \"Vector3D\", \"Vector\", \"\",0.1,0,0\n",
            "",
        )
        .replace("}\nConnections:  {\n", anim)
}

#[test]
fn nodes_baked_for_their_inherit_type_alone_become_animated_joints() {
    let text = animated_pivots();
    let scene = super::load::load(text.as_bytes(), Path::new("x.fbx")).unwrap();
    let baked = super::anim::bake(&scene, Path::new("x.fbx")).unwrap();
    let (guess, real) = (
        super::anim::curve_nodes(&scene),
        super::anim::animated_nodes(&baked),
    );
    // The case the importer builds twice: the curves name fewer nodes than ufbx bakes.
    assert!(
        guess.len() < real.len() && guess.is_subset(&real),
        "{guess:?} {real:?}"
    );
    let imported = import_slice(text.as_bytes(), Path::new("x.fbx")).expect("imports");
    let asset = &imported.asset;
    let clip = &asset.clips[0];
    assert_eq!(clip.name, "grow");
    let mid = asset.skeleton.find("mid").expect("mid is a joint");
    assert!(
        clip.tracks.iter().any(|t| joint_of(t.target) == Some(mid)),
        "mid has tracks of its own: {:?}",
        clip.tracks.iter().map(|t| t.target).collect::<Vec<_>>()
    );
    // Every joint where ufbx's own evaluation of the stack puts it, mid-way.
    let t = 0.5;
    let skeleton = &asset.skeleton;
    let world = joint_world_at(asset, clip, t);
    let anim = &scene.anim_stacks[0].anim;
    let at = ufbx::evaluate_scene(&scene, anim, f64::from(t), ufbx::EvaluateOpts::default())
        .expect("ufbx evaluates the stack");
    let checked = assert_joints_at_nodes(skeleton, &world, &at, "mid-way");
    assert_eq!(checked, 3);
}

#[test]
fn an_animated_non_uniform_scale_over_an_offset_is_warned() {
    // animated_pivots() with mid's rotation offset kept: at rest the scale is uniform
    // (2, 2, 2), but the stack makes it (3, 2, 2), and the helper drops the offset.
    let text = animated_pivots().replace(
        "\t\t\tP: \"InheritType\", \"enum\", \"\", \"\",2\n",
        "\t\t\tP: \"InheritType\", \"enum\", \"\", \"\",2\n\t\t\tP: \"RotationOffset\", \"Vector3D\", \"Vector\", \"\",0.1,0,0\n",
    );
    let imported = import_slice(text.as_bytes(), Path::new("x.fbx")).expect("imports");
    let warned: Vec<String> = (imported.warnings.iter())
        .map(ToString::to_string)
        .filter(|w| w.contains("has no exact joint transform"))
        .collect();
    assert_eq!(warned.len(), 1, "{:?}", imported.warnings);
    // Without the offset the helper is exact: no warning.
    let exact = import_slice(animated_pivots().as_bytes(), Path::new("x.fbx")).unwrap();
    assert!(exact
        .warnings
        .iter()
        .all(|w| !w.to_string().contains("no exact joint")));
}

/// The joint a track animates, if any.
fn joint_of(target: rigport_model::TrackTarget) -> Option<rigport_model::JointIndex> {
    use rigport_model::TrackTarget::{Rotation, Scale, Translation};
    match target {
        Translation(j) | Rotation(j) | Scale(j) => Some(j),
        _ => None,
    }
}

/// Every joint's model-space matrix at clip time `t` (forward kinematics written here, on
/// the tracks as the model defines them: lerp, shortest-path slerp).
fn joint_world_at(
    asset: &rigport_model::Asset,
    clip: &rigport_model::Clip,
    t: f32,
) -> Vec<rigport_model::glam::Mat4> {
    use rigport_model::TrackTarget::{Rotation, Scale, Translation};
    let mut world: Vec<rigport_model::glam::Mat4> = Vec::new();
    for (j, joint) in asset.skeleton.joints().iter().enumerate() {
        let mut local = joint.rest_local;
        for track in
            (clip.tracks.iter()).filter(|tr| joint_of(tr.target).map(|x| x.get()) == Some(j))
        {
            let keys = rigport_model::interp::Keys::of(track);
            let mut v = [0.0f32; 3];
            match track.target {
                Translation(_) => {
                    keys.sample(t, &mut v);
                    local.translation = v.into();
                }
                Scale(_) => {
                    keys.sample(t, &mut v);
                    local.scale = v.into();
                }
                Rotation(_) => {
                    local.rotation = rigport_model::glam::Quat::from_array(keys.sample_rotation(t));
                }
                _ => {}
            }
        }
        let m = local.to_mat4();
        world.push(match joint.parent {
            Some(p) => world[p.get()] * m,
            None => m,
        });
    }
    world
}

/// Every corpus FBX clip's key values are what ufbx's own evaluation of the stack gives
/// at that key time: each joint's local translation (within 1e-5 of the skeleton's size),
/// rotation (1e-5 rad) and scale (1e-5). The keys are ufbx's bake samples: the source's
/// keys, and 30 a second where ufbx resamples a curve; a curve keyed at 19.5 or more keys
/// a second is not resampled (`BakeOpts::minimum_sample_rate`), and the clip is linear
/// between its keys, as Blender and three.js read such curves too.
#[test]
fn corpus_clip_keys_are_ufbx_evaluation_of_the_stacks() {
    use rigport_model::TrackTarget::{Rotation, Scale, Translation};
    let Some(dir) = corpus(FBX) else {
        return;
    };
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("fbx")))
        .collect();
    files.sort();
    let mut clips = 0;
    for path in &files {
        let bytes = std::fs::read(path).unwrap();
        let asset = import_slice(&bytes, path).unwrap().asset;
        let scene = super::load::load(&bytes, path).unwrap();
        let (lo, hi) = (asset.skeleton.model_rest_matrices().iter())
            .map(|m| m.w_axis.truncate())
            .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| (lo.min(p), hi.max(p)));
        // One unit for a skeleton of one joint.
        let size = match (hi - lo).length() {
            0.0 => 1.0,
            d => d,
        };
        for (clip, stack) in asset.clips.iter().zip(scene.anim_stacks.iter()) {
            let first_key = (stack.anim.layers.iter())
                .flat_map(|l| l.anim_values.iter())
                .flat_map(|v| v.curves.iter().flatten())
                .filter_map(|c| c.keyframes.first().map(|k| k.time))
                .fold(f64::MAX, f64::min);
            let offset = stack.time_begin.min(first_key);
            let mut times: Vec<f32> = clip
                .tracks
                .iter()
                .flat_map(|t| t.times.iter().copied())
                .collect();
            times.sort_by(f32::total_cmp);
            times.dedup();
            // (translation / size, rotation radians, scale) worst, with where.
            let mut worst = [
                (0.0f32, String::new()),
                (0.0, String::new()),
                (0.0, String::new()),
            ];
            for &t in &times {
                let opts = ufbx::EvaluateOpts::default();
                let at = ufbx::evaluate_scene(&scene, &stack.anim, offset + f64::from(t), opts)
                    .expect("ufbx evaluates the stack");
                for track in &clip.tracks {
                    let Some(j) = joint_of(track.target) else {
                        continue;
                    };
                    let Some(k) = track.times.iter().position(|&x| x == t) else {
                        continue;
                    };
                    let name = &asset.skeleton.joint(j).name;
                    let Some(node) = at.nodes.iter().find(|n| &*n.element.name == name.as_str())
                    else {
                        continue;
                    };
                    let local = &node.local_transform;
                    let v = track.key_value(k);
                    let (slot, d) = match track.target {
                        Translation(_) => (
                            0,
                            Vec3::from_slice(v).distance(super::skeleton::vec3(&local.translation))
                                / size,
                        ),
                        Rotation(_) => {
                            // The angle between the two, in f64: an f32 `acos` near 1 cannot
                            // tell apart rotations closer than 6.9e-4 rad.
                            let q = local.rotation;
                            let theirs = rigport_model::glam::DQuat::from_xyzw(q.x, q.y, q.z, q.w);
                            let ours = rigport_model::glam::Quat::from_slice(v).as_dquat();
                            let d = ours.conjugate() * theirs;
                            (1, (2.0 * d.xyz().length().atan2(d.w.abs())) as f32)
                        }
                        Scale(_) => (
                            2,
                            Vec3::from_slice(v).distance(super::skeleton::vec3(&local.scale)),
                        ),
                        _ => continue,
                    };
                    if d > worst[slot].0 {
                        worst[slot] = (d, format!("{name} at {t} s"));
                    }
                }
            }
            eprintln!(
                "{} [{}]: {} key times, worst translation {:.2e} of the size ({}), rotation {:.2e} rad ({}), scale {:.2e} ({})",
                path.file_name().unwrap().to_string_lossy(),
                clip.name,
                times.len(),
                worst[0].0, worst[0].1, worst[1].0, worst[1].1, worst[2].0, worst[2].1,
            );
            assert!(
                worst.iter().all(|w| w.0 < 1e-5),
                "{} [{}]: {worst:?}",
                path.display(),
                clip.name
            );
            clips += 1;
        }
    }
    assert!(clips >= 6, "{clips} clips compared");
}
