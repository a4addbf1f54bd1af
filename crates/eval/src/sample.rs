//! Clip sampling: a clip and a time to local joint transforms.
//!
//! A [`Clip`] is checked against a skeleton once ([`CompiledClip::new`]); a [`SampleJob`] then
//! evaluates it at any time into a caller-owned buffer without allocating. Interpolation
//! follows glTF 2.0 Appendix C ("Interpolation"):
//! - `STEP`: the value of the last key at or before the time;
//! - `LINEAR`: lerp for vectors, shortest-path slerp for rotations (normalized);
//! - `CUBICSPLINE`: the cubic Hermite spline with values stored `[in_tangent, value,
//!   out_tangent]` per key and tangents scaled by the key interval; rotations are
//!   normalized after interpolating.
//!
//! Before a track's first key it holds the first value, after its last key the last value
//! (glTF leaves this to the client; every viewer clamps).
//!
//! [`bake`] goes the other way: per-frame poses into a clip with `LINEAR` tracks.

mod grid;

pub use grid::{FrameGrid, MAX_FRAMES};

use glam::{Quat, Vec3};
use rigport_model::interp::{self, Keys, VALUE};
use rigport_model::{Clip, Interpolation, Skeleton, Track, TrackTarget, Transform};

/// Key times closer than this (seconds) are one frame in [`CompiledClip::key_times`].
///
/// Tracks that share frames may carry times that differ by float noise (`k / 30` computed
/// in different ways); one microsecond is far below any frame interval (1/1000 s at most).
pub const KEY_TIME_EPSILON: f32 = 1e-6;

/// The most joint samples (frames × joints) one resampling step may produce: 2^26, about
/// 2.7 GB of transforms. Guards against requests like `--fps 1e9` aborting on allocation.
pub const MAX_SAMPLES: usize = 1 << 26;

/// A clip that does not fit a skeleton, a sampling job whose buffers do not fit the clip,
/// or frames that cannot be baked.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// A track animates a joint the skeleton does not have.
    #[error("track {track} targets joint {joint}, but the skeleton has {joints} joints")]
    JointOutOfRange {
        /// Index of the track in [`Clip::tracks`].
        track: usize,
        /// The joint index it names.
        joint: usize,
        /// How many joints the skeleton has.
        joints: usize,
    },
    /// A track has no keys.
    #[error("track {track} has no keys")]
    NoKeys {
        /// Index of the track.
        track: usize,
    },
    /// A track's value count does not match its key count.
    #[error("track {track}: expected {expected} values ({keys} keys), found {found}")]
    ValueCount {
        /// Index of the track.
        track: usize,
        /// Its number of keys.
        keys: usize,
        /// `keys * components` (three times that for cubic splines).
        expected: usize,
        /// Its number of values.
        found: usize,
    },
    /// A morph-weight track's value count is not a positive multiple of its key count.
    #[error("track {track}: {found} weight values are not a positive multiple of {keys} keys")]
    WeightCount {
        /// Index of the track.
        track: usize,
        /// Floats its key count requires per morph target (`keys`, or `3 * keys` for
        /// cubic splines).
        keys: usize,
        /// Its number of values.
        found: usize,
    },
    /// A key time is NaN or infinite.
    #[error("track {track} key {key}: time {time} is not finite")]
    NonFiniteTime {
        /// Index of the track.
        track: usize,
        /// Index of the key.
        key: usize,
        /// The time, in seconds.
        time: f32,
    },
    /// Key times do not strictly increase.
    #[error("track {track} key {key}: time {time} does not come after {previous}")]
    TimeNotIncreasing {
        /// Index of the track.
        track: usize,
        /// Index of the key.
        key: usize,
        /// Its time, in seconds.
        time: f32,
        /// The previous key's time, in seconds.
        previous: f32,
    },
    /// A value is NaN or infinite.
    #[error("track {track}: value {index} is not finite")]
    NonFiniteValue {
        /// Index of the track.
        track: usize,
        /// Index of the float in [`Track::values`].
        index: usize,
    },
    /// A rotation key is the zero quaternion, which is no rotation at all.
    #[error("track {track} key {key}: the rotation has zero length")]
    ZeroRotation {
        /// Index of the track.
        track: usize,
        /// Index of the key.
        key: usize,
    },
    /// Two tracks animate the same channel of the same joint (or the same mesh's weights).
    #[error("tracks {first} and {second} both animate the {}", describe(.target))]
    DuplicateChannel {
        /// The earlier track.
        first: usize,
        /// The later track.
        second: usize,
        /// The channel both animate.
        target: TrackTarget,
    },
    /// A buffer has the wrong length.
    #[error("{what}: expected {expected} elements, found {found}")]
    Length {
        /// Which buffer.
        what: &'static str,
        /// The length the other inputs require.
        expected: usize,
        /// Its length.
        found: usize,
    },
    /// A sample time is NaN or infinite.
    #[error("sample time {time} is not finite")]
    NonFiniteSampleTime {
        /// The time, in seconds.
        time: f32,
    },
    /// [`bake`] was given no frames.
    #[error("bake: no frame times")]
    NoFrames,
    /// [`bake`] frame times are not finite and strictly increasing.
    #[error("bake: frame {frame} time {time} does not come after {previous}")]
    FrameTime {
        /// Index of the frame.
        frame: usize,
        /// Its time, in seconds.
        time: f32,
        /// The previous frame's time (negative infinity for the first frame).
        previous: f32,
    },
    /// A [`bake`] frame holds NaN, infinity or a zero rotation on a baked channel.
    #[error("bake: frame {frame} joint {joint}: non-finite transform or zero rotation")]
    FrameValue {
        /// Index of the frame.
        frame: usize,
        /// Index of the joint.
        joint: usize,
    },
    /// A resampling step would produce more than [`MAX_SAMPLES`] joint samples.
    #[error("{frames} frames x {joints} joints exceed the limit of {limit} samples")]
    TooManySamples {
        /// Frames requested.
        frames: usize,
        /// Joints per frame.
        joints: usize,
        /// [`MAX_SAMPLES`].
        limit: usize,
    },
}

/// `"rotation of joint #3"`, for error messages.
fn describe(target: &TrackTarget) -> String {
    match target {
        TrackTarget::Translation(j) => format!("translation of {j}"),
        TrackTarget::Rotation(j) => format!("rotation of {j}"),
        TrackTarget::Scale(j) => format!("scale of {j}"),
        TrackTarget::MorphWeights(m) => format!("morph weights of {m}"),
    }
}

/// Which track (index into [`Clip::tracks`]) drives each channel of one joint.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct JointTracks {
    translation: Option<usize>,
    rotation: Option<usize>,
    scale: Option<usize>,
}

/// A clip checked against a skeleton once: per joint, which track drives T, R, S.
///
/// Building one validates every track (see [`CompiledClip::new`]); sampling it with
/// [`SampleJob`] then needs no per-key checks and allocates nothing.
#[derive(Clone, Debug)]
pub struct CompiledClip<'a> {
    clip: &'a Clip,
    joints: Vec<JointTracks>,
    weight_tracks: Vec<usize>,
    key_times: Vec<f32>,
    start: f32,
    end: f32,
}

/// Checks one track's keys and values (not its target).
fn check_track(index: usize, track: &Track) -> Result<(), SampleError> {
    let keys = track.times.len();
    if keys == 0 {
        return Err(SampleError::NoKeys { track: index });
    }
    let mut previous = f32::NEG_INFINITY;
    for (key, &time) in track.times.iter().enumerate() {
        if !time.is_finite() {
            return Err(SampleError::NonFiniteTime {
                track: index,
                key,
                time,
            });
        }
        if time <= previous {
            return Err(SampleError::TimeNotIncreasing {
                track: index,
                key,
                time,
                previous,
            });
        }
        previous = time;
    }
    let found = track.values.len();
    if let TrackTarget::MorphWeights(_) = track.target {
        let per_target = match track.interpolation {
            Interpolation::CubicSpline => 3 * keys,
            _ => keys,
        };
        if found == 0 || found % per_target != 0 {
            return Err(SampleError::WeightCount {
                track: index,
                keys: per_target,
                found,
            });
        }
    } else {
        let expected = keys * track.floats_per_key();
        if found != expected {
            return Err(SampleError::ValueCount {
                track: index,
                keys,
                expected,
                found,
            });
        }
    }
    if let Some(bad) = track.values.iter().position(|v| !v.is_finite()) {
        return Err(SampleError::NonFiniteValue {
            track: index,
            index: bad,
        });
    }
    if let TrackTarget::Rotation(_) = track.target {
        if let Some(key) = (0..keys).find(|&k| quat_key(track, k, VALUE).length_squared() == 0.0) {
            return Err(SampleError::ZeroRotation { track: index, key });
        }
    }
    Ok(())
}

impl<'a> CompiledClip<'a> {
    /// Checks `clip` against `skeleton` and records which track drives each joint channel.
    ///
    /// Only the skeleton's joint count is used; rest poses come with each [`SampleJob`].
    ///
    /// # Errors
    /// The first problem found, in track order: a joint index out of range
    /// ([`SampleError::JointOutOfRange`]), no keys, a value count that does not match
    /// `times × components` ([`SampleError::ValueCount`], [`SampleError::WeightCount`]),
    /// times that are not finite or not strictly increasing, non-finite values, a zero
    /// rotation key, or two tracks on the same joint channel or mesh
    /// ([`SampleError::DuplicateChannel`]).
    pub fn new(clip: &'a Clip, skeleton: &Skeleton) -> Result<Self, SampleError> {
        let joint_count = skeleton.len();
        let mut joints = vec![JointTracks::default(); joint_count];
        let mut weight_tracks: Vec<usize> = Vec::new();
        let mut start = f32::INFINITY;
        let mut end = f32::NEG_INFINITY;
        for (index, track) in clip.tracks.iter().enumerate() {
            let slot = match track.target {
                TrackTarget::Translation(j) | TrackTarget::Rotation(j) | TrackTarget::Scale(j) => {
                    let tracks = joints
                        .get_mut(j.get())
                        .ok_or(SampleError::JointOutOfRange {
                            track: index,
                            joint: j.get(),
                            joints: joint_count,
                        })?;
                    Some(match track.target {
                        TrackTarget::Translation(_) => &mut tracks.translation,
                        TrackTarget::Rotation(_) => &mut tracks.rotation,
                        _ => &mut tracks.scale,
                    })
                }
                TrackTarget::MorphWeights(mesh) => {
                    if let Some(&first) = weight_tracks.iter().find(|&&w| {
                        clip.tracks
                            .get(w)
                            .is_some_and(|t| t.target == TrackTarget::MorphWeights(mesh))
                    }) {
                        return Err(SampleError::DuplicateChannel {
                            first,
                            second: index,
                            target: track.target,
                        });
                    }
                    None
                }
            };
            match slot {
                Some(Some(first)) => {
                    return Err(SampleError::DuplicateChannel {
                        first: *first,
                        second: index,
                        target: track.target,
                    })
                }
                Some(slot) => *slot = Some(index),
                None => weight_tracks.push(index),
            }
            check_track(index, track)?;
            if let (Some(&first), Some(&last)) = (track.times.first(), track.times.last()) {
                start = start.min(first);
                end = end.max(last);
            }
        }
        if start > end {
            // No tracks: an empty clip lasts no time, at 0.
            start = 0.0;
            end = 0.0;
        }
        let has_joint_tracks = clip
            .tracks
            .iter()
            .any(|t| !matches!(t.target, TrackTarget::MorphWeights(_)));
        let mut key_times: Vec<f32> = clip
            .tracks
            .iter()
            .filter(|t| !has_joint_tracks || !matches!(t.target, TrackTarget::MorphWeights(_)))
            .flat_map(|t| t.times.iter().copied())
            .collect();
        key_times.sort_by(f32::total_cmp);
        key_times.dedup_by(|later, earlier| *later - *earlier <= KEY_TIME_EPSILON);
        Ok(Self {
            clip,
            joints,
            weight_tracks,
            key_times,
            start,
            end,
        })
    }

    /// The clip.
    pub fn clip(&self) -> &'a Clip {
        self.clip
    }

    /// Number of skeleton joints the clip was compiled for (the length of a
    /// [`SampleJob`]'s `rest` and `output`).
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// The earliest key time of any track, in seconds (0 for a clip without tracks).
    pub fn start(&self) -> f32 {
        self.start
    }

    /// The latest key time of any track, in seconds (0 for a clip without tracks).
    pub fn end(&self) -> f32 {
        self.end
    }

    /// `end - start`, in seconds.
    pub fn duration(&self) -> f32 {
        self.end - self.start
    }

    /// Sorted, de-duplicated union of all joint-track key times (the clip's frames), in
    /// seconds. Times within [`KEY_TIME_EPSILON`] of the previous one are merged. A clip
    /// with only morph-weight tracks uses their times instead.
    pub fn key_times(&self) -> Vec<f32> {
        self.key_times.clone()
    }

    /// Frames per second implied by the key times: the reciprocal of the median spacing
    /// (the upper median for an even count, so one long hold does not decide it); `None`
    /// for fewer than 2 key times.
    pub fn fps(&self) -> Option<f32> {
        let mut gaps: Vec<f32> = self.key_times.windows(2).map(|w| w[1] - w[0]).collect();
        gaps.sort_by(f32::total_cmp);
        let median = *gaps.get(gaps.len() / 2)?;
        (median > 0.0).then(|| 1.0 / median)
    }

    /// The morph-weight tracks, in clip order.
    pub fn weight_tracks(&self) -> impl Iterator<Item = &'a Track> + '_ {
        let tracks = &self.clip.tracks;
        self.weight_tracks.iter().filter_map(|&w| tracks.get(w))
    }
}

/// Samples a [`CompiledClip`] at one time into local joint transforms.
///
/// Channels the clip animates are interpolated (see the module docs); channels it does not
/// animate are copied from `rest`. Morph-weight tracks are ignored here; use
/// [`sample_weights`].
pub struct SampleJob<'a> {
    /// The clip, compiled for the skeleton `rest` belongs to.
    pub clip: &'a CompiledClip<'a>,
    /// Time in seconds; clamped to `[clip.start(), clip.end()]`. Must be finite.
    pub time: f32,
    /// The skeleton's rest local transforms, one per joint.
    pub rest: &'a [Transform],
    /// Output: local transform per joint (same length as `rest`).
    pub output: &'a mut [Transform],
}

impl SampleJob<'_> {
    /// Checks buffer lengths against the clip's joint count and that the time is finite.
    ///
    /// # Errors
    /// [`SampleError::Length`] or [`SampleError::NonFiniteSampleTime`].
    pub fn validate(&self) -> Result<(), SampleError> {
        let n = self.clip.joint_count();
        for (what, found) in [("rest", self.rest.len()), ("output", self.output.len())] {
            if found != n {
                return Err(SampleError::Length {
                    what,
                    expected: n,
                    found,
                });
            }
        }
        if !self.time.is_finite() {
            return Err(SampleError::NonFiniteSampleTime { time: self.time });
        }
        Ok(())
    }

    /// Runs the job. Allocates nothing; finds each key interval by binary search.
    ///
    /// # Errors
    /// As [`SampleJob::validate`], which it calls first.
    pub fn run(&mut self) -> Result<(), SampleError> {
        self.validate()?;
        let time = self.time.clamp(self.clip.start, self.clip.end);
        let tracks = &self.clip.clip.tracks;
        let track = |index: Option<usize>| index.and_then(|i| tracks.get(i));
        for ((out, rest), channels) in self.output.iter_mut().zip(self.rest).zip(&self.clip.joints)
        {
            *out = *rest;
            if let Some(t) = track(channels.translation) {
                out.translation = sample_vec3(t, time);
            }
            if let Some(t) = track(channels.rotation) {
                out.rotation = sample_rotation(t, time);
            }
            if let Some(t) = track(channels.scale) {
                out.scale = sample_vec3(t, time);
            }
        }
        Ok(())
    }
}

/// Samples any track's raw components at `time` (seconds, clamped to the track's keys) into
/// `out`, one float per component: the weight of each morph target for a morph-weight
/// track. Nothing is normalized. Allocates nothing.
///
/// The track's times are assumed strictly increasing, as [`CompiledClip::new`] checks.
///
/// # Errors
/// [`SampleError::NoKeys`] for a track without keys, [`SampleError::ValueCount`] if its
/// values do not fill whole keys, [`SampleError::Length`] if `out` does not hold one float
/// per component, [`SampleError::NonFiniteSampleTime`] for a NaN or infinite time. Errors
/// about the track name it as track 0 (the function sees only that one).
pub fn sample_weights(track: &Track, time: f32, out: &mut [f32]) -> Result<(), SampleError> {
    let keys = track.times.len();
    if keys == 0 {
        return Err(SampleError::NoKeys { track: 0 });
    }
    let components = track.components();
    let expected = keys * track.floats_per_key();
    if track.values.len() != expected || components == 0 {
        return Err(SampleError::ValueCount {
            track: 0,
            keys,
            expected,
            found: track.values.len(),
        });
    }
    if out.len() != components {
        return Err(SampleError::Length {
            what: "weights",
            expected: components,
            found: out.len(),
        });
    }
    if !time.is_finite() {
        return Err(SampleError::NonFiniteSampleTime { time });
    }
    Keys::of(track).sample(time, out);
    Ok(())
}

/// A 3-component track (translation, scale) at `time`, as the sampler evaluates it
/// (`rigport_model::interp`, the one keyframe interpolation).
pub(crate) fn sample_vec3(track: &Track, time: f32) -> Vec3 {
    let mut out = [0.0; 3];
    Keys::of(track).sample(time, &mut out);
    Vec3::from_array(out)
}

/// Element `element` of rotation key `k` as a (not necessarily unit) quaternion.
fn quat_key(track: &Track, k: usize, element: usize) -> Quat {
    Quat::from_array(Keys::of(track).quat_key(k, element))
}

/// A rotation track at `time`, unit length.
fn sample_rotation(track: &Track, time: f32) -> Quat {
    Quat::from_array(Keys::of(track).sample_rotation(time))
}

/// Shortest-path spherical linear interpolation between unit quaternions, normalized
/// ([`interp::slerp`]).
pub(crate) fn slerp(a: Quat, b: Quat, u: f32) -> Quat {
    Quat::from_array(interp::slerp(a.to_array(), b.to_array(), u))
}

/// Blends two local transforms with weight `w` on `b`: lerp translation and scale,
/// shortest-path slerp rotation.
///
/// `w <= 0` returns `a` and `w >= 1` returns `b` exactly (not merely within float error), so
/// a blend that ends on a pose reproduces it bit for bit.
pub(crate) fn blend(a: &Transform, b: &Transform, w: f32) -> Transform {
    if w <= 0.0 {
        return *a;
    }
    if w >= 1.0 {
        return *b;
    }
    Transform {
        translation: a.translation.lerp(b.translation, w),
        rotation: slerp(a.rotation, b.rotation, w),
        scale: a.scale.lerp(b.scale, w),
    }
}

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
pub(crate) fn rest_locals(skeleton: &Skeleton) -> Vec<Transform> {
    skeleton.joints().iter().map(|j| j.rest_local).collect()
}

/// `frames` times evenly spaced over `[start, end]` (seconds), both ends included exactly;
/// `[start]` for a single frame.
pub(crate) fn even_times(start: f32, end: f32, frames: usize) -> Vec<f32> {
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
pub(crate) fn check_budget(frames: usize, joints: usize) -> Result<(), SampleError> {
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
pub(crate) fn sample_frames(
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
pub(crate) fn sample_weight_frames(
    track: &Track,
    source_times: &[f32],
) -> Result<Vec<f32>, SampleError> {
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
pub(crate) fn resample_weight_tracks(
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use glam::EulerRot;
    use proptest::prelude::*;
    use rigport_model::{Joint, JointIndex, MeshIndex};

    /// A chain of `n` joints with distinct rest transforms.
    pub(crate) fn chain(n: usize) -> Skeleton {
        let joints = (0..n)
            .map(|i| Joint {
                name: format!("j{i}"),
                parent: i.checked_sub(1).map(|p| JointIndex(p as u32)),
                rest_local: Transform {
                    translation: Vec3::new(0.1 * i as f32, 1.0, -0.2),
                    rotation: Quat::from_rotation_z(0.1 * i as f32),
                    scale: Vec3::splat(1.0 + 0.01 * i as f32),
                },
            })
            .collect();
        Skeleton::new(joints).unwrap()
    }

    /// A smooth clip on `skeleton`: per joint a rotation of the form
    /// `euler(a·sin(w·t + p), a/2·cos(w·t), 0.3·sin(2w·t))` (`params[j % len] = (a, w, p)`),
    /// plus a root translation walking along +X and +Z with a vertical bob, keyed `frames`
    /// times at `fps` (LINEAR, via [`bake`] so keys are unit and sign-continuous).
    pub(crate) fn smooth_clip(
        joints: usize,
        frames: usize,
        fps: f32,
        params: &[(f32, f32, f32)],
    ) -> Clip {
        let times: Vec<f32> = (0..frames).map(|k| k as f32 / fps).collect();
        let mut poses = Vec::with_capacity(frames * joints);
        for &t in &times {
            for j in 0..joints {
                let (a, w, p) = params[j % params.len()];
                poses.push(Transform {
                    translation: Vec3::new(1.3 * t, 1.0 + 0.05 * (6.0 * t).sin(), 0.2 * t),
                    rotation: Quat::from_euler(
                        EulerRot::ZYX,
                        a * (w * t + p).sin(),
                        0.5 * a * (w * t).cos(),
                        0.3 * (2.0 * w * t).sin(),
                    ),
                    scale: Vec3::ONE,
                });
            }
        }
        let mut mask = ChannelMask::none(joints);
        mask.rotation = vec![true; joints];
        mask.translation[0] = true;
        bake("smooth", &times, &poses, &mask).unwrap()
    }

    pub(crate) fn track(
        target: TrackTarget,
        interpolation: Interpolation,
        times: &[f32],
        values: &[f32],
    ) -> Track {
        Track {
            target,
            interpolation,
            times: times.to_vec(),
            values: values.to_vec(),
        }
    }

    pub(crate) fn rot(j: u32) -> TrackTarget {
        TrackTarget::Rotation(JointIndex(j))
    }

    pub(crate) fn tra(j: u32) -> TrackTarget {
        TrackTarget::Translation(JointIndex(j))
    }

    pub(crate) fn sample_at(clip: &Clip, skeleton: &Skeleton, time: f32) -> Vec<Transform> {
        let compiled = CompiledClip::new(clip, skeleton).unwrap();
        let rest = rest_locals(skeleton);
        let mut out = vec![Transform::IDENTITY; skeleton.len()];
        SampleJob {
            clip: &compiled,
            time,
            rest: &rest,
            output: &mut out,
        }
        .run()
        .unwrap();
        out
    }

    /// Angle in radians between the rotations two quaternions represent.
    ///
    /// Kahan's `2·atan2(|a−b|, |a+b|)` (times 2: quaternions use half angles); `acos` of a
    /// float32 dot product near 1 is off by ~1e-3 rad for identical inputs.
    pub(crate) fn angle(a: Quat, b: Quat) -> f32 {
        let (a, b) = (a.normalize(), b.normalize());
        let b = if a.dot(b) < 0.0 { -b } else { b };
        4.0 * (a - b).length().atan2((a + b).length())
    }

    // ---- the naive reference: linear search, glTF Appendix C formulas in f64 ----

    fn naive_component(track: &Track, time: f32, c: usize) -> f64 {
        let comps = track.components();
        let cubic = track.interpolation == Interpolation::CubicSpline;
        let at = |k: usize, e: usize| {
            let slot = if cubic { 3 * k + e } else { k };
            f64::from(track.values[slot * comps + c])
        };
        let n = track.times.len();
        let t = f64::from(time);
        if t <= f64::from(track.times[0]) {
            return at(0, 1);
        }
        if t >= f64::from(track.times[n - 1]) {
            return at(n - 1, 1);
        }
        let mut k = 0;
        while f64::from(track.times[k + 1]) <= t {
            k += 1;
        }
        let (t0, t1) = (f64::from(track.times[k]), f64::from(track.times[k + 1]));
        let td = t1 - t0;
        let u = (t - t0) / td;
        match track.interpolation {
            Interpolation::Step => at(k, 1),
            Interpolation::Linear => (1.0 - u) * at(k, 1) + u * at(k + 1, 1),
            Interpolation::CubicSpline => {
                let (u2, u3) = (u * u, u * u * u);
                (2.0 * u3 - 3.0 * u2 + 1.0) * at(k, 1)
                    + td * (u3 - 2.0 * u2 + u) * at(k, 2)
                    + (-2.0 * u3 + 3.0 * u2) * at(k + 1, 1)
                    + td * (u3 - u2) * at(k + 1, 0)
            }
        }
    }

    /// glTF Appendix C slerp: `a = acos|d|`, `s = sign(d)`.
    fn naive_slerp(a: [f64; 4], b: [f64; 4], u: f64) -> [f64; 4] {
        let dot: f64 = (0..4).map(|i| a[i] * b[i]).sum();
        let s = if dot < 0.0 { -1.0 } else { 1.0 };
        let angle = dot.abs().min(1.0).acos();
        let (wa, wb) = if angle < 1e-9 {
            (1.0 - u, u)
        } else {
            (
                ((1.0 - u) * angle).sin() / angle.sin(),
                (u * angle).sin() / angle.sin(),
            )
        };
        let r: Vec<f64> = (0..4).map(|i| wa * a[i] + s * wb * b[i]).collect();
        let len = r.iter().map(|v| v * v).sum::<f64>().sqrt();
        [r[0] / len, r[1] / len, r[2] / len, r[3] / len]
    }

    fn naive_rotation(track: &Track, time: f32) -> Quat {
        let key = |k: usize| {
            let q = track.key_value(k);
            let len = q.iter().map(|v| f64::from(*v).powi(2)).sum::<f64>().sqrt();
            [0, 1, 2, 3].map(|i| f64::from(q[i]) / len)
        };
        let n = track.times.len();
        let r = if track.interpolation == Interpolation::Linear
            && time > track.times[0]
            && time < track.times[n - 1]
        {
            let k = track.times.iter().rposition(|&t| t <= time).unwrap();
            let u =
                f64::from(time - track.times[k]) / f64::from(track.times[k + 1] - track.times[k]);
            naive_slerp(key(k), key(k + 1), u)
        } else {
            let c = [0, 1, 2, 3].map(|c| naive_component(track, time, c));
            let len = c.iter().map(|v| v * v).sum::<f64>().sqrt();
            c.map(|v| v / len)
        };
        Quat::from_xyzw(r[0] as f32, r[1] as f32, r[2] as f32, r[3] as f32)
    }

    // ---- strategies ----

    fn quat() -> impl Strategy<Value = Quat> {
        prop::array::uniform3(-3.2f32..3.2)
            .prop_map(|r| Quat::from_euler(EulerRot::ZYX, r[0], r[1], r[2]))
    }

    fn key_times(max: usize) -> impl Strategy<Value = Vec<f32>> {
        prop::collection::vec(0.01f32..0.5, 1..max).prop_map(|gaps| {
            let mut t = 0.0;
            gaps.iter()
                .map(|g| {
                    let now = t;
                    t += g;
                    now
                })
                .collect()
        })
    }

    fn interpolation() -> impl Strategy<Value = Interpolation> {
        prop_oneof![
            Just(Interpolation::Step),
            Just(Interpolation::Linear),
            Just(Interpolation::CubicSpline)
        ]
    }

    /// A random track on `target` with `times`, values in [-2, 2] (rotations: random unit
    /// quaternions, random signs; cubic tangents in [-2, 2]).
    fn random_track(target: TrackTarget) -> impl Strategy<Value = Track> {
        (key_times(12), interpolation()).prop_flat_map(move |(times, interpolation)| {
            let n = times.len();
            let per_key = if interpolation == Interpolation::CubicSpline {
                3
            } else {
                1
            };
            (
                prop::collection::vec(-2.0f32..2.0, n * 4 * per_key),
                prop::collection::vec(quat(), n),
                prop::collection::vec(any::<bool>(), n),
            )
                .prop_map(move |(raw, quats, flips)| {
                    let comps = match target {
                        TrackTarget::Rotation(_) => 4,
                        _ => 3,
                    };
                    let mut values: Vec<f32> = raw[..n * comps * per_key].to_vec();
                    if comps == 4 {
                        for k in 0..n {
                            let q = if flips[k] { -quats[k] } else { quats[k] };
                            let at = if per_key == 3 { (3 * k + 1) * 4 } else { k * 4 };
                            values[at..at + 4].copy_from_slice(&q.to_array());
                        }
                    }
                    Track {
                        target,
                        interpolation,
                        times: times.clone(),
                        values,
                    }
                })
        })
    }

    proptest! {
        #[test]
        fn sampling_matches_the_naive_reference(
            translation in random_track(tra(0)),
            rotation in random_track(rot(0)),
            scale in random_track(TrackTarget::Scale(JointIndex(0))),
            probes in prop::collection::vec(-0.5f32..7.0, 16),
        ) {
            let skeleton = chain(1);
            let clip = Clip { name: "c".into(), tracks: vec![translation.clone(), rotation.clone(), scale.clone()] };
            for &time in &probes {
                // The job clamps to the clip; the reference clamps per track.
                let compiled = CompiledClip::new(&clip, &skeleton).unwrap();
                let t = time.clamp(compiled.start(), compiled.end());
                let got = sample_at(&clip, &skeleton, time)[0];
                for (track, v) in [(&translation, got.translation), (&scale, got.scale)] {
                    for c in 0..3 {
                        let want = naive_component(track, t, c);
                        prop_assert!((f64::from(v[c]) - want).abs() <= 1e-4 * (1.0 + want.abs()),
                            "{:?} at {t}: component {c} {} vs {want}", track.interpolation, v[c]);
                    }
                }
                let want = naive_rotation(&rotation, t);
                prop_assert!(angle(got.rotation, want) < 1e-3,
                    "{:?} at {t}: {:?} vs {want:?}", rotation.interpolation, got.rotation);
                prop_assert!((got.rotation.length() - 1.0).abs() < 1e-5, "norm {}", got.rotation.length());
            }
        }

        #[test]
        fn linear_sampling_at_key_times_returns_the_keys(
            translation in random_track(tra(0)),
            rotation in random_track(rot(1)),
        ) {
            let skeleton = chain(2);
            let translation = Track { interpolation: Interpolation::Linear, times: translation.times.clone(), values: translation.values[..translation.times.len() * 3].to_vec(), ..translation };
            let n = rotation.times.len();
            let values: Vec<f32> = (0..n).flat_map(|k| rotation.key_value(k).to_vec()).collect();
            let rotation = Track { interpolation: Interpolation::Linear, values, ..rotation };
            let clip = Clip { name: "c".into(), tracks: vec![translation.clone(), rotation.clone()] };
            for (k, &t) in translation.times.iter().enumerate() {
                let got = sample_at(&clip, &skeleton, t)[0].translation;
                prop_assert!(got.abs_diff_eq(Vec3::from_slice(translation.key_value(k)), 1e-6), "key {k}: {got}");
            }
            for (k, &t) in rotation.times.iter().enumerate() {
                let got = sample_at(&clip, &skeleton, t)[1].rotation;
                let want = Quat::from_slice(rotation.key_value(k));
                prop_assert!(got.abs_diff_eq(want, 1e-6), "key {k}: {got:?} vs {want:?}");
            }
        }

        #[test]
        fn slerp_endpoints_and_unit_length(a in quat(), b in quat(), flip in any::<bool>(), u in 0.0f32..1.0) {
            let b = if flip { -b } else { b };
            prop_assert!(slerp(a, b, 0.0).abs_diff_eq(a, 1e-6));
            let end = slerp(a, b, 1.0);
            prop_assert!(end.abs_diff_eq(b, 1e-6) || end.abs_diff_eq(-b, 1e-6), "{end:?} vs {b:?}");
            let mid = slerp(a, b, u);
            prop_assert!((mid.length() - 1.0).abs() < 1e-6);
            // Shortest path: the angle travelled is u times the whole angle.
            prop_assert!((angle(a, mid) - u * angle(a, b)).abs() < 2e-3, "{} vs {}", angle(a, mid), u * angle(a, b));
        }

        #[test]
        fn sampling_a_bake_at_the_frame_times_gives_the_frames(
            times in key_times(10),
            poses in prop::collection::vec((prop::array::uniform3(-2.0f32..2.0), quat(), any::<bool>(), prop::array::uniform3(0.5f32..2.0)), 30),
        ) {
            let skeleton = chain(3);
            let joints = 3;
            let frames: Vec<Transform> = (0..times.len() * joints).map(|i| {
                let (t, q, flip, s) = poses[i % poses.len()];
                Transform { translation: Vec3::from(t), rotation: if flip { -q } else { q }, scale: Vec3::from(s) }
            }).collect();
            let clip = bake("b", &times, &frames, &ChannelMask::all(joints)).unwrap();
            for (f, &t) in times.iter().enumerate() {
                let got = sample_at(&clip, &skeleton, t);
                for j in 0..joints {
                    let want = frames[f * joints + j];
                    prop_assert!(got[j].translation.abs_diff_eq(want.translation, 1e-6));
                    prop_assert!(got[j].scale.abs_diff_eq(want.scale, 1e-6));
                    prop_assert!(angle(got[j].rotation, want.rotation) < 1e-3, "frame {f} joint {j}: {:?} vs {:?}", got[j].rotation, want.rotation);
                    prop_assert!(got[j].rotation.abs_diff_eq(want.rotation, 1e-6) || got[j].rotation.abs_diff_eq(-want.rotation, 1e-6));
                }
            }
            // Sign continuity of every baked rotation track.
            for track in clip.tracks.iter().filter(|t| matches!(t.target, TrackTarget::Rotation(_))) {
                for k in 1..track.times.len() {
                    let d = Quat::from_slice(track.key_value(k - 1)).dot(Quat::from_slice(track.key_value(k)));
                    prop_assert!(d >= 0.0, "key {k}: dot {d}");
                }
            }
        }
    }

    #[test]
    fn cubic_spline_reproduces_a_cubic_with_tangents_scaled_by_the_interval() {
        // x(t) = t³ on keys 0 and 2 s (interval 2): values 0, 8; derivatives 0, 12. A
        // Hermite spline reproduces any cubic exactly, so x(1) = 1 and x(1.5) = 3.375;
        // forgetting the interval factor would give 0.5 + ... instead.
        let skeleton = chain(1);
        let values = [
            0.0, 0.0, 0.0, /**/ 0.0, 1.0, 0.0, /**/ 0.0, 0.0,
            0.0, // key 0: in, value, out
            12.0, 0.0, 0.0, /**/ 8.0, 1.0, 0.0, /**/ 12.0, 0.0, 0.0, // key 1
        ];
        let clip = Clip {
            name: "cubic".into(),
            tracks: vec![track(
                tra(0),
                Interpolation::CubicSpline,
                &[0.0, 2.0],
                &values,
            )],
        };
        for (t, want) in [(0.0, 0.0), (1.0, 1.0), (1.5, 3.375), (2.0, 8.0), (5.0, 8.0)] {
            let got = sample_at(&clip, &skeleton, t)[0].translation;
            assert!((got.x - want).abs() < 1e-5, "t={t}: {} vs {want}", got.x);
            assert!((got.y - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn step_holds_and_unanimated_channels_are_rest() {
        let skeleton = chain(2);
        let rest = rest_locals(&skeleton);
        let clip = Clip {
            name: "step".into(),
            tracks: vec![track(
                tra(1),
                Interpolation::Step,
                &[1.0, 2.0, 3.0],
                &[1., 0., 0., 2., 0., 0., 3., 0., 0.],
            )],
        };
        for (t, want) in [
            (0.0, 1.0),
            (1.0, 1.0),
            (1.99, 1.0),
            (2.0, 2.0),
            (2.5, 2.0),
            (3.0, 3.0),
            (9.0, 3.0),
        ] {
            let got = sample_at(&clip, &skeleton, t);
            assert_eq!(got[1].translation.x, want, "t={t}");
            assert_eq!(got[1].rotation, rest[1].rotation);
            assert_eq!(got[1].scale, rest[1].scale);
            assert_eq!(got[0], rest[0]);
        }
        let compiled = CompiledClip::new(&clip, &skeleton).unwrap();
        assert_eq!(
            (compiled.start(), compiled.end(), compiled.duration()),
            (1.0, 3.0, 2.0)
        );
    }

    #[test]
    fn key_times_are_the_union_and_fps_the_median_spacing() {
        let skeleton = chain(2);
        let clip = Clip {
            name: "k".into(),
            tracks: vec![
                track(
                    tra(0),
                    Interpolation::Linear,
                    &[0.0, 0.1, 0.2, 0.6],
                    &[0.0; 12],
                ),
                track(
                    rot(1),
                    Interpolation::Linear,
                    &[0.1, 0.3, 0.4],
                    &[0., 0., 0., 1.].repeat(3),
                ),
                track(
                    TrackTarget::MorphWeights(MeshIndex(0)),
                    Interpolation::Linear,
                    &[5.0, 6.0],
                    &[0.0; 4],
                ),
            ],
        };
        let compiled = CompiledClip::new(&clip, &skeleton).unwrap();
        assert_eq!(compiled.key_times(), vec![0.0, 0.1, 0.2, 0.3, 0.4, 0.6]);
        // Gaps 0.1, 0.1, 0.1, 0.1, 0.2 (up to float noise): median 0.1.
        assert!(
            (compiled.fps().unwrap() - 10.0).abs() < 1e-3,
            "{:?}",
            compiled.fps()
        );
        // Weights count towards the clip's range but not its frames.
        assert_eq!((compiled.start(), compiled.end()), (0.0, 6.0));
        let single = Clip {
            name: "one".into(),
            tracks: vec![track(tra(0), Interpolation::Linear, &[0.5], &[0.0; 3])],
        };
        assert_eq!(CompiledClip::new(&single, &skeleton).unwrap().fps(), None);
        let empty = Clip::default();
        let compiled = CompiledClip::new(&empty, &skeleton).unwrap();
        assert_eq!(
            (compiled.start(), compiled.end(), compiled.fps()),
            (0.0, 0.0, None)
        );
    }

    #[test]
    fn compile_rejects_each_invalid_field() {
        let skeleton = chain(2);
        let ok_rot = [0., 0., 0., 1., 0., 0., 0., 1.];
        let cases: Vec<(Vec<Track>, SampleError)> = vec![
            (
                vec![track(rot(2), Interpolation::Linear, &[0., 1.], &ok_rot)],
                SampleError::JointOutOfRange {
                    track: 0,
                    joint: 2,
                    joints: 2,
                },
            ),
            (
                vec![track(rot(0), Interpolation::Linear, &[], &[])],
                SampleError::NoKeys { track: 0 },
            ),
            (
                vec![track(
                    rot(0),
                    Interpolation::Linear,
                    &[0., 1.],
                    &ok_rot[..7],
                )],
                SampleError::ValueCount {
                    track: 0,
                    keys: 2,
                    expected: 8,
                    found: 7,
                },
            ),
            (
                vec![track(
                    rot(0),
                    Interpolation::CubicSpline,
                    &[0., 1.],
                    &ok_rot,
                )],
                SampleError::ValueCount {
                    track: 0,
                    keys: 2,
                    expected: 24,
                    found: 8,
                },
            ),
            (
                vec![track(
                    TrackTarget::MorphWeights(MeshIndex(0)),
                    Interpolation::Linear,
                    &[0., 1.],
                    &[0.; 3],
                )],
                SampleError::WeightCount {
                    track: 0,
                    keys: 2,
                    found: 3,
                },
            ),
            (
                vec![track(
                    tra(0),
                    Interpolation::Linear,
                    &[0., f32::NAN],
                    &[0.; 6],
                )],
                SampleError::NonFiniteTime {
                    track: 0,
                    key: 1,
                    time: f32::NAN,
                },
            ),
            (
                vec![track(
                    tra(0),
                    Interpolation::Linear,
                    &[0., 1., 1.],
                    &[0.; 9],
                )],
                SampleError::TimeNotIncreasing {
                    track: 0,
                    key: 2,
                    time: 1.0,
                    previous: 1.0,
                },
            ),
            (
                vec![track(
                    tra(0),
                    Interpolation::Linear,
                    &[0., 1.],
                    &[0., 0., 0., 0., f32::INFINITY, 0.],
                )],
                SampleError::NonFiniteValue { track: 0, index: 4 },
            ),
            (
                vec![track(
                    rot(0),
                    Interpolation::Linear,
                    &[0., 1.],
                    &[0., 0., 0., 1., 0., 0., 0., 0.],
                )],
                SampleError::ZeroRotation { track: 0, key: 1 },
            ),
            (
                vec![
                    track(rot(1), Interpolation::Linear, &[0., 1.], &ok_rot),
                    track(tra(1), Interpolation::Linear, &[0.], &[0.; 3]),
                    track(rot(1), Interpolation::Step, &[0., 1.], &ok_rot),
                ],
                SampleError::DuplicateChannel {
                    first: 0,
                    second: 2,
                    target: rot(1),
                },
            ),
            (
                vec![
                    track(
                        TrackTarget::MorphWeights(MeshIndex(3)),
                        Interpolation::Linear,
                        &[0.],
                        &[0.],
                    ),
                    track(
                        TrackTarget::MorphWeights(MeshIndex(3)),
                        Interpolation::Linear,
                        &[0.],
                        &[0.],
                    ),
                ],
                SampleError::DuplicateChannel {
                    first: 0,
                    second: 1,
                    target: TrackTarget::MorphWeights(MeshIndex(3)),
                },
            ),
        ];
        for (tracks, want) in cases {
            let clip = Clip {
                name: "bad".into(),
                tracks,
            };
            let got = CompiledClip::new(&clip, &skeleton).err();
            // NaN != NaN: compare the messages.
            assert_eq!(
                got.as_ref().map(ToString::to_string),
                Some(want.to_string()),
                "{got:?}"
            );
        }
        let err = SampleError::DuplicateChannel {
            first: 0,
            second: 2,
            target: rot(1),
        };
        assert_eq!(
            err.to_string(),
            "tracks 0 and 2 both animate the rotation of joint #1"
        );
    }

    #[test]
    fn job_validates_lengths_and_time() {
        let skeleton = chain(2);
        let clip = Clip::default();
        let compiled = CompiledClip::new(&clip, &skeleton).unwrap();
        let rest = rest_locals(&skeleton);
        let mut short = [Transform::IDENTITY; 1];
        let job = SampleJob {
            clip: &compiled,
            time: 0.0,
            rest: &rest,
            output: &mut short,
        };
        assert_eq!(
            job.validate(),
            Err(SampleError::Length {
                what: "output",
                expected: 2,
                found: 1
            })
        );
        let mut out = [Transform::IDENTITY; 2];
        let mut job = SampleJob {
            clip: &compiled,
            time: f32::INFINITY,
            rest: &rest,
            output: &mut out,
        };
        assert!(matches!(
            job.run(),
            Err(SampleError::NonFiniteSampleTime { .. })
        ));
        let job = SampleJob {
            clip: &compiled,
            time: 0.0,
            rest: &rest[..1],
            output: &mut out,
        };
        assert!(matches!(
            job.validate(),
            Err(SampleError::Length { what: "rest", .. })
        ));
    }

    #[test]
    fn weights_sample_in_all_modes_and_check_sizes() {
        let mesh = TrackTarget::MorphWeights(MeshIndex(0));
        let linear = track(
            mesh,
            Interpolation::Linear,
            &[0.0, 1.0],
            &[0.0, 1.0, 1.0, 0.0],
        );
        let mut out = [0.0; 2];
        sample_weights(&linear, 0.25, &mut out).unwrap();
        assert_eq!(out, [0.25, 0.75]);
        let step = Track {
            interpolation: Interpolation::Step,
            ..linear.clone()
        };
        sample_weights(&step, 0.99, &mut out).unwrap();
        assert_eq!(out, [0.0, 1.0]);
        // One target, cubic with zero tangents: smoothstep, 0.5 at the middle.
        let cubic = track(
            mesh,
            Interpolation::CubicSpline,
            &[0.0, 1.0],
            &[0., 0., 0., 0., 1., 0.],
        );
        let mut one = [0.0];
        sample_weights(&cubic, 0.5, &mut one).unwrap();
        assert!((one[0] - 0.5).abs() < 1e-6);
        sample_weights(&cubic, 0.25, &mut one).unwrap();
        assert!((one[0] - 0.15625).abs() < 1e-6, "{}", one[0]);
        assert_eq!(
            sample_weights(&linear, 0.5, &mut one),
            Err(SampleError::Length {
                what: "weights",
                expected: 2,
                found: 1
            })
        );
        let broken = track(mesh, Interpolation::Linear, &[0.0, 1.0], &[0.0; 3]);
        assert!(matches!(
            sample_weights(&broken, 0.5, &mut one),
            Err(SampleError::ValueCount { .. })
        ));
    }

    #[test]
    fn bake_rejects_bad_input_and_keeps_signs_continuous() {
        let frames = [Transform::IDENTITY; 4];
        let mask = ChannelMask::all(2);
        assert_eq!(
            bake("x", &[0.0, 0.0], &frames, &mask).err(),
            Some(SampleError::FrameTime {
                frame: 1,
                time: 0.0,
                previous: 0.0
            })
        );
        assert!(matches!(
            bake("x", &[0.0, f32::NAN], &frames, &mask),
            Err(SampleError::FrameTime { frame: 1, .. })
        ));
        assert_eq!(
            bake("x", &[0.0], &frames, &mask).err(),
            Some(SampleError::Length {
                what: "frames",
                expected: 2,
                found: 4
            })
        );
        assert_eq!(
            bake("x", &[], &[], &mask).err(),
            Some(SampleError::NoFrames)
        );
        let mut zero = frames;
        zero[3].rotation = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
        assert_eq!(
            bake("x", &[0.0, 1.0], &zero, &mask).err(),
            Some(SampleError::FrameValue { frame: 1, joint: 1 })
        );
        // Not baked, so not checked.
        let only_translation = ChannelMask {
            rotation: vec![false; 2],
            ..ChannelMask::all(2)
        };
        assert!(bake("x", &[0.0, 1.0], &zero, &only_translation).is_ok());
        let uneven = ChannelMask {
            scale: vec![true],
            ..ChannelMask::all(2)
        };
        assert!(matches!(
            bake("x", &[0.0, 1.0], &frames, &uneven),
            Err(SampleError::Length {
                what: "channels.scale",
                ..
            })
        ));

        // Rotations alternate sign and grow by 0.3 rad: baked keys all have dot >= 0.
        let q = |i: usize| {
            let q = Quat::from_rotation_y(0.3 * i as f32) * 2.0; // not unit either
            if i % 2 == 1 {
                -q
            } else {
                q
            }
        };
        let frames: Vec<Transform> = (0..6)
            .map(|i| Transform {
                rotation: q(i),
                ..Transform::IDENTITY
            })
            .collect();
        let times: Vec<f32> = (0..6).map(|i| i as f32 / 30.0).collect();
        let mask = ChannelMask {
            translation: vec![false],
            rotation: vec![true],
            scale: vec![false],
        };
        let clip = bake("signs", &times, &frames, &mask).unwrap();
        assert_eq!(clip.tracks.len(), 1);
        let track = &clip.tracks[0];
        assert_eq!(track.interpolation, Interpolation::Linear);
        for k in 0..6 {
            let key = Quat::from_slice(track.key_value(k));
            assert!((key.length() - 1.0).abs() < 1e-6);
            assert!(angle(key, q(k)) < 1e-3);
            if k > 0 {
                assert!(
                    key.dot(Quat::from_slice(track.key_value(k - 1))) >= 0.0,
                    "key {k}"
                );
            }
        }
    }

    #[test]
    fn channel_masks() {
        let clip = Clip {
            name: "m".into(),
            tracks: vec![
                track(tra(0), Interpolation::Linear, &[0.], &[0.; 3]),
                track(rot(1), Interpolation::Linear, &[0.], &[0., 0., 0., 1.]),
                track(rot(7), Interpolation::Linear, &[0.], &[0., 0., 0., 1.]),
                track(
                    TrackTarget::MorphWeights(MeshIndex(0)),
                    Interpolation::Linear,
                    &[0.],
                    &[0.],
                ),
            ],
        };
        let mask = ChannelMask::of_clip(&clip, 2);
        assert_eq!(mask.translation, vec![true, false]);
        assert_eq!(mask.rotation, vec![false, true]);
        assert_eq!(mask.scale, vec![false, false]);
        let mut union = ChannelMask::none(1);
        union.scale[0] = true;
        union.union_with(&mask);
        assert_eq!(union.translation, vec![true, false]);
        assert_eq!(union.scale, vec![true, false]);
        assert_eq!(ChannelMask::all(3).rotation, vec![true; 3]);
    }
}
