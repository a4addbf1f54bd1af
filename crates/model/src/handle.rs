//! IK handle tracks: model-space targets over time for chosen joints (`HANDLES.json`).

use glam::Vec3;

use crate::JointIndex;

/// One handle: a joint, the effector point in the joint's frame, and its target track.
#[derive(Clone, Debug, PartialEq)]
pub struct HandleTrack {
    /// The driven joint.
    pub joint: JointIndex,
    /// Its name.
    pub name: String,
    /// The effector point in the joint's local frame (zero: the joint's origin).
    pub offset: Vec3,
    /// Weight in the solve, finite and `> 0`.
    pub weight: f32,
    /// Whether positions are offsets from the effector's rest position (model space).
    pub relative: bool,
    /// Key times in seconds, at least one, finite, `>= 0` and strictly increasing.
    pub times: Vec<f32>,
    /// Target positions, one per key (model space, or offsets when `relative`).
    pub positions: Vec<Vec3>,
}

/// The handles of one handles file.
#[derive(Clone, Debug, PartialEq)]
pub struct HandleSet {
    /// Frames per second the source asks for, finite and `> 0`.
    pub fps: Option<f32>,
    /// At least one track, at most one per joint, in source order.
    pub tracks: Vec<HandleTrack>,
}
