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
//! [`SampleJob`]: rigport_eval::sample::SampleJob

use rigport_model::{Clip, Interpolation, Skeleton, Track, TrackTarget};

use rigport_eval::sample::{
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
/// [`rigport_eval::sample::MAX_SAMPLES`] joint samples would be needed; [`RetimeError::Output`]
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
    let frames = if steps < rigport_eval::sample::MAX_SAMPLES as f64 {
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
mod tests;
