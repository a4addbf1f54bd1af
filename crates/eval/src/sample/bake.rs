//! The other way from sampling: per-frame local poses baked into a clip with `LINEAR`
//! tracks ([`bake`], [`ChannelMask`]), and the helpers that sample a clip at many times
//! (every frame's pose, morph weights) for the jobs that bake.

use glam::Quat;
use rigport_model::{Clip, Interpolation, Skeleton, Track, TrackTarget, Transform};

use super::{sample_weights, CompiledClip, SampleError, SampleJob, MAX_SAMPLES};

/// Which channels of each joint a baked clip gets tracks for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChannelMask {
    /// Per joint: bake a translation track.
    pub translation: Vec<bool>,
    /// Per joint: bake a rotation track.
    pub rotation: Vec<bool>,
    /// Per joint: bake a scale track.
    pub scale: Vec<bool>,
}

impl ChannelMask {
    /// The channels `clip` animates, for a skeleton of `joints` joints (tracks on joints
    /// beyond that are ignored).
    pub fn of_clip(clip: &Clip, joints: usize) -> Self {
        let mut mask = Self::none(joints);
        for track in &clip.tracks {
            let (channel, j) = match track.target {
                TrackTarget::Translation(j) => (&mut mask.translation, j),
                TrackTarget::Rotation(j) => (&mut mask.rotation, j),
                TrackTarget::Scale(j) => (&mut mask.scale, j),
                TrackTarget::MorphWeights(_) => continue,
            };
            if let Some(flag) = channel.get_mut(j.get()) {
                *flag = true;
            }
        }
        mask
    }

    /// Every channel of `joints` joints.
    pub fn all(joints: usize) -> Self {
        Self {
            translation: vec![true; joints],
            rotation: vec![true; joints],
            scale: vec![true; joints],
        }
    }

    /// No channel of `joints` joints.
    pub fn none(joints: usize) -> Self {
        Self {
            translation: vec![false; joints],
            rotation: vec![false; joints],
            scale: vec![false; joints],
        }
    }

    /// Adds `other`'s channels to these (growing to the longer joint count).
    pub fn union_with(&mut self, other: &ChannelMask) {
        for (mine, theirs) in [
            (&mut self.translation, &other.translation),
            (&mut self.rotation, &other.rotation),
            (&mut self.scale, &other.scale),
        ] {
            if mine.len() < theirs.len() {
                mine.resize(theirs.len(), false);
            }
            for (m, t) in mine.iter_mut().zip(theirs) {
                *m |= *t;
            }
        }
    }
}

/// Bakes per-frame local poses into a clip named `name` with `LINEAR` tracks.
///
/// `times` are the frame times in seconds (finite, strictly increasing); `frames` holds
/// `times.len() × joints` local transforms, frame-major (`frames[f * joints + j]`), where
/// `joints` is the length of the mask's vectors. Tracks are emitted per joint in order,
/// translation, rotation, scale, for the channels `channels` selects. Rotations are
/// normalized and made sign-continuous (`q` negated when `dot(previous, q) < 0`), so
/// linear interpolation between keys takes the short way and the glTF validator's
/// sign-continuity check holds.
///
/// # Errors
/// [`SampleError::Length`] if the mask's vectors differ in length or `frames` is not
/// `times.len() × joints`; [`SampleError::NoFrames`]; [`SampleError::FrameTime`] for
/// non-finite or non-increasing times; [`SampleError::FrameValue`] for a non-finite
/// transform or zero rotation on a baked channel.
pub fn bake(
    name: &str,
    times: &[f32],
    frames: &[Transform],
    channels: &ChannelMask,
) -> Result<Clip, SampleError> {
    let joints = channels.translation.len();
    for (what, found) in [
        ("channels.rotation", channels.rotation.len()),
        ("channels.scale", channels.scale.len()),
    ] {
        if found != joints {
            return Err(SampleError::Length {
                what,
                expected: joints,
                found,
            });
        }
    }
    if frames.len() != times.len() * joints {
        return Err(SampleError::Length {
            what: "frames",
            expected: times.len() * joints,
            found: frames.len(),
        });
    }
    if times.is_empty() {
        return Err(SampleError::NoFrames);
    }
    let mut previous = f32::NEG_INFINITY;
    for (frame, &time) in times.iter().enumerate() {
        if !(time.is_finite() && time > previous) {
            return Err(SampleError::FrameTime {
                frame,
                time,
                previous,
            });
        }
        previous = time;
    }
    let mut tracks = Vec::new();
    if joints == 0 {
        return Ok(Clip {
            name: name.to_string(),
            tracks,
        });
    }
    let keys = times.len();
    for j in 0..joints {
        let column = || frames.iter().skip(j).step_by(joints).enumerate();
        let wants = |mask: &[bool]| mask.get(j).copied().unwrap_or(false);
        let bad = |frame| SampleError::FrameValue { frame, joint: j };
        let track = |target, values| Track {
            target,
            interpolation: Interpolation::Linear,
            times: times.to_vec(),
            values,
        };
        let joint = rigport_model::JointIndex(j as u32);
        if wants(&channels.translation) {
            let mut values = Vec::with_capacity(keys * 3);
            for (f, t) in column() {
                if !t.translation.is_finite() {
                    return Err(bad(f));
                }
                values.extend_from_slice(&t.translation.to_array());
            }
            tracks.push(track(TrackTarget::Translation(joint), values));
        }
        if wants(&channels.rotation) {
            let mut values = Vec::with_capacity(keys * 4);
            let mut previous: Option<Quat> = None;
            for (f, t) in column() {
                let length = t.rotation.length();
                if !(length.is_finite() && length > 0.0) {
                    return Err(bad(f));
                }
                let mut q = t.rotation * (1.0 / length);
                if previous.is_some_and(|p| p.dot(q) < 0.0) {
                    q = -q;
                }
                previous = Some(q);
                values.extend_from_slice(&q.to_array());
            }
            tracks.push(track(TrackTarget::Rotation(joint), values));
        }
        if wants(&channels.scale) {
            let mut values = Vec::with_capacity(keys * 3);
            for (f, t) in column() {
                if !t.scale.is_finite() {
                    return Err(bad(f));
                }
                values.extend_from_slice(&t.scale.to_array());
            }
            tracks.push(track(TrackTarget::Scale(joint), values));
        }
    }
    Ok(Clip {
        name: name.to_string(),
        tracks,
    })
}

/// The skeleton's rest local transforms, one per joint.
pub fn rest_locals(skeleton: &Skeleton) -> Vec<Transform> {
    skeleton.joints().iter().map(|j| j.rest_local).collect()
}

/// `frames` times evenly spaced over `[start, end]` (seconds), both ends included exactly;
/// `[start]` for a single frame.
pub fn even_times(start: f32, end: f32, frames: usize) -> Vec<f32> {
    let last = frames.saturating_sub(1);
    (0..frames)
        .map(|k| {
            if k == 0 {
                start
            } else if k == last {
                end
            } else {
                // In f64 so `k / last` does not round before it is scaled.
                (f64::from(start) + f64::from(end - start) * k as f64 / last as f64) as f32
            }
        })
        .collect()
}

/// Checks that `frames × joints` joint samples stay within [`MAX_SAMPLES`].
pub fn check_budget(frames: usize, joints: usize) -> Result<(), SampleError> {
    if frames.saturating_mul(joints.max(1)) > MAX_SAMPLES {
        return Err(SampleError::TooManySamples {
            frames,
            joints,
            limit: MAX_SAMPLES,
        });
    }
    Ok(())
}

/// Samples `clip` at every time in `times` (seconds): `times.len() × joints` local
/// transforms, frame-major, as [`bake`] takes them.
pub fn sample_frames(
    clip: &CompiledClip<'_>,
    rest: &[Transform],
    times: &[f32],
) -> Result<Vec<Transform>, SampleError> {
    let joints = rest.len();
    check_budget(times.len(), joints)?;
    let mut frames = vec![Transform::IDENTITY; times.len() * joints];
    if joints > 0 {
        for (&time, output) in times.iter().zip(frames.chunks_exact_mut(joints)) {
            SampleJob {
                clip,
                time,
                rest,
                output,
            }
            .run()?;
        }
    }
    Ok(frames)
}

/// Samples one morph-weight track at every time in `source_times` (seconds) into
/// `times.len() × components` weights, frame-major.
pub fn sample_weight_frames(track: &Track, source_times: &[f32]) -> Result<Vec<f32>, SampleError> {
    let components = track.components();
    check_budget(source_times.len(), components)?;
    let mut values = vec![0.0; source_times.len() * components];
    if components > 0 {
        for (&time, out) in source_times.iter().zip(values.chunks_exact_mut(components)) {
            sample_weights(track, time, out)?;
        }
    }
    Ok(values)
}

/// Every morph-weight track of `clip` sampled at `source_times` and stored as a `LINEAR`
/// track keyed at `times` (same length), in clip order.
pub fn resample_weight_tracks(
    clip: &CompiledClip<'_>,
    source_times: &[f32],
    times: &[f32],
) -> Result<Vec<Track>, SampleError> {
    clip.weight_tracks()
        .map(|track| {
            Ok(Track {
                target: track.target,
                interpolation: Interpolation::Linear,
                times: times.to_vec(),
                values: sample_weight_frames(track, source_times)?,
            })
        })
        .collect()
}
