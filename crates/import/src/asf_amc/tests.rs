use std::collections::HashMap;

use glam::{DMat3, DVec3, Mat4, Quat, Vec3};
use rigport_model::conventions::EulerOrder;
use rigport_model::{Clip, Interpolation, JointIndex, TrackTarget, Transform};

use super::*;
use crate::Problem;

const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/asf_amc");

fn fixture(name: &str) -> PathBuf {
    Path::new(FIXTURES).join(name)
}

/// The corpus folder, or `None` (after printing SKIPPED) when it is absent outside CI.
fn corpus(sub: &str) -> Option<PathBuf> {
    rigport_testkit::corpus(&format!("3_acclaim_asf_amc/{sub}"))
}

fn rot(axis: u8, angle_rad: f64) -> DMat3 {
    match axis {
        b'x' => DMat3::from_rotation_x(angle_rad),
        b'y' => DMat3::from_rotation_y(angle_rad),
        _ => DMat3::from_rotation_z(angle_rad),
    }
}

/// FORMATS.md "Acclaim ASF/AMC" applied directly, with rotation matrices and a walk down
/// the hierarchy: `W = W_parent · C · M · C⁻¹`, a bone starts at its parent's end (the
/// root's position under the root) and ends at `start + W · direction · length`. The
/// root: `C` from `orientation` in `axis` order, `M` from the rotation part of `order`,
/// position `position + (TX, TY, TZ)`. Translation dofs move a bone's start by
/// `W_parent · C · t` (the module's documented choice). Returns the root's position,
/// every bone's start under its name, and every leaf bone's end as `<bone>_end`.
fn reference_positions(asf: &Asf, amc: &Amc, k: usize) -> HashMap<String, DVec3> {
    let amc_unit = amc.angle.unwrap_or(asf.units.angle);
    let c_of = |order: EulerOrder, angles: DVec3| {
        order.as_str().bytes().fold(DMat3::IDENTITY, |c, axis| {
            let a = match axis {
                b'x' => angles.x,
                b'y' => angles.y,
                _ => angles.z,
            };
            rot(axis, asf.units.angle.to_radians(a)) * c
        })
    };
    let motion = |dofs: &[Dof], values: &[f64]| {
        let mut m = DMat3::IDENTITY;
        let mut t = DVec3::ZERO;
        assert_eq!(dofs.len(), values.len());
        for (d, &v) in dofs.iter().zip(values) {
            match d {
                Dof::Rx => m = rot(b'x', amc_unit.to_radians(v)) * m,
                Dof::Ry => m = rot(b'y', amc_unit.to_radians(v)) * m,
                Dof::Rz => m = rot(b'z', amc_unit.to_radians(v)) * m,
                Dof::Tx => t.x = v,
                Dof::Ty => t.y = v,
                Dof::Tz => t.z = v,
                Dof::L => {}
            }
        }
        (m, t)
    };
    let frame = amc.frame_values(k).unwrap();
    // Slice the frame by walking the dof counts (independently of channel_ranges).
    let mut at = asf.root.order.len();
    let root_values = &frame[..at];
    let mut bone_values = Vec::new();
    for bone in &asf.bones {
        bone_values.push(&frame[at..at + bone.dofs.len()]);
        at += bone.dofs.len();
    }
    assert_eq!(at, frame.len());

    let mut out = HashMap::new();
    let (m_root, t_root) = motion(&asf.root.order, root_values);
    let c_root = c_of(asf.root.axis, asf.root.orientation);
    let w_root = c_root * m_root * c_root.inverse();
    let root_pos = asf.root.position + t_root;
    out.insert("root".to_string(), root_pos);
    let mut stack: Vec<(usize, DVec3, DMat3)> = (0..asf.bones.len())
        .filter(|&b| asf.bones[b].parent.is_none())
        .map(|b| (b, root_pos, w_root))
        .collect();
    while let Some((b, start, w_parent)) = stack.pop() {
        let bone = &asf.bones[b];
        let c = c_of(bone.axis_order, bone.axis);
        let (m, t) = motion(&bone.dofs, bone_values[b]);
        let w = w_parent * c * m * c.inverse();
        let start = start + w_parent * c * t;
        let end = start + w * (bone.direction * bone.length);
        out.insert(bone.name.clone(), start);
        let children: Vec<usize> = (0..asf.bones.len())
            .filter(|&c| asf.bones[c].parent == Some(b))
            .collect();
        if children.is_empty() {
            out.insert(format!("{}_end", bone.name), end);
        }
        for child in children {
            stack.push((child, end, w));
        }
    }
    out
}

/// Model-space joint positions from the asset's rest pose with clip key `k` applied.
fn asset_positions(asset: &Asset, clip: &Clip, k: usize) -> HashMap<String, Vec3> {
    let joints = asset.skeleton.joints();
    let mut local: Vec<Transform> = joints.iter().map(|j| j.rest_local).collect();
    for track in &clip.tracks {
        let v = track.key_value(k);
        match track.target {
            TrackTarget::Translation(j) => local[j.get()].translation = Vec3::from_slice(v),
            TrackTarget::Rotation(j) => local[j.get()].rotation = Quat::from_slice(v),
            other => panic!("unexpected track {other:?}"),
        }
    }
    let mut world: Vec<Mat4> = Vec::with_capacity(joints.len());
    for (j, joint) in joints.iter().enumerate() {
        let m = local[j].to_mat4();
        let model = match joint.parent {
            Some(p) => world[p.get()] * m,
            None => m,
        };
        world.push(model);
    }
    joints
        .iter()
        .zip(&world)
        .map(|(j, m)| (j.name.clone(), m.w_axis.truncate()))
        .collect()
}

/// The largest extent of the rest pose's bounding box: the "skeleton height" the FK
/// tolerance is relative to.
fn height(asset: &Asset) -> f64 {
    let points: Vec<Vec3> = asset
        .skeleton
        .model_rest_matrices()
        .iter()
        .map(|m| m.w_axis.truncate())
        .collect();
    let min = points.iter().fold(Vec3::splat(f32::MAX), |a, &p| a.min(p));
    let max = points.iter().fold(Vec3::splat(f32::MIN), |a, &p| a.max(p));
    f64::from((max - min).max_element())
}

/// Checks clip `clip` of `imported` against [`reference_positions`] on every frame of
/// `amc` (max deviation <= 1e-5 * height: f32 FK on values up to ~40 units rounds at
/// ~5e-6), the key times and the quaternions. Returns the largest deviation.
fn check_fk(asf: &Asf, amc: &Amc, imported: &Imported, clip: usize, fps: f32) -> f64 {
    let asset = &imported.asset;
    let clip = &asset.clips[clip];
    let tolerance = 1e-5 * height(asset);
    let mut worst = 0.0_f64;
    for k in 0..amc.frames.len() {
        let expected = reference_positions(asf, amc, k);
        let got = asset_positions(asset, clip, k);
        assert_eq!(expected.len(), got.len(), "joint count");
        for (name, want) in &expected {
            let have = got[name].as_dvec3();
            let d = have.distance(*want);
            worst = worst.max(d);
            assert!(
                d <= tolerance,
                "{}: frame {k} joint {name}: {have} vs {want} (off by {d}, tolerance {tolerance})",
                amc.path.display()
            );
        }
    }
    for track in &clip.tracks {
        assert_eq!(track.times.len(), amc.frames.len());
        assert_eq!(track.interpolation, Interpolation::Linear);
        for (k, &t) in track.times.iter().enumerate() {
            assert_eq!(t, (k as f64 / f64::from(fps)) as f32);
        }
        if let TrackTarget::Rotation(_) = track.target {
            let mut previous: Option<Quat> = None;
            for k in 0..track.times.len() {
                let q = Quat::from_slice(track.key_value(k));
                assert!((q.length() - 1.0).abs() < 1e-6, "{q}");
                if let Some(p) = previous {
                    assert!(p.dot(q) >= 0.0, "sign flip at key {k}: {p} then {q}");
                }
                previous = Some(q);
            }
        }
    }
    worst
}

fn frame_line_count(text: &str) -> usize {
    text.lines()
        .filter(|l| {
            let t = l.trim();
            !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit())
        })
        .count()
}

/// The ASF a `<stem>[__variant].amc` fixture belongs to.
fn asf_for(amc: &Path) -> PathBuf {
    let stem = amc.file_stem().unwrap().to_string_lossy();
    let base = stem.split("__").next().unwrap();
    amc.with_file_name(format!("{base}.asf"))
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn every_fixture_imports_and_matches_the_formula() {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(FIXTURES)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    let mut asfs = 0;
    let mut amcs = 0;
    for path in &entries {
        match path.extension().and_then(|e| e.to_str()) {
            Some("asf") => {
                asfs += 1;
                let imported = import(path, &[], DEFAULT_FPS).unwrap_or_else(|e| panic!("{e}"));
                assert!(imported.asset.clips.is_empty());
                assert!(imported.asset.validate().is_ok());
                // One joint per bone, the root, and one per leaf bone.
                let asf = parse_asf(&read(path), path).unwrap();
                let leaves = (0..asf.bones.len())
                    .filter(|&b| !asf.bones.iter().any(|c| c.parent == Some(b)))
                    .count();
                assert_eq!(imported.asset.skeleton.len(), 1 + asf.bones.len() + leaves);
            }
            Some("amc") => {
                amcs += 1;
                let asf_path = asf_for(path);
                let asf = parse_asf(&read(&asf_path), &asf_path).unwrap();
                let text = read(path);
                let amc = parse_amc(&text, path, &asf).unwrap_or_else(|e| panic!("{e}"));
                assert_eq!(amc.frames.len(), frame_line_count(&text));
                let fps = 30.0;
                let imported = import(&asf_path, std::slice::from_ref(path), fps)
                    .unwrap_or_else(|e| panic!("{e}"));
                let clip = &imported.asset.clips[0];
                assert_eq!(clip.name, path.file_stem().unwrap().to_string_lossy());
                let worst = check_fk(&asf, &amc, &imported, 0, fps);
                println!("{}: max FK deviation {worst:e}", path.display());
                for w in &imported.warnings {
                    println!("  warning: {w}");
                }
            }
            _ => {}
        }
    }
    assert!(asfs >= 8 && amcs >= 8, "{asfs} ASF and {amcs} AMC fixtures");
}

#[test]
fn chain_skeleton_and_units() {
    let asf = parse_asf(&read(&fixture("chain.asf")), &fixture("chain.asf")).unwrap();
    assert_eq!(asf.version.as_deref(), Some("1.10"));
    assert_eq!(asf.name.as_deref(), Some("chain"));
    assert_eq!(asf.units.length, Some(0.45));
    assert_eq!(asf.units.mass, Some(1.0));
    assert_eq!(asf.units.angle, AngleUnit::Degrees);
    assert_eq!(asf.documentation.len(), 1);
    let shin = &asf.bones[2];
    assert_eq!(shin.name, "shin");
    assert_eq!(shin.id, Some(3));
    assert_eq!(shin.axis, DVec3::new(-35.0, 15.0, 50.0));
    assert_eq!(shin.axis_order, EulerOrder::Zxy);
    assert_eq!(shin.dofs, vec![Dof::Rz, Dof::Rx]);
    assert_eq!(shin.limits, vec![(-90.0, 90.0), (-10.0, 170.0)]);
    assert_eq!(shin.parent, Some(1));
    assert_eq!(shin.line, 37);
    assert_eq!(shin.hierarchy_line, 59);
    let foot = &asf.bones[3];
    assert_eq!(foot.limits[0], (f64::NEG_INFINITY, f64::INFINITY));
    assert_eq!(foot.dofs, vec![Dof::Ry, Dof::Rz, Dof::Rx]);
    assert_eq!(asf.channel_count(), 6 + 3 + 2 + 3);
    assert_eq!(asf.channel_ranges(), vec![0..6, 6..6, 6..9, 9..11, 11..14]);

    let imported = to_asset("chain", &asf, &[], DEFAULT_FPS).unwrap();
    assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
    let asset = &imported.asset;
    let mpu = asset.meters_per_unit.unwrap();
    assert!((mpu - 0.0254 / 0.45).abs() < 1e-15);
    let s = &asset.skeleton;
    let names: Vec<&str> = s.joints().iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["root", "hip", "thigh", "shin", "foot", "foot_end"]);
    let parents: Vec<Option<u32>> = s.parents().map(|p| p.map(|j| j.0)).collect();
    assert_eq!(parents, [None, Some(0), Some(1), Some(2), Some(3), Some(4)]);
    // Each joint sits at its bone's start: offset = the parent bone's direction*length.
    let t = |name: &str| s.joint(s.find(name).unwrap()).rest_local;
    assert_eq!(t("hip").translation, Vec3::ZERO);
    assert_eq!(t("thigh").translation, Vec3::new(1.2, -1.6, 0.0));
    assert_eq!(t("shin").translation, Vec3::new(0.0, -7.0, 0.0));
    assert_eq!(t("foot_end").translation, Vec3::new(0.0, 0.0, 2.0));
    assert!(s
        .joints()
        .iter()
        .all(|j| j.rest_local.rotation == Quat::IDENTITY));
    // The bones' dof/limits as IK limits: shin `dof rz rx`, `limits (-90 90) (-10 170)` in
    // its `axis` frame, y locked; foot's infinite limits become ±180°.
    let limit = |name: &str| {
        let j = s.find(name).unwrap();
        *s.limits().iter().find(|l| l.joint == j).unwrap()
    };
    let shin_l = limit("shin");
    assert_eq!(shin_l.order, EulerOrder::Zxy);
    let deg = |v: Vec3| v * std::f32::consts::PI / 180.0;
    assert!(
        (shin_l.min_rad - deg(Vec3::new(-10.0, 0.0, -90.0)))
            .abs()
            .max_element()
            < 1e-6
    );
    assert!(
        (shin_l.max_rad - deg(Vec3::new(170.0, 0.0, 90.0)))
            .abs()
            .max_element()
            < 1e-6
    );
    let c = super::skeleton::euler(
        EulerOrder::Zxy,
        DVec3::new(-35.0, 15.0, 50.0) * std::f64::consts::PI / 180.0,
    );
    assert!(shin_l.frame.angle_between(c.as_quat()) < 1e-6);
    let foot_l = limit("foot");
    assert_eq!(foot_l.min_rad.y, -std::f32::consts::PI);
    assert_eq!(foot_l.max_rad.y, std::f32::consts::PI);
    // `hip` lists no dof: fully locked.
    assert_eq!(limit("hip").max_rad, Vec3::ZERO);
}

#[test]
fn chain_motion_matches_the_formula_on_every_frame() {
    // The hand-made 3-bone check the mapping rests on: non-trivial axis angles in
    // three axis orders (XYZ, ZXY, YZX), dof orders rx ry rz / rz rx / ry rz rx, and
    // angles up to 179 degrees.
    let asf = parse_asf(&read(&fixture("chain.asf")), &fixture("chain.asf")).unwrap();
    let amc = parse_amc(&read(&fixture("chain.amc")), &fixture("chain.amc"), &asf).unwrap();
    assert_eq!(amc.frames.len(), 4);
    assert!(amc.fully_specified);
    assert_eq!(amc.angle, Some(AngleUnit::Degrees));
    assert_eq!(
        amc.frame_values(0).unwrap(),
        [1.5, 17.25, -3.0, 5.0, 10.0, -15.0, -30.0, 12.0, 8.0, 20.0, 45.0, 10.0, -5.0, 15.0]
    );
    let motions = [("walk".to_string(), amc)];
    let imported = to_asset("chain", &asf, &motions, 60.0).unwrap();
    let worst = check_fk(&asf, &motions[0].1, &imported, 0, 60.0);
    assert!(worst < 1e-5, "{worst}");
    // The formula is not trivially satisfied: the motion moves the foot's end.
    let rest = reference_positions(&asf, &motions[0].1, 3);
    let moved = reference_positions(&asf, &motions[0].1, 2);
    assert!(rest["foot_end"].distance(moved["foot_end"]) > 1.0);
    let clip = &imported.asset.clips[0];
    assert_eq!(clip.name, "walk");
    // Root translation + rotation, and a rotation track per rotating bone.
    assert_eq!(clip.tracks.len(), 2 + 3);
    assert!((clip.duration() - 3.0 / 60.0).abs() < 1e-7);
    // Root translation keys are the frame's TX TY TZ (position is 0).
    let root_t = &clip.tracks[0];
    assert_eq!(root_t.target, TrackTarget::Translation(JointIndex(0)));
    assert_eq!(root_t.key_value(1), [1.75, 17.3, -2.5]);
}

#[test]
fn a_local_rotation_is_c_m_c_inverse() {
    // One bone, one frame, by hand: axis 0 0 90 XYZ (C = Rz(90)), dof rx = 90. In the
    // bone's frame x is the world's y, so the bone turns 90 degrees about world y.
    let text = ":root\n order TX TY TZ RX RY RZ\n axis XYZ\n position 0 0 0\n orientation 0 0 0\n:bonedata\n begin\n name b\n direction 1 0 0\n length 2\n axis 0 0 90 XYZ\n dof rx\n end\n:hierarchy\n begin\n root b\n end\n";
    let asf = parse_asf(text, Path::new("t.asf")).unwrap();
    let amc = parse_amc("1\nroot 0 0 0 0 0 0\nb 90\n", Path::new("t.amc"), &asf).unwrap();
    let imported = to_asset("t", &asf, &[("m".into(), amc)], 1.0).unwrap();
    let got = asset_positions(&imported.asset, &imported.asset.clips[0], 0);
    // World y rotation by 90 degrees takes +x to -z.
    assert!(
        got["b_end"].abs_diff_eq(Vec3::new(0.0, 0.0, -2.0), 1e-6),
        "{}",
        got["b_end"]
    );
}

#[test]
fn root_frame_rest_frame_and_channel_order() {
    let asf_path = fixture("root_frame.asf");
    let asf = parse_asf(&read(&asf_path), &asf_path).unwrap();
    assert_eq!(
        asf.root.order,
        [Dof::Rz, Dof::Ry, Dof::Rx, Dof::Tx, Dof::Ty, Dof::Tz]
    );
    assert_eq!(asf.root.axis, EulerOrder::Zyx);
    assert_eq!(asf.root.position, DVec3::new(1.0, 2.0, 3.0));
    assert_eq!(asf.root.orientation, DVec3::new(10.0, -20.0, 30.0));
    assert_eq!(asf.units.meters_per_unit(), Some(0.0254));
    let imported = import(&asf_path, &[fixture("root_frame.amc")], DEFAULT_FPS).unwrap();
    let asset = &imported.asset;
    // Frame 1 is all zeros: the rest pose, whatever the root's orientation.
    let posed = asset_positions(asset, &asset.clips[0], 0);
    let rest = asset.skeleton.model_rest_matrices();
    for (j, joint) in asset.skeleton.joints().iter().enumerate() {
        let r = rest[j].w_axis.truncate();
        assert!(posed[&joint.name].abs_diff_eq(r, 1e-6), "{}", joint.name);
    }
    assert_eq!(
        asset.skeleton.joint(JointIndex(0)).rest_local.translation,
        Vec3::new(1.0, 2.0, 3.0)
    );
    // Frame 2 translates by the last three values (TX TY TZ come after the rotations).
    let root_t = &asset.clips[0].tracks[0];
    assert_eq!(root_t.key_value(1), [1.5, 1.75, 4.0]);
}

#[test]
fn amc_angle_header_overrides_the_asf() {
    let asf_path = fixture("radians.asf");
    let asf = parse_asf(&read(&asf_path), &asf_path).unwrap();
    assert_eq!(asf.units.angle, AngleUnit::Radians);
    assert_eq!(asf.bones[1].limits, [(-0.17, 2.97)]);
    let rad = parse_amc(
        &read(&fixture("radians.amc")),
        &fixture("radians.amc"),
        &asf,
    )
    .unwrap();
    let deg = parse_amc(
        &read(&fixture("radians__degrees.amc")),
        &fixture("radians__degrees.amc"),
        &asf,
    )
    .unwrap();
    assert_eq!(rad.angle, None);
    assert_eq!(deg.angle, Some(AngleUnit::Degrees));
    let imported = to_asset(
        "radians",
        &asf,
        &[("rad".into(), rad), ("deg".into(), deg)],
        DEFAULT_FPS,
    )
    .unwrap();
    let clips = &imported.asset.clips;
    assert_eq!(clips[0].name, "rad");
    assert_eq!(clips[1].name, "deg");
    for k in 0..2 {
        let a = asset_positions(&imported.asset, &clips[0], k);
        let b = asset_positions(&imported.asset, &clips[1], k);
        for (name, p) in &a {
            assert!(p.abs_diff_eq(b[name], 1e-5), "{name}: {p} vs {}", b[name]);
        }
    }
    // Read as degrees, the radian values would barely move the leg: the unit matters.
    let end = |clip: &Clip| asset_positions(&imported.asset, clip, 0)["lower_end"];
    assert!(end(&clips[0]).distance(Vec3::new(0.0, 0.0, 0.0)) > 1.0);
}

#[test]
fn text_quirks_parse_like_clean_text() {
    let asf_path = fixture("quirks.asf");
    let asf = parse_asf(&read(&asf_path), &asf_path).unwrap();
    assert_eq!(asf.units.length, Some(0.45));
    assert_eq!(asf.units.angle, AngleUnit::Degrees);
    assert_eq!(asf.documentation, ["free text"]);
    assert_eq!(asf.root.axis, EulerOrder::Xyz);
    let names: Vec<&str> = asf.bones.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["Hip", "Thigh"]);
    assert_eq!(asf.bones[1].axis_order, EulerOrder::Xyz);
    assert_eq!(asf.bones[1].dofs, [Dof::Rx, Dof::Ry, Dof::Rz]);
    assert_eq!(
        asf.bones[1].limits,
        [(-160.0, 20.0), (-70.0, 70.0), (-60.0, 70.0)]
    );
    assert_eq!(asf.bones[1].line, 29);
    let amc = parse_amc(&read(&fixture("quirks.amc")), &fixture("quirks.amc"), &asf).unwrap();
    assert_eq!(amc.frames.len(), 2);
    assert_eq!(
        amc.frames[1],
        AmcFrame {
            number: 2,
            line: 10
        }
    );
    assert_eq!(
        amc.frame_values(1).unwrap(),
        [1.25, 17.1, -2.5, 6.0, 9.0, -14.0, -25.0, 10.0, 5.0]
    );
    assert!(amc.held.is_empty());
}

#[test]
fn unordered_bones_are_sorted_parents_first() {
    let imported = import(
        &fixture("unordered.asf"),
        &[fixture("unordered.amc")],
        DEFAULT_FPS,
    )
    .unwrap();
    let s = &imported.asset.skeleton;
    let names: Vec<&str> = s.joints().iter().map(|j| j.name.as_str()).collect();
    // Every parent before its children.
    for (j, joint) in s.joints().iter().enumerate() {
        if let Some(p) = joint.parent {
            assert!(p.get() < j);
        }
    }
    let parent = |name: &str| {
        let j = s.joint(s.find(name).unwrap());
        s.joint(j.parent.unwrap()).name.clone()
    };
    assert_eq!(parent("pelvis"), "root");
    assert_eq!(parent("spine"), "pelvis");
    assert_eq!(parent("head"), "spine");
    assert_eq!(parent("lfoot"), "lleg");
    assert_eq!(parent("lfoot_end"), "lfoot");
    assert_eq!(parent("rleg_end"), "rleg");
    assert_eq!(names.len(), 1 + 6 + 3);
    // pelvis has no dofs: no track; spine (rz ry) gets one.
    let clip = &imported.asset.clips[0];
    let targets: Vec<TrackTarget> = clip.tracks.iter().map(|t| t.target).collect();
    assert!(!targets.contains(&TrackTarget::Rotation(s.find("pelvis").unwrap())));
    assert!(targets.contains(&TrackTarget::Rotation(s.find("spine").unwrap())));
    // Tracks come in joint order.
    assert!(targets.windows(2).all(|w| w[0] < w[1]));
}

#[test]
fn translation_dofs_move_along_the_bone_frame_and_l_is_noted() {
    let imported = import(
        &fixture("translation.asf"),
        &[fixture("translation.amc")],
        DEFAULT_FPS,
    )
    .unwrap();
    let s = &imported.asset.skeleton;
    let clip = &imported.asset.clips[0];
    let slider = s.find("slider").unwrap();
    let track = clip
        .tracks
        .iter()
        .find(|t| t.target == TrackTarget::Translation(slider))
        .unwrap();
    // C = Rz(90): t = (0.5, -1, 2) in the bone frame is (1, 0.5, 2) in the parent's.
    let v = Vec3::from_slice(track.key_value(0));
    assert!(v.abs_diff_eq(Vec3::new(1.0, 0.5, 2.0), 1e-6), "{v}");
    let notes: Vec<String> = imported.warnings.iter().map(ToString::to_string).collect();
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(
            notes[0].ends_with("translation.asf:29: bone \"stretch\": the length dof `l` is not supported; its values are ignored"),
            "{}",
            notes[0]
        );
    // Without motions nothing is lost, so no note.
    let skeleton_only = import(&fixture("translation.asf"), &[], DEFAULT_FPS).unwrap();
    assert!(skeleton_only.warnings.is_empty());
}

#[test]
fn missing_bones_hold_their_previous_value() {
    let asf = parse_asf(&read(&fixture("chain.asf")), &fixture("chain.asf")).unwrap();
    let path = fixture("chain__held.amc");
    let amc = parse_amc(&read(&path), &path, &asf).unwrap();
    assert_eq!(
        amc.held,
        [
            HeldValue {
                frame: 0,
                bone: Some(2)
            },
            HeldValue {
                frame: 2,
                bone: None
            },
            HeldValue {
                frame: 2,
                bone: Some(3)
            },
        ]
    );
    // Frame 1's shin is at rest; frame 3's root and foot are frame 2's.
    assert_eq!(amc.frame_values(0).unwrap()[9..11], [0.0, 0.0]);
    let (f1, f2) = (amc.frame_values(1).unwrap(), amc.frame_values(2).unwrap());
    assert_eq!(f2[..6], f1[..6]);
    assert_eq!(f2[11..], f1[11..]);
    assert_eq!(f2[6..9], [170.0, -80.0, 95.0]);
    let imported = to_asset("chain", &asf, &[("held".into(), amc)], DEFAULT_FPS).unwrap();
    let messages: Vec<String> = imported.warnings.iter().map(ToString::to_string).collect();
    assert_eq!(messages.len(), 1, "{messages:?}");
    assert!(matches!(imported.warnings[0], Warning::Repaired { .. }));
    assert!(
            messages[0].ends_with("chain__held.amc:5: repaired: 3 bone entries were missing from 2 frames (the first: \"shin\" in frame 1); each held its value from the frame before (the rest pose in the first frame)"),
            "{}",
            messages[0]
        );
}

#[test]
fn frame_number_gaps_are_noted_and_keys_stay_in_file_order() {
    let imported = import(
        &fixture("chain.asf"),
        &[fixture("chain__gaps.amc")],
        DEFAULT_FPS,
    )
    .unwrap();
    let messages: Vec<String> = imported.warnings.iter().map(ToString::to_string).collect();
    assert_eq!(messages.len(), 1, "{messages:?}");
    assert!(
            messages[0].ends_with("chain__gaps.amc:14: frame numbers are not consecutive in 1 place (the first: frame 5 after frame 2); kept the file's order, key k at k / 120 s"),
            "{}",
            messages[0]
        );
    let times = &imported.asset.clips[0].tracks[0].times;
    assert_eq!(times.len(), 4);
    assert_eq!(times[2], (2.0_f64 / 120.0) as f32);
}

#[test]
fn no_units_and_skipped_parts() {
    let imported = import(&fixture("no_units.asf"), &[], DEFAULT_FPS).unwrap();
    assert_eq!(imported.asset.meters_per_unit, None);
    assert!(imported.warnings.is_empty());
    let asf = parse_asf(&read(&fixture("no_units.asf")), &fixture("no_units.asf")).unwrap();
    assert_eq!(asf.units, Units::default());

    let imported = import(&fixture("skipped.asf"), &[], DEFAULT_FPS).unwrap();
    let messages: Vec<String> = imported.warnings.iter().map(ToString::to_string).collect();
    assert_eq!(messages.len(), 2, "{messages:?}");
    assert!(
        messages[0].ends_with("skipped.asf:10: skipped `units time`: rigport does not use it"),
        "{}",
        messages[0]
    );
    assert!(
        messages[1].ends_with("skipped.asf:16: skipped `:skin`: rigport does not use it"),
        "{}",
        messages[1]
    );
    assert_eq!(imported.asset.skeleton.len(), 3);
}

#[test]
fn clips_follow_the_amc_order_and_fps_is_checked() {
    let asf = fixture("chain.asf");
    let amcs = [fixture("chain__gaps.amc"), fixture("chain.amc")];
    let imported = import(&asf, &amcs, 24.0).unwrap();
    let names: Vec<&str> = imported
        .asset
        .clips
        .iter()
        .map(|c| c.name.as_str())
        .collect();
    assert_eq!(names, ["chain__gaps", "chain"]);
    assert_eq!(imported.asset.name, "chain");
    for fps in [0.0, -30.0, f32::NAN, f32::INFINITY] {
        let e = import(&asf, &amcs, fps).unwrap_err().to_string();
        assert!(
            e.ends_with(&format!(
                "chain.asf: the frame rate must be finite and positive, got {fps} fps"
            )),
            "{e}"
        );
    }
    // An AMC parsed against another skeleton is refused, not misread.
    let other = parse_asf(
        &read(&fixture("root_frame.asf")),
        &fixture("root_frame.asf"),
    )
    .unwrap();
    let chain = parse_asf(&read(&asf), &asf).unwrap();
    let amc = parse_amc(&read(&amcs[1]), &amcs[1], &chain).unwrap();
    let e = to_asset("x", &other, &[("m".into(), amc)], 30.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("it was parsed against another skeleton"), "{e}");
}

// ------------------------------------------------------------------------------
// One negative test per invalid field.

/// A valid ASF; the line numbers below refer to it.
const BASE: &str = "\
:units
  length 0.45
  angle deg
:root
  order TX TY TZ RX RY RZ
  axis XYZ
  position 0 0 0
  orientation 0 0 0
:bonedata
  begin
    id 1
    name a
    direction 0 1 0
    length 2
    axis 0 0 0 XYZ
    dof rx ry rz
    limits (-10 10)
           (-20 20)
           (-30 30)
  end
  begin
    id 2
    name b
    direction 1 0 0
    length 1
    axis 0 0 10 XYZ
    dof rz
  end
:hierarchy
  begin
    root a
    a b
  end
";

/// The error for BASE with `old` replaced by `new` (which must occur).
fn asf_err(old: &str, new: &str) -> String {
    assert!(BASE.contains(old), "{old:?}");
    let text = BASE.replacen(old, new, 1);
    parse_asf(&text, Path::new("t.asf"))
        .expect_err("should fail")
        .to_string()
}

#[test]
fn base_is_valid() {
    let asf = parse_asf(BASE, Path::new("t.asf")).unwrap();
    assert_eq!(asf.bones.len(), 2);
    let imported = to_asset("t", &asf, &[], 30.0).unwrap();
    assert_eq!(imported.asset.skeleton.len(), 4);
}

#[test]
fn asf_errors_name_the_line() {
    let cases: &[(&str, &str, &str)] = &[
            ("direction 0 1 0", "direction 0 x 0", "t.asf:13:17: direction \"x\" is not a number"),
            ("direction 0 1 0", "direction 0 1", "t.asf:13: expected 3 numbers after `direction`, found \"direction 0 1\""),
            ("direction 0 1 0", "direction 0 1 0 0", "t.asf:13: expected 3 numbers after `direction`, found \"direction 0 1 0 0\""),
            ("length 2", "length -1.#IND", "t.asf:14:12: length \"-1.#IND\" is not a number"),
            ("length 2", "length inf", "t.asf:14:12: length \"inf\" is not finite"),
            ("length 2", "length -2", "t.asf:14:12: a bone length must not be negative, got -2"),
            ("length 2", "length", "t.asf:14: expected one number after `length`, found \"length\""),
            ("dof rz", "dof rq", "t.asf:27:9: expected a dof (tx ty tz rx ry rz l), found \"rq\""),
            ("dof rz", "dof", "t.asf:27: expected at least one dof: a dof (tx ty tz rx ry rz l), found \"dof\""),
            ("dof rx ry rz", "dof rx ry rx", "t.asf:16:15: dof rx is listed twice"),
            ("axis 0 0 10 XYZ", "axis 0 0 10 XYW", "t.asf:26:17: expected an axis order (XYZ, XZY, YXZ, YZX, ZXY or ZYX), found \"XYW\""),
            ("axis 0 0 10 XYZ", "axis 0 0 10", "t.asf:26: expected 3 angles and an axis order after `axis` (e.g. `axis 0 0 20 XYZ`), found \"axis 0 0 10\""),
            ("axis 0 0 10 XYZ", "axis 0 0 1e999 XYZ", "t.asf:26:14: axis angle \"1e999\" is out of range for f64"),
            ("id 2", "id two", "t.asf:22:8: bone id \"two\" is not a number"),
            ("id 2", "idx 2", "t.asf:22:5: expected a bone entry (`id`, `name`, `direction`, `length`, `axis`, `dof`, `limits`, `end`), found \"idx\""),
            ("    id 2\n", "    id 2\n    id 3\n", "t.asf:23: `id` in the bone block is given twice (first on line 22)"),
            ("name b", "name a", "t.asf:23:10: two bones are named \"a\" (the first on line 12)"),
            ("name b", "name Root", "t.asf:23:10: a bone cannot be named \"Root\": the name is reserved for the root"),
            ("name b", "name b c", "t.asf:23: expected one bone name (no spaces) after `name`, found \"name b c\""),
            ("           (-30 30)\n", "", "t.asf:17: bone \"a\" has 2 limit pairs for 3 dofs"),
            ("(-20 20)", "(-20 20", "t.asf:18: expected a complete `(min max)` pair on one line, found \"(-20 20\""),
            ("(-20 20)", "(-20 nan)", "t.asf:18:17: expected a limit (a number, `inf` or `-inf`), found \"nan\""),
            ("(-20 20)", "-20 20", "t.asf:18:12: expected a bone entry (`id`, `name`, `direction`, `length`, `axis`, `dof`, `limits`, `end`), found \"-20\""),
            ("limits (-10 10)", "limits -10 10", "t.asf:17:12: expected `(` (a limit pair), found \"-10\""),
            ("limits (-10 10)", "limits (-10 10 5)", "t.asf:17:20: expected `)` after two limits, found \"5\""),
            ("    length 1\n", "", "t.asf:27: the bone block opened on line 21 has no `length`"),
            ("    name b\n", "", "t.asf:27: the bone block opened on line 21 has no `name`"),
            ("    dof rz\n  end\n", "    dof rz\n", "t.asf:28: the bone block opened on line 21 has no `end` before the next section starts"),
            ("  begin\n    id 2", "  begin\n  begin\n    id 2", "t.asf:22: `begin` inside the bone block opened on line 21 (missing `end`)"),
            ("  end\n  begin\n    id 2", "  end\n  start\n    id 2", "t.asf:21: expected `begin` (a bone block), found \"start\""),
            ("  end\n:hierarchy", "  end x\n:hierarchy", "t.asf:28:7: expected nothing after `end`, found \"x\""),
            ("a b\n", "a c\n", "t.asf:32:7: unknown bone \"c\": `:bonedata` has no bone of that name"),
            ("a b\n", "x b\n", "t.asf:32:5: unknown bone \"x\": `:bonedata` has no bone of that name"),
            ("a b\n", "a b root\n", "t.asf:32:9: the root cannot be a child"),
            ("a b\n", "b b\n", "t.asf:32:7: bone \"b\" is listed as its own child"),
            ("root a\n", "root a b\n", "t.asf:32:7: bone \"b\" already is a child of \"root\" (line 31)"),
            ("a b\n", "a\n", "t.asf:23: bone \"b\" is not listed as a child in `:hierarchy`, so it has no place in the skeleton"),
            ("root a\n    a b\n", "b a\n    a b\n", "t.asf:31: bones b -> a form a parent cycle, not connected to the root"),
            ("    a b\n  end\n", "    a b\n", "t.asf:32: truncated: the `:hierarchy` block opened on line 30 has no `end` before the file ends"),
            (":hierarchy\n  begin\n", ":hierarchy\n  start\n", "t.asf:30: expected `begin` (the hierarchy block), found \"start\""),
            ("    a b\n  end\n", "    a b\n  end\n  more\n", "t.asf:34: expected the next `:section` (the hierarchy block has ended), found \"more\""),
            ("  length 0.45", "  length 0", "t.asf:2:10: the length unit must be positive, got 0"),
            ("  length 0.45", "  length 0.45 m", "t.asf:2: expected a `:units` entry `name value` (`mass 1.0`, `length 0.45`, `angle deg`), found \"length 0.45 m\""),
            ("  angle deg", "  angle grad", "t.asf:3:9: expected `deg` or `rad`, found \"grad\""),
            ("  angle deg", "  angle deg\n  ANGLE rad", "t.asf:4: `angle` in `:units` is given twice (first on line 3)"),
            ("order TX TY TZ RX RY RZ", "order TX TY TZ RX RY L", "t.asf:5:24: expected a root dof (TX TY TZ RX RY RZ), found \"L\""),
            ("  axis XYZ\n", "", "t.asf:4: `:root` has no `axis` line"),
            ("  axis XYZ", "  axis XYZ ZYX", "t.asf:6: expected one axis order after `axis` (e.g. `axis XYZ`), found \"axis XYZ ZYX\""),
            ("  position 0 0 0", "  position 0 0", "t.asf:7: expected 3 numbers after `position`, found \"position 0 0\""),
            ("  orientation 0 0 0", "  orientation 0 0 0\n  scale 1", "t.asf:9:3: expected `order`, `axis`, `position` or `orientation`, found \"scale\""),
            (":units\n", "hello\n:units\n", "t.asf:1: expected a `:keyword` line (`:units`, `:root`, `:bonedata`, `:hierarchy`, ...), found \"hello\""),
            (":root\n", ":units\n:root\n", "t.asf:4: `:units` is given twice (first on line 1)"),
            (":root\n", ":root x\n", "t.asf:4:7: expected nothing after `:root` (its entries go on the next lines), found \"x\""),
        ];
    for (old, new, expected) in cases {
        assert_eq!(
            &asf_err(old, new),
            expected,
            "replacing {old:?} with {new:?}"
        );
    }
}

#[test]
fn asf_missing_sections_and_empty_files() {
    let root_only =
        ":root\n  order TX TY TZ RX RY RZ\n  axis XYZ\n  position 0 0 0\n  orientation 0 0 0\n";
    let e = parse_asf(root_only, Path::new("t.asf")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.asf:5: truncated: the file ends without a `:bonedata` section"
    );
    assert!(matches!(e.problem, Problem::Truncated(_)));
    let e = parse_asf(":units\n  length 1\n", Path::new("t.asf")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.asf:2: truncated: the file ends without a `:root` section"
    );
    let cut = &BASE[..BASE.find("    length 1").unwrap()];
    assert_eq!(
        parse_asf(cut, Path::new("t.asf")).unwrap_err().to_string(),
        "t.asf:24: truncated: the bone block opened on line 21 has no `end` before the file ends"
    );
    for empty in ["", "\n\n", "# only a comment\r\n  \r\n"] {
        let e = parse_asf(empty, Path::new("t.asf")).unwrap_err();
        assert!(matches!(e.problem, Problem::Empty), "{e}");
    }
    // A root with no bones is a valid (one-joint) skeleton.
    let asf = parse_asf(&format!("{root_only}:bonedata\n"), Path::new("t.asf")).unwrap();
    assert_eq!(
        to_asset("t", &asf, &[], 30.0).unwrap().asset.skeleton.len(),
        1
    );
}

#[test]
fn end_joint_names_must_not_clash_with_bones() {
    let text = BASE
        .replacen("name b", "name a_end", 1)
        .replacen("a b\n", "root a_end\n", 1);
    let asf = parse_asf(&text, Path::new("t.asf")).unwrap();
    let e = to_asset("t", &asf, &[], 30.0).unwrap_err().to_string();
    assert_eq!(
        e,
        "t.asf:23: bone \"a_end\" has the name rigport gives the end joint of leaf bone \"a\""
    );
}

#[test]
fn edited_asf_structs_do_not_panic() {
    // `Asf` fields are public: a cycle or a dangling parent edited in is an error.
    let mut asf = parse_asf(BASE, Path::new("t.asf")).unwrap();
    asf.bones[0].parent = Some(1);
    let e = to_asset("t", &asf, &[], 30.0).unwrap_err().to_string();
    assert_eq!(
        e,
        "t.asf:31: bones b -> a form a parent cycle, not connected to the root"
    );
    asf.bones[0].parent = Some(7);
    let e = to_asset("t", &asf, &[], 30.0).unwrap_err().to_string();
    assert_eq!(
        e,
        "t.asf:31: bone \"a\" names parent bone #7, but there are 2 bones"
    );
    let mut asf = parse_asf(BASE, Path::new("t.asf")).unwrap();
    asf.bones[0].length = 1e39;
    let e = to_asset("t", &asf, &[], 30.0).unwrap_err().to_string();
    assert!(
        e.starts_with("t.asf:23: joint \"b\": its rest offset"),
        "{e}"
    );
}

const BASE_AMC: &str = ":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\na 1 2 3\nb 4\n";

fn amc_err(old: &str, new: &str) -> String {
    assert!(BASE_AMC.contains(old), "{old:?}");
    let asf = parse_asf(BASE, Path::new("t.asf")).unwrap();
    parse_amc(&BASE_AMC.replacen(old, new, 1), Path::new("t.amc"), &asf)
        .expect_err("should fail")
        .to_string()
}

#[test]
fn amc_errors_name_the_line() {
    let cases: &[(&str, &str, &str)] = &[
            ("a 1 2 3", "a 1 2", "t.amc:5: \"a\" has 2 values, but its dofs (rx ry rz) need 3"),
            ("a 1 2 3", "a 1 2 3 4", "t.amc:5: \"a\" has 4 values, but its dofs (rx ry rz) need 3"),
            ("root 0 0 0 0 0 0", "root 0 0 0", "t.amc:4: \"root\" has 3 values, but its dofs (tx ty tz rx ry rz) need 6"),
            ("b 4", "c 4", "t.amc:6:1: unknown bone \"c\": the skeleton t.asf has no bone of that name"),
            ("b 4", "B 4", "t.amc:6:1: unknown bone \"B\": the skeleton t.asf has no bone of that name"),
            ("b 4", "b 4x", "t.amc:6:3: dof value \"4x\" is not a number"),
            ("b 4", "b nan", "t.amc:6:3: dof value \"nan\" is not finite"),
            ("b 4", "b 4\na 1 2 3", "t.amc:7: \"a\" in frame 1 is given twice (first on line 5)"),
            ("1\n", "", "t.amc:3: the bone line for \"root\" comes before the first frame number"),
            ("1\n", "-1\n", "t.amc:3:1: expected a frame number (a non-negative integer), found \"-1\""),
            ("1\n", "1.5\n", "t.amc:3:1: expected a frame number (a non-negative integer), found \"1.5\""),
            ("1\n", "99999999999999999999999\n", "t.amc:3:1: frame number \"99999999999999999999999\" is out of range for u64"),
            ("b 4\n", "b 4\n:DEGREES\n", "t.amc:7: expected a frame number or a bone line (`:` header lines come before the first frame), found \":DEGREES\""),
            (":DEGREES\n", ":DEGREES\n:radians\n", "t.amc:3: :radians contradicts the angle unit given on line 2"),
        ];
    for (old, new, expected) in cases {
        assert_eq!(
            &amc_err(old, new),
            expected,
            "replacing {old:?} with {new:?}"
        );
    }
    let asf = parse_asf(BASE, Path::new("t.asf")).unwrap();
    let e = parse_amc(":FULLY-SPECIFIED\n:DEGREES\n", Path::new("t.amc"), &asf).unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.amc:2: truncated: the file ends before its first frame"
    );
    let e = parse_amc("\r\n# nothing\n", Path::new("t.amc"), &asf).unwrap_err();
    assert!(matches!(e.problem, Problem::Empty), "{e}");
    // Huge values parse, but a translation beyond f32 is refused at its frame.
    let amc = parse_amc("1\nroot 1e300 0 0 0 0 0\n", Path::new("t.amc"), &asf).unwrap();
    let e = to_asset("t", &asf, &[("m".into(), amc)], 30.0)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "t.amc:1: frame 1: the translation of joint \"root\" does not fit 32-bit floats"
    );
    // Too many frames for distinct f32 key times at a tiny rate.
    let amc = parse_amc("1\n2\n", Path::new("t.amc"), &asf).unwrap();
    let e = to_asset("t", &asf, &[("m".into(), amc)], 1e-40)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("t.amc: frame 1 at"), "{e}");
}

#[test]
fn amc_bones_without_dofs_may_be_listed_and_lines_may_break_oddly() {
    let text = "\
:units\n angle deg\n:root\n order TX TY TZ RX RY RZ\n axis XYZ\n position 0 0 0\n orientation 0 0 0\n\
:bonedata\n begin\n name a\n direction 0 1 0\n length 1\n axis 0 0 0 XYZ\n end\n\
:hierarchy\n begin\n root a\n end\n";
    let asf = parse_asf(text, Path::new("t.asf")).unwrap();
    let amc = parse_amc(
        "1\rroot 0 1 0 0 0 0\ra\r2\r\nroot 0 2 0 0 0 0 # comment\n",
        Path::new("t.amc"),
        &asf,
    )
    .unwrap();
    assert_eq!(
        amc.frames,
        [
            AmcFrame { number: 1, line: 1 },
            AmcFrame { number: 2, line: 4 }
        ]
    );
    assert_eq!(
        amc.values,
        [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0]
    );
    let e = parse_amc("1\na 5\n", Path::new("t.amc"), &asf)
        .unwrap_err()
        .to_string();
    assert_eq!(e, "t.amc:2: \"a\" has 1 values, but its dofs (none) need 0");
}

// ------------------------------------------------------------------------------
// Fuzzing: truncations and byte edits never panic.

const FUZZ_SEEDS: [(&str, &str); 3] = [
    (
        include_str!("../../../../fixtures/asf_amc/chain.asf"),
        include_str!("../../../../fixtures/asf_amc/chain.amc"),
    ),
    (
        include_str!("../../../../fixtures/asf_amc/quirks.asf"),
        include_str!("../../../../fixtures/asf_amc/quirks.amc"),
    ),
    (
        include_str!("../../../../fixtures/asf_amc/translation.asf"),
        include_str!("../../../../fixtures/asf_amc/translation.amc"),
    ),
];

/// Bytes that steer edits towards the format's own tokens.
const INTERESTING: &[u8] = b"0123456789 .-+eE\n\r\t#():,xyzXYZrtlLa_";

fn edit(text: &str, cut: f64, edits: &[(f64, u8, bool, u8)]) -> String {
    let mut bytes = text.as_bytes().to_vec();
    for &(at, byte, interesting, op) in edits {
        let i = ((at * bytes.len() as f64) as usize).min(bytes.len());
        let b = if interesting {
            INTERESTING[byte as usize % INTERESTING.len()]
        } else {
            byte
        };
        match op {
            0 if i < bytes.len() => bytes[i] = b,
            1 => bytes.insert(i, b),
            _ if i < bytes.len() => {
                bytes.remove(i);
            }
            _ => {}
        }
    }
    bytes.truncate(((cut * bytes.len() as f64) as usize).min(bytes.len()));
    String::from_utf8_lossy(&bytes).into_owned()
}

fn run_all(asf_text: &str, amc_text: &str) {
    let Ok(asf) = parse_asf(asf_text, Path::new("f.asf")) else {
        return;
    };
    let _ = to_asset("f", &asf, &[], 30.0);
    if let Ok(amc) = parse_amc(amc_text, Path::new("f.amc"), &asf) {
        let _ = to_asset("f", &asf, &[("m".into(), amc)], 30.0);
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(512))]
    #[test]
    fn truncated_or_edited_files_never_panic(
        seed in 0_usize..FUZZ_SEEDS.len(),
        cut_asf in 0.0_f64..=1.0,
        cut_amc in 0.0_f64..=1.0,
        edits in proptest::collection::vec(
            (0.0_f64..1.0, proptest::prelude::any::<u8>(), proptest::prelude::any::<bool>(), 0_u8..3),
            0..10,
        ),
    ) {
        let (asf, amc) = FUZZ_SEEDS[seed];
        let (asf_edits, amc_edits) = edits.split_at(edits.len() / 2);
        let asf_edited = edit(asf, 1.0, asf_edits);
        let amc_edited = edit(amc, cut_amc, amc_edits);
        // Edited ASF with the pristine motion, pristine ASF with the edited motion,
        // both edited, and a truncated ASF.
        run_all(&asf_edited, amc);
        run_all(asf, &amc_edited);
        run_all(&asf_edited, &amc_edited);
        run_all(&edit(asf, cut_asf, &[]), amc);
    }
}

// ------------------------------------------------------------------------------
// The corpus.

#[test]
fn corpus_motions_match_the_formula() {
    let Some(dir) = corpus("usc_csci520_mocapPlayer__shreyabhaumik") else {
        return;
    };
    for (asf_name, amc_name) in [
        ("07-walk.asf", "07_05-walk.amc"),
        ("09-run.asf", "09_06-run.amc"),
        ("131-dance.asf", "131_04-dance.amc"),
    ] {
        let (asf_path, amc_path) = (dir.join(asf_name), dir.join(amc_name));
        let (asf_text, amc_text) = (read(&asf_path), read(&amc_path));
        // Parse + to_asset, timed as the best of 3 runs (the machine is shared).
        let mut best = std::time::Duration::MAX;
        let mut result = None;
        for _ in 0..3 {
            let start = std::time::Instant::now();
            let asf = parse_asf(&asf_text, &asf_path).unwrap_or_else(|e| panic!("{e}"));
            let amc = parse_amc(&amc_text, &amc_path, &asf).unwrap_or_else(|e| panic!("{e}"));
            let motions = [(amc_name.to_string(), amc)];
            let imported =
                to_asset(asf_name, &asf, &motions, DEFAULT_FPS).unwrap_or_else(|e| panic!("{e}"));
            best = best.min(start.elapsed());
            result = Some((asf, motions, imported));
        }
        let (asf, motions, imported) = result.unwrap();
        let elapsed = best;
        let amc = &motions[0].1;
        println!(
            "{amc_name}: {} frames, parse + to_asset {elapsed:?}",
            amc.frames.len()
        );
        assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
        let asset = &imported.asset;
        assert_eq!(asf.bones.len(), 30);
        // 30 bones, the root and 7 leaf ends (toes, head, fingers and thumbs).
        assert_eq!(asset.skeleton.len(), 38);
        assert_eq!(asset.meters_per_unit, Some(0.0254 / 0.45));
        let frames = frame_line_count(&amc_text);
        assert_eq!(amc.frames.len(), frames);
        let clip = &asset.clips[0];
        assert!(clip.tracks.iter().all(|t| t.times.len() == frames));
        // Root translation and rotation plus one rotation per bone with dofs (29 of 30:
        // lhipjoint and rhipjoint have none, so 28... counted from the ASF).
        let rotating = asf.bones.iter().filter(|b| !b.dofs.is_empty()).count();
        assert_eq!(clip.tracks.len(), 2 + rotating);
        let worst = check_fk(&asf, amc, &imported, 0, DEFAULT_FPS);
        println!("  max FK deviation {worst:e} (height {})", height(asset));

        // Physical sanity the formula comparison cannot give (both sides share the
        // conventions): y is up, so the head stays above the root and the toes below
        // it. (Both feet need not reach the same floor: in 07_05 the lowest left and
        // right foot points differ by 1.3 units, also in an independent Python FK.)
        for k in 0..frames {
            let p = asset_positions(asset, clip, k);
            assert!(
                p["head"].y > p["root"].y && p["root"].y > p["ltoes"].y,
                "frame {k}"
            );
        }

        // Bone lengths stay constant: every joint keeps its rest distance to its parent.
        let rest: Vec<f32> = asset
            .skeleton
            .joints()
            .iter()
            .map(|j| j.rest_local.translation.length())
            .collect();
        let tolerance = 1e-5 * height(asset) as f32;
        for k in 0..frames {
            let p = asset_positions(asset, clip, k);
            for (j, joint) in asset.skeleton.joints().iter().enumerate() {
                let Some(parent) = joint.parent else { continue };
                let parent = &asset.skeleton.joint(parent).name;
                let d = p[&joint.name].distance(p[parent]);
                assert!(
                    (d - rest[j]).abs() <= tolerance,
                    "{amc_name} frame {k}: {} is {d} from {parent}, {} at rest",
                    joint.name,
                    rest[j]
                );
            }
        }
    }
}

#[test]
fn corpus_legs_only_skeleton_imports() {
    let Some(dir) = corpus("lowerbody_edge_case__cvikramk_TimeGAN") else {
        return;
    };
    let imported = import(&dir.join("02.asf"), &[], DEFAULT_FPS).unwrap_or_else(|e| panic!("{e}"));
    assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
    let s = &imported.asset.skeleton;
    let names: Vec<&str> = s.joints().iter().map(|j| j.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "root",
            "lhipjoint",
            "lfemur",
            "ltibia",
            "ltibia_end",
            "rhipjoint",
            "rfemur",
            "rtibia",
            "rtibia_end"
        ]
    );
    assert!(imported.asset.clips.is_empty());
    assert_eq!(imported.asset.meters_per_unit, Some(0.0254 / 0.45));
    // The shin hangs below the knee: ltibia's end is 7.28717 units from its start.
    let end = s
        .joint(s.find("ltibia_end").unwrap())
        .rest_local
        .translation;
    assert!((end.length() - 7.28717).abs() < 1e-5);
}
