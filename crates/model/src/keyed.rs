//! Hand-authored animation input: rotations relative to the rest pose, and keyed poses.
//!
//! These are what `POSE.json` and `KEYS.json` hold once their joint names are resolved
//! against a skeleton (`rigport_import::json`); the evaluator turns them into poses and
//! clips (`rigport_anim::keyed`).

use glam::{Quat, Vec3};

use crate::JointIndex;

/// A rotation in a joint's rest frame: the joint's local rotation becomes
/// `rest_rotation * rotation` (translation and scale kept).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestRotation {
    /// The rotated joint.
    pub joint: JointIndex,
    /// The rotation, unit length.
    pub rotation: Quat,
}

/// One key of [`PoseKeys`]: a whole pose (joints not listed stay at rest).
#[derive(Clone, Debug, PartialEq)]
pub struct PoseKey {
    /// Seconds, finite and `>= 0`.
    pub time: f32,
    /// The key's position in its file (0-based), for messages.
    pub index: usize,
    /// Rotations in the joints' rest frames, at most one per joint.
    pub rotations: Vec<RestRotation>,
    /// Added to the first root's rest translation (source units), when given.
    pub translation: Option<Vec3>,
}

/// Keyframed poses that become a clip with one `LINEAR` key per entry.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseKeys {
    /// The clip name, when the source gives one.
    pub name: Option<String>,
    /// At least one key, times strictly increasing.
    pub keys: Vec<PoseKey>,
}
