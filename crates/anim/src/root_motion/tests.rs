use super::*;
use glam::{Mat4, Quat, Vec3};
use rigport_eval::test_support::sample_at;
use rigport_model::{
    Influences, Interpolation, Joint, MeshIndex, Skeleton, SkinBinding, Track, TrackTarget,
    Transform,
};

const FPS: f32 = 30.0;
const WALK_SPEED: f32 = 1.4;
const SWAY: f32 = 0.03;
const BOB: f32 = 0.02;
const CYCLE_S: f32 = 1.0;

fn joint(name: &str, parent: Option<u32>, rest: Transform) -> Joint {
    Joint {
        name: name.into(),
        parent: parent.map(JointIndex),
        rest_local: rest,
    }
}

fn offset(x: f32, y: f32, z: f32) -> Transform {
    Transform::from_translation(Vec3::new(x, y, z))
}

/// A walker: `hips` (index `first`) with a leg below it, walking along +z at
/// [`WALK_SPEED`], swaying sideways once per [`CYCLE_S`] and bobbing twice, turning by
/// `turn_rad_s` about +y. With `armature`, an armature joint (scaled 0.01, turned -90°
/// about x, as Mixamo's) comes first and the hips numbers are in its space.
fn walker(armature: bool, turn_rad_s: f32) -> Asset {
    let mut joints = Vec::new();
    if armature {
        joints.push(joint(
            "Armature",
            None,
            Transform {
                translation: Vec3::new(0.5, 0.0, -0.2),
                rotation: Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
                scale: Vec3::splat(0.01),
            },
        ));
    }
    let first = joints.len() as u32;
    let parent = armature.then_some(0);
    joints.push(joint("hips", parent, offset(0.0, 1.0, 0.0)));
    joints.push(joint("leg", Some(first), offset(0.1, -0.5, 0.0)));
    joints.push(joint("foot", Some(first + 1), offset(0.0, -0.45, 0.0)));
    let skeleton = Skeleton::new(joints).expect("valid");
    let frames = 91;
    let times: Vec<f32> = (0..frames).map(|k| k as f32 / FPS).collect();
    let mut translations = Vec::new();
    let mut rotations = Vec::new();
    for &t in &times {
        let phase = std::f32::consts::TAU * t / CYCLE_S;
        let heading = turn_rad_s * t;
        let turn = Quat::from_rotation_y(heading);
        let along = turn * Vec3::new(SWAY * phase.sin(), 0.0, WALK_SPEED * t);
        let model = Vec3::new(along.x, 1.0 + BOB * (2.0 * phase).sin(), along.z);
        let rotation = turn * Quat::from_rotation_y(0.1 * phase.sin());
        // In the armature's space when there is one: inverse of its rest transform.
        let (m, r) = if armature {
            let a = skeleton.joint(JointIndex(0)).rest_local.to_mat4();
            (
                a.inverse().transform_point3(model),
                Quat::from_rotation_x(std::f32::consts::FRAC_PI_2) * rotation,
            )
        } else {
            (model, rotation)
        };
        translations.extend_from_slice(&m.to_array());
        rotations.extend_from_slice(&r.to_array());
    }
    let track = |target, values| Track {
        target,
        interpolation: Interpolation::Linear,
        times: times.clone(),
        values,
    };
    let hips = JointIndex(first);
    let leg_swing: Vec<f32> = (times.iter())
        .flat_map(|&t| Quat::from_rotation_x(0.4 * (std::f32::consts::TAU * t).sin()).to_array())
        .collect();
    Asset {
        skeleton,
        skins: vec![SkinBinding {
            mesh: MeshIndex(0),
            joints: vec![hips, JointIndex(first + 1)],
            inv_bind: vec![Mat4::IDENTITY; 2],
            influences: Influences::default(),
            method: Default::default(),
        }],
        clips: vec![Clip {
            name: "walk".into(),
            tracks: vec![
                track(TrackTarget::Translation(hips), translations),
                track(TrackTarget::Rotation(hips), rotations),
                track(TrackTarget::Rotation(JointIndex(first + 1)), leg_swing),
            ],
        }],
        ..Asset::default()
    }
}

/// Model matrices of every joint at every key time of clip 0.
fn model_frames(asset: &Asset) -> Vec<Vec<Mat4>> {
    let clip = &asset.clips[0];
    let compiled = rigport_eval::sample::CompiledClip::new(clip, &asset.skeleton).expect("fits");
    (compiled.key_times().iter())
        .map(|&t| {
            let local = sample_at(clip, &asset.skeleton, t);
            let mut model: Vec<Mat4> = Vec::with_capacity(local.len());
            for (j, l) in local.iter().enumerate() {
                let m = l.to_mat4();
                model.push(match asset.skeleton.joints()[j].parent {
                    Some(p) => model[p.get()] * m,
                    None => m,
                });
            }
            model
        })
        .collect()
}

fn options(mode: RootMotion, yaw: bool) -> RootMotionOptions {
    RootMotionOptions {
        mode,
        yaw,
        ..RootMotionOptions::default()
    }
}

#[test]
fn smoothing_follows_a_line_to_the_ends_and_averages_a_cycle_away_inside() {
    let times: Vec<f64> = (0..121).map(|k| f64::from(k) / 30.0).collect();
    let line: Vec<f64> = times.iter().map(|t| 3.0 - 1.5 * t).collect();
    for window in [0.0, 0.2, 1.0, 10.0] {
        let s = smooth(&times, &line, window);
        for (a, b) in s.iter().zip(&line) {
            assert!((a - b).abs() < 1e-12, "window {window}: {a} vs {b}");
        }
    }
    let swaying: Vec<f64> = (times.iter())
        .map(|t| 2.0 * t + 0.1 * (std::f64::consts::TAU * t).sin())
        .collect();
    let s = smooth(&times, &swaying, 1.0);
    // Inside (a whole cycle fits in the window): the 31 samples of one cycle average the
    // sine to zero, up to the sampling of its ends.
    for (k, (a, t)) in s.iter().zip(&times).enumerate().take(105).skip(16) {
        assert!(
            (a - 2.0 * t).abs() < 0.1 * 0.04,
            "key {k}: {a} vs {}",
            2.0 * t
        );
    }
    assert_eq!(smooth(&times, &swaying, 0.0), swaying);
}

#[test]
fn keep_changes_nothing() {
    let mut asset = walker(false, 0.0);
    let before = asset.clone();
    let report = root_motion(
        &mut asset,
        JointIndex(0),
        Vec3::Y,
        &options(RootMotion::Keep, true),
    );
    assert_eq!(report.expect("keep").travel, vec![]);
    assert_eq!(asset, before);
}

#[test]
fn in_place_keeps_the_sway_and_the_height_and_removes_the_travel() {
    // By default the hips are held over the origin exactly.
    let mut asset = walker(false, 0.0);
    root_motion(
        &mut asset,
        JointIndex(0),
        Vec3::Y,
        &options(RootMotion::InPlace, false),
    )
    .expect("in place");
    for m in model_frames(&asset) {
        let p = m[0].w_axis;
        assert!(Vec3::new(p.x, 0.0, p.z).length() < 1e-5, "{p}");
    }
    // A 1 s window keeps the sway about the smoothed path.
    for armature in [false, true] {
        let mut asset = walker(armature, 0.0);
        let hips = JointIndex(u32::from(armature));
        let before = model_frames(&asset);
        let report = root_motion(
            &mut asset,
            hips,
            Vec3::Y,
            &RootMotionOptions {
                window_s: 1.0,
                ..options(RootMotion::InPlace, false)
            },
        )
        .expect("in place");
        let travel = &report.travel[0];
        assert!(
            (travel.distance - WALK_SPEED * 3.0).abs() < 0.01,
            "{travel:?}"
        );
        // The heading sways ±5.7°; at the ends the fitted line leans with it.
        assert!(
            (travel.speed - WALK_SPEED).abs() < 0.01 && travel.turn_deg.abs() < 10.0,
            "{travel:?}"
        );
        assert_eq!((report.root, report.added_joint), (None, false));
        assert_eq!(asset.skeleton.len(), before[0].len());
        let after = model_frames(&asset);
        let mut worst_ground: f32 = 0.0;
        for (b, a) in before.iter().zip(&after) {
            let (pb, pa) = (b[hips.get()].w_axis, a[hips.get()].w_axis);
            assert!((pb.y - pa.y).abs() < 1e-6, "{} vs {}", pb.y, pa.y);
            worst_ground = worst_ground.max(Vec3::new(pa.x, 0.0, pa.z).length());
            // The hips' pose relative to the path: the legs move as before.
            let leg = |m: &[Mat4]| m[hips.get()].inverse() * m[hips.get() + 2];
            assert!(leg(b).abs_diff_eq(leg(a), 1e-4));
        }
        // Sway (3 cm) stays, travel (4.2 m) is gone; near the ends the fitted line
        // leaves a little more than the sway.
        assert!(
            worst_ground < 2.0 * SWAY && worst_ground > 0.5 * SWAY,
            "{worst_ground}"
        );
        if armature {
            // The armature keeps its rest (no track); the chain below it moved.
            assert!(!(asset.clips[0].tracks.iter())
                .any(|t| t.target == TrackTarget::Translation(JointIndex(0))));
        }
    }
}

#[test]
fn extract_adds_a_root_whose_track_with_the_hips_gives_the_original_hips() {
    for yaw in [false, true] {
        let mut asset = walker(false, 0.6);
        let before = model_frames(&asset);
        let report = root_motion(
            &mut asset,
            JointIndex(0),
            Vec3::Y,
            &options(RootMotion::Extract, yaw),
        )
        .expect("extract");
        assert_eq!(
            (report.root, report.added_joint),
            (Some(JointIndex(0)), true)
        );
        assert!(
            (report.travel[0].turn_deg - 0.6f32.to_degrees() * 3.0).abs() < 10.0,
            "{:?}",
            report.travel
        );
        assert_eq!(asset.skeleton.joint(JointIndex(0)).name, ROOT_NAME);
        assert_eq!(
            asset.skeleton.joint(JointIndex(1)).parent,
            Some(JointIndex(0))
        );
        assert_eq!(asset.skins[0].joints, vec![JointIndex(1), JointIndex(2)]);
        let after = model_frames(&asset);
        for (b, a) in before.iter().zip(&after) {
            for j in 0..b.len() {
                assert!(
                    b[j].abs_diff_eq(a[j + 1], 2e-5),
                    "joint {j}: {} vs {}",
                    b[j],
                    a[j + 1]
                );
            }
            // The root stays on the ground and (with yaw) turns about up only.
            let root = a[0];
            assert!(root.w_axis.y.abs() < 1e-6);
            assert!(root.transform_vector3(Vec3::Y).abs_diff_eq(Vec3::Y, 1e-6));
        }
        // With yaw the hips face one way relative to the root, give or take the sway.
        let hips_local = |m: &[Mat4]| (m[0].inverse() * m[1]).transform_vector3(Vec3::Z);
        let turned = hips_local(&after[0]).angle_between(hips_local(&after[after.len() - 1]));
        assert_eq!(turned < 0.2, yaw, "{turned}");
    }
}

#[test]
fn extract_puts_the_travel_on_an_existing_top_joint() {
    let mut asset = walker(true, 0.3);
    let before = model_frames(&asset);
    let report = root_motion(
        &mut asset,
        JointIndex(1),
        Vec3::Y,
        &options(RootMotion::Extract, true),
    )
    .expect("extract");
    assert_eq!(
        (report.root, report.added_joint),
        (Some(JointIndex(0)), false)
    );
    let after = model_frames(&asset);
    for (b, a) in before.iter().zip(&after) {
        for j in 1..b.len() {
            assert!(
                b[j].abs_diff_eq(a[j], 1e-4),
                "joint {j}: {} vs {}",
                b[j],
                a[j]
            );
        }
    }
    // The armature now travels (on a turning walk, 4.2 m along a spiral) and turns.
    let moved = after[after.len() - 1][0].w_axis.truncate() - after[0][0].w_axis.truncate();
    assert!(moved.length() > 3.0 && moved.y.abs() < 1e-4, "{moved}");
}

#[test]
fn up_along_z_keeps_the_z_component() {
    // The same walker seen in a Z-up model space: up is +z, the ground x-y.
    let mut asset = walker(false, 0.0);
    let to_z = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
    for track in &mut asset.clips[0].tracks {
        match track.target {
            TrackTarget::Translation(_) => (track.values.chunks_exact_mut(3)).for_each(|v| {
                let p = to_z * Vec3::from_slice(v);
                v.copy_from_slice(&p.to_array());
            }),
            TrackTarget::Rotation(JointIndex(0)) => {
                (track.values.chunks_exact_mut(4)).for_each(|v| {
                    v.copy_from_slice(&(to_z * Quat::from_slice(v)).to_array());
                })
            }
            _ => {}
        }
    }
    let before = model_frames(&asset);
    root_motion(
        &mut asset,
        JointIndex(0),
        Vec3::Z,
        &options(RootMotion::InPlace, true),
    )
    .expect("in place");
    for (b, a) in before.iter().zip(&model_frames(&asset)) {
        assert!((b[0].w_axis.z - a[0].w_axis.z).abs() < 1e-6);
        assert!(a[0].w_axis.truncate().truncate().length() < 2.0 * SWAY);
    }
}

#[test]
fn bad_inputs_are_refused_and_leave_the_asset() {
    let mut asset = walker(false, 0.0);
    let before = asset.clone();
    let extract = options(RootMotion::Extract, false);
    assert!(matches!(
        root_motion(&mut asset, JointIndex(9), Vec3::Y, &extract),
        Err(RootMotionError::NoSuchJoint { hips: 9, joints: 3 })
    ));
    let bad = RootMotionOptions {
        window_s: -1.0,
        ..extract
    };
    assert!(root_motion(&mut asset, JointIndex(0), Vec3::Y, &bad).is_err());
    assert_eq!(asset, before);
}
