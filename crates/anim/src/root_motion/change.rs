//! The joints a root-motion change touches and their new local transforms: `P⁻¹` or `P`
//! premultiplied on a top joint, or conjugated through the top joint onto its children.

use glam::{DQuat, DVec3, Vec3};
use rigport_model::{Clip, Interpolation, JointIndex, Track, TrackTarget, Transform};

use super::path::{self, ClipPath};

/// The path at one key: move along the ground by `s`, turn by `turn` about up.
#[derive(Clone, Copy)]
pub(super) struct Move {
    pub s: DVec3,
    pub turn: DQuat,
}

/// Whether the path is taken out of the hips (`Remove`: `P⁻¹`) or carried by the top
/// joint (`Carry`: the top gets `P`, its children `P⁻¹` in its frame).
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Way {
    Remove,
    Carry,
}

pub(super) enum Plan {
    /// The top joint (the hips, or a top with non-uniform scale) gets `P⁻¹ · T`.
    Root(JointIndex),
    /// The top joint's listed children get `T⁻¹ · Q · T · C` (`Q = P⁻¹`); with `Carry`
    /// the top joint gets `P · T`.
    Children(JointIndex, Vec<JointIndex>, Way),
    /// A new root above the top joint carries `P`; the top joint gets `P⁻¹ · T`.
    NewRoot(JointIndex),
}

/// A clip's local transform of `joint` at every key (`frames` is frame-major).
fn column(path: &ClipPath, joints: usize, joint: JointIndex) -> Vec<Transform> {
    (path.frames.iter().skip(joint.get()).step_by(joints.max(1)))
        .copied()
        .collect()
}

/// Whether the joint's scale is uniform (to 1e-6 relative) at every key.
pub(super) fn uniform_scale(path: &ClipPath, joints: usize, joint: JointIndex) -> bool {
    column(path, joints, joint).iter().all(|t| {
        let s = t.scale;
        let tolerance = 1e-6 * s.abs().max_element();
        (s.x - s.y).abs() <= tolerance && (s.x - s.z).abs() <= tolerance && s.x > 0.0
    })
}

/// `Q · T` for a root joint `T` and a rigid model-space `Q = (rotation, translation)`.
fn premultiply(q: (DQuat, DVec3), t: &Transform) -> Transform {
    let (translation, rotation, _) = path::trs(t);
    Transform {
        translation: (q.0 * translation + q.1).as_vec3(),
        rotation: (q.0 * rotation).normalize().as_quat(),
        scale: t.scale,
    }
}

/// `T⁻¹ · Q · T · C` for a child `C` of the top joint `T` (uniform scale `σ`):
/// rotation `R_T⁻¹ R_Q R_T R_C`, translation `R_M t_C + R_T⁻¹ (R_Q t_T + t_Q − t_T) / σ`.
fn conjugate(q: (DQuat, DVec3), top: &Transform, c: &Transform) -> Transform {
    let (t_top, r_top, s_top) = path::trs(top);
    let (t_c, r_c, _) = path::trs(c);
    let r_m = r_top.inverse() * q.0 * r_top;
    let t_m = r_top.inverse() * (q.0 * t_top + q.1 - t_top) / s_top.x;
    Transform {
        translation: (r_m * t_c + t_m).as_vec3(),
        rotation: (r_m * r_c).normalize().as_quat(),
        scale: c.scale,
    }
}

impl Move {
    /// `P` as (rotation, translation).
    fn forward(self) -> (DQuat, DVec3) {
        (self.turn, self.s)
    }

    /// `P` as a joint's local transform.
    pub fn as_transform(self) -> Transform {
        Transform {
            translation: self.s.as_vec3(),
            rotation: self.turn.normalize().as_quat(),
            scale: Vec3::ONE,
        }
    }

    /// `P⁻¹` as (rotation, translation).
    fn inverse(self) -> (DQuat, DVec3) {
        let r = self.turn.inverse();
        (r, -(r * self.s))
    }
}

/// The changed joints' local transforms at every key (old joint numbering).
pub(super) fn changes(
    path: &ClipPath,
    moves: &[Move],
    plan: &Plan,
    joints: usize,
) -> Vec<(JointIndex, Vec<Transform>)> {
    let mut changed: Vec<(JointIndex, Vec<Transform>)> = Vec::new();
    match plan {
        Plan::Root(top) | Plan::NewRoot(top) => {
            let values = (column(path, joints, *top).iter().zip(moves))
                .map(|(t, m)| premultiply(m.inverse(), t))
                .collect();
            changed.push((*top, values));
        }
        Plan::Children(top, children, way) => {
            let tops = column(path, joints, *top);
            for &c in children {
                let values = (column(path, joints, c).iter().zip(&tops).zip(moves))
                    .map(|((c, t), m)| conjugate(m.inverse(), t, c))
                    .collect();
                changed.push((c, values));
            }
            if *way == Way::Carry {
                let values = (tops.iter().zip(moves))
                    .map(|(t, m)| premultiply(m.forward(), t))
                    .collect();
                changed.push((*top, values));
            }
        }
    }
    changed
}

/// Replaces the translation and rotation tracks of each changed joint in `clip`.
pub(super) fn replace_tracks(
    clip: &mut Clip,
    times: &[f32],
    changed: Vec<(JointIndex, Vec<Transform>)>,
) {
    let replaced = |j: JointIndex| changed.iter().any(|(c, _)| *c == j);
    clip.tracks.retain(|t| match t.target {
        TrackTarget::Translation(j) | TrackTarget::Rotation(j) => !replaced(j),
        _ => true,
    });
    for (joint, values) in changed {
        clip.tracks.extend(tracks_of(joint, times, &values));
    }
}

/// `LINEAR` translation and rotation tracks of `joint` holding `values` at `times`, the
/// rotations sign-continuous.
fn tracks_of(joint: JointIndex, times: &[f32], values: &[Transform]) -> [Track; 2] {
    let mut rotations: Vec<f32> = Vec::with_capacity(values.len() * 4);
    let mut previous: Option<glam::Quat> = None;
    for v in values {
        let q = match previous {
            Some(p) if p.dot(v.rotation) < 0.0 => -v.rotation,
            _ => v.rotation,
        };
        previous = Some(q);
        rotations.extend_from_slice(&q.to_array());
    }
    let track = |target, values| Track {
        target,
        interpolation: Interpolation::Linear,
        times: times.to_vec(),
        values,
    };
    [
        track(
            TrackTarget::Translation(joint),
            values
                .iter()
                .flat_map(|v| v.translation.to_array())
                .collect(),
        ),
        track(TrackTarget::Rotation(joint), rotations),
    ]
}
