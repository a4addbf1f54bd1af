//! Unit tests of the whole foot lock.

use glam::{Quat, Vec3};
use rigport_model::{
    Clip, Interpolation, Joint, JointIndex, Skeleton, Track, TrackTarget, Transform,
};

use super::*;

/// One leg, 0.95 tall, hips drifting `drift` forward over a second at 30 fps.
fn drifting_leg(drift: f32) -> (Skeleton, Clip) {
    let joint = |name: &str, parent: Option<u32>, t: Vec3| Joint {
        name: name.into(),
        parent: parent.map(JointIndex),
        rest_local: Transform::from_translation(t),
    };
    let skeleton = Skeleton::new(vec![
        joint("Hips", None, Vec3::new(0.0, 1.0, 0.0)),
        joint("LeftUpLeg", Some(0), Vec3::new(0.1, 0.0, 0.0)),
        joint("LeftLeg", Some(1), Vec3::new(0.0, -0.45, 0.05)),
        joint("LeftFoot", Some(2), Vec3::new(0.0, -0.45, -0.05)),
        joint("LeftToeBase", Some(3), Vec3::new(0.0, -0.05, 0.1)),
    ])
    .unwrap();
    let times: Vec<f32> = (0..31).map(|f| f as f32 / 30.0).collect();
    let values = times.iter().flat_map(|t| [0.0, 1.0, drift * t]).collect();
    let clip = Clip {
        name: "drift".into(),
        tracks: vec![Track {
            target: TrackTarget::Translation(JointIndex(0)),
            interpolation: Interpolation::Linear,
            times,
            values,
        }],
    };
    (skeleton, clip)
}

#[test]
fn a_drifting_planted_foot_is_held() {
    let (skeleton, clip) = drifting_leg(0.02);
    let (legs, _) = find_feet(&skeleton).unwrap();
    let locked = footlock(
        &skeleton,
        &clip,
        &legs,
        Vec3::Y,
        &FootlockOptions::default(),
    )
    .unwrap();
    eprintln!("{:#?}", locked.feet);
    assert!(locked.feet[0].after.max < 1e-5);
}

fn chain(names: &[(&str, Option<&str>)]) -> Skeleton {
    let index = |n: &str| names.iter().position(|(m, _)| *m == n).unwrap() as u32;
    Skeleton::new(
        names
            .iter()
            .map(|(name, parent)| Joint {
                name: (*name).into(),
                parent: parent.map(|p| JointIndex(index(p))),
                rest_local: Transform::from_translation(Vec3::new(0.0, -0.1, 0.01)),
            })
            .collect(),
    )
    .unwrap()
}

fn names_of(skeleton: &Skeleton, legs: &[Leg]) -> Vec<[String; 4]> {
    let n = |j: JointIndex| skeleton.joint(j).name.clone();
    legs.iter()
        .map(|l| {
            [
                n(l.hip),
                n(l.knee),
                n(l.ankle),
                l.toe.map(n).unwrap_or_default(),
            ]
        })
        .collect()
}

#[test]
fn feet_are_found_by_the_names_of_common_skeletons() {
    // CMU ASF, one leg only (the truncated corpus ASF has both; any subset works).
    let cmu = chain(&[
        ("root", None),
        ("rhipjoint", Some("root")),
        ("rfemur", Some("rhipjoint")),
        ("rtibia", Some("rfemur")),
        ("rfoot", Some("rtibia")),
        ("rtoes", Some("rfoot")),
    ]);
    let (legs, convention) = find_feet(&cmu).unwrap();
    assert_eq!(convention, "CMU ASF");
    assert_eq!(legs[0].label, "right");
    assert_eq!(
        names_of(&cmu, &legs),
        [["rfemur", "rtibia", "rfoot", "rtoes"].map(String::from)]
    );
    // Mixamo's namespace and Bandai's suffixes.
    let mixamo = chain(&[
        ("mixamorig:Hips", None),
        ("mixamorig:LeftUpLeg", Some("mixamorig:Hips")),
        ("mixamorig:LeftLeg", Some("mixamorig:LeftUpLeg")),
        ("mixamorig:LeftFoot", Some("mixamorig:LeftLeg")),
        ("mixamorig:LeftToeBase", Some("mixamorig:LeftFoot")),
        ("mixamorig:RightUpLeg", Some("mixamorig:Hips")),
        ("mixamorig:RightLeg", Some("mixamorig:RightUpLeg")),
        ("mixamorig:RightFoot", Some("mixamorig:RightLeg")),
    ]);
    let (legs, _) = find_feet(&mixamo).unwrap();
    assert_eq!(legs.len(), 2);
    assert_eq!(
        mixamo.joint(legs[0].toe.unwrap()).name,
        "mixamorig:LeftToeBase"
    );
    assert_eq!(legs[1].toe, None);
    let bandai = chain(&[
        ("joint_Root", None),
        ("Hips", Some("joint_Root")),
        ("UpperLeg_L", Some("Hips")),
        ("LowerLeg_L", Some("UpperLeg_L")),
        ("Foot_L", Some("LowerLeg_L")),
        ("Toes_L", Some("Foot_L")),
    ]);
    assert_eq!(find_feet(&bandai).unwrap().1, "Bandai Namco BVH");
}

#[test]
fn pinocchio_human_template_has_ankles_without_toes() {
    let mut joints: Vec<(String, Option<String>)> = vec![("root".into(), None)];
    let parents = [
        "root", "bone_1", "root", "bone_2", "bone_4", "bone_5", "bone_6", "bone_2", "bone_8",
        "bone_9", "bone_10", "root", "bone_12", "bone_13", "root", "bone_15", "bone_16",
    ];
    for (k, p) in parents.iter().enumerate() {
        joints.push((format!("bone_{}", k + 1), Some(p.to_string())));
    }
    // Parents first: bone_4's parent bone_2 and bone_8's parent bone_2 come earlier.
    let refs: Vec<(&str, Option<&str>)> = joints
        .iter()
        .map(|(n, p)| (n.as_str(), p.as_deref()))
        .collect();
    let human = chain(&refs);
    let (legs, convention) = find_feet(&human).unwrap();
    assert_eq!(convention, "Pinocchio human template");
    let expect = |a: [&str; 3]| [a[0], a[1], a[2], ""].map(String::from);
    assert_eq!(
        names_of(&human, &legs),
        [
            expect(["bone_5", "bone_6", "bone_7"]),
            expect(["bone_9", "bone_10", "bone_11"])
        ]
    );
    // Another 18-joint Pinocchio skeleton is not taken for a human.
    let mut other = refs.clone();
    other[7].1 = Some("bone_2");
    assert_eq!(find_feet(&chain(&other)), Err(FootlockError::NoFeet));
}

#[test]
fn named_feet_are_checked() {
    let (skeleton, _) = drifting_leg(0.0);
    let spec = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let (legs, how) = resolve_feet(&skeleton, &spec(&["LeftFoot,LeftToeBase"])).unwrap();
    assert_eq!(
        (legs.len(), how, legs[0].label.as_str()),
        (1, "named", "LeftFoot")
    );
    assert_eq!(
        resolve_feet(&skeleton, &spec(&["LeftFoot,Nope"])),
        Err(FootlockError::UnknownJoint {
            name: "Nope".into()
        })
    );
    assert!(matches!(
        resolve_feet(&skeleton, &spec(&["LeftUpLeg"])),
        Err(FootlockError::NotALeg { joint, .. }) if joint == "LeftUpLeg"
    ));
    assert!(matches!(
        resolve_feet(&skeleton, &spec(&["LeftToeBase,LeftFoot"])),
        Err(FootlockError::NotALeg { joint, .. }) if joint == "LeftFoot"
    ));
    assert_eq!(
        resolve_feet(&skeleton, &spec(&["LeftFoot", "LeftToeBase"])),
        Err(FootlockError::SharedLeg {
            joint: "LeftLeg".into()
        })
    );
    let arm = chain(&[("Shoulder", None), ("Elbow", Some("Shoulder"))]);
    assert_eq!(find_feet(&arm), Err(FootlockError::NoFeet));
    assert!(FootlockError::NoFeet.to_string().contains("lfoot"));
}

#[test]
fn options_and_inputs_are_validated() {
    let (skeleton, clip) = drifting_leg(0.02);
    let (legs, _) = find_feet(&skeleton).unwrap();
    let bad = FootlockOptions {
        hysteresis: 0.5,
        ..FootlockOptions::default()
    };
    assert!(matches!(
        footlock(&skeleton, &clip, &legs, Vec3::Y, &bad),
        Err(FootlockError::Option {
            name: "hysteresis",
            ..
        })
    ));
    let options = FootlockOptions::default();
    assert_eq!(
        footlock(&skeleton, &clip, &[], Vec3::Y, &options),
        Err(FootlockError::NoLegs)
    );
    let one_key = Clip {
        name: "still".into(),
        tracks: vec![Track {
            times: vec![0.0],
            values: vec![0.0, 1.0, 0.0],
            ..clip.tracks[0].clone()
        }],
    };
    assert_eq!(
        footlock(&skeleton, &one_key, &legs, Vec3::Y, &options),
        Err(FootlockError::TooShort { frames: 1 })
    );
}

/// The drifting leg, but from frame 16 on the knee bends and the foot swings up and back:
/// one contact in the first half.
fn step(skeleton: &Skeleton, clip: &Clip) -> Clip {
    let times = clip.tracks[0].times.clone();
    let values = times
        .iter()
        .enumerate()
        .flat_map(|(f, _)| {
            let bend = if f < 16 { 0.0 } else { 0.12 * (f - 15) as f32 };
            Quat::from_rotation_x(bend).to_array()
        })
        .collect();
    let knee = skeleton.find("LeftLeg").unwrap();
    let mut clip = clip.clone();
    clip.tracks.push(Track {
        target: TrackTarget::Rotation(knee),
        interpolation: Interpolation::Linear,
        times,
        values,
    });
    clip
}

#[test]
fn legs_change_only_near_contacts_and_blend_without_popping() {
    let (skeleton, drift) = drifting_leg(0.06);
    let clip = step(&skeleton, &drift);
    let (legs, _) = find_feet(&skeleton).unwrap();
    let options = FootlockOptions::default();
    let locked = footlock(&skeleton, &clip, &legs, Vec3::Y, &options).unwrap();
    let foot = &locked.feet[0];
    let ankle = &foot.contacts[0];
    assert_eq!((ankle.joint.as_str(), ankle.start_frame), ("LeftFoot", 0));
    assert!(ankle.end_frame < 16, "{:?}", foot.contacts);
    assert!(foot.after.max < 1e-5 && foot.before.max > 0.02, "{foot:?}");

    let sample = |c: &Clip| {
        let compiled = CompiledClip::new(c, &skeleton).unwrap();
        sample_frames(&compiled, &rest_locals(&skeleton), &compiled.key_times()).unwrap()
    };
    let (before, after) = (sample(&clip), sample(&locked.clip));
    let last_contact = foot.contacts.iter().map(|c| c.end_frame).max().unwrap();
    let blend = (options.blend * 30.0).round() as usize;
    for (f, (b, a)) in before
        .chunks_exact(5)
        .zip(after.chunks_exact(5))
        .enumerate()
    {
        // The hips never change; after the last blend frame, nothing does.
        assert_eq!(a[0], b[0]);
        if f > last_contact + blend {
            // Equal up to the bake's renormalization of rotations.
            for (ja, jb) in a.iter().zip(b) {
                assert_eq!(ja.translation, jb.translation, "frame {f}");
                assert!(ja.rotation.abs_diff_eq(jb.rotation, 1e-6), "frame {f}");
            }
        }
    }
    // No pop: the ankle never steps more than the source does plus the steepest weight
    // change (smoothstep: 1.5 per blend span) times the distance from source to pin.
    let ankle_at = |frames: &[Transform]| -> Vec<Vec3> {
        let model =
            |l: &[Transform]| rigport_eval::Pose { local: l.to_vec() }.model_matrices(&skeleton);
        frames
            .chunks_exact(5)
            .map(|l| model(l).unwrap()[3].w_axis.truncate())
            .collect()
    };
    let (pb, pa) = (ankle_at(&before), ankle_at(&after));
    let step_of = |p: &[Vec3]| {
        p.windows(2)
            .map(|w| (w[1] - w[0]).length())
            .fold(0.0, f32::max)
    };
    let gap = pb.iter().map(|p| (*p - ankle.pin).length());
    let gap = gap.take(ankle.end_frame + blend + 1).fold(0.0, f32::max);
    let bound = step_of(&pb) + 1.5 / (blend + 1) as f32 * gap;
    assert!(step_of(&pa) <= bound, "step {} > {bound}", step_of(&pa));
    // Without the blend the foot would jump the whole gap in one frame.
    assert!(step_of(&pa) < gap + step_of(&pb));
}

/// Model-space (hip, knee, ankle) positions of the drifting leg per key time of `clip`.
fn leg_positions(skeleton: &Skeleton, clip: &Clip) -> Vec<[Vec3; 3]> {
    let compiled = CompiledClip::new(clip, skeleton).unwrap();
    let frames = sample_frames(&compiled, &rest_locals(skeleton), &compiled.key_times()).unwrap();
    frames
        .chunks_exact(skeleton.len())
        .map(|l| {
            let m = rigport_eval::Pose { local: l.to_vec() }
                .model_matrices(skeleton)
                .unwrap();
            [1, 2, 3].map(|j| m[j].w_axis.truncate())
        })
        .collect()
}

#[test]
fn a_leg_pulled_past_its_reach_stays_bent_and_stretches_within_the_limit() {
    // The hips drift 0.3 forward in a second while the foot is planted: the leg (0.9 long,
    // nearly straight) would have to grow by several percent to hold the foot at the end.
    let (skeleton, clip) = drifting_leg(0.3);
    let mut clip = clip;
    // A slow drift the detector takes for a contact: plant it explicitly by lowering the
    // speed threshold's bar (the foot moves at 0.3/0.95 heights per second).
    let options = FootlockOptions {
        speed: 0.5,
        ..FootlockOptions::default()
    };
    clip.name = "pulled".into();
    let (legs, _) = find_feet(&skeleton).unwrap();
    let locked = footlock(&skeleton, &clip, &legs, Vec3::Y, &options).unwrap();
    let foot = &locked.feet[0];
    assert!(!foot.contacts.is_empty(), "{foot:?}");
    assert!(foot.stretch <= options.max_stretch + 1e-6, "{foot:?}");
    let (src, out) = (
        leg_positions(&skeleton, &clip),
        leg_positions(&skeleton, &locked.clip),
    );
    let angle = |[h, k, a]: [Vec3; 3]| solve::knee_angle(h, k, a).to_degrees();
    let lengths = |[h, k, a]: [Vec3; 3]| (k - h).length() + (a - k).length();
    let limit_deg = options.max_knee_speed_deg / 30.0;
    for f in 0..src.len() {
        // Never straight (the source is at 167°: the knee is 0.05 off the line over 0.9).
        assert!(angle(out[f]) < 179.0, "frame {f}: {}°", angle(out[f]));
        assert!(lengths(out[f]) <= lengths(src[f]) * (1.0 + options.max_stretch) + 1e-5);
        if f > 0 {
            let step = (angle(out[f]) - angle(out[f - 1])) - (angle(src[f]) - angle(src[f - 1]));
            assert!(step.abs() <= limit_deg + 1e-3, "frame {f}: {step}°");
        }
    }
    // Wherever a contact is reported, the ankle is held.
    for c in foot.contacts.iter().filter(|c| c.joint == "LeftFoot") {
        for (f, frame) in out
            .iter()
            .enumerate()
            .take(c.end_frame + 1)
            .skip(c.start_frame)
        {
            assert!((frame[2] - c.pin).length() < 1e-5, "frame {f}");
        }
    }
    assert!(foot.after.max < 1e-5, "{foot:?}");
}

#[test]
fn the_knee_turns_no_faster_than_the_limit_beyond_the_source() {
    // A pin far from the source ankle pulls the knee hard as the leg eases in: with a
    // tight limit the turn per frame is capped (and frames held back are counted).
    let (skeleton, drift) = drifting_leg(0.06);
    let clip = step(&skeleton, &drift);
    let (legs, _) = find_feet(&skeleton).unwrap();
    let options = FootlockOptions {
        max_knee_speed_deg: 30.0,
        ..FootlockOptions::default()
    };
    let locked = footlock(&skeleton, &clip, &legs, Vec3::Y, &options).unwrap();
    assert!(
        locked.feet[0].knee_step_deg <= 1.0 + 1e-3,
        "{:?}",
        locked.feet[0]
    );
    let (src, out) = (
        leg_positions(&skeleton, &clip),
        leg_positions(&skeleton, &locked.clip),
    );
    let angle = |[h, k, a]: [Vec3; 3]| solve::knee_angle(h, k, a).to_degrees();
    for f in 1..src.len() {
        let step = (angle(out[f]) - angle(out[f - 1])) - (angle(src[f]) - angle(src[f - 1]));
        assert!(step.abs() <= 1.0 + 1e-2, "frame {f}: {step}°");
    }
}

#[test]
fn a_clip_without_contacts_says_why_and_suggests_a_rate() {
    // The hips run forward at 10 units a second (10.5 heights/s): no foot is ever slow,
    // and 18 m/s is no human's foot: the clip plays too fast.
    let (skeleton, clip) = drifting_leg(10.0);
    let (legs, _) = find_feet(&skeleton).unwrap();
    let locked = footlock(
        &skeleton,
        &clip,
        &legs,
        Vec3::Y,
        &FootlockOptions::default(),
    )
    .unwrap();
    assert!(locked.feet[0].contacts.is_empty());
    assert_eq!(locked.clip, clip);
    let [Warning::NoContacts {
        message,
        suggested_fps: Some(fps),
        ..
    }] = &locked.warnings[..]
    else {
        panic!("{:?}", locked.warnings)
    };
    assert!(
        message.contains("no foot stays under the contact speed"),
        "{message}"
    );
    assert!(message.contains("too fast"), "{message}");
    assert!(*fps < 30.0, "{fps}");
    assert_eq!(locked.warnings[0].code(), "W006");

    // Slow but never on the ground: a foot raised and lowered that never rests.
    let speeds = [
        diagnose::FootSpeeds::of(&[0.1, 0.1, 0.1, 0.1], &[false, true, false, true], 2),
        diagnose::FootSpeeds::of(&[0.1, 0.05, 0.1, 0.1], &[true, true, true, false], 2),
    ];
    assert_eq!(speeds[0].slowest_low, f32::INFINITY);
    assert_eq!((speeds[1].slowest_low, speeds[1].median), (0.1, 0.1));
    let options = FootlockOptions::default();
    assert_eq!(diagnose::no_contact_cause(&speeds, 120.0, &options), None);
    let fast = [diagnose::FootSpeeds::of(&[4.0; 8], &[true; 8], 2)];
    let cause = diagnose::no_contact_cause(&fast, 120.0, &options).unwrap();
    // 6.8 m/s, 1.36x a plausible median: recorded at 60 fps at most.
    assert_eq!(cause.rate, Some((2.0, 60.0)));
}
