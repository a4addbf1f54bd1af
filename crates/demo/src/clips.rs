//! The demo's clips, built in Rust: `wave` and `twist` are keyed whole poses baked by
//! [`rigport_anim::keyed::clip`], `reach` an IK handle track solved by
//! [`rigport_ik::clip::solve_clip`]. Each also exists as the JSON example file that
//! `rigport demo` writes beside its outputs (for `rigport animate` and `rigport ik`); a test
//! checks that the files' parsers give exactly the keys and handles built here.

use glam::Vec3;
use rigport_model::conventions::EulerOrder;
use rigport_model::{HandleSet, HandleTrack, PoseKey, PoseKeys, RestRotation, Skeleton};

use crate::DemoError;

/// The frame rate every demo clip is keyed at, frames per second.
pub const KEY_FPS: f32 = 30.0;

/// `wave.keys.json`: the keys of [`wave_keys`], as `rigport animate` reads them.
pub const WAVE_KEYS_JSON: &str = r#"{
  "name": "wave",
  "fps": 30,
  "keys": [
    {"frame": 0,  "pose": {}},
    {"frame": 15, "pose": {"forearm_l": {"euler_deg": [0, 0, 75]}, "hand_l": {"euler_deg": [0, 0, 40]},
                           "head": {"euler_deg": [10, 0, 0]}}, "translation": [0, -0.02, 0]},
    {"frame": 30, "pose": {"forearm_l": {"euler_deg": [0, 0, 80]}, "hand_l": {"euler_deg": [0, 0, 80]},
                           "head": {"euler_deg": [-5, 10, 0]}}},
    {"frame": 45, "pose": {"forearm_l": {"euler_deg": [0, 0, 75]}, "hand_l": {"euler_deg": [0, 0, 30]},
                           "head": {"euler_deg": [10, -10, 0]}}, "translation": [0, -0.02, 0]},
    {"frame": 60, "pose": {}}
  ]
}
"#;

/// `twist.keys.json`: the keys of [`twist_keys`].
pub const TWIST_KEYS_JSON: &str = r#"{
  "name": "twist",
  "fps": 30,
  "keys": [
    {"frame": 0,  "pose": {}},
    {"frame": 30, "pose": {"hand_l": {"euler_deg": [150, 0, 0]}}},
    {"frame": 60, "pose": {}}
  ]
}
"#;

/// `reach.handles.json`: the handles of [`reach_handles`], as `rigport ik` reads them.
pub const REACH_HANDLES_JSON: &str = r#"{
  "fps": 30,
  "handles": [
    {"joint": "fingertip_l", "root": "shoulder_l", "relative": true, "offset": [0.16, 0, 0],
     "keys": [{"time": 0, "position": [0, 0, 0]},
              {"time": 1, "position": [-0.35, 0.15, 0.35]},
              {"time": 2, "position": [0, 0, 0]}]},
    {"joint": "toe_l", "pin": true, "orient": true, "root": "thigh_l"},
    {"joint": "toe_r", "pin": true, "orient": true, "root": "thigh_r"}
  ]
}
"#;

/// The time of the twist clip's largest twist, seconds (frame 30 of [`twist_keys`]).
pub const TWIST_PEAK_S: f32 = 1.0;

/// One key: `frame` at [`KEY_FPS`], Euler angles (degrees, order `xyz`) per joint name in
/// the order given (the example files list them sorted, as their parser returns them), and
/// an optional root translation, metres.
struct KeySpec<'a> {
    frame: u16,
    pose: &'a [(&'a str, [f32; 3])],
    translation: Option<[f32; 3]>,
}

/// Shorthand for a [`KeySpec`].
const fn key<'a>(
    frame: u16,
    pose: &'a [(&'a str, [f32; 3])],
    translation: Option<[f32; 3]>,
) -> KeySpec<'a> {
    KeySpec {
        frame,
        pose,
        translation,
    }
}

/// Keys for `skeleton` as the `KEYS.json` parser builds them (times `frame / fps`, pose
/// entries in order, Euler order `xyz`).
///
/// # Errors
/// [`DemoError::UnknownJoint`] when `skeleton` lacks a joint the keys name.
fn pose_keys(skeleton: &Skeleton, name: &str, specs: &[KeySpec]) -> Result<PoseKeys, DemoError> {
    let mut keys = Vec::with_capacity(specs.len());
    for (index, spec) in specs.iter().enumerate() {
        let mut rotations = Vec::with_capacity(spec.pose.len());
        for &(joint, angles_deg) in spec.pose {
            rotations.push(RestRotation {
                joint: find(skeleton, joint)?,
                rotation: EulerOrder::Xyz.to_quat_deg(angles_deg),
            });
        }
        keys.push(PoseKey {
            time: f32::from(spec.frame) / KEY_FPS,
            index,
            rotations,
            translation: spec.translation.map(Vec3::from),
        });
    }
    Ok(PoseKeys {
        name: Some(name.to_owned()),
        keys,
    })
}

/// The joint of `skeleton` named `name`.
fn find(skeleton: &Skeleton, name: &str) -> Result<rigport_model::JointIndex, DemoError> {
    skeleton
        .find(name)
        .ok_or_else(|| DemoError::UnknownJoint(name.to_owned()))
}

/// The keyframed clip `wave`: the left arm waves (bone `forearm_l` is the upper arm, bone
/// `hand_l` the forearm: Pinocchio names a bone after the joint it ends at), the head nods,
/// the body bobs; the last key equals the first so the clip loops. 2 s.
///
/// # Errors
/// [`DemoError::UnknownJoint`] for a skeleton other than the demo's.
pub fn wave_keys(skeleton: &Skeleton) -> Result<PoseKeys, DemoError> {
    let bob = Some([0.0, -0.02, 0.0]);
    pose_keys(
        skeleton,
        "wave",
        &[
            key(0, &[], None),
            key(
                15,
                &[
                    ("forearm_l", [0.0, 0.0, 75.0]),
                    ("hand_l", [0.0, 0.0, 40.0]),
                    ("head", [10.0, 0.0, 0.0]),
                ],
                bob,
            ),
            key(
                30,
                &[
                    ("forearm_l", [0.0, 0.0, 80.0]),
                    ("hand_l", [0.0, 0.0, 80.0]),
                    ("head", [-5.0, 10.0, 0.0]),
                ],
                None,
            ),
            key(
                45,
                &[
                    ("forearm_l", [0.0, 0.0, 75.0]),
                    ("hand_l", [0.0, 0.0, 30.0]),
                    ("head", [10.0, -10.0, 0.0]),
                ],
                bob,
            ),
            key(60, &[], None),
        ],
    )
}

/// The LBS-vs-DQS clip `twist`: the left forearm (bone `hand_l`, from the elbow at
/// x = 0.46 m to the wrist at x = 0.71 m) twists about its own axis, 0 -> 150 deg -> 0 over
/// 2 s. The demo's joints have identity rest rotations (Pinocchio layout) and pose entries
/// rotate in the joint's rest frame, so the bone axis is the rest frame's +X. Linear
/// blending of a 150 deg twist with the untwisted upper arm collapses the skin where the
/// weights blend ("candy wrapper", Kavan et al. 2008, fig. 1); DQS keeps its volume.
///
/// # Errors
/// [`DemoError::UnknownJoint`] for a skeleton other than the demo's.
pub fn twist_keys(skeleton: &Skeleton) -> Result<PoseKeys, DemoError> {
    pose_keys(
        skeleton,
        "twist",
        &[
            key(0, &[], None),
            key(30, &[("hand_l", [150.0, 0.0, 0.0])], None),
            key(60, &[], None),
        ],
    )
}

/// The IK handles of clip `reach`: the left fingertip (bone `fingertip_l` turns about the
/// wrist; the 0.16 m offset along +X puts the effector at the finger's tip) reaches forward
/// and up (offsets from its rest position, metres), then returns, 2 s, moving only the arm
/// (`root`: `shoulder_l`); both toes are pinned (position and rotation), the root stays.
///
/// # Errors
/// [`DemoError::UnknownJoint`] for a skeleton other than the demo's.
pub fn reach_handles(skeleton: &Skeleton) -> Result<HandleSet, DemoError> {
    let mut reach = HandleTrack::keyed(
        find(skeleton, "fingertip_l")?,
        "fingertip_l",
        vec![0.0, 1.0, 2.0],
        vec![Vec3::ZERO, Vec3::new(-0.35, 0.15, 0.35), Vec3::ZERO],
    );
    reach.offset = Vec3::new(0.16, 0.0, 0.0);
    reach.relative = true;
    reach.root = Some(find(skeleton, "shoulder_l")?);
    let mut tracks = vec![reach];
    for (toe, thigh) in [("toe_l", "thigh_l"), ("toe_r", "thigh_r")] {
        let mut pin = HandleTrack::keyed(find(skeleton, toe)?, toe, Vec::new(), Vec::new());
        pin.pin = true;
        pin.orient = true;
        pin.root = Some(find(skeleton, thigh)?);
        tracks.push(pin);
    }
    Ok(HandleSet {
        fps: Some(KEY_FPS),
        tracks,
        base: None,
        root_motion: None,
        limits: Vec::new(),
    })
}

/// `1_pinocchio.keys.json`: the keys of [`model1_keys`].
pub const MODEL1_KEYS_JSON: &str = r#"{
  "name": "arms",
  "fps": 30,
  "keys": [
    {"frame": 0,  "pose": {}},
    {"frame": 15, "pose": {"bone_13": {"euler_deg": [0, 0, -60]}, "bone_14": {"euler_deg": [0, 0, -30]},
                           "bone_16": {"euler_deg": [0, 0, 60]},  "bone_17": {"euler_deg": [0, 0, 30]}}},
    {"frame": 30, "pose": {}}
  ]
}
"#;

/// A small posed clip `arms` for the corpus's Model1 human (Pinocchio bone names: `bone_13`
/// and `bone_16` are the upper arms, turning about the shoulders at joints 12 and 15;
/// `bone_14` and `bone_17` the forearms): both arms rise sideways and come back down. 1 s.
///
/// # Errors
/// [`DemoError::UnknownJoint`] for a skeleton without those bones.
pub fn model1_keys(skeleton: &Skeleton) -> Result<PoseKeys, DemoError> {
    pose_keys(
        skeleton,
        "arms",
        &[
            key(0, &[], None),
            key(
                15,
                &[
                    ("bone_13", [0.0, 0.0, -60.0]),
                    ("bone_14", [0.0, 0.0, -30.0]),
                    ("bone_16", [0.0, 0.0, 60.0]),
                    ("bone_17", [0.0, 0.0, 30.0]),
                ],
                None,
            ),
            key(30, &[], None),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The example files parse to exactly the keys and handles built in Rust, so the files
    /// `rigport demo` writes reproduce its clips.
    #[test]
    fn example_files_match_the_rust_clips() {
        let rig = crate::character(1);
        let asset = crate::assemble(rig).expect("the demo assembles").asset;
        let skeleton = &asset.skeleton;
        let dir = std::env::temp_dir().join(format!("rigport-demo-clips-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let write = |name: &str, text: &str| {
            let path = dir.join(name);
            std::fs::write(&path, text).expect("write");
            path
        };
        let keys = |text| rigport_import::json::keys::read(&write("k.json", text), skeleton);
        assert_eq!(
            keys(WAVE_KEYS_JSON).expect("wave"),
            wave_keys(skeleton).expect("wave")
        );
        assert_eq!(
            keys(TWIST_KEYS_JSON).expect("twist"),
            twist_keys(skeleton).expect("twist")
        );
        let handles =
            rigport_import::json::handles::read(&write("h.json", REACH_HANDLES_JSON), skeleton);
        assert_eq!(
            handles.expect("reach"),
            reach_handles(skeleton).expect("reach")
        );
        // Model1's bone names, on a stand-in skeleton with the same names.
        let names: Vec<String> = (0..18)
            .map(|k| {
                if k == 0 {
                    "root".into()
                } else {
                    format!("bone_{k}")
                }
            })
            .collect();
        let joints = names
            .iter()
            .enumerate()
            .map(|(k, name)| rigport_model::Joint {
                name: name.clone(),
                parent: (k > 0).then_some(rigport_model::JointIndex(0)),
                rest_local: rigport_model::Transform::IDENTITY,
            })
            .collect();
        let model1 = Skeleton::new(joints).expect("a star skeleton");
        let parsed = rigport_import::json::keys::read(&write("m.json", MODEL1_KEYS_JSON), &model1);
        assert_eq!(
            parsed.expect("model1"),
            model1_keys(&model1).expect("model1")
        );
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
