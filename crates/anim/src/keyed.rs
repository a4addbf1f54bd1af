//! Keyed poses ([`PoseKeys`], e.g. from `KEYS.json`) into a clip.

use rigport_model::{Clip, PoseKeys, Skeleton, Transform};

use rigport_eval::sample::{bake, ChannelMask, SampleError};
use rigport_eval::Pose;

/// The clip of `keys` on `skeleton`: one `LINEAR` key per entry (whole poses: unlisted
/// joints at rest), rotation tracks for every joint any key rotates, a translation track
/// on the first root when any key moves it (a rest-pose clip gets a root rotation track, so
/// it lasts as long as its keys). Named after `keys.name`, else `default_name`. A skeleton
/// without joints gives a clip without tracks.
///
/// # Errors
/// As [`bake`]: times not strictly increasing, non-finite values.
///
/// ```
/// use rigport_model::glam::{Quat, Vec3};
/// use rigport_model::{PoseKey, PoseKeys, RestRotation};
///
/// let skeleton = rigport_model::Skeleton::new(vec![rigport_model::Joint {
///     name: "root".into(),
///     parent: None,
///     rest_local: rigport_model::Transform::IDENTITY,
/// }])
/// .expect("one root");
/// let root = skeleton.find("root").expect("a root");
/// let key = |time, angle: f32| PoseKey {
///     time,
///     index: 0,
///     rotations: vec![RestRotation { joint: root, rotation: Quat::from_rotation_z(angle) }],
///     translation: Some(Vec3::Y * time),
/// };
/// let keys = PoseKeys { name: None, keys: vec![key(0.0, 0.0), key(1.0, 1.0)] };
/// let clip = rigport_anim::keyed::clip(&skeleton, &keys, "nod")?;
/// assert_eq!(clip.name, "nod");
/// assert_eq!(clip.tracks.len(), 2); // root translation and rotation
/// assert_eq!(clip.duration(), 1.0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn clip(skeleton: &Skeleton, keys: &PoseKeys, default_name: &str) -> Result<Clip, SampleError> {
    let n = skeleton.len();
    let name = keys.name.as_deref().unwrap_or(default_name);
    let Some(root) = skeleton.roots().next() else {
        return bake(name, &[0.0], &[], &ChannelMask::none(0));
    };
    let mut mask = ChannelMask::none(n);
    let mut moved = false;
    let mut frames: Vec<Transform> = Vec::with_capacity(keys.keys.len() * n);
    for key in &keys.keys {
        for r in &key.rotations {
            if let Some(flag) = mask.rotation.get_mut(r.joint.get()) {
                *flag = true;
            }
        }
        let mut pose = Pose::rest(skeleton);
        pose.apply(&key.rotations);
        if let Some(t) = key.translation {
            moved = true;
            pose.local[root.get()].translation += t;
        }
        frames.extend_from_slice(&pose.local);
    }
    mask.translation[root.get()] = moved;
    if !mask.rotation.iter().any(|r| *r) && !moved {
        // A clip of rest poses still needs a track to exist and last as long as its keys.
        mask.rotation[root.get()] = true;
    }
    let times: Vec<f32> = keys.keys.iter().map(|k| k.time).collect();
    bake(name, &times, &frames, &mask)
}
