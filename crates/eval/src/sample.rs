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

mod bake;
mod grid;

pub use bake::{
    bake, check_budget, even_times, resample_weight_tracks, rest_locals, sample_frames,
    sample_weight_frames, ChannelMask,
};
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
        self.run_with(sample_rotation)
    }

    /// [`SampleJob::run`] with rotations as a viewer composes them: the keys as stored,
    /// not normalized ([`rigport_model::interp::Keys::sample_rotation_as_stored`]), for
    /// `rigport eval`, which shows what three.js and UsdSkel show. Every other job works on
    /// unit rotations ([`SampleJob::run`]).
    ///
    /// # Errors
    /// As [`SampleJob::validate`], which it calls first.
    pub fn run_as_stored(&mut self) -> Result<(), SampleError> {
        self.run_with(|track, time| {
            Quat::from_array(Keys::of(track).sample_rotation_as_stored(time))
        })
    }

    fn run_with(
        &mut self,
        sample_rotation: impl Fn(&Track, f32) -> Quat,
    ) -> Result<(), SampleError> {
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
pub fn sample_vec3(track: &Track, time: f32) -> Vec3 {
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
pub fn slerp(a: Quat, b: Quat, u: f32) -> Quat {
    Quat::from_array(interp::slerp(a.to_array(), b.to_array(), u))
}

/// Blends two local transforms with weight `w` on `b`: lerp translation and scale,
/// shortest-path slerp rotation.
///
/// `w <= 0` returns `a` and `w >= 1` returns `b` exactly (not merely within float error), so
/// a blend that ends on a pose reproduces it bit for bit.
pub fn blend(a: &Transform, b: &Transform, w: f32) -> Transform {
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

#[cfg(test)]
mod tests;
