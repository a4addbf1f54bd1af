use glam::{Quat, Vec3};
use rigport_model::{Clip, JointIndex, Skeleton, Transform};

use super::*;
use rigport_eval::sample::{rest_locals, sample_frames, CompiledClip};

/// World positions of every joint at every key time of `clip`, frame-major.
fn world(skeleton: &Skeleton, clip: &Clip, times: &[f32]) -> Vec<Vec3> {
    let compiled = CompiledClip::new(clip, skeleton).expect("clip fits");
    let frames = sample_frames(&compiled, &rest_locals(skeleton), times).expect("samples");
    positions(skeleton, &frames).expect("fk")
}

fn demo() -> rigport_model::Asset {
    rigport_demo::build(1).expect("demo builds").asset
}

fn run(source: &Skeleton, clip: &Clip, target: &Skeleton, options: &RetargetOptions) -> Retargeted {
    let map = auto_map(source, target, Vec3::Y, Vec3::Y, Some(clip)).expect("a map");
    let input = RetargetInput {
        source,
        source_up: Vec3::Y,
        clip,
        target,
        target_up: Vec3::Y,
        map: &map,
    };
    retarget(&input, options).expect("retargets")
}

#[test]
fn identity_on_the_demo_returns_the_motion() {
    let asset = demo();
    for clip in &asset.clips {
        let out = run(
            &asset.skeleton,
            clip,
            &asset.skeleton,
            &RetargetOptions::default(),
        );
        let times = CompiledClip::new(clip, &asset.skeleton)
            .expect("fits")
            .key_times();
        let (a, b) = (
            world(&asset.skeleton, clip, &times),
            world(&asset.skeleton, &out.clip, &times),
        );
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| x.distance(*y))
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-5 * out.report.height, "{}: {worst}", clip.name);
    }
}

/// The demo's arms point along ±x in rest (a T pose). The target's rest pose lowers them
/// by 40 degrees at the shoulder joint (`forearm_*`, which turns the upper arm): an A pose.
#[test]
fn t_pose_source_drives_an_a_pose_target_by_world_directions() {
    let asset = demo();
    let source = &asset.skeleton;
    let mut joints = source.joints().to_vec();
    for (name, sign) in [("forearm_l", -1.0f32), ("forearm_r", 1.0)] {
        let j = source.find(name).expect("shoulder joint").get();
        joints[j].rest_local.rotation = Quat::from_rotation_z(sign * 40f32.to_radians());
    }
    let target = Skeleton::new(joints).expect("same topology");
    let clip = &asset.clips[0]; // the wave: the right arm up and waving
    let out = run(source, clip, &target, &RetargetOptions::default());
    let times = CompiledClip::new(clip, source).expect("fits").key_times();
    let (a, b) = (
        world(source, clip, &times),
        world(&target, &out.clip, &times),
    );
    let n = source.len();
    let mut worst = 0.0f32;
    for side in ["l", "r"] {
        let bones = [
            (format!("forearm_{side}"), format!("hand_{side}")),
            (format!("hand_{side}"), format!("fingertip_{side}")),
        ];
        for (from, to) in bones {
            let (i, j) = (
                source.find(&from).expect("joint").get(),
                source.find(&to).expect("joint").get(),
            );
            for f in 0..times.len() {
                let ds = a[f * n + j] - a[f * n + i];
                let dt = b[f * n + j] - b[f * n + i];
                worst = worst.max(ds.angle_between(dt).to_degrees());
            }
        }
    }
    assert!(
        worst < 1.0,
        "arms differ from the source's directions by {worst} degrees"
    );
    // Without the rest-pose alignment the arm would be 40 degrees off.
    let rest_angle = {
        let r = target.model_rest_matrices();
        let (i, j) = (
            target.find("forearm_l").expect("j").get(),
            target.find("hand_l").expect("j").get(),
        );
        (r[j].w_axis - r[i].w_axis)
            .truncate()
            .angle_between(Vec3::X)
            .to_degrees()
    };
    assert!((rest_angle - 40.0).abs() < 1e-3, "{rest_angle}");
}

#[test]
fn pinocchio_sides_follow_the_rest_pose() {
    // Pinocchio's human template (skeleton.cpp), facing +z: its `l` joints at -x.
    let points: [(f32, f32, f32, i32); 18] = [
        (0.0, 0.5, 0.0, -1),
        (0.0, 0.15, 0.0, 0),
        (0.0, 0.0, 0.0, 1),
        (0.0, 0.7, 0.0, 0),
        (-0.1, 0.0, 0.0, 2),
        (-0.15, -0.35, 0.05, 4),
        (-0.15, -0.8, 0.0, 5),
        (-0.15, -0.8, 0.1, 6),
        (0.1, 0.0, 0.0, 2),
        (0.15, -0.35, 0.05, 8),
        (0.15, -0.8, 0.0, 9),
        (0.15, -0.8, 0.1, 10),
        (-0.2, 0.5, 0.0, 0),
        (-0.4, 0.25, 0.075, 12),
        (-0.6, 0.0, 0.15, 13),
        (0.2, 0.5, 0.0, 0),
        (0.4, 0.25, 0.075, 15),
        (0.6, 0.0, 0.15, 16),
    ];
    // rigport's layout: `root` at point 0, `bone_k` at the head of the bone ending at k.
    let at = |k: usize| Vec3::new(points[k].0, points[k].1, points[k].2);
    let mut joints = vec![rigport_model::Joint {
        name: "root".into(),
        parent: None,
        rest_local: Transform::from_translation(at(0)),
    }];
    for k in 1..18 {
        let head = points[k].3 as usize;
        let parent_bone = points[head].3;
        let (parent, parent_head) = if parent_bone < 0 {
            (0, 0)
        } else {
            (head, parent_bone as usize)
        };
        joints.push(rigport_model::Joint {
            name: format!("bone_{k}"),
            parent: Some(JointIndex(parent as u32)),
            rest_local: Transform::from_translation(at(head) - at(parent_head)),
        });
    }
    let skeleton = Skeleton::new(joints).expect("the template");
    let roles = maps::resolve(&skeleton, &maps::PINOCCHIO_HUMAN, Vec3::Y);
    let role_of = |name: &str| {
        let j = skeleton.find(name).expect("joint");
        roles.iter().find(|(_, x)| *x == j).map(|(r, _)| *r)
    };
    assert_eq!(role_of("bone_5"), Some("RightUpperLeg"));
    assert_eq!(role_of("bone_9"), Some("LeftUpperLeg"));
    assert_eq!(role_of("bone_16"), Some("LeftUpperArm"));
}

#[test]
fn bad_maps_are_refused() {
    let asset = demo();
    let s = &asset.skeleton;
    let clip = &asset.clips[0];
    let twice = JointMap {
        pairs: vec![
            MapPair {
                source: JointIndex(0),
                target: JointIndex(0),
                role: None,
            },
            MapPair {
                source: JointIndex(1),
                target: JointIndex(0),
                role: None,
            },
        ],
        pelvis: (JointIndex(0), JointIndex(0)),
        how: "test".into(),
    };
    let input = RetargetInput {
        source: s,
        source_up: Vec3::Y,
        clip,
        target: s,
        target_up: Vec3::Y,
        map: &twice,
    };
    assert!(matches!(
        retarget(&input, &RetargetOptions::default()),
        Err(RetargetError::MappedTwice(_))
    ));
    let out_of_range = JointMap {
        pairs: vec![MapPair {
            source: JointIndex(999),
            target: JointIndex(0),
            role: None,
        }],
        ..twice.clone()
    };
    let input = RetargetInput {
        map: &out_of_range,
        ..input
    };
    assert!(matches!(
        retarget(&input, &RetargetOptions::default()),
        Err(RetargetError::MapIndex { .. })
    ));
}

/// A map that leaves a limb unmoved, or puts a leg on the other leg, is refused naming the
/// joints; `allow_partial` retargets it with a coded warning.
#[test]
fn partial_maps_are_refused_unless_allowed() {
    let asset = demo();
    let s = &asset.skeleton;
    let clip = &asset.clips[0];
    let full = auto_map(s, s, Vec3::Y, Vec3::Y, Some(clip)).expect("a map");
    let joint = |name: &str| s.find(name).expect("joint");
    let left_arm = ["upper_arm_l", "forearm_l", "hand_l", "fingertip_l"].map(joint);
    let no_left_arm: Vec<(JointIndex, JointIndex)> = full
        .pairs
        .iter()
        .filter(|p| !left_arm.contains(&p.source))
        .map(|p| (p.source, p.target))
        .collect();
    let swapped: Vec<(JointIndex, JointIndex)> = full
        .pairs
        .iter()
        .map(|p| {
            let name = &s.joint(p.source).name;
            let other = match name.strip_suffix("_l") {
                Some(stem) if stem == "shin" => format!("{stem}_r"),
                _ => name.clone(),
            };
            (p.source, joint(&other))
        })
        .filter(|(src, t)| s.joint(*src).name != "shin_r" || *t != joint("shin_r"))
        .collect();
    let run = |pairs: &[(JointIndex, JointIndex)], allow_partial: bool| {
        let map = JointMap::from_pairs(s, pairs, Some(full.pelvis), "test").expect("pairs");
        let input = RetargetInput {
            source: s,
            source_up: Vec3::Y,
            clip,
            target: s,
            target_up: Vec3::Y,
            map: &map,
        };
        let options = RetargetOptions {
            allow_partial,
            ..RetargetOptions::default()
        };
        retarget(&input, &options)
    };
    match run(&no_left_arm, false) {
        Err(RetargetError::PartialMap(problems)) => assert_eq!(
            problems,
            vec![MapProblem::Unmapped {
                limb: Limb::LeftArm,
                joints: vec!["forearm_l".into(), "hand_l".into()],
            }]
        ),
        other => panic!("{other:?}"),
    }
    let out = run(&no_left_arm, true).expect("allowed");
    let warning = out
        .warnings
        .iter()
        .find(|w| w.code() == "W004")
        .expect("a W004 warning");
    assert!(
        warning.to_string().contains("left arm (forearm_l, hand_l)"),
        "{warning}"
    );
    match run(&swapped, false) {
        Err(RetargetError::PartialMap(problems)) => assert!(
            problems.contains(&MapProblem::WrongLimb {
                source: "shin_l".into(),
                source_limb: Limb::LeftLeg,
                target: "shin_r".into(),
                target_limb: Limb::RightLeg,
            }),
            "{problems:?}"
        ),
        other => panic!("{other:?}"),
    }
}
