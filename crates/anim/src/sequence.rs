//! Sequencing: concatenation with crossfades, seamless loops, trimming.
//!
//! Every function here samples its input(s) with [`SampleJob`](rigport_eval::sample::SampleJob)
//! and bakes the result with [`bake`]: `LINEAR` tracks, sign-continuous unit quaternions,
//! morph weights resampled alongside (lerp).
//!
//! **Root motion.** A skeleton's roots (joints without a parent) carry the character
//! through the world. Concatenation moves each next clip's root translation horizontally
//! (X and Z; +Y is up, see [`rigport_model::conventions`]) so that it continues from where
//! the previous clip ended instead of jumping back to its own origin: a walk followed by
//! a run does not teleport. Heights (Y) and root rotations are not changed, so a clip
//! whose heading differs from the previous clip's end turns during the crossfade (or
//! snaps, without one). [`make_loop`] leaves the root's horizontal position as authored:
//! its per-cycle drift `last − first` is the root motion an engine accumulates per cycle.

use std::collections::BTreeMap;

use rigport_model::{Clip, Interpolation, MeshIndex, Skeleton, Track, TrackTarget, Transform};

use rigport_eval::sample::{
    bake, blend, check_budget, even_times, resample_weight_tracks, rest_locals, sample_frames,
    sample_weight_frames, ChannelMask, CompiledClip, SampleError, KEY_TIME_EPSILON, MAX_SAMPLES,
};

/// Why clips cannot be concatenated, looped or trimmed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SequenceError {
    /// [`concatenate`] was given no clips.
    #[error("no clips to concatenate")]
    Empty,
    /// A clip does not fit the skeleton (see [`CompiledClip::new`]).
    #[error("clip {clip} does not fit the skeleton")]
    Clip {
        /// Index of the clip in the input.
        clip: usize,
        /// What is wrong with it.
        #[source]
        source: SampleError,
    },
    /// No frame rate was given and the clip has fewer than 2 key times to imply one.
    #[error("clip {clip} has fewer than 2 key times, so no frame rate; give one")]
    NoFps {
        /// Index of the clip.
        clip: usize,
    },
    /// A frame rate that is not finite and positive.
    #[error("frame rate {fps} is not a positive finite number")]
    BadFps {
        /// The frame rate, in frames per second.
        fps: f32,
    },
    /// The crossfades at a clip's ends would leave it no frame of its own.
    #[error(
        "a crossfade of {crossfade} frames at {ends} end(s) does not fit clip {clip} ({frames} frames)"
    )]
    CrossfadeTooLong {
        /// Index of the clip.
        clip: usize,
        /// Its frame count at the output frame rate.
        frames: usize,
        /// The crossfade length, in frames.
        crossfade: usize,
        /// How many of its ends are crossfaded (1 for the first and last clip, else 2).
        ends: usize,
    },
    /// Two clips animate the same mesh with different numbers of morph targets.
    #[error(
        "morph weights of {mesh}: clip {first} has {expected} targets, clip {clip} has {found}"
    )]
    MorphTargets {
        /// The mesh.
        mesh: MeshIndex,
        /// The first clip animating it.
        first: usize,
        /// Its target count there.
        expected: usize,
        /// The clip that disagrees.
        clip: usize,
        /// Its target count there.
        found: usize,
    },
    /// A loop blend length outside `1..frames` (the last frame must stay after the blend
    /// starts and at least one frame must blend).
    #[error("a loop blend of {blend_frames} frames does not fit a clip of {frames} frames (1 to frames - 1)")]
    LoopBlend {
        /// The blend length asked for, in frames.
        blend_frames: usize,
        /// The clip's frame count (key times).
        frames: usize,
    },
    /// Trim bounds that are not finite or not increasing.
    #[error("trim range [{start}, {end}] must be finite with start < end")]
    TrimRange {
        /// Start, in seconds.
        start: f32,
        /// End, in seconds.
        end: f32,
    },
    /// Trim bounds that do not overlap the clip.
    #[error("trim range [{start}, {end}] does not overlap the clip [{clip_start}, {clip_end}]")]
    TrimOutside {
        /// Start, in seconds.
        start: f32,
        /// End, in seconds.
        end: f32,
        /// The clip's first key time, in seconds.
        clip_start: f32,
        /// The clip's last key time, in seconds.
        clip_end: f32,
    },
    /// Sampling or baking the result failed (e.g. more than
    /// [`rigport_eval::sample::MAX_SAMPLES`] joint samples).
    #[error("cannot sample or bake the result")]
    Sample(#[source] SampleError),
}

/// The skeleton's root joints, as a flag per joint.
fn root_flags(skeleton: &Skeleton) -> Vec<bool> {
    skeleton.parents().map(|p| p.is_none()).collect()
}

/// Frames of `joints` transforms, as chunks; `max(1)` keeps `chunks_exact` valid for a
/// skeleton without joints (whose frame buffers are empty).
fn chunk(joints: usize) -> usize {
    joints.max(1)
}

/// One input clip of [`concatenate`], resampled at the output frame rate.
struct Part {
    /// Local transforms, `frames × joints`, frame-major.
    poses: Vec<Transform>,
    /// Per mesh with weights anywhere in the sequence: `frames × targets` weights.
    weights: BTreeMap<MeshIndex, Vec<f32>>,
    /// Frame count.
    frames: usize,
}

/// Concatenates `clips` (each animating `skeleton`) into one clip, crossfading
/// `crossfade_frames` frames at every seam.
///
/// The output is sampled at `fps` (frames per second) or, when `None`, at the first clip's
/// frame rate ([`CompiledClip::fps`]), starting at 0 s. Each clip is resampled to
/// `round(duration × fps) + 1` frames spread evenly over its own `[start, end]`, so its
/// first and last poses are kept exactly (its speed changes by less than half a frame over
/// its length when the duration is not a whole number of frames).
///
/// Each next clip starts `crossfade_frames` frames before the previous one ends; during
/// that overlap the output blends the two with a weight on the next clip rising
/// `1/(c+1), 2/(c+1), …, c/(c+1)` (so the frames on either side are the pure clips):
/// slerp for rotations, lerp for translations, scales and morph weights. With no
/// crossfade the next clip's first frame directly follows the previous clip's last.
///
/// Root motion (see the module docs): each next clip's roots are shifted in X and Z so
/// that its first frame sits where the previous clip is at the frame the next one starts
/// on; with no crossfade, that is one frame past the previous clip's end, extrapolated from
/// its last step, so the root keeps its speed across the seam.
///
/// Channels are the union of the inputs' channels; a clip that does not animate one holds
/// the rest pose there (and weight 0 for a mesh it does not animate). The name is the
/// clips' names joined by `+`.
///
/// # Errors
/// [`SequenceError::Empty`], [`SequenceError::Clip`], [`SequenceError::NoFps`],
/// [`SequenceError::BadFps`], [`SequenceError::CrossfadeTooLong`] when the crossfades at a
/// clip's ends would cover all its frames, [`SequenceError::MorphTargets`],
/// [`SequenceError::Sample`].
pub fn concatenate(
    clips: &[&Clip],
    skeleton: &Skeleton,
    crossfade_frames: usize,
    fps: Option<f32>,
) -> Result<Clip, SequenceError> {
    if clips.is_empty() {
        return Err(SequenceError::Empty);
    }
    let compiled = clips
        .iter()
        .enumerate()
        .map(|(clip, c)| {
            CompiledClip::new(c, skeleton).map_err(|source| SequenceError::Clip { clip, source })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let fps = match fps {
        Some(fps) => fps,
        None => compiled
            .first()
            .and_then(CompiledClip::fps)
            .ok_or(SequenceError::NoFps { clip: 0 })?,
    };
    if !(fps.is_finite() && fps > 0.0) {
        return Err(SequenceError::BadFps { fps });
    }
    let joints = skeleton.len();
    let rest = rest_locals(skeleton);
    let crossfade = crossfade_frames;

    // Every mesh with morph weights anywhere, with its target count and first clip.
    let mut meshes: BTreeMap<MeshIndex, (usize, usize)> = BTreeMap::new();
    for (clip, c) in compiled.iter().enumerate() {
        for track in c.weight_tracks() {
            let TrackTarget::MorphWeights(mesh) = track.target else {
                continue;
            };
            let found = track.components();
            let &mut (expected, first) = meshes.entry(mesh).or_insert((found, clip));
            if found != expected {
                return Err(SequenceError::MorphTargets {
                    mesh,
                    first,
                    expected,
                    clip,
                    found,
                });
            }
        }
    }

    // Resample every clip at the output rate.
    let count = compiled.len();
    let mut parts = Vec::with_capacity(count);
    let mut total = 0usize;
    for (clip, c) in compiled.iter().enumerate() {
        let steps = f64::from(c.duration()) * f64::from(fps);
        if steps >= MAX_SAMPLES as f64 {
            return Err(SequenceError::Sample(SampleError::TooManySamples {
                frames: usize::MAX,
                joints,
                limit: MAX_SAMPLES,
            }));
        }
        let frames = steps.round() as usize + 1;
        let ends = usize::from(clip > 0) + usize::from(clip + 1 < count);
        if crossfade > 0 && crossfade.saturating_mul(ends) >= frames {
            return Err(SequenceError::CrossfadeTooLong {
                clip,
                frames,
                crossfade,
                ends,
            });
        }
        total = total.saturating_add(frames);
        check_budget(total, joints).map_err(SequenceError::Sample)?;
        let times = even_times(c.start(), c.end(), frames);
        let poses = sample_frames(c, &rest, &times).map_err(SequenceError::Sample)?;
        let mut weights = BTreeMap::new();
        for (&mesh, &(targets, _)) in &meshes {
            let track = c
                .weight_tracks()
                .find(|t| t.target == TrackTarget::MorphWeights(mesh));
            let values = match track {
                Some(track) => {
                    sample_weight_frames(track, &times).map_err(SequenceError::Sample)?
                }
                None => vec![0.0; frames * targets],
            };
            weights.insert(mesh, values);
        }
        parts.push(Part {
            poses,
            weights,
            frames,
        });
    }
    let total = total - crossfade * (count - 1);

    // Root motion: shift each next clip's roots in X and Z to continue the previous one.
    let roots = root_flags(skeleton);
    for i in 1..count {
        let (done, rest_parts) = parts.split_at_mut(i);
        let (Some(prev), Some(next)) = (done.last(), rest_parts.first_mut()) else {
            continue;
        };
        let at = |frame: usize, joint: usize| {
            prev.poses
                .get(frame * joints + joint)
                .map_or(glam::Vec3::ZERO, |t| t.translation)
        };
        let start_frame = prev.frames - crossfade;
        for (joint, _) in roots.iter().enumerate().filter(|(_, r)| **r) {
            let anchor = if start_frame < prev.frames {
                at(start_frame, joint)
            } else if prev.frames >= 2 {
                // One frame past the end: continue the last step.
                let last = at(prev.frames - 1, joint);
                last + (last - at(prev.frames - 2, joint))
            } else {
                at(prev.frames - 1, joint)
            };
            let first = next.poses.get(joint).map_or(anchor, |t| t.translation);
            let mut offset = anchor - first;
            offset.y = 0.0;
            for pose in next.poses.iter_mut().skip(joint).step_by(chunk(joints)) {
                pose.translation += offset;
            }
        }
    }

    // Lay the clips out, blending each overlap.
    let mut poses = vec![Transform::IDENTITY; total * joints];
    let mut weights: BTreeMap<MeshIndex, Vec<f32>> = meshes
        .iter()
        .map(|(&mesh, &(targets, _))| (mesh, vec![0.0; total * targets]))
        .collect();
    let mut begin = 0;
    for (i, part) in parts.iter().enumerate() {
        let fade = if i > 0 { crossfade } else { 0 };
        let weight = |k: usize| (k + 1) as f32 / (fade + 1) as f32;
        let dst = poses.chunks_exact_mut(chunk(joints)).skip(begin);
        for (k, (out, src)) in dst.zip(part.poses.chunks_exact(chunk(joints))).enumerate() {
            if k < fade {
                let w = weight(k);
                for (o, s) in out.iter_mut().zip(src) {
                    *o = blend(o, s, w);
                }
            } else {
                out.copy_from_slice(src);
            }
        }
        for (mesh, out) in &mut weights {
            let Some(src) = part.weights.get(mesh) else {
                continue;
            };
            let targets = meshes.get(mesh).map_or(1, |m| m.0).max(1);
            let dst = out.chunks_exact_mut(targets).skip(begin);
            for (k, (o, s)) in dst.zip(src.chunks_exact(targets)).enumerate() {
                if k < fade {
                    let w = weight(k);
                    o.iter_mut().zip(s).for_each(|(o, s)| *o += (s - *o) * w);
                } else {
                    o.copy_from_slice(s);
                }
            }
        }
        // The next clip starts `crossfade` frames before this one ends (checked to fit).
        begin += part.frames.saturating_sub(crossfade);
    }

    let times: Vec<f32> = (0..total)
        .map(|g| (g as f64 / f64::from(fps)) as f32)
        .collect();
    let mut mask = ChannelMask::none(joints);
    for clip in clips {
        mask.union_with(&ChannelMask::of_clip(clip, joints));
    }
    let name = clips
        .iter()
        .map(|c| c.name.as_str())
        .collect::<Vec<_>>()
        .join("+");
    let mut out = bake(&name, &times, &poses, &mask).map_err(SequenceError::Sample)?;
    out.tracks
        .extend(weights.into_iter().map(|(mesh, values)| Track {
            target: TrackTarget::MorphWeights(mesh),
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values,
        }));
    Ok(out)
}

/// Makes `clip` loop seamlessly: its last `blend_frames` frames blend towards its first
/// pose, so the last frame equals the first.
///
/// Frames are the clip's key times ([`CompiledClip::key_times`]); frame `n − b + j`
/// (`j = 0 … b−1`) blends with weight `(j + 1) / b` towards frame 0: slerp for rotations,
/// lerp for translations, scales and morph weights. The last frame is therefore frame 0
/// exactly (up to the quaternion sign [`bake`] picks for continuity).
///
/// Root translation: the roots' X and Z are left as authored, so the horizontal drift
/// stays continuous through the blend; the last frame is `first + drift`, where the drift
/// `last − first` is the root motion an engine carries from one cycle into the next (a
/// viewer that simply restarts the clip jumps back by it; for an in-place clip it is ~0).
/// The roots' height (Y) blends like every other channel.
///
/// The result keeps the name, times and channels, with `LINEAR` tracks.
///
/// # Errors
/// [`SequenceError::Clip`] if the clip does not fit the skeleton;
/// [`SequenceError::LoopBlend`] unless `1 <= blend_frames < frames`;
/// [`SequenceError::Sample`].
pub fn make_loop(
    clip: &Clip,
    skeleton: &Skeleton,
    blend_frames: usize,
) -> Result<Clip, SequenceError> {
    let compiled = CompiledClip::new(clip, skeleton)
        .map_err(|source| SequenceError::Clip { clip: 0, source })?;
    let times = compiled.key_times();
    let n = times.len();
    if blend_frames == 0 || blend_frames >= n {
        return Err(SequenceError::LoopBlend {
            blend_frames,
            frames: n,
        });
    }
    let joints = skeleton.len();
    let rest = rest_locals(skeleton);
    let mut poses = sample_frames(&compiled, &rest, &times).map_err(SequenceError::Sample)?;
    let roots = root_flags(skeleton);
    let weight = |j: usize| (j + 1) as f32 / blend_frames as f32;
    let first: Vec<Transform> = poses.iter().take(joints).copied().collect();
    let tail = poses
        .chunks_exact_mut(chunk(joints))
        .skip(n - blend_frames)
        .enumerate();
    for (j, frame) in tail {
        let w = weight(j);
        for ((pose, start), &root) in frame.iter_mut().zip(&first).zip(&roots) {
            let mut blended = blend(pose, start, w);
            if root {
                blended.translation.x = pose.translation.x;
                blended.translation.z = pose.translation.z;
            }
            *pose = blended;
        }
    }
    let mut out = bake(
        &clip.name,
        &times,
        &poses,
        &ChannelMask::of_clip(clip, joints),
    )
    .map_err(SequenceError::Sample)?;
    let mut weights =
        resample_weight_tracks(&compiled, &times, &times).map_err(SequenceError::Sample)?;
    for track in &mut weights {
        let targets = track.components().max(1);
        let start: Vec<f32> = track.values.iter().take(targets).copied().collect();
        let tail = track
            .values
            .chunks_exact_mut(targets)
            .skip(n - blend_frames)
            .enumerate();
        for (j, frame) in tail {
            let w = weight(j);
            for (v, s) in frame.iter_mut().zip(&start) {
                *v = if w >= 1.0 { *s } else { *v + (s - *v) * w };
            }
        }
    }
    out.tracks.extend(weights);
    Ok(out)
}

/// The part of `clip` between `start` and `end` (seconds), shifted to start at 0.
///
/// The range is first clamped to the clip's `[start, end]`. The result has a frame at each
/// cut point (sampled there) and at every clip key time strictly inside the range (key
/// times within 10 µs of a cut are dropped in favour of the cut, so no near-zero
/// interval appears), as `LINEAR` tracks on the clip's channels, with the clip's name.
/// `LINEAR` sources are reproduced exactly; `STEP` and `CUBICSPLINE` tracks are baked to
/// linear at the clip's key times.
///
/// # Errors
/// [`SequenceError::TrimRange`] unless both are finite and `start < end`;
/// [`SequenceError::Clip`]; [`SequenceError::TrimOutside`] if the range does not overlap
/// the clip; [`SequenceError::Sample`].
pub fn trim(clip: &Clip, skeleton: &Skeleton, start: f32, end: f32) -> Result<Clip, SequenceError> {
    if !(start.is_finite() && end.is_finite() && start < end) {
        return Err(SequenceError::TrimRange { start, end });
    }
    let compiled = CompiledClip::new(clip, skeleton)
        .map_err(|source| SequenceError::Clip { clip: 0, source })?;
    let (from, to) = (start.max(compiled.start()), end.min(compiled.end()));
    if from >= to {
        return Err(SequenceError::TrimOutside {
            start,
            end,
            clip_start: compiled.start(),
            clip_end: compiled.end(),
        });
    }
    let margin = 10.0 * KEY_TIME_EPSILON;
    let mut source = vec![from];
    source.extend(
        compiled
            .key_times()
            .into_iter()
            .filter(|&t| t > from + margin && t < to - margin),
    );
    source.push(to);
    let times: Vec<f32> = source.iter().map(|&t| t - from).collect();
    let poses =
        sample_frames(&compiled, &rest_locals(skeleton), &source).map_err(SequenceError::Sample)?;
    let mut out = bake(
        &clip.name,
        &times,
        &poses,
        &ChannelMask::of_clip(clip, skeleton.len()),
    )
    .map_err(SequenceError::Sample)?;
    out.tracks
        .extend(resample_weight_tracks(&compiled, &source, &times).map_err(SequenceError::Sample)?);
    Ok(out)
}

#[cfg(test)]
mod tests;
