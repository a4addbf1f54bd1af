//! Unit tests of the whole foot lock.

use glam::Vec3;
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
