//! The motion as a clip: a translation and a rotation track per joint with channels.

use glam::{DQuat, DVec3};
use rigport_model::{Clip, Interpolation, JointIndex, Track, TrackTarget};

use crate::problem::{Limit, Missing};
use crate::{ImportError, Location};

use super::types::{Bvh, BvhJoint};

/// The clip of a checked [`Bvh`] with at least one frame and one channel.
pub(super) fn clip(
    name: &str,
    bvh: &Bvh,
    channel_count: usize,
    at_line: &dyn Fn(usize) -> Location,
) -> Result<Clip, ImportError> {
    let frames = bvh.frame_count;
    // Computed in f64 and rounded once, so long clips do not accumulate error.
    let times: Vec<f32> = (0..frames)
        .map(|k| (k as f64 * bvh.frame_time) as f32)
        .collect();
    if times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(ImportError::at(
            at_line(bvh.motion_line),
            Limit::FrameTime {
                frame_time: bvh.frame_time,
                frames,
            },
        ));
    }
    let broken =
        |j: &BvhJoint| ImportError::at(at_line(j.line), Missing::JointValues(j.name.clone()));
    let joints = &bvh.joints;
    // Joints' tracks are independent: a large clip builds them on two threads, the joints
    // split where half the channels are done, and keeps them in joint order.
    let tracks = if bvh.motion.len() >= PARALLEL_TRACK_VALUES && joints.len() >= 2 {
        let half = channel_count / 2;
        let mid = joints
            .iter()
            .position(|j| j.first_channel >= half)
            .unwrap_or(joints.len())
            .clamp(1, joints.len() - 1);
        let (first, second) = joints.split_at(mid);
        let (a, b) = crate::join(
            || joint_tracks(bvh, 0, first, channel_count, &times),
            || joint_tracks(bvh, mid, second, channel_count, &times),
        );
        let mut tracks = a.map_err(broken)?;
        tracks.extend(b.map_err(broken)?);
        tracks
    } else {
        joint_tracks(bvh, 0, joints, channel_count, &times).map_err(broken)?
    };
    Ok(Clip {
        name: name.to_string(),
        tracks,
    })
}

/// Clips of at least this many values build their tracks on two threads.
const PARALLEL_TRACK_VALUES: usize = 16 * 1024;

/// The translation and rotation tracks of `joints`, the joints of `bvh` from index `first`
/// on (in joint order, translation first), keyed at `times`. `Err(joint)`: the joint's
/// channels lie outside the frame values, or its index does not fit a [`JointIndex`].
fn joint_tracks<'b>(
    bvh: &Bvh,
    first: usize,
    joints: &'b [BvhJoint],
    channel_count: usize,
    times: &[f32],
) -> Result<Vec<Track>, &'b BvhJoint> {
    let frames = times.len();
    let mut tracks = Vec::new();
    for (i, joint) in (first..).zip(joints) {
        let index = JointIndex(u32::try_from(i).map_err(|_| joint)?);
        let range = joint.first_channel..joint.first_channel + joint.channels.len();
        // The joint's channels by kind, as (index within the joint's values, axis), in file
        // order: worked out once rather than per frame.
        let positions: Vec<(usize, usize)> = (joint.channels.iter().enumerate())
            .filter(|(_, c)| !c.is_rotation())
            .map(|(k, c)| (k, c.axis()))
            .collect();
        let rotations: Vec<(usize, DVec3)> = (joint.channels.iter().enumerate())
            .filter(|(_, c)| c.is_rotation())
            .map(|(k, c)| (k, AXES[c.axis()]))
            .collect();
        if !positions.is_empty() {
            let mut values = Vec::with_capacity(3 * frames);
            for frame in bvh.motion.chunks_exact(channel_count) {
                let own = frame.get(range.clone()).ok_or(joint)?;
                let mut t = joint.offset.to_array();
                for &(k, axis) in &positions {
                    if let (Some(slot), Some(&v)) = (t.get_mut(axis), own.get(k)) {
                        *slot = v;
                    }
                }
                values.extend_from_slice(&t);
            }
            tracks.push(Track {
                target: TrackTarget::Translation(index),
                interpolation: Interpolation::Linear,
                times: times.to_vec(),
                values,
            });
        }
        if !rotations.is_empty() {
            let mut values = Vec::with_capacity(4 * frames);
            let mut previous = DQuat::IDENTITY;
            for frame in bvh.motion.chunks_exact(channel_count) {
                let own = frame.get(range.clone()).ok_or(joint)?;
                let mut q = DQuat::IDENTITY;
                for &(k, axis) in &rotations {
                    if let Some(&v) = own.get(k) {
                        // The first listed rotation is the outermost: R = R1 · R2 · R3.
                        q *= DQuat::from_axis_angle(axis, f64::from(v).to_radians());
                    }
                }
                q = q.normalize();
                if previous.dot(q) < 0.0 {
                    q = -q;
                }
                previous = q;
                values.extend_from_slice(&q.as_quat().to_array());
            }
            tracks.push(Track {
                target: TrackTarget::Rotation(index),
                interpolation: Interpolation::Linear,
                times: times.to_vec(),
                values,
            });
        }
    }
    Ok(tracks)
}

/// Unit axes by [`Channel::axis`](super::types::Channel::axis).
const AXES: [DVec3; 3] = [DVec3::X, DVec3::Y, DVec3::Z];
