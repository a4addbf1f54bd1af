//! Time warping: resampling, speed, warp curves and reversal.
//!
//! glTF has no notion of non-linear time, so every warp is baked to linear samples
//! (FORMATS.md, glTF section: "Non-linear time (time warps) must be baked to linear
//! samples"). Resampling modes ([`Retime::Frames`], [`Retime::Fps`], [`Retime::Warp`])
//! sample the source with [`SampleJob`] and bake the result with [`bake`]: `LINEAR` tracks
//! on exactly the channels the source animates ([`ChannelMask::of_clip`]), sign-continuous
//! unit quaternions, the source's name, and its morph-weight tracks resampled (lerp) at the
//! same times.
//!
//! [`Retime::Speed`] and [`Retime::Reverse`] are affine maps of time, so they move the keys
//! instead of resampling: key times are mapped, cubic-spline tangents (per-second
//! derivatives) are scaled by the speed or negated and swapped, and each track keeps its
//! interpolation mode. This is exact for `LINEAR` and `CUBICSPLINE`, and for `STEP` under
//! speed changes; a reversed `STEP` track shows every key at its mirrored time, but between
//! keys it holds the later key's value where the source held the earlier's (a
//! right-continuous step mirrored is left-continuous, which glTF cannot express).
//! `LINEAR` and `STEP` rotation keys are made sign-continuous (which does not change the
//! rotations they interpolate to); `CUBICSPLINE` rotation keys keep their signs, since
//! flipping one would change the spline.
//!
//! [`SampleJob`]: crate::sample::SampleJob

use rigport_model::{Clip, Interpolation, Skeleton, Track, TrackTarget};

use crate::sample::{
    bake, check_budget, even_times, resample_weight_tracks, rest_locals, sample_frames,
    ChannelMask, CompiledClip, SampleError,
};

/// How far (seconds) a warp key's source time may lie outside the clip and still be
/// accepted, clamped to the clip's end. A millisecond absorbs clips whose last key is
/// `1.999998` s (60 frames of `0.0333333` s) when the user writes `2`, and is a quarter of
/// a frame at 240 fps, so it never hides a real mistake.
pub const WARP_CLIP_TOLERANCE: f32 = 1e-3;

/// A change of a clip's timing. See [`retime`].
#[derive(Clone, Debug, PartialEq)]
pub enum Retime {
    /// Resample to this many frames (at least 2), evenly spaced over the clip's
    /// `[start, end]`, both ends included.
    Frames(usize),
    /// Resample at this many frames per second (finite, > 0): `start + k / fps` while
    /// before the end, then the end itself (even if off the grid).
    Fps(f32),
    /// Play this many times as fast (finite, > 0): the duration becomes `duration / speed`.
    /// Exact: key times are scaled about the start, not resampled.
    Speed(f32),
    /// Map output time to source time with a piecewise linear curve, sampled at the
    /// source's frame rate over the curve's output range.
    Warp(WarpCurve),
    /// Play backwards: `t -> start + end - t` (`end - t` for a clip starting at 0). Exact.
    Reverse,
}

/// A piecewise linear map from output time to source time, both in seconds.
///
/// Keys have finite, non-negative, strictly increasing output times and finite,
/// non-decreasing (monotone) source times, so the warped clip never plays backwards (use
/// [`Retime::Reverse`] for that); a flat stretch holds a pose. [`retime`] also requires
/// every source time to lie within the clip (within [`WARP_CLIP_TOLERANCE`]).
#[derive(Clone, Debug, PartialEq)]
pub struct WarpCurve {
    /// `(output_seconds, source_seconds)`, at least 2.
    keys: Vec<(f32, f32)>,
    /// Each key as the user wrote it, for error messages.
    texts: Vec<String>,
}

/// What is wrong with one warp key.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum WarpProblem {
    /// The key is not two numbers separated by a colon.
    #[error("expected output_seconds:source_seconds, e.g. 1:0.4")]
    Syntax,
    /// A time is NaN or infinite.
    #[error("times must be finite")]
    NotFinite,
    /// The output time is negative (glTF key times are >= 0).
    #[error("output time {time} is negative")]
    NegativeOutput {
        /// The output time, in seconds.
        time: f32,
    },
    /// The output time does not come after the previous key's.
    #[error("output time does not come after {previous}")]
    OutputNotIncreasing {
        /// The previous key's output time, in seconds.
        previous: f32,
    },
    /// The source time is smaller than the previous key's.
    #[error("source time goes backwards from {previous}")]
    SourceBackwards {
        /// The previous key's source time, in seconds.
        previous: f32,
    },
    /// The source time lies outside the clip.
    #[error("source time is outside the clip [{start}, {end}]")]
    OutsideClip {
        /// The clip's first key time, in seconds.
        start: f32,
        /// The clip's last key time, in seconds.
        end: f32,
    },
}

/// Why a clip cannot be retimed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RetimeError {
    /// The clip does not fit the skeleton (see [`CompiledClip::new`]).
    #[error("the clip does not fit the skeleton")]
    Clip(#[source] SampleError),
    /// Sampling or baking the result failed (e.g. too many samples).
    #[error("cannot resample the clip")]
    Sample(#[source] SampleError),
    /// Moving the keys produced an invalid clip (e.g. a speed so large that distinct key
    /// times round to the same float).
    #[error("the retimed keys are invalid")]
    Output(#[source] SampleError),
    /// [`Retime::Frames`] with fewer than 2 frames.
    #[error("resampling needs at least 2 frames, got {frames}")]
    TooFewFrames {
        /// The frame count asked for.
        frames: usize,
    },
    /// [`Retime::Frames`] on a clip whose keys all lie at one time.
    #[error("the clip lasts no time, so {frames} frames cannot be spread over it")]
    ZeroDuration {
        /// The frame count asked for.
        frames: usize,
    },
    /// A frame rate that is not finite and positive.
    #[error("frame rate {fps} is not a positive finite number")]
    BadFps {
        /// The frame rate, in frames per second.
        fps: f32,
    },
    /// A speed factor that is not finite and positive.
    #[error("speed {speed} is not a positive finite number (use Reverse to play backwards)")]
    BadSpeed {
        /// The factor.
        speed: f32,
    },
    /// [`Retime::Warp`] on a clip with fewer than 2 key times: no frame rate to sample at.
    #[error("the clip has fewer than 2 key times, so no frame rate to sample a warp at")]
    NoFps,
    /// A warp curve with fewer than 2 keys.
    #[error("a warp curve needs at least 2 keys, found {found}")]
    TooFewWarpKeys {
        /// How many keys it has.
        found: usize,
    },
    /// One warp key is invalid. `index` counts from 0.
    #[error("warp key {index} ({key}): {problem}")]
    WarpKey {
        /// Index of the key.
        index: usize,
        /// The key as written (`output:source`).
        key: String,
        /// What is wrong with it.
        problem: WarpProblem,
    },
}

impl WarpCurve {
    /// Builds a curve from `(output_seconds, source_seconds)` keys.
    ///
    /// # Errors
    /// [`RetimeError::TooFewWarpKeys`] for fewer than 2 keys; [`RetimeError::WarpKey`] for
    /// the first key with a non-finite or negative output time, an output time not after
    /// the previous one, or a source time before the previous one.
    pub fn new(keys: Vec<(f32, f32)>) -> Result<Self, RetimeError> {
        let texts = keys.iter().map(|(o, s)| format!("{o}:{s}")).collect();
        Self::checked(keys, texts)
    }

    /// Parses `"0:0,1:0.4,2:2"`: comma-separated `output_seconds:source_seconds` keys
    /// (spaces around numbers allowed).
    ///
    /// # Errors
    /// [`RetimeError::WarpKey`] with [`WarpProblem::Syntax`] for a key that is not two
    /// numbers around a colon (an empty key included), then as [`WarpCurve::new`].
    pub fn parse(text: &str) -> Result<Self, RetimeError> {
        let mut keys = Vec::new();
        let mut texts = Vec::new();
        for (index, piece) in text.split(',').enumerate() {
            let piece = piece.trim();
            let key = piece
                .split_once(':')
                .and_then(|(o, s)| Some((o.trim().parse().ok()?, s.trim().parse().ok()?)))
                .ok_or_else(|| RetimeError::WarpKey {
                    index,
                    key: piece.to_string(),
                    problem: WarpProblem::Syntax,
                })?;
            keys.push(key);
            texts.push(piece.to_string());
        }
        Self::checked(keys, texts)
    }

    fn checked(keys: Vec<(f32, f32)>, texts: Vec<String>) -> Result<Self, RetimeError> {
        if keys.len() < 2 {
            return Err(RetimeError::TooFewWarpKeys { found: keys.len() });
        }
        let curve = Self { keys, texts };
        let mut previous: Option<(f32, f32)> = None;
        for (index, &(output, source)) in curve.keys.iter().enumerate() {
            let problem = if !(output.is_finite() && source.is_finite()) {
                Some(WarpProblem::NotFinite)
            } else if output < 0.0 {
                Some(WarpProblem::NegativeOutput { time: output })
            } else {
                match previous {
                    Some((p, _)) if output <= p => {
                        Some(WarpProblem::OutputNotIncreasing { previous: p })
                    }
                    Some((_, p)) if source < p => {
                        Some(WarpProblem::SourceBackwards { previous: p })
                    }
                    _ => None,
                }
            };
            if let Some(problem) = problem {
                return Err(curve.key_error(index, problem));
            }
            previous = Some((output, source));
        }
        Ok(curve)
    }

    fn key_error(&self, index: usize, problem: WarpProblem) -> RetimeError {
        RetimeError::WarpKey {
            index,
            key: self.texts.get(index).cloned().unwrap_or_default(),
            problem,
        }
    }

    /// The keys, `(output_seconds, source_seconds)`, output times strictly increasing.
    pub fn keys(&self) -> &[(f32, f32)] {
        &self.keys
    }

    /// The output time range `[first, last]` in seconds.
    pub fn output_range(&self) -> (f32, f32) {
        let first = self.keys.first().map_or(0.0, |k| k.0);
        let last = self.keys.last().map_or(0.0, |k| k.0);
        (first, last)
    }

    /// The source time (seconds) for output time `output` (seconds): linear between keys,
    /// the first or last key's source time outside the output range.
    pub fn source_time(&self, output: f32) -> f32 {
        let after = self.keys.partition_point(|k| k.0 <= output);
        match (
            after.checked_sub(1).and_then(|k| self.keys.get(k)),
            self.keys.get(after),
        ) {
            (Some(&(o0, s0)), Some(&(o1, s1))) => s0 + (s1 - s0) * ((output - o0) / (o1 - o0)),
            (Some(&(_, s)), None) | (None, Some(&(_, s))) => s,
            (None, None) => 0.0,
        }
    }

    /// Checks every source time against the clip's `[start, end]` (seconds).
    fn check_within(&self, start: f32, end: f32) -> Result<(), RetimeError> {
        for (index, &(_, source)) in self.keys.iter().enumerate() {
            if source < start - WARP_CLIP_TOLERANCE || source > end + WARP_CLIP_TOLERANCE {
                return Err(self.key_error(index, WarpProblem::OutsideClip { start, end }));
            }
        }
        Ok(())
    }
}

/// Retimes `clip` (animating `skeleton`) as `how` says; see [`Retime`] and the module docs.
///
/// The result has the same name and animates the same channels and meshes. Resampled
/// results hold `LINEAR` tracks whose keys all share the sample times; [`Retime::Speed`]
/// and [`Retime::Reverse`] keep each track's keys and interpolation mode.
///
/// # Errors
/// [`RetimeError::Clip`] if the clip does not fit the skeleton; per mode:
/// [`RetimeError::TooFewFrames`], [`RetimeError::ZeroDuration`], [`RetimeError::BadFps`],
/// [`RetimeError::BadSpeed`], [`RetimeError::NoFps`], [`RetimeError::WarpKey`] (a source
/// time outside the clip); [`RetimeError::Sample`] when more than
/// [`crate::sample::MAX_SAMPLES`] joint samples would be needed; [`RetimeError::Output`]
/// if moved keys collapse.
pub fn retime(clip: &Clip, skeleton: &Skeleton, how: &Retime) -> Result<Clip, RetimeError> {
    let compiled = CompiledClip::new(clip, skeleton).map_err(RetimeError::Clip)?;
    let (start, end) = (compiled.start(), compiled.end());
    match how {
        &Retime::Frames(frames) => {
            if frames < 2 {
                return Err(RetimeError::TooFewFrames { frames });
            }
            if end <= start {
                return Err(RetimeError::ZeroDuration { frames });
            }
            check_budget(frames, skeleton.len()).map_err(RetimeError::Sample)?;
            let times = even_times(start, end, frames);
            resample(&compiled, skeleton, &times, &times)
        }
        &Retime::Fps(fps) => {
            let times = grid(start, end, fps, skeleton.len())?;
            resample(&compiled, skeleton, &times, &times)
        }
        &Retime::Speed(speed) => {
            if !(speed.is_finite() && speed > 0.0) {
                return Err(RetimeError::BadSpeed { speed });
            }
            // Tangents are derivatives per second: playing `speed` times as fast
            // multiplies them by `speed` (and the Hermite's interval factor shrinks by the
            // same amount, so the curve's shape is unchanged).
            let map = |t: f32| (f64::from(start) + f64::from(t - start) / f64::from(speed)) as f32;
            move_keys(clip, skeleton, map, speed, false)
        }
        Retime::Reverse => move_keys(clip, skeleton, |t| (start + end) - t, 1.0, true),
        Retime::Warp(curve) => {
            let fps = compiled.fps().ok_or(RetimeError::NoFps)?;
            curve.check_within(start, end)?;
            let (first, last) = curve.output_range();
            let times = grid(first, last, fps, skeleton.len())?;
            let source: Vec<f32> = times
                .iter()
                .map(|&t| curve.source_time(t).clamp(start, end))
                .collect();
            resample(&compiled, skeleton, &source, &times)
        }
    }
}

/// `start`, then `start + k / fps` while more than a thousandth of a frame before `end`,
/// then `end` (so an end on the grid is not doubled by float noise); `[start]` when the two
/// are equal.
fn grid(start: f32, end: f32, fps: f32, joints: usize) -> Result<Vec<f32>, RetimeError> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(RetimeError::BadFps { fps });
    }
    let (start, end, fps) = (f64::from(start), f64::from(end), f64::from(fps));
    let steps = ((end - start) * fps).max(0.0);
    let frames = if steps < crate::sample::MAX_SAMPLES as f64 {
        steps.ceil() as usize + 1
    } else {
        usize::MAX
    };
    check_budget(frames, joints).map_err(RetimeError::Sample)?;
    let mut times = Vec::with_capacity(frames.saturating_add(1));
    times.push(start as f32);
    let stop = end - 1e-3 / fps;
    for k in 1u32.. {
        let t = start + f64::from(k) / fps;
        if t >= stop {
            break;
        }
        times.push(t as f32);
    }
    if times.last().is_some_and(|&last| (end as f32) > last) {
        times.push(end as f32);
    }
    Ok(times)
}

/// Samples `compiled` at `source_times` and bakes the poses (and morph weights) at `times`.
fn resample(
    compiled: &CompiledClip<'_>,
    skeleton: &Skeleton,
    source_times: &[f32],
    times: &[f32],
) -> Result<Clip, RetimeError> {
    let clip = compiled.clip();
    let rest = rest_locals(skeleton);
    let frames = sample_frames(compiled, &rest, source_times).map_err(RetimeError::Sample)?;
    let mask = ChannelMask::of_clip(clip, skeleton.len());
    let mut out = bake(&clip.name, times, &frames, &mask).map_err(RetimeError::Sample)?;
    out.tracks.extend(
        resample_weight_tracks(compiled, source_times, times).map_err(RetimeError::Sample)?,
    );
    Ok(out)
}

/// Maps every key time with `map` (reversing key order when `reverse`), scales cubic
/// tangents by `tangent_scale` (negated and swapped when reversing: the in-tangent of the
/// reversed key is minus the out-tangent of the original), and checks the result.
fn move_keys(
    clip: &Clip,
    skeleton: &Skeleton,
    map: impl Fn(f32) -> f32,
    tangent_scale: f32,
    reverse: bool,
) -> Result<Clip, RetimeError> {
    let tracks = clip
        .tracks
        .iter()
        .map(|track| move_track(track, &map, tangent_scale, reverse))
        .collect();
    let out = Clip {
        name: clip.name.clone(),
        tracks,
    };
    CompiledClip::new(&out, skeleton).map_err(RetimeError::Output)?;
    Ok(out)
}

fn move_track(
    track: &Track,
    map: &impl Fn(f32) -> f32,
    tangent_scale: f32,
    reverse: bool,
) -> Track {
    let per_key = track.floats_per_key();
    let components = track.components();
    let mut times: Vec<f32> = track.times.iter().map(|&t| map(t)).collect();
    if per_key == 0 {
        // Checked clips never get here (weights need at least one target).
        return Track {
            times,
            ..track.clone()
        };
    }
    let mut keys: Vec<&[f32]> = track.values.chunks_exact(per_key).collect();
    if reverse {
        times.reverse();
        keys.reverse();
    }
    let mut values = Vec::with_capacity(track.values.len());
    for key in keys {
        if track.interpolation == Interpolation::CubicSpline {
            let (in_tangent, rest) = key.split_at(components);
            let (value, out_tangent) = rest.split_at(components);
            let (new_in, new_out, sign) = if reverse {
                (out_tangent, in_tangent, -tangent_scale)
            } else {
                (in_tangent, out_tangent, tangent_scale)
            };
            values.extend(new_in.iter().map(|v| v * sign));
            values.extend_from_slice(value);
            values.extend(new_out.iter().map(|v| v * sign));
        } else {
            values.extend_from_slice(key);
        }
    }
    if matches!(track.target, TrackTarget::Rotation(_))
        && track.interpolation != Interpolation::CubicSpline
    {
        make_sign_continuous(&mut values);
    }
    Track {
        target: track.target,
        interpolation: track.interpolation,
        times,
        values,
    }
}

/// Negates each xyzw quaternion whose dot product with the previous (already fixed) one is
/// negative. `q` and `-q` are the same rotation, and shortest-path slerp ignores the sign,
/// so `LINEAR` and `STEP` tracks sample identically afterwards.
fn make_sign_continuous(values: &mut [f32]) {
    let mut previous: Option<[f32; 4]> = None;
    for q in values.chunks_exact_mut(4) {
        if let Some(p) = previous {
            let dot: f32 = p.iter().zip(q.iter()).map(|(a, b)| a * b).sum();
            if dot < 0.0 {
                q.iter_mut().for_each(|v| *v = -*v);
            }
        }
        previous = Some([q[0], q[1], q[2], q[3]]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::tests::{angle, chain, rot, sample_at, smooth_clip, tra, track};
    use glam::Quat;
    use proptest::prelude::*;
    use rigport_model::{JointIndex, MeshIndex};

    const FPS: f32 = 30.0;

    fn params() -> Vec<(f32, f32, f32)> {
        vec![(0.8, 2.0, 0.3), (1.2, 3.1, -1.0), (0.4, 5.0, 2.0)]
    }

    /// Every rotation track's consecutive keys have a non-negative dot product.
    fn assert_sign_continuous(clip: &Clip) {
        for track in &clip.tracks {
            if let TrackTarget::Rotation(_) = track.target {
                for k in 1..track.times.len() {
                    let d = Quat::from_slice(track.key_value(k - 1))
                        .dot(Quat::from_slice(track.key_value(k)));
                    assert!(d >= 0.0, "{:?} key {k}: dot {d}", track.target);
                }
            }
        }
    }

    fn targets(clip: &Clip) -> Vec<TrackTarget> {
        let mut t: Vec<_> = clip.tracks.iter().map(|t| t.target).collect();
        t.sort();
        t
    }

    /// The largest difference between two clips' samples at `probes` (seconds in `a`),
    /// `b` sampled at `map(t)`: (translation distance, rotation angle in radians).
    fn max_difference(
        a: &Clip,
        b: &Clip,
        skeleton: &Skeleton,
        probes: impl Iterator<Item = f32>,
        map: impl Fn(f32) -> f32,
    ) -> (f32, f32) {
        let mut worst = (0.0f32, 0.0f32);
        for t in probes {
            let (pa, pb) = (sample_at(a, skeleton, t), sample_at(b, skeleton, map(t)));
            for (x, y) in pa.iter().zip(&pb) {
                worst.0 = worst
                    .0
                    .max(x.translation.distance(y.translation))
                    .max(x.scale.distance(y.scale));
                worst.1 = worst.1.max(angle(x.rotation, y.rotation));
            }
        }
        worst
    }

    #[test]
    fn same_frame_count_is_the_identity() {
        let skeleton = chain(4);
        let clip = smooth_clip(4, 31, FPS, &params());
        let out = retime(&clip, &skeleton, &Retime::Frames(31)).unwrap();
        assert_eq!(out.name, clip.name);
        assert_eq!(targets(&out), targets(&clip));
        let mut worst = 0.0f32;
        for (a, b) in clip.tracks.iter().zip(&out.tracks) {
            assert_eq!(a.target, b.target);
            assert_eq!(b.interpolation, Interpolation::Linear);
            assert_eq!(a.times.len(), b.times.len());
            for (x, y) in a
                .times
                .iter()
                .zip(&b.times)
                .chain(a.values.iter().zip(&b.values))
            {
                worst = worst.max((x - y).abs());
            }
        }
        assert!(worst <= 1e-6, "largest difference {worst}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn up_then_down_sampling_comes_back(
            p in prop::collection::vec((0.1f32..1.5, 0.5f32..6.0, -3.0f32..3.0), 1..4),
            frames in 2usize..40,
        ) {
            let skeleton = chain(3);
            let clip = smooth_clip(3, frames, FPS, &p);
            let up = retime(&clip, &skeleton, &Retime::Frames(2 * frames - 1)).unwrap();
            let back = retime(&up, &skeleton, &Retime::Frames(frames)).unwrap();
            let times = &clip.tracks[0].times;
            let (dt, da) = max_difference(&clip, &back, &skeleton, times.iter().copied(), |t| t);
            prop_assert!(da <= 1e-4, "rotation differs by {da} rad");
            prop_assert!(dt <= 1e-5, "translation differs by {dt}");
            for (a, b) in clip.tracks.iter().zip(&back.tracks) {
                prop_assert_eq!(a.times.len(), b.times.len());
            }
        }

        #[test]
        fn speed_and_reverse_move_keys_exactly_in_every_mode(
            interpolation in prop_oneof![Just(Interpolation::Step), Just(Interpolation::Linear), Just(Interpolation::CubicSpline)],
            raw in prop::collection::vec(-1.0f32..1.0, 6 * 4 * 3),
            start in 0.0f32..2.0,
            speed in 0.25f32..4.0,
            probes in prop::collection::vec(0.0f32..1.0, 12),
        ) {
            // Translation and rotation tracks with 6 keys at uneven times from `start`.
            let skeleton = chain(1);
            let times: Vec<f32> = [0.0, 0.1, 0.25, 0.3, 0.6, 1.0].iter().map(|t| start + t).collect();
            let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
            let mut rotation = raw[..6 * 4 * per_key].to_vec();
            for k in 0..6 {
                let at = if per_key == 3 { (3 * k + 1) * 4 } else { 4 * k };
                rotation[at + 3] += 2.0; // keep keys well away from zero
            }
            let clip = Clip {
                name: "moves".into(),
                tracks: vec![
                    track(tra(0), interpolation, &times, &raw[..6 * 3 * per_key]),
                    track(rot(0), interpolation, &times, &rotation),
                ],
            };
            let (s, e) = (start, start + 1.0);
            let probes = probes.iter().map(|u| s + u);
            let fast = retime(&clip, &skeleton, &Retime::Speed(speed)).unwrap();
            let (dt, da) = max_difference(&clip, &fast, &skeleton, probes.clone(), |t| s + (t - s) / speed);
            prop_assert!(dt < 1e-4 && da < 1e-3, "speed: {dt} {da}");
            prop_assert!((CompiledClip::new(&fast, &skeleton).unwrap().duration() - 1.0 / speed).abs() < 1e-5);
            let reversed = retime(&clip, &skeleton, &Retime::Reverse).unwrap();
            // STEP holds mirror to the other side of each key, so compare it at the keys only.
            let (dt, da) = if interpolation == Interpolation::Step {
                max_difference(&clip, &reversed, &skeleton, times.iter().copied(), |t| s + e - t)
            } else {
                max_difference(&clip, &reversed, &skeleton, probes, |t| s + e - t)
            };
            prop_assert!(dt < 1e-4 && da < 1e-3, "reverse: {dt} {da}");
            for out in [&fast, &reversed] {
                prop_assert!(out.tracks.iter().all(|t| t.interpolation == interpolation));
            }
        }
    }

    #[test]
    fn speed_half_doubles_the_duration_and_keeps_the_keys() {
        let skeleton = chain(3);
        let clip = smooth_clip(3, 25, FPS, &params());
        let slow = retime(&clip, &skeleton, &Retime::Speed(0.5)).unwrap();
        assert!((slow.duration() - 2.0 * clip.duration()).abs() < 1e-6);
        for (a, b) in clip.tracks.iter().zip(&slow.tracks) {
            assert_eq!(a.times.len(), b.times.len());
            assert_eq!(a.values, b.values);
        }
        assert_sign_continuous(&slow);
    }

    #[test]
    fn reverse_twice_is_the_identity() {
        let skeleton = chain(3);
        let mut clip = smooth_clip(3, 20, FPS, &params());
        // A cubic track too, whose tangents must be negated and swapped.
        clip.tracks.push(track(
            TrackTarget::Scale(JointIndex(2)),
            Interpolation::CubicSpline,
            &[0.0, 0.2, 0.5],
            &[
                0.1, 0.2, 0.3, 1.0, 1.1, 1.2, -0.3, 0.2, 0.1, /**/ 0.5, 0.5, 0.5, 1.5, 1.0,
                0.8, 0.0, 0.1, 0.2, /**/ 1.0, 0.0, 2.0, 0.9, 0.9, 0.9, 3.0, 3.0, 3.0,
            ],
        ));
        let once = retime(&clip, &skeleton, &Retime::Reverse).unwrap();
        let cubic = once.tracks.last().unwrap();
        // The first reversed key was the last: in = -(old out), value, out = -(old in).
        assert_eq!(
            &cubic.values[..9],
            &[-3.0, -3.0, -3.0, 0.9, 0.9, 0.9, -1.0, -0.0, -2.0]
        );
        assert!((cubic.times[0] - (0.0 + clip.duration() - 0.5)).abs() < 1e-6);
        assert_sign_continuous(&once);
        let twice = retime(&once, &skeleton, &Retime::Reverse).unwrap();
        for (a, b) in clip.tracks.iter().zip(&twice.tracks) {
            assert_eq!(a.target, b.target);
            for (x, y) in a.times.iter().zip(&b.times) {
                assert!((x - y).abs() <= 1e-6, "{x} vs {y}");
            }
            assert_eq!(a.values, b.values);
        }
    }

    #[test]
    fn fps_includes_an_off_grid_end_and_resamples_weights() {
        let skeleton = chain(2);
        let weights = TrackTarget::MorphWeights(MeshIndex(0));
        let clip = Clip {
            name: "w".into(),
            tracks: vec![
                track(
                    tra(1),
                    Interpolation::Linear,
                    &[0.0, 0.9],
                    &[0.0, 0.0, 0.0, 0.9, 0.0, 0.0],
                ),
                track(
                    weights,
                    Interpolation::Linear,
                    &[0.0, 0.9],
                    &[0.0, 1.0, 0.9, 0.1],
                ),
            ],
        };
        let out = retime(&clip, &skeleton, &Retime::Fps(4.0)).unwrap();
        assert_eq!(targets(&out), targets(&clip));
        let times = &out.tracks[0].times;
        assert_eq!(times, &vec![0.0, 0.25, 0.5, 0.75, 0.9]);
        let w = out.tracks.iter().find(|t| t.target == weights).unwrap();
        assert_eq!(&w.times, times);
        assert!(
            (w.values[2] - 0.25).abs() < 1e-6 && (w.values[3] - 0.75).abs() < 1e-6,
            "{:?}",
            w.values
        );
        // On the grid: the end is not doubled.
        let on_grid = retime(&clip, &skeleton, &Retime::Fps(10.0)).unwrap();
        assert_eq!(on_grid.tracks[0].times.len(), 10);
        assert_eq!(*on_grid.tracks[0].times.last().unwrap(), 0.9);
    }

    #[test]
    fn warp_samples_the_source_at_the_warped_time() {
        let skeleton = chain(3);
        let clip = smooth_clip(3, 31, FPS, &params());
        let curve = WarpCurve::parse("0:0, 1:0.25 ,2:1").unwrap();
        let out = retime(&clip, &skeleton, &Retime::Warp(curve.clone())).unwrap();
        assert_eq!(targets(&out), targets(&clip));
        let times = out.tracks[0].times.clone();
        assert_eq!(times.len(), 61, "2 s at the source's 30 fps");
        assert_eq!(*times.last().unwrap(), 2.0);
        // At every output key the pose is the source's at warp(t); between keys it is
        // linear in the output, so compare at the keys.
        let (dt, da) = max_difference(&out, &clip, &skeleton, times.iter().copied(), |t| {
            curve.source_time(t)
        });
        assert!(dt < 1e-5 && da < 1e-5, "{dt} {da}");
        assert_eq!(curve.source_time(0.5), 0.125);
        assert_eq!(curve.source_time(1.5), 0.625);
        assert_eq!(curve.source_time(9.0), 1.0);
        assert_sign_continuous(&out);
        // A flat stretch holds a pose.
        let hold = WarpCurve::parse("0:0.5,1:0.5").unwrap();
        let held = retime(&clip, &skeleton, &Retime::Warp(hold)).unwrap();
        let (_, da) = max_difference(&held, &clip, &skeleton, [0.0, 0.3, 1.0].into_iter(), |_| {
            0.5
        });
        assert!(da < 1e-5);
    }

    #[test]
    fn warp_errors_name_the_key() {
        let err = |text: &str| WarpCurve::parse(text).unwrap_err().to_string();
        assert_eq!(
            err("0:0,0.5:1.2,1:1.3,2:0.5"),
            "warp key 3 (2:0.5): source time goes backwards from 1.3"
        );
        assert_eq!(
            err("0:0,1:0.4,1:2"),
            "warp key 2 (1:2): output time does not come after 1"
        );
        assert_eq!(
            err("0:0,1-2"),
            "warp key 1 (1-2): expected output_seconds:source_seconds, e.g. 1:0.4"
        );
        assert_eq!(
            err("0:0,,1:1"),
            "warp key 1 (): expected output_seconds:source_seconds, e.g. 1:0.4"
        );
        assert_eq!(
            err("0:0,1:x"),
            "warp key 1 (1:x): expected output_seconds:source_seconds, e.g. 1:0.4"
        );
        assert_eq!(err("0:0,1:inf"), "warp key 1 (1:inf): times must be finite");
        assert_eq!(
            err("-1:0,1:1"),
            "warp key 0 (-1:0): output time -1 is negative"
        );
        assert_eq!(err("0:0"), "a warp curve needs at least 2 keys, found 1");
        assert_eq!(
            WarpCurve::new(vec![(0.0, 1.0), (1.0, 0.5)])
                .unwrap_err()
                .to_string(),
            "warp key 1 (1:0.5): source time goes backwards from 1"
        );
        // Outside the clip (1 s long), beyond the millisecond tolerance.
        let skeleton = chain(3);
        let clip = smooth_clip(3, 31, FPS, &params());
        let outside = WarpCurve::parse("0:0,1:1.0005,2:1.5").unwrap();
        assert_eq!(
            retime(&clip, &skeleton, &Retime::Warp(outside))
                .unwrap_err()
                .to_string(),
            "warp key 2 (2:1.5): source time is outside the clip [0, 1]"
        );
        let within = WarpCurve::parse("0:0,1:1.0005").unwrap();
        assert!(retime(&clip, &skeleton, &Retime::Warp(within)).is_ok());
    }

    #[test]
    fn invalid_requests_are_errors() {
        let skeleton = chain(3);
        let clip = smooth_clip(3, 5, FPS, &params());
        let run = |how: Retime| retime(&clip, &skeleton, &how).unwrap_err();
        assert_eq!(
            run(Retime::Frames(1)),
            RetimeError::TooFewFrames { frames: 1 }
        );
        assert_eq!(run(Retime::Fps(0.0)), RetimeError::BadFps { fps: 0.0 });
        assert!(matches!(
            run(Retime::Fps(f32::NAN)),
            RetimeError::BadFps { .. }
        ));
        assert_eq!(
            run(Retime::Speed(-1.0)),
            RetimeError::BadSpeed { speed: -1.0 }
        );
        assert!(matches!(
            run(Retime::Fps(1e9)),
            RetimeError::Sample(SampleError::TooManySamples { .. })
        ));
        assert!(matches!(
            run(Retime::Frames(usize::MAX)),
            RetimeError::Sample(SampleError::TooManySamples { .. })
        ));
        // A speed so high that distinct key times (far from 0) collapse to one float.
        let late = Clip {
            name: "late".into(),
            tracks: vec![track(
                tra(0),
                Interpolation::Linear,
                &[1000.0, 1000.5],
                &[0.0; 6],
            )],
        };
        assert!(matches!(
            retime(&late, &skeleton, &Retime::Speed(1e9)),
            Err(RetimeError::Output(SampleError::TimeNotIncreasing { .. }))
        ));
        let pose = Clip {
            name: "pose".into(),
            tracks: vec![track(
                rot(0),
                Interpolation::Linear,
                &[0.0],
                &[0.0, 0.0, 0.0, 1.0],
            )],
        };
        let run = |how: Retime| retime(&pose, &skeleton, &how);
        assert_eq!(
            run(Retime::Frames(3)).unwrap_err(),
            RetimeError::ZeroDuration { frames: 3 }
        );
        let warp = WarpCurve::parse("0:0,1:0").unwrap();
        assert_eq!(run(Retime::Warp(warp)).unwrap_err(), RetimeError::NoFps);
        assert_eq!(run(Retime::Fps(30.0)).unwrap().tracks[0].times, vec![0.0]);
        let bad = Clip {
            name: "bad".into(),
            tracks: vec![track(
                rot(5),
                Interpolation::Linear,
                &[0.0],
                &[0.0, 0.0, 0.0, 1.0],
            )],
        };
        assert!(matches!(
            retime(&bad, &skeleton, &Retime::Reverse),
            Err(RetimeError::Clip(SampleError::JointOutOfRange { .. }))
        ));
    }
}
