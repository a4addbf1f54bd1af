//! COLLADA importer tests: small documents written here, one feature each, and one test
//! per error class with its line.

use std::path::Path;

use rigport_model::glam::{Quat, Vec3};
use rigport_model::{TrackTarget, UpAxis};

use super::*;

/// A document with `asset` inside `<asset>` and `body` after it.
pub(super) fn dae(asset: &str, body: &str) -> String {
    format!(
        "<?xml version=\"1.0\"?>\n<COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" \
         version=\"1.4.1\">\n<asset>{asset}</asset>\n{body}\n</COLLADA>\n"
    )
}

/// A visual scene holding `nodes`, with `libraries` before it.
pub(super) fn scene(libraries: &str, nodes: &str) -> String {
    dae(
        "",
        &format!(
            "{libraries}\n<library_visual_scenes><visual_scene id=\"s\">\n{nodes}\n\
             </visual_scene></library_visual_scenes>\n<scene><instance_visual_scene url=\"#s\"/></scene>"
        ),
    )
}

pub(super) fn import_str(text: &str) -> Imported {
    match import_slice(text.as_bytes(), Path::new("t.dae")) {
        Ok(i) => i,
        Err(e) => panic!("{e}"),
    }
}

pub(super) fn error_of(text: &str) -> ImportError {
    match import_slice(text.as_bytes(), Path::new("t.dae")) {
        Ok(_) => panic!("imported a broken document"),
        Err(e) => e,
    }
}

/// The 1-based line of the first line of `text` holding `needle`.
pub(super) fn line_of(text: &str, needle: &str) -> usize {
    1 + text
        .lines()
        .position(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("{needle:?} not in the document"))
}

pub(super) fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

/// A unit quad (4 positions, 1 normal) as a `<geometry id="quad">` whose one primitive
/// is `primitive`.
pub(super) fn quad(primitive: &str) -> String {
    format!(
        "<library_geometries><geometry id=\"quad\" name=\"Quad\"><mesh>\n\
         <source id=\"p\"><float_array id=\"pa\" count=\"12\">0 0 0 1 0 0 1 1 0 0 1 0</float_array>\n\
         <technique_common><accessor source=\"#pa\" count=\"4\" stride=\"3\"><param name=\"X\" type=\"float\"/>\
         <param name=\"Y\" type=\"float\"/><param name=\"Z\" type=\"float\"/></accessor></technique_common></source>\n\
         <source id=\"n\"><float_array id=\"na\" count=\"3\">0 0 1</float_array>\n\
         <technique_common><accessor source=\"#na\" count=\"1\" stride=\"3\"/></technique_common></source>\n\
         <vertices id=\"v\"><input semantic=\"POSITION\" source=\"#p\"/></vertices>\n\
         {primitive}\n</mesh></geometry></library_geometries>"
    )
}

#[test]
fn transform_elements_compose_in_document_order() {
    // translate then rotate: the rotation applies first, so the child's offset turns.
    let text = scene(
        "",
        "<node id=\"a\" type=\"JOINT\"><translate>1 0 0</translate><rotate>0 0 1 90</rotate>\n\
         <node id=\"b\" type=\"JOINT\"><translate>1 0 0</translate></node></node>\n\
         <node id=\"c\" type=\"JOINT\"><rotate>0 0 1 90</rotate><translate>1 0 0</translate></node>",
    );
    let asset = import_str(&text).asset;
    let j = asset.skeleton.joints();
    assert_eq!(j.len(), 3);
    let world_b = j[0].rest_local.to_mat4() * j[1].rest_local.to_mat4();
    assert!(close(world_b.w_axis.truncate(), Vec3::new(1.0, 1.0, 0.0)));
    // rotate then translate: the translation is turned.
    assert!(close(j[2].rest_local.translation, Vec3::new(0.0, 1.0, 0.0)));
    let expected = Quat::from_rotation_z(90f32.to_radians());
    assert!(j[2].rest_local.rotation.dot(expected).abs() > 1.0 - 1e-6);
}

#[test]
fn unit_and_up_axis_give_the_scene_frame() {
    let text = dae(
        "<unit name=\"centimeter\" meter=\"0.01\"/><up_axis>Z_UP</up_axis>",
        "<library_visual_scenes><visual_scene id=\"s\"><node id=\"a\" type=\"JOINT\"/></visual_scene></library_visual_scenes>",
    );
    let asset = import_str(&text).asset;
    assert_eq!(asset.meters_per_unit, Some(0.01));
    assert_eq!(asset.frame.up_axis, UpAxis::Z);
    // X_UP: +X in the file is up (+Y) in the model's frame, -Y is +X.
    let text = dae(
        "<up_axis>X_UP</up_axis>",
        "<library_visual_scenes><visual_scene id=\"s\"><node id=\"a\" type=\"JOINT\"/></visual_scene></library_visual_scenes>",
    );
    let asset = import_str(&text).asset;
    assert_eq!(asset.meters_per_unit, Some(1.0));
    let m = asset.frame.model_to_gltf(asset.meters_per_unit);
    let up = m.transform_point3(rigport_model::glam::DVec3::X);
    assert!(
        (up - rigport_model::glam::DVec3::Y).length() < 1e-12,
        "{up}"
    );
    let right = m.transform_point3(-rigport_model::glam::DVec3::Y);
    assert!(
        (right - rigport_model::glam::DVec3::X).length() < 1e-12,
        "{right}"
    );
}

#[test]
fn polylist_and_triangles_share_input_offsets_and_keep_polygons() {
    let poly = "<polylist count=\"1\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/>\
                <input semantic=\"NORMAL\" source=\"#n\" offset=\"1\"/><vcount>4</vcount>\
                <p>0 0 1 0 2 0 3 0</p></polylist>";
    let text = scene(
        &quad(poly),
        "<node id=\"m\"><instance_geometry url=\"#quad\"/></node>",
    );
    let mesh = &import_str(&text).asset.meshes[0];
    assert_eq!(mesh.name, "Quad");
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(mesh.polygons, vec![4]);
    assert_eq!(mesh.source_vertex, vec![0, 1, 2, 3]);
    assert!(mesh
        .normals
        .as_ref()
        .is_some_and(|n| n.iter().all(|n| close(*n, Vec3::Z))));
    // Triangles: one index per input per corner; a repeated tuple is one vertex.
    let tris = "<triangles count=\"2\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/>\
                <input semantic=\"NORMAL\" source=\"#n\" offset=\"1\"/>\
                <p>0 0 1 0 2 0 0 0 2 0 3 0</p></triangles>";
    let text = scene(
        &quad(tris),
        "<node id=\"m\"><instance_geometry url=\"#quad\"/></node>",
    );
    let mesh = &import_str(&text).asset.meshes[0];
    assert_eq!(mesh.positions.len(), 4);
    assert!(mesh.polygons.is_empty());
    assert!(close(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0)));
}

/// A skin of the quad on joint `j` with `bind_shape`; every vertex fully on `j`.
pub(super) fn skinned(bind_shape: &str) -> String {
    let tris = "<triangles count=\"2\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/>\
                <p>0 1 2 0 2 3</p></triangles>";
    let controllers = format!(
        "{}\n<library_controllers><controller id=\"skin\"><skin source=\"#quad\">\n\
         <bind_shape_matrix>{bind_shape}</bind_shape_matrix>\n\
         <source id=\"jn\"><Name_array id=\"jna\" count=\"1\">J</Name_array>\
         <technique_common><accessor source=\"#jna\" count=\"1\"/></technique_common></source>\n\
         <source id=\"ib\"><float_array id=\"iba\" count=\"16\">1 0 0 0 0 1 0 -2 0 0 1 0 0 0 0 1</float_array>\
         <technique_common><accessor source=\"#iba\" count=\"1\" stride=\"16\"/></technique_common></source>\n\
         <source id=\"w\"><float_array id=\"wa\" count=\"1\">1</float_array>\
         <technique_common><accessor source=\"#wa\" count=\"1\"/></technique_common></source>\n\
         <joints><input semantic=\"JOINT\" source=\"#jn\"/><input semantic=\"INV_BIND_MATRIX\" source=\"#ib\"/></joints>\n\
         <vertex_weights count=\"4\"><input semantic=\"JOINT\" source=\"#jn\" offset=\"0\"/>\
         <input semantic=\"WEIGHT\" source=\"#w\" offset=\"1\"/>\n<vcount>1 1 1 1</vcount>\n\
         <v>0 0 0 0 0 0 0 0</v></vertex_weights>\n</skin></controller></library_controllers>",
        quad(tris)
    );
    scene(
        &controllers,
        "<node id=\"root\" sid=\"root\" type=\"JOINT\"><translate>0 2 0</translate>\
         <node id=\"jnode\" sid=\"J\" name=\"arm\" type=\"JOINT\"/></node>\n\
         <node id=\"m\"><translate>9 9 9</translate><instance_controller url=\"#skin\"><skeleton>#root</skeleton></instance_controller></node>",
    )
}

#[test]
fn skin_applies_the_bind_shape_matrix_and_reads_row_major_inverse_binds() {
    let asset = import_str(&skinned("1 0 0 0 0 1 0 0 0 0 1 5 0 0 0 1")).asset;
    let mesh = &asset.meshes[0];
    // The bind shape moves the points by +5 z; the instance node's own transform does not
    // apply to a skinned mesh.
    assert!(close(mesh.positions[2], Vec3::new(1.0, 1.0, 5.0)));
    assert_eq!(mesh.attached_to, None);
    let skin = &asset.skins[0];
    // The joint is found by its sid below the <skeleton> root.
    assert_eq!(asset.skeleton.joint(skin.joints[0]).name, "arm");
    assert!(close(
        skin.inv_bind[0].w_axis.truncate(),
        Vec3::new(0.0, -2.0, 0.0)
    ));
    assert!(skin
        .influences
        .rows()
        .all(|r| r.len() == 1 && r[0].weight == 1.0));
}

/// One joint `j` whose `<rotate sid="rz">` is animated by `channels` (inside
/// `<library_animations>`), plus `clips`.
fn animated(channels: &str, clips: &str) -> String {
    scene(
        &format!("<library_animations>{channels}</library_animations>{clips}"),
        "<node id=\"j\" type=\"JOINT\"><rotate sid=\"rz\">0 0 1 0</rotate></node>",
    )
}

/// An `<animation id>` driving `target` with keys `times`/`values`, all LINEAR.
fn animation(id: &str, target: &str, times: &str, values: &str) -> String {
    let n = times.split_whitespace().count();
    format!(
        "<animation id=\"{id}\">\n\
         <source id=\"{id}-i\"><float_array id=\"{id}-ia\" count=\"{n}\">{times}</float_array>\
         <technique_common><accessor source=\"#{id}-ia\" count=\"{n}\"/></technique_common></source>\n\
         <source id=\"{id}-o\"><float_array id=\"{id}-oa\" count=\"{n}\">{values}</float_array>\
         <technique_common><accessor source=\"#{id}-oa\" count=\"{n}\"/></technique_common></source>\n\
         <sampler id=\"{id}-s\"><input semantic=\"INPUT\" source=\"#{id}-i\"/><input semantic=\"OUTPUT\" source=\"#{id}-o\"/></sampler>\n\
         <channel source=\"#{id}-s\" target=\"{target}\"/>\n</animation>"
    )
}

#[test]
fn a_rotate_angle_channel_keeps_a_full_turn_between_keys() {
    let text = animated(&animation("a", "j/rz.ANGLE", "0 1", "0 360"), "");
    let asset = import_str(&text).asset;
    assert_eq!(asset.clips.len(), 1);
    assert_eq!(asset.clips[0].name, "t");
    let track = asset.clips[0]
        .tracks
        .iter()
        .find(|t| matches!(t.target, TrackTarget::Rotation(_)))
        .expect("a rotation track");
    // 360 degrees in steps of at most 90: keys at 0, 0.25, 0.5, 0.75, 1.
    assert_eq!(track.times, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
    let at = |k: usize| Quat::from_slice(&track.values[4 * k..4 * k + 4]);
    let half = Quat::from_rotation_z(std::f32::consts::PI);
    assert!(at(2).dot(half).abs() > 1.0 - 1e-6, "{:?}", at(2));
    // Sign-continuous, so slerp turns the same way all along.
    for k in 1..5 {
        assert!(at(k - 1).dot(at(k)) > 0.0);
    }
}

#[test]
fn animation_clips_split_the_timeline_into_named_clips() {
    let channels = format!(
        "{}{}",
        animation("first", "j/rz.ANGLE", "0 1", "0 45"),
        animation("second", "j/rz.ANGLE", "2 3", "0 -45")
    );
    let clips = "<library_animation_clips>\
        <animation_clip id=\"c1\" name=\"wave\" start=\"0\" end=\"1\"><instance_animation url=\"#first\"/></animation_clip>\
        <animation_clip id=\"c2\" name=\"bow\" start=\"2\" end=\"3\"><instance_animation url=\"#second\"/></animation_clip>\
        </library_animation_clips>";
    let asset = import_str(&animated(&channels, clips)).asset;
    let names: Vec<&str> = asset.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["wave", "bow"]);
    for clip in &asset.clips {
        assert!((clip.duration() - 1.0).abs() < 1e-6, "{}", clip.duration());
        let r = clip
            .tracks
            .iter()
            .find(|t| matches!(t.target, TrackTarget::Rotation(_)))
            .expect("rotation");
        assert_eq!(r.times.first(), Some(&0.0));
    }
    // The second clip's last key is -45 degrees about z.
    let r = &asset.clips[1].tracks[1];
    let last = Quat::from_slice(&r.values[r.values.len() - 4..]);
    assert!(last.dot(Quat::from_rotation_z(-45f32.to_radians())).abs() > 1.0 - 1e-6);
}

#[test]
fn collada_is_told_by_its_root_element() {
    assert!(is_collada(
        b"<?xml version=\"1.0\"?>\n<!-- made by hand -->\n<COLLADA version=\"1.4.1\">"
    ));
    assert!(is_collada(b"\xEF\xBB\xBF<COLLADA>"));
    assert!(!is_collada(b"<?xml version=\"1.0\"?><COLLADAX>"));
    assert!(!is_collada(b"<svg>"));
    assert!(!is_collada(b""));
}

#[test]
fn the_fixture_chains_skin_over_morph_with_its_material_and_clips() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/collada");
    for file in ["skinned_quad.dae", "skinned_quad.zae"] {
        let imported = match import(&root.join(file)) {
            Ok(i) => i,
            Err(e) => panic!("{e}"),
        };
        let asset = &imported.asset;
        assert_eq!(asset.meters_per_unit, Some(0.01), "{file}");
        assert_eq!(asset.frame.up_axis, UpAxis::Z);
        let mesh = &asset.meshes[0];
        assert_eq!(mesh.polygons, vec![4]);
        // NORMALIZED morph: target - base, default weight from MORPH_WEIGHT.
        assert_eq!(mesh.morph_weights, vec![0.25]);
        assert!(close(
            mesh.morph_targets[0].position_deltas[2],
            Vec3::new(0.0, -5.0, 0.0)
        ));
        // The skin over the morph: two joints, the last vertices split half and half.
        let skin = &asset.skins[0];
        assert_eq!(skin.influences.vertex(2).len(), 2);
        assert!(close(
            skin.inv_bind[1].w_axis.truncate(),
            Vec3::new(0.0, 0.0, -10.0)
        ));
        let names: Vec<&str> = asset.clips.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["bend", "spin"]);
        // The texture is absent on purpose: a W004 warning at the <image> line.
        assert!(imported.warnings.iter().any(|w| matches!(
            w,
            rigport_model::Warning::Incomplete { location, message }
                if location.contains(":10:5: element <image>") && message.contains("checker.png")
        )));
        assert!(mesh.material.is_some() && asset.images.is_empty());
    }
}

#[test]
fn every_loss_is_a_coded_warning_at_its_element() {
    let warnings_of = |text: &str| -> Vec<String> {
        import_str(text)
            .warnings
            .iter()
            .map(|w| {
                assert_eq!(w.code(), "W004", "{w}");
                w.to_string()
            })
            .collect()
    };
    let clean = scene(
        &quad(
            "<triangles count=\"2\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/>\
             <p>0 1 2 0 2 3</p></triangles>",
        ),
        "<node id=\"m\"><instance_geometry url=\"#quad\"/></node>",
    );
    assert!(warnings_of(&clean).is_empty());
    // Vertex colours, named at their <input>.
    let coloured = scene(
        &quad(
            "<triangles count=\"2\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/>\
             <input semantic=\"COLOR\" source=\"#n\" offset=\"1\"/>\
             <p>0 0 1 0 2 0 0 0 2 0 3 0</p></triangles>",
        ),
        "<node id=\"m\"><instance_geometry url=\"#quad\"/></node>",
    );
    let w = warnings_of(&coloured);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("element <input>") && w[0].contains("vertex colours"),
        "{w:?}"
    );
    // A polygon with a hole keeps its outer ring.
    let holed = scene(
        &quad(
            "<polygons count=\"1\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/>\
             <ph><p>0 1 2 3</p><h>0 1 2</h></ph></polygons>",
        ),
        "<node id=\"m\"><instance_geometry url=\"#quad\"/></node>",
    );
    let w = warnings_of(&holed);
    assert!(w.len() == 1 && w[0].contains("element <h>"), "{w:?}");
    // A joint with a skew.
    let skewed = skinned("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1").replace(
        "<node id=\"jnode\" sid=\"J\" name=\"arm\" type=\"JOINT\"/>",
        "<node id=\"jnode\" sid=\"J\" name=\"arm\" type=\"JOINT\"><skew>30 1 0 0 0 1 0</skew></node>",
    );
    let w = warnings_of(&skewed);
    assert!(
        w.len() == 1 && w[0].contains("shear") && w[0].contains("\"arm\""),
        "{w:?}"
    );
    // Influences on joint -1 (the bind shape).
    let on_shape = skinned("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1")
        .replace("<vcount>1 1 1 1</vcount>", "<vcount>2 1 1 1</vcount>")
        .replace("<v>0 0 0 0 0 0 0 0</v>", "<v>0 0 -1 0 0 0 0 0 0 0</v>");
    let w = warnings_of(&on_shape);
    assert!(
        w.len() == 1 && w[0].contains("1 influences on joint -1"),
        "{w:?}"
    );
}
