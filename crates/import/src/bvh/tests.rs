use glam::{DMat3, DMat4, DVec3, Mat4, Quat, Vec3};
use rigport_model::conventions::EulerOrder;
use rigport_model::{Interpolation, TrackTarget};

use super::motion::{frame_values, frames_on_two_threads, PARALLEL_MOTION_BYTES};
use super::*;

const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/bvh");
const CORPUS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/corpus/4_bvh");
const CORPUS_FILES: [&str; 4] = [
    "bandai_namco_ds1/dataset-1_dash_normal_001.bvh",
    "bandai_namco_ds1/dataset-1_kick_normal_001.bvh",
    "bandai_namco_ds1/dataset-1_walk_normal_002.bvh",
    "cmu_cgspeed__nobuyuki83_delfem2/walk.bvh",
];
const KICK: &str = "bandai_namco_ds1/dataset-1_kick_normal_001.bvh";

/// Lines: 1 HIERARCHY, 2 ROOT, 3 {, 4 OFFSET, 5 CHANNELS, 6 JOINT, 7 {, 8 OFFSET,
/// 9 CHANNELS, 10 End Site, 11 {, 12 OFFSET, 13 }, 14 }, 15 }, 16 MOTION, 17 Frames,
/// 18 Frame Time, 19-20 frames.
const BASE: &str = "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  JOINT Spine\n  {\n    OFFSET 0 1 0\n    CHANNELS 1 Xrotation\n    End Site\n    {\n      OFFSET 0 1 0\n    }\n  }\n}\nMOTION\nFrames: 2\nFrame Time: 0.5\n1 2 3 4\n5 6 7 8\n";

/// `BASE` with its 1-based line `n` replaced by `with` (which may hold several lines).
fn base_with(n: usize, with: &str) -> String {
    BASE.split('\n')
        .enumerate()
        .map(|(i, l)| if i + 1 == n { with } else { l })
        .collect::<Vec<_>>()
        .join("\n")
}

fn parse_str(text: &str) -> Result<Bvh, ImportError> {
    parse(text, Path::new("t.bvh"))
}

fn err(text: &str) -> String {
    match parse_str(text) {
        Ok(b) => panic!("parsed: {b:?}"),
        Err(e) => e.to_string(),
    }
}

fn fixture(name: &str) -> (Bvh, Imported) {
    let path = Path::new(FIXTURES).join(name);
    let text = std::fs::read_to_string(&path).unwrap();
    let bvh = parse(&text, &path).unwrap_or_else(|e| panic!("{e}"));
    let imported = import(&path).unwrap_or_else(|e| panic!("{e}"));
    (bvh, imported)
}

/// FORMATS.md evaluated directly from the parsed channels, in f64 matrices: world
/// positions of the joints, then of the end sites.
fn reference_positions(bvh: &Bvh, k: usize) -> Vec<DVec3> {
    let frame = bvh.frame(k).unwrap();
    let mut world: Vec<DMat4> = Vec::new();
    for j in &bvh.joints {
        let mut t = j.offset.as_dvec3();
        let mut r = DMat3::IDENTITY;
        for (i, c) in j.channels.iter().enumerate() {
            let v = f64::from(frame[j.first_channel + i]);
            match c {
                Channel::Xposition => t.x = v,
                Channel::Yposition => t.y = v,
                Channel::Zposition => t.z = v,
                Channel::Xrotation => r *= DMat3::from_rotation_x(v.to_radians()),
                Channel::Yrotation => r *= DMat3::from_rotation_y(v.to_radians()),
                Channel::Zrotation => r *= DMat3::from_rotation_z(v.to_radians()),
            }
        }
        let local = DMat4::from_translation(t) * DMat4::from_mat3(r);
        world.push(match j.parent {
            Some(p) => world[p] * local,
            None => local,
        });
    }
    let mut out: Vec<DVec3> = world.iter().map(|m| m.w_axis.truncate()).collect();
    for e in &bvh.end_sites {
        out.push(world[e.parent].transform_point3(e.offset.as_dvec3()));
    }
    out
}

/// World positions of every asset joint at key `k`: rest transforms overridden by the
/// clip's key `k` values, composed in f32.
fn asset_positions(asset: &Asset, k: usize) -> Vec<Vec3> {
    let mut locals: Vec<Transform> = asset
        .skeleton
        .joints()
        .iter()
        .map(|j| j.rest_local)
        .collect();
    if let Some(clip) = asset.clips.first() {
        for track in &clip.tracks {
            let v = track.key_value(k);
            match track.target {
                TrackTarget::Translation(j) => locals[j.get()].translation = Vec3::from_slice(v),
                TrackTarget::Rotation(j) => locals[j.get()].rotation = Quat::from_slice(v),
                _ => panic!("unexpected track {:?}", track.target),
            }
        }
    }
    let mut world: Vec<Mat4> = Vec::new();
    for (joint, local) in asset.skeleton.joints().iter().zip(&locals) {
        let m = local.to_mat4();
        world.push(match joint.parent {
            Some(p) => world[p.get()] * m,
            None => m,
        });
    }
    world.iter().map(|m| m.w_axis.truncate()).collect()
}

/// Checks the imported asset against the parsed file on every frame: FK against the
/// reference, constant bone lengths for joints without position channels, unit and
/// sign-continuous rotation keys, key times. Returns the largest position error
/// relative to the figure's extent.
fn check_asset(bvh: &Bvh, imported: &Imported, label: &str) -> f64 {
    let asset = &imported.asset;
    assert!(asset.validate().is_ok(), "{label}");
    assert_eq!(asset.meters_per_unit, None);
    assert_eq!(
        asset.skeleton.len(),
        bvh.joints.len() + bvh.end_sites.len(),
        "{label}"
    );
    let clip = &asset.clips[0];
    let rotations = bvh
        .joints
        .iter()
        .filter(|j| j.channels.iter().any(|c| c.is_rotation()))
        .count();
    let positions = bvh
        .joints
        .iter()
        .filter(|j| j.channels.iter().any(|c| !c.is_rotation()))
        .count();
    assert_eq!(clip.tracks.len(), rotations + positions, "{label}");
    for track in &clip.tracks {
        assert_eq!(track.interpolation, Interpolation::Linear);
        assert_eq!(track.times.len(), bvh.frame_count, "{label}");
        for (k, t) in track.times.iter().enumerate() {
            assert!(
                (f64::from(*t) - k as f64 * bvh.frame_time).abs() < 1e-6 * (1.0 + f64::from(*t))
            );
        }
        if let TrackTarget::Rotation(_) = track.target {
            for w in track.values.chunks_exact(4).collect::<Vec<_>>().windows(2) {
                let (a, b) = (Quat::from_slice(w[0]), Quat::from_slice(w[1]));
                assert!((b.length() - 1.0).abs() < 1e-6, "{label}: {b}");
                assert!(a.dot(b) >= 0.0, "{label}: sign flip {a} -> {b}");
            }
        }
    }
    // Which asset joints keep a fixed distance to their parent.
    let rigid: Vec<bool> = bvh
        .joints
        .iter()
        .map(|j| j.parent.is_some() && j.channels.iter().all(|c| c.is_rotation()))
        .chain(bvh.end_sites.iter().map(|_| true))
        .collect();
    let mut worst = 0.0_f64;
    for k in 0..bvh.frame_count {
        let expected = reference_positions(bvh, k);
        let got = asset_positions(asset, k);
        let extent = expected
            .iter()
            .fold(1.0_f64, |m, p| m.max(p.abs().max_element()));
        for (i, (e, g)) in expected.iter().zip(&got).enumerate() {
            let error = (g.as_dvec3() - *e).length() / extent;
            worst = worst.max(error);
            // f32 composition of ~10 transforms of values up to `extent`: a few ulps
            // each (1 ulp = 6e-8 relative).
            assert!(
                error < 2e-6,
                "{label} frame {k} joint {i} ({}): {g} vs {e}, relative error {error:e}",
                asset.skeleton.joints()[i].name
            );
        }
        for (i, joint) in asset.skeleton.joints().iter().enumerate() {
            if let (true, Some(p)) = (rigid[i], joint.parent) {
                let length = (got[i] - got[p.get()]).length();
                let rest = joint.rest_local.translation.length();
                assert!(
                    (length - rest).abs() <= 2e-6 * extent as f32,
                    "{label} frame {k}: bone {} has length {length}, rest {rest}",
                    joint.name
                );
            }
        }
    }
    worst
}

#[test]
fn fixtures_match_reference_fk() {
    for (name, frames, frame_time) in [
        ("mixed_orders.bvh", 4, 0.04),
        ("crlf_tabs.bvh", 4, 0.04),
        ("joint_positions.bvh", 3, 0.0333333),
        ("end_sites.bvh", 2, 0.1),
        ("multiple_roots.bvh", 2, 0.5),
        ("duplicate_names.bvh", 1, 0.04),
        ("truncated.bvh", 3, 0.04),
        ("extra_frames.bvh", 2, 0.04),
    ] {
        let (bvh, imported) = fixture(name);
        assert_eq!(
            (bvh.frame_count, bvh.frame_time),
            (frames, frame_time),
            "{name}"
        );
        assert_eq!(imported.asset.name, name.trim_end_matches(".bvh"));
        assert_eq!(imported.asset.clips[0].name, imported.asset.name);
        let worst = check_asset(&bvh, &imported, name);
        println!("{name}: largest relative FK error {worst:e}");
    }
}

#[test]
fn quirks_fixture_imports_like_the_plain_one() {
    let (plain_bvh, plain) = fixture("mixed_orders.bvh");
    let (quirky_bvh, quirky) = fixture("crlf_tabs.bvh");
    assert!(plain.warnings.is_empty() && quirky.warnings.is_empty());
    assert_eq!(plain_bvh.motion, quirky_bvh.motion);
    assert_eq!(plain.asset.skeleton, quirky.asset.skeleton);
    assert_eq!(plain.asset.clips[0].tracks, quirky.asset.clips[0].tracks);
    let names: Vec<&str> = plain
        .asset
        .skeleton
        .joints()
        .iter()
        .map(|j| j.name.as_str())
        .collect();
    assert_eq!(
        names,
        [
            "Hips",
            "Spine",
            "Head",
            "LeftLeg",
            "LeftFoot",
            "RightLeg",
            "Head_end",
            "LeftFoot_end",
            "RightLeg_end"
        ]
    );
    let lines: Vec<usize> = plain_bvh.joints.iter().map(|j| j.line).collect();
    assert_eq!(lines, [2, 6, 10, 20, 24, 34]);
    assert_eq!(plain_bvh.motion_line, 44);
}

#[test]
fn rotation_channels_multiply_in_listed_order() {
    // R = Rz(90) · Rx(90): the end site (0, 1, 0) goes to Rz·(0, 0, 1) = (0, 0, 1).
    // The other order, Rx·Rz, would give (-1, 0, 0).
    let text = "HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n CHANNELS 2 Zrotation Xrotation\n End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\nFrames: 1\nFrame Time: 1\n90 90\n";
    let asset = to_asset("r", &parse_str(text).unwrap()).unwrap().asset;
    let end = asset_positions(&asset, 0)[1];
    assert!(end.abs_diff_eq(Vec3::Z, 1e-6), "{end}");
    // The model's conventions name `Zrotation Xrotation Yrotation` Yxz.
    let (bvh, imported) = fixture("mixed_orders.bvh");
    let hips = &imported.asset.clips[0].tracks[1];
    assert_eq!(hips.target, TrackTarget::Rotation(JointIndex(0)));
    for k in 0..bvh.frame_count {
        let [z, x, y] = bvh.frame(k).unwrap()[3..6] else {
            unreachable!()
        };
        let expected = EulerOrder::Yxz.to_quat_deg([x, y, z]);
        let got = Quat::from_slice(hips.key_value(k));
        assert!(
            got.dot(expected).abs() > 1.0 - 1e-6,
            "{k}: {got} vs {expected}"
        );
    }
}

#[test]
fn position_channels_replace_the_offset() {
    let (bvh, imported) = fixture("joint_positions.bvh");
    let asset = &imported.asset;
    let hips = asset.skeleton.find("Hips").unwrap();
    assert_eq!(
        asset.skeleton.joint(hips).rest_local.translation,
        Vec3::new(0.0, 90.0, -3.0)
    );
    let track = |target| {
        asset.clips[0]
            .tracks
            .iter()
            .find(|t| t.target == target)
            .unwrap()
    };
    assert_eq!(
        track(TrackTarget::Translation(hips)).key_value(1),
        [0.5, 88.0, -2.5]
    );
    // Tail has only Yposition: x and z stay the OFFSET's.
    let tail = asset.skeleton.find("Tail").unwrap();
    assert_eq!(bvh.joints[tail.get()].channels[1], Channel::Yposition);
    assert_eq!(
        track(TrackTarget::Translation(tail)).key_value(1),
        [-10.0, 2.0, 0.0]
    );
    // Its rotation skips the position channel: Zrotation 45, Xrotation -30, Yrotation 60.
    let expected = EulerOrder::Yxz.to_quat_deg([-30.0, 60.0, 45.0]);
    let got = Quat::from_slice(track(TrackTarget::Rotation(tail)).key_value(1));
    assert!(got.dot(expected).abs() > 1.0 - 1e-6, "{got} vs {expected}");
}

#[test]
fn fixture_features() {
    let names = |i: &Imported| -> Vec<String> {
        i.asset
            .skeleton
            .joints()
            .iter()
            .map(|j| j.name.clone())
            .collect()
    };
    let (bvh, ends) = fixture("end_sites.bvh");
    assert!(ends.warnings.is_empty(), "{:?}", ends.warnings);
    assert_eq!(
        names(&ends),
        [
            "Hips",
            "Head",
            "Head_end",
            "Hand",
            "Antenna",
            "Head_end_2",
            "Head_end_end",
            "Hand_end",
            "Hand_end_2"
        ]
    );
    let parents: Vec<usize> = bvh.end_sites.iter().map(|e| e.parent).collect();
    assert_eq!(parents, [1, 2, 3, 3]);
    let skeleton = &ends.asset.skeleton;
    assert_eq!(skeleton.joint(JointIndex(7)).parent, Some(JointIndex(3)));
    assert_eq!(
        skeleton.joint(JointIndex(8)).rest_local.translation,
        Vec3::new(1.0, 1.0, 0.0)
    );

    let (_, roots) = fixture("multiple_roots.bvh");
    let roots: Vec<&str> = roots
        .asset
        .skeleton
        .roots()
        .map(|r| roots.asset.skeleton.joint(r).name.as_str())
        .collect();
    assert_eq!(roots, ["Body", "Prop"]);

    let (_, dup) = fixture("duplicate_names.bvh");
    assert_eq!(
        names(&dup),
        ["Hips", "Arm", "Arm_2", "Arm_end", "Arm_2_end"]
    );
    assert_eq!(dup.warnings.len(), 1);
    assert!(
            dup.warnings[0].to_string().ends_with(
                "duplicate_names.bvh:15: repaired: joint name \"Arm\" is also used at line 6: renamed \"Arm_2\""
            ),
            "{}",
            dup.warnings[0]
        );

    let (bvh, truncated) = fixture("truncated.bvh");
    assert_eq!((bvh.frames_declared, bvh.frame_count), (5, 3));
    assert_eq!(bvh.motion.len(), 27);
    assert_eq!(truncated.warnings.len(), 1);
    let Warning::Incomplete { location, message } = &truncated.warnings[0] else {
        panic!("{:?}", truncated.warnings)
    };
    assert!(location.ends_with("truncated.bvh:22"), "{location}");
    assert_eq!(
            message,
            "`Frames: 5` but the file holds 3 complete frames (the cut-off frame at line 22 is dropped): the clip has 3"
        );

    let (bvh, extra) = fixture("extra_frames.bvh");
    assert_eq!((bvh.frames_declared, bvh.frame_count), (2, 2));
    assert_eq!(bvh.motion, [0.0, 0.0, 0.0, 10.0, 0.0, 0.0]);
    assert_eq!(extra.warnings.len(), 1);
    assert!(
            extra.warnings[0].to_string().ends_with(
                "extra_frames.bvh:17: repaired: 2 lines after the 2 frames `Frames:` declares are ignored"
            ),
            "{}",
            extra.warnings[0]
        );
}

#[test]
fn lenient_where_writers_differ() {
    // Multi-word names are joined as Blender does; `{` may end the name line; labels
    // vary in case and spacing; a frame count of 0 gives a skeleton without a clip.
    let text = "\u{feff}hierarchy\r\nroot Left Hip {\r\n\toffset 1 2 3\r\n\tchannels 1 XROTATION\r\n\tend site {\r\n\t\tOFFSET 0 1 0\r\n\t}\r\n}\r\nmotion\r\nFRAMES:0\r\nFrameTime 0.01\r\n";
    let bvh = parse_str(text).unwrap();
    assert_eq!(bvh.joints[0].name, "Left_Hip");
    assert_eq!(bvh.joints[0].channels, [Channel::Xrotation]);
    assert_eq!((bvh.frames_declared, bvh.frame_time), (0, 0.01));
    assert_eq!(
        bvh.warnings,
        [Warning::Repaired {
            location: "t.bvh:2".into(),
            message:
                "joint name \"Left Hip\" has several words: named \"Left_Hip\" (as Blender does)"
                    .into()
        }]
    );
    let imported = to_asset("x", &bvh).unwrap();
    assert!(imported.asset.clips.is_empty());
    assert_eq!(
        imported.warnings.last().unwrap().to_string(),
        "t.bvh:9: no frames: the asset has no clip"
    );
    // Joints without CHANNELS lines: frames are blank lines.
    let static_only =
        "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\n}\nMOTION\nFrames: 3\nFrame Time: 1\n\n\n\n";
    let bvh = parse_str(static_only).unwrap();
    assert_eq!((bvh.frame_count, bvh.channel_count()), (3, 0));
    let imported = to_asset("s", &bvh).unwrap();
    assert!(imported.asset.clips.is_empty());
    assert_eq!(imported.asset.skeleton.len(), 1);
}

#[test]
fn names_are_made_unique_and_decoded() {
    // A later joint literally named like a renamed one is renamed too.
    let text = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nJOINT A\n{\nOFFSET 1 0 0\n}\nJOINT A_2\n{\nOFFSET 2 0 0\n}\n}\nMOTION\nFrames: 1\nFrame Time: 1\n\nstray\n";
    let imported = to_asset("n", &parse_str(text).unwrap()).unwrap();
    let names: Vec<&str> = imported
        .asset
        .skeleton
        .joints()
        .iter()
        .map(|j| j.name.as_str())
        .collect();
    assert_eq!(names, ["A", "A_2", "A_2_2"]);
    let warnings: Vec<String> = imported.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(
        warnings,
        [
            "t.bvh:18: repaired: 1 lines after the 1 frames `Frames:` declares are ignored",
            "t.bvh:5: repaired: joint name \"A\" is also used at line 2: renamed \"A_2\"",
            "t.bvh:9: repaired: joint name \"A_2\" is also used at line 5: renamed \"A_2_2\"",
            "t.bvh:14: no joint has channels: the asset has no clip",
        ]
    );
    // Latin-1 names: replaced, with a warning at the line.
    let latin1 = b"HIERARCHY\nROOT H\xfcfte\n";
    let (text, warning) = decode(latin1, Path::new("l.bvh"));
    assert_eq!(text, "HIERARCHY\nROOT H\u{fffd}fte\n");
    assert_eq!(
        warning.unwrap().to_string(),
        "l.bvh:2: repaired: not UTF-8: invalid bytes were replaced by U+FFFD"
    );
    assert!(decode(b"ok", Path::new("l.bvh")).1.is_none());
}

#[test]
fn deep_nesting_does_not_overflow() {
    let depth = 20_000;
    let mut text = String::from("HIERARCHY\n");
    for i in 0..depth {
        text += &format!(
            "{} J{i}\n{{\nOFFSET 0 1 0\nCHANNELS 1 Zrotation\n",
            if i == 0 { "ROOT" } else { "JOINT" }
        );
    }
    text += &"}\n".repeat(depth);
    text += "MOTION\nFrames: 1\nFrame Time: 1\n";
    text += &"1 ".repeat(depth);
    let bvh = parse_str(&text).unwrap();
    assert_eq!(bvh.joints.len(), depth);
    assert_eq!(bvh.joints[depth - 1].parent, Some(depth - 2));
    let asset = to_asset("deep", &bvh).unwrap().asset;
    assert_eq!(asset.skeleton.len(), depth);
}

#[test]
fn hierarchy_errors_name_line_and_column() {
    let cases: &[(String, &str)] = &[
            ("".into(), "t.bvh: the file is empty"),
            (" \r\n\n".into(), "t.bvh: the file is empty"),
            ("ROOT Hips\n".into(), "t.bvh:1:1: expected HIERARCHY, found \"ROOT\""),
            (base_with(2, "JOINT Hips"), "t.bvh:2:1: expected ROOT, found \"JOINT\""),
            (base_with(2, "MOTION"), "t.bvh:2:1: expected ROOT, found \"MOTION\""),
            (base_with(2, "ROOT"), "t.bvh:2:1: ROOT needs a joint name on its line"),
            (base_with(2, "ROOT {"), "t.bvh:2:1: ROOT needs a joint name on its line"),
            (base_with(3, "  ["), "t.bvh:3:3: expected {, found \"[\""),
            (base_with(4, "    CHANNELS 0"), "t.bvh:4:5: expected OFFSET, found \"CHANNELS\""),
            (base_with(4, "  OFFSET 0 1.2.3 0"), "t.bvh:4:12: OFFSET value \"1.2.3\" is not a number"),
            (base_with(4, "  OFFSET 0 inf 0"), "t.bvh:4:12: OFFSET value \"inf\" is not finite"),
            (base_with(4, "  OFFSET 0 0\n 0"), "t.bvh:4:3: OFFSET needs 3 numbers on its line"),
            (base_with(4, "  OFFSET 0 0 0 0"), "t.bvh:4:16: expected the end of the line after OFFSET's 3 numbers, found \"0\""),
            (base_with(5, "  CHANNELS"), "t.bvh:5:3: CHANNELS needs a channel count on its line"),
            (base_with(5, "  CHANNELS three Zrotation"), "t.bvh:5:12: channel count \"three\" is not a number"),
            (base_with(5, "  CHANNELS 7 Zrotation"), "t.bvh:5:12: CHANNELS 7: a joint has at most 6 channels (3 positions, 3 rotations)"),
            (base_with(5, "  CHANNELS 3 Zrotation Xrotation"), "t.bvh:5:3: CHANNELS 3 lists 2 channel names on its line"),
            (base_with(5, "  CHANNELS 2 Zrotation Xrotation Yrotation"), "t.bvh:5:34: CHANNELS 2 lists more than 2 channel names"),
            (base_with(5, "  CHANNELS 2 Zrotation Xrotation JOINT"), "t.bvh:5:34: expected the end of the line after the channel names, found \"JOINT\""),
            (base_with(5, "  CHANNELS 3 Zrotation Xscale Yrotation"), "t.bvh:5:24: expected a channel name (Xposition, Yposition, Zposition, Xrotation, Yrotation or Zrotation), found \"Xscale\""),
            (base_with(5, "  CHANNELS 3 Zrotation Xrotation zROTATION"), "t.bvh:5:34: channel Zrotation is listed twice"),
            (base_with(6, "  JOIN Spine"), "t.bvh:6:3: expected JOINT, End Site or }, found \"JOIN\""),
            (base_with(10, "    End"), "t.bvh:10:5: End needs Site on its line"),
            (base_with(10, "    End Sight"), "t.bvh:10:9: expected Site, found \"Sight\""),
            (base_with(10, "    End Site Tip"), "t.bvh:10:14: expected the end of the line after End Site, found \"Tip\""),
            (base_with(13, "      CHANNELS 0\n    }"), "t.bvh:13:7: expected }, found \"CHANNELS\""),
            // Unbalanced braces: one too many, one missing (MOTION inside a joint), and
            // the file ending inside a joint.
            (base_with(15, "}\n}"), "t.bvh:16:1: expected ROOT or MOTION, found \"}\""),
            (base_with(15, ""), "t.bvh:16:1: expected JOINT, End Site or }, found \"MOTION\""),
            (BASE.split("}\n}\nMOTION").next().unwrap().to_string(), "t.bvh:13: truncated: the file ends inside joint \"Spine\" (line 6): expected JOINT, End Site or }"),
            (BASE.split("MOTION").next().unwrap().to_string(), "t.bvh:15: truncated: the file ends where ROOT or MOTION was expected"),
            (base_with(16, "MOTION 3"), "t.bvh:16:8: expected the end of the line after MOTION, found \"3\""),
        ];
    for (text, expected) in cases {
        assert_eq!(&err(text), expected, "{text}");
    }
}

/// `BASE`'s hierarchy with `frames` frame lines (`Frames:` says `declared`), large
/// enough past a few thousand frames for the two-thread reader.
fn long_motion(frames: usize, declared: usize) -> String {
    let mut text = BASE.split("Frames").next().unwrap().to_string();
    text.push_str(&format!("Frames: {declared}\nFrame Time: 0.01\n"));
    for k in 0..frames {
        let a = k as f32 * 0.37;
        text.push_str(&format!("{a} {} -{} {}e-1\r\n", a * 2.0, k % 91, k));
        if k % 1000 == 7 {
            text.push_str("  \n");
        }
    }
    text
}

/// Large motion read on two threads equals the line-by-line reading, value for value;
/// a bad, cut-off or extra line in either half is still reported at its own line.
#[test]
fn two_thread_motion_equals_line_by_line() {
    let text = long_motion(6000, 6000);
    let body = &text[text.find("Frame Time").unwrap()..];
    let data = &body[body.find('\n').unwrap() + 1..];
    assert!(data.len() >= 2 * PARALLEL_MOTION_BYTES);
    let fast = frames_on_two_threads(data, 4, 6000).expect("the two-thread path applies");
    let mut slow = Vec::new();
    for line in data.split('\n').filter(|l| !l.trim_ascii().is_empty()) {
        frame_values(line, 4, &mut slow).unwrap_or_else(|_| panic!("{line}"));
    }
    assert_eq!(fast.len(), 6000 * 4);
    assert!(fast
        .iter()
        .zip(&slow)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    let bvh = parse_str(&text).unwrap();
    assert_eq!((bvh.frames_declared, bvh.frame_count), (6000, 6000));
    assert!(bvh.warnings.is_empty());
    assert!(bvh
        .motion
        .iter()
        .zip(&slow)
        .all(|(a, b)| a.to_bits() == b.to_bits()));

    // Not the declared count, or a bad line in the second half: the line-by-line path
    // takes over and says where.
    assert!(frames_on_two_threads(data, 4, 5999).is_none());
    let bvh = parse_str(&long_motion(6000, 5000)).unwrap();
    assert_eq!(bvh.frame_count, 5000);
    assert!(
        matches!(&bvh.warnings[..], [Warning::Repaired { message, .. }]
            if message.starts_with("1000 lines after the 5000 frames"))
    );
    let bvh = parse_str(&long_motion(5000, 6000)).unwrap();
    assert_eq!(bvh.frame_count, 5000);
    assert!(matches!(&bvh.warnings[..], [Warning::Incomplete { .. }]));
    let lines: Vec<&str> = text.split('\n').collect();
    let bad_line = lines.len() - 100;
    let mut broken = lines.clone();
    broken[bad_line - 1] = "1 2 x 4";
    assert_eq!(
        err(&broken.join("\n")),
        format!("t.bvh:{bad_line}:5: motion value \"x\" is not a number")
    );
}

#[test]
fn motion_errors_name_line_and_column() {
    let cases: &[(String, &str)] = &[
        (
            BASE.split("Frames").next().unwrap().to_string(),
            "t.bvh:16: truncated: the file ends where `Frames: <count>` was expected",
        ),
        (
            base_with(17, "Frame: 2"),
            "t.bvh:17:1: expected `Frames: <count>`, found \"Frame: 2\"",
        ),
        (
            base_with(17, "Frames:"),
            "t.bvh:17:1: expected `Frames: <count>`, found \"Frames:\"",
        ),
        (
            base_with(17, "Frames: 2 3"),
            "t.bvh:17:1: expected `Frames: <count>`, found \"Frames: 2 3\"",
        ),
        (
            base_with(17, "Frames:\t-2"),
            "t.bvh:17:9: frame count \"-2\" is out of range for usize",
        ),
        (
            base_with(17, "Frames: 2.0"),
            "t.bvh:17:9: frame count \"2.0\" is not a number",
        ),
        (
            base_with(18, "Frame Rate: 0.5"),
            "t.bvh:18:1: expected `Frame Time: <seconds>`, found \"Frame Rate: 0.5\"",
        ),
        (
            base_with(18, "Frame Time: fast"),
            "t.bvh:18:13: Frame Time \"fast\" is not a number",
        ),
        (
            base_with(18, "Frame Time: 0"),
            "t.bvh:18:13: Frame Time 0 is not a number of seconds > 0",
        ),
        (
            base_with(18, "Frame Time: -0.1"),
            "t.bvh:18:13: Frame Time -0.1 is not a number of seconds > 0",
        ),
        (
            base_with(18, "Frame Time: NaN"),
            "t.bvh:18:13: Frame Time \"NaN\" is not finite",
        ),
        (
            base_with(18, "Frame Time: inf"),
            "t.bvh:18:13: Frame Time \"inf\" is not finite",
        ),
        // A wrong value count anywhere but a truncated file's last line.
        (
            base_with(19, "1 2 3"),
            "t.bvh:19: 3 values, expected 4 (one per channel)",
        ),
        (
            base_with(19, "1 2 3 4 5"),
            "t.bvh:19: 5 values, expected 4 (one per channel)",
        ),
        (
            base_with(20, "5 6 7 8 9"),
            "t.bvh:20: 5 values, expected 4 (one per channel)",
        ),
        (
            base_with(19, "1 x 3 4"),
            "t.bvh:19:3: motion value \"x\" is not a number",
        ),
        (
            base_with(19, "1 2 NaN 4"),
            "t.bvh:19:5: motion value \"NaN\" is not finite",
        ),
        (
            base_with(19, "1 2 3 1e39"),
            "t.bvh:19:7: motion value \"1e39\" is out of range for f32",
        ),
        // The last line has a bad value that is not its last: corruption, not a cut.
        (
            base_with(20, "5 6 x 8"),
            "t.bvh:20:5: motion value \"x\" is not a number",
        ),
    ];
    for (text, expected) in cases {
        assert_eq!(&err(text), expected, "{text}");
    }
    // A short or cut last line of a truncated file is dropped with a warning.
    for last in ["5 6 7", "5 6 7 8.5e", "5"] {
        let bvh = parse_str(&base_with(20, last)).unwrap();
        assert_eq!((bvh.frames_declared, bvh.frame_count), (2, 1), "{last}");
        assert_eq!(bvh.motion, [1.0, 2.0, 3.0, 4.0]);
        assert_eq!(
                bvh.warnings,
                [Warning::Incomplete {
                    location: "t.bvh:20".into(),
                    message: "`Frames: 2` but the file holds 1 complete frames (the cut-off frame at line 20 is dropped): the clip has 1".into()
                }]
            );
    }
    // The file ends after the header: no frames, an incomplete warning, no clip.
    let bvh = parse_str(BASE.split("1 2 3 4").next().unwrap()).unwrap();
    assert_eq!(bvh.frame_count, 0);
    assert_eq!(
        bvh.warnings[0].to_string(),
        "t.bvh:18: `Frames: 2` but the file holds 0 complete frames: the clip has 0"
    );
    assert!(to_asset("e", &bvh).unwrap().asset.clips.is_empty());
}

#[test]
fn to_asset_rejects_inconsistent_structs() {
    let good = parse_str(BASE).unwrap();
    let reject = |edit: &dyn Fn(&mut Bvh), expected: &str| {
        let mut bvh = good.clone();
        edit(&mut bvh);
        assert_eq!(to_asset("x", &bvh).unwrap_err().to_string(), expected);
    };
    reject(
        &|b| b.joints[0].parent = Some(1),
        "t.bvh:2: joint 0 (\"Hips\") names parent 1, which is not an earlier joint",
    );
    reject(
        &|b| b.joints[1].first_channel = 0,
        "t.bvh:6: joint \"Spine\" starts at channel 0 but the joints before it have 3",
    );
    reject(
        &|b| b.joints[0].channels[2] = Channel::Zrotation,
        "t.bvh:2: joint \"Hips\" lists channel Zrotation twice",
    );
    reject(
        &|b| b.end_sites[0].parent = 2,
        "t.bvh:10: the end site names joint 2, but there are 2 joints",
    );
    reject(
        &|b| b.motion.push(0.0),
        "t.bvh:16: 9 motion values for 2 frames of 4 channels",
    );
    reject(
        &|b| b.frame_time = 0.0,
        "t.bvh:16: Frame Time 0.0 is not a number of seconds > 0",
    );
    reject(
        &|b| b.joints[1].offset.x = f32::NAN,
        "t.bvh: invalid skeleton: joint 1 (\"Spine\") has a non-finite rest transform",
    );
    reject(
        &|b| b.motion[7] = f32::INFINITY,
        "t.bvh: the imported asset is invalid: clip \"x\" track 1: has a non-finite value",
    );
    reject(
        &|b| b.frame_time = 1e-46,
        "t.bvh:16: Frame Time 1e-46 s is too small for 2 frames to get increasing f32 key times",
    );
    // Also works on a hand-built struct.
    assert!(to_asset("x", &good).is_ok());
}

proptest::proptest! {
    #[test]
    fn never_panics_on_edited_fixtures(
        which in 0_usize..4,
        edits in proptest::collection::vec(
            (proptest::num::usize::ANY, 0_u8..3, proptest::sample::select(
                b"0123456789 .-+eE{}\n\r\tXYZxyzrotpsinOFSETJMRC:".to_vec()
            )),
            0..6,
        ),
        cut in proptest::num::usize::ANY,
    ) {
        let sources = [
            include_str!("../../../../fixtures/bvh/mixed_orders.bvh"),
            include_str!("../../../../fixtures/bvh/joint_positions.bvh"),
            include_str!("../../../../fixtures/bvh/end_sites.bvh"),
            include_str!("../../../../fixtures/bvh/crlf_tabs.bvh"),
        ];
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
        let text = String::from_utf8_lossy(&bytes);
        if let Ok(bvh) = parse(&text, Path::new("p.bvh")) {
            let _ = to_asset("p", &bvh);
        }
    }
}

/// `Frames:` and `Frame Time:` read from the text independently of the parser.
fn header(text: &str) -> (usize, f64) {
    let value = |label: &str| {
        text.lines()
            .find_map(|l| l.trim().strip_prefix(label))
            .unwrap()
            .trim()
            .to_string()
    };
    (
        value("Frames:").parse().unwrap(),
        value("Frame Time:").parse().unwrap(),
    )
}

fn corpus_present() -> bool {
    rigport_testkit::corpus("4_bvh").is_some()
}

#[test]
fn corpus_files_match_reference_fk() {
    if !corpus_present() {
        return;
    }
    for file in CORPUS_FILES {
        let path = Path::new(CORPUS).join(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let start = std::time::Instant::now();
        let imported = import(&path).unwrap_or_else(|e| panic!("{e}"));
        println!("{file}: import {:?}", start.elapsed());
        assert!(
            imported.warnings.is_empty(),
            "{file}: {:?}",
            imported.warnings
        );
        let bvh = parse(&text, &path).unwrap();
        let (frames, frame_time) = header(&text);
        assert_eq!(bvh.frames_declared, frames, "{file}");
        assert_eq!(bvh.frame_count, frames, "{file}");
        assert_eq!(bvh.frame_time, frame_time, "{file}");
        let frame_lines = text
            .lines()
            .skip_while(|l| !l.trim().starts_with("Frame Time"))
            .skip(1)
            .filter(|l| !l.trim().is_empty())
            .count();
        assert_eq!(frame_lines, frames, "{file}");
        let joint_lines = text
            .lines()
            .filter(|l| matches!(l.split_whitespace().next(), Some("ROOT" | "JOINT")))
            .count();
        let end_lines = text.lines().filter(|l| l.trim() == "End Site").count();
        assert_eq!(
            (bvh.joints.len(), bvh.end_sites.len()),
            (joint_lines, end_lines),
            "{file}"
        );
        let duration = imported.asset.clips[0].duration();
        assert!((f64::from(duration) - (frames - 1) as f64 * frame_time).abs() < 1e-5);
        let worst = check_asset(&bvh, &imported, file);
        println!(
            "  {frames} frames, {} joints, largest relative FK error {worst:e}",
            imported.asset.skeleton.len()
        );
        if file.starts_with("bandai") {
            // Position channels replace the OFFSETs (FORMATS.md): the hips' channels put
            // them 80-95 cm up and the spine chain adds about 41 cm to the head joint.
            // Adding channels to OFFSETs would double every bone and put the hips
            // alone at about 176 cm.
            let head = imported.asset.skeleton.find("Head").unwrap();
            let y = (0..frames)
                .map(|k| asset_positions(&imported.asset, k)[head.get()].y)
                .fold(f32::MIN, f32::max);
            println!("  head at most {y} cm up");
            assert!(
                (100.0..170.0).contains(&y),
                "{file}: head at most {y} cm up"
            );
        }
    }
    let walk = parse(
        &std::fs::read_to_string(Path::new(CORPUS).join(CORPUS_FILES[3])).unwrap(),
        Path::new("walk.bvh"),
    )
    .unwrap();
    assert_eq!((walk.frame_count, walk.joints.len()), (344, 31));
    assert!((1.0 / walk.frame_time - 120.0).abs() < 1e-2);
}

/// Release-mode timing of the largest corpus file:
/// `cargo test --release -p rigport-import --lib bvh::tests::kick_timing -- --ignored --nocapture`.
#[test]
#[ignore = "timing; run in release"]
fn kick_timing() {
    if !corpus_present() {
        return;
    }
    let path = Path::new(CORPUS).join(KICK);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut parse_times = Vec::new();
    let mut total_times = Vec::new();
    for _ in 0..50 {
        let start = std::time::Instant::now();
        let bvh = parse(&text, &path).unwrap();
        let parsed = start.elapsed();
        let imported = to_asset("kick", &bvh).unwrap();
        total_times.push(start.elapsed());
        parse_times.push(parsed);
        assert_eq!(imported.asset.clips.len(), 1);
    }
    parse_times.sort();
    total_times.sort();
    println!(
        "kick ({} bytes): parse median {:?} (min {:?}), parse + to_asset median {:?} (min {:?})",
        text.len(),
        parse_times[25],
        parse_times[0],
        total_times[25],
        total_times[0]
    );
}
