//! Key reduction with a bound on world-space joint position error.
//!
//! [`reduce`] removes keys from LINEAR joint tracks while every joint's model-space
//! position, at every original key time, stays within a tolerance of the unreduced clip's.
//! It works in three steps:
//!
//! 1. Each reducible track gets a *local* tolerance (metres of translation, radians of
//!    rotation, scale units) derived from the world tolerance: a rotation error `θ` at a joint
//!    moves a descendant at distance `r` by at most `2 r sin(θ/2) <= r θ`; a translation
//!    error `δ` moves the joint and its subtree by at most `|parent scale| δ`; a scale error
//!    `δ` moves a descendant by at most `r δ / |scale|`. The world budget is shared by the
//!    `N` reducible tracks on the longest chain through the track: each gets `1/√N` of it,
//!    not `1/N`, because the errors of different tracks rarely line up (verification
//!    catches the frames where they do, and `1/N` kept about 1.6 times as many keys on
//!    random 30-joint motion for the same tolerance).
//! 2. Douglas–Peucker key removal per track against its local tolerance (first and last key
//!    always kept), with the same interpolation a viewer uses (lerp, shortest-path slerp).
//! 3. Verification by forward kinematics at every original key time. Where a joint's error
//!    exceeds the tolerance, the local tolerances of every reduced track above it shrink and
//!    step 2 repeats; after a few rounds, tracks of chains that still fail are restored
//!    whole. Restoring every track reproduces the clip exactly, so the loop always ends with
//!    the bound met.

use glam::{Mat4, Quat, Vec3, Vec4};
use rigport_model::{Clip, Interpolation, JointIndex, Skeleton, Track, TrackTarget, Transform};

use rigport_eval::{EvalError, LocalToModelJob};

mod curve;

use curve::{lerp3, quat_at, sample_quat, sample_vec3, Slerp};

/// What [`reduce`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReduceStats {
    /// Keys over every track of the clip before reduction (all tracks, including those kept
    /// as they are).
    pub keys_before: usize,
    /// Keys over every track of the reduced clip.
    pub keys_after: usize,
    /// The largest distance, in the skeleton's length unit, between a joint's model-space
    /// position in the reduced and in the original clip, over every joint and every
    /// original key time. At most the tolerance given to [`reduce`].
    pub max_error: f32,
}

/// Why [`reduce`] could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ReduceError {
    /// The tolerance is negative, NaN or infinite.
    #[error("tolerance {tolerance} must be finite and non-negative")]
    Tolerance {
        /// The tolerance given.
        tolerance: f32,
    },
    /// A track animates a joint the skeleton does not have.
    #[error("clip {clip:?} track {track}: targets {joint}, but the skeleton has {joints} joints")]
    UnknownJoint {
        /// Clip name.
        clip: String,
        /// Track index in the clip.
        track: usize,
        /// The joint it names.
        joint: JointIndex,
        /// How many joints the skeleton has.
        joints: usize,
    },
    /// A joint track's keys cannot be sampled.
    #[error("clip {clip:?} track {track}: {problem}")]
    BadTrack {
        /// Clip name.
        clip: String,
        /// Track index in the clip.
        track: usize,
        /// What is wrong.
        problem: TrackProblem,
    },
    /// Forward kinematics rejected its inputs (a skeleton not stored parents-first).
    #[error(transparent)]
    Eval(#[from] EvalError),
}

/// What is wrong with a track, as reported in [`ReduceError::BadTrack`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TrackProblem {
    /// The track has no key.
    #[error("has no keys")]
    NoKeys,
    /// Key times are not finite or not strictly increasing.
    #[error("key {key}: time is not finite or not after the previous key's")]
    Times {
        /// The first offending key.
        key: usize,
    },
    /// The value count does not match the key count.
    #[error("expected {expected} values for its keys, found {found}")]
    ValueCount {
        /// `keys * components` (three times that for cubic splines).
        expected: usize,
        /// The length of `values`.
        found: usize,
    },
    /// A value is NaN or infinite.
    #[error("has a non-finite value")]
    NonFinite,
    /// A rotation key is the zero quaternion, which is no rotation.
    #[error("rotation key {key} has zero length")]
    ZeroRotation {
        /// The key.
        key: usize,
    },
}

/// Removes keys from LINEAR joint tracks so that, at every original key time, every
/// joint's world-space position differs from the unreduced clip's by at most `tolerance`
/// (in the skeleton's length unit). STEP/CUBICSPLINE and morph-weight tracks are kept as is.
///
/// "World" is model space (the skeleton's roots under the identity). The original key times
/// are those of every joint track of the clip. Tracks keep their first and last keys, so
/// every track's time range and the clip's duration are unchanged; kept keys keep their
/// values bit for bit. With `tolerance == 0` only keys that interpolation reproduces exactly
/// (runs of equal values) are removed.
///
/// Joint rotations without a descendant move no joint; so that their keys are not all
/// thrown away, a leaf's rotation is held to the tolerance at one parent-bone length from
/// the joint, as if the bone went on (this part is not verified by FK: no joint is there).
/// When a clip holds two tracks for the same property (which glTF export drops), the first
/// is the one sampled and reduced; the later ones are kept as they are.
///
/// # Errors
/// [`ReduceError::Tolerance`] for a negative or non-finite tolerance;
/// [`ReduceError::UnknownJoint`] and [`ReduceError::BadTrack`] for joint tracks that cannot
/// be sampled (morph-weight tracks are not inspected).
pub fn reduce(
    clip: &Clip,
    skeleton: &Skeleton,
    tolerance: f32,
) -> Result<(Clip, ReduceStats), ReduceError> {
    reduce_with(clip, skeleton, tolerance, Tuning::DEFAULT)
}

/// Knobs of the reduction loop; tests loosen them to drive the verification paths.
#[derive(Clone, Copy, Debug)]
struct Tuning {
    /// Multiplies every initial local tolerance (1 in production).
    budget_scale: f32,
    /// Rounds of tolerance tightening before failing chains are restored whole.
    tighten_rounds: usize,
}

impl Tuning {
    const DEFAULT: Self = Self {
        budget_scale: 1.0,
        tighten_rounds: 12,
    };
}

/// [`reduce`] with explicit [`Tuning`].
fn reduce_with(
    clip: &Clip,
    skeleton: &Skeleton,
    tolerance: f32,
    tuning: Tuning,
) -> Result<(Clip, ReduceStats), ReduceError> {
    if !tolerance.is_finite() || tolerance < 0.0 {
        return Err(ReduceError::Tolerance { tolerance });
    }
    let channels = collect_channels(clip, skeleton)?;
    let keys_before: usize = clip.tracks.iter().map(|t| t.times.len()).sum();
    let mut reducer = Reducer::new(skeleton, tolerance, tuning, channels)?;
    let max_error = reducer.run()?;
    let mut out = clip.clone();
    for chan in &reducer.channels {
        if let (Some(reduced), Some(slot)) = (&chan.reduced, out.tracks.get_mut(chan.track)) {
            *slot = reduced.clone();
        }
    }
    let keys_after = out.tracks.iter().map(|t| t.times.len()).sum();
    Ok((
        out,
        ReduceStats {
            keys_before,
            keys_after,
            max_error,
        },
    ))
}

/// Which joint property a track animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Translation,
    Rotation,
    Scale,
}

impl Kind {
    fn slot(self) -> usize {
        match self {
            Kind::Translation => 0,
            Kind::Rotation => 1,
            Kind::Scale => 2,
        }
    }
}

/// One sampled joint track (the first of the clip for its joint and property).
struct Channel<'a> {
    joint: usize,
    kind: Kind,
    /// Index in `clip.tracks`.
    track: usize,
    original: &'a Track,
    /// LINEAR with more than two keys: keys can go.
    reducible: bool,
    /// Local tolerance: length unit (translation), radians (rotation), scale units (scale).
    eps: f32,
    /// The reduced track, `None` while the original is used.
    reduced: Option<Track>,
    /// Normalized rotation keys (rotation channels only), shared by the simplifier.
    quats: Vec<Quat>,
}

impl Channel<'_> {
    fn current(&self) -> &Track {
        self.reduced.as_ref().unwrap_or(self.original)
    }
}

/// Validates every joint track and keeps the first per joint and property.
fn collect_channels<'a>(
    clip: &'a Clip,
    skeleton: &Skeleton,
) -> Result<Vec<Channel<'a>>, ReduceError> {
    let joints = skeleton.len();
    let mut seen = vec![[false; 3]; joints];
    let mut out = Vec::new();
    for (ti, track) in clip.tracks.iter().enumerate() {
        let (joint, kind) = match track.target {
            TrackTarget::Translation(j) => (j, Kind::Translation),
            TrackTarget::Rotation(j) => (j, Kind::Rotation),
            TrackTarget::Scale(j) => (j, Kind::Scale),
            TrackTarget::MorphWeights(_) => continue,
        };
        let bad = |problem| ReduceError::BadTrack {
            clip: clip.name.clone(),
            track: ti,
            problem,
        };
        let Some(slot) = seen.get_mut(joint.get()) else {
            return Err(ReduceError::UnknownJoint {
                clip: clip.name.clone(),
                track: ti,
                joint,
                joints,
            });
        };
        if track.times.is_empty() {
            return Err(bad(TrackProblem::NoKeys));
        }
        if let Some(key) = track.times.iter().enumerate().position(|(k, t)| {
            !t.is_finite() || (k > 0 && track.times.get(k - 1).is_some_and(|p| t <= p))
        }) {
            return Err(bad(TrackProblem::Times { key }));
        }
        let comps = if kind == Kind::Rotation { 4 } else { 3 };
        let per_key = if track.interpolation == Interpolation::CubicSpline {
            3 * comps
        } else {
            comps
        };
        let expected = track.times.len() * per_key;
        if track.values.len() != expected {
            return Err(bad(TrackProblem::ValueCount {
                expected,
                found: track.values.len(),
            }));
        }
        if track.values.iter().any(|v| !v.is_finite()) {
            return Err(bad(TrackProblem::NonFinite));
        }
        let mut quats = Vec::new();
        if kind == Kind::Rotation {
            let offset = if track.interpolation == Interpolation::CubicSpline {
                4
            } else {
                0
            };
            for (key, chunk) in track.values.chunks_exact(per_key).enumerate() {
                let q = quat_at(chunk, offset);
                if !q.is_finite() {
                    return Err(bad(TrackProblem::ZeroRotation { key }));
                }
                quats.push(q);
            }
        }
        if std::mem::replace(&mut slot[kind.slot()], true) {
            continue;
        }
        out.push(Channel {
            joint: joint.get(),
            kind,
            track: ti,
            original: track,
            reducible: track.interpolation == Interpolation::Linear && track.times.len() > 2,
            eps: 0.0,
            reduced: None,
            quats,
        });
    }
    Ok(out)
}

/// The state of one reduction.
struct Reducer<'a> {
    tolerance: f32,
    tuning: Tuning,
    channels: Vec<Channel<'a>>,
    parents: Vec<Option<JointIndex>>,
    rest: Vec<Transform>,
    /// Per joint: channel index per [`Kind::slot`].
    chan_of: Vec<[Option<usize>; 3]>,
    /// Sorted union of every channel's key times.
    times: Vec<f32>,
    /// Original model-space positions, `times.len() * joints`, time-major.
    original: Vec<Vec3>,
    /// Scratch for forward kinematics.
    local: Vec<Transform>,
    model: Vec<Mat4>,
    cursors: Vec<usize>,
}

impl<'a> Reducer<'a> {
    fn new(
        skeleton: &Skeleton,
        tolerance: f32,
        tuning: Tuning,
        channels: Vec<Channel<'a>>,
    ) -> Result<Self, ReduceError> {
        let n = skeleton.len();
        let mut chan_of = vec![[None; 3]; n];
        for (ci, c) in channels.iter().enumerate() {
            if let Some(slot) = chan_of.get_mut(c.joint) {
                slot[c.kind.slot()] = Some(ci);
            }
        }
        let mut times: Vec<f32> = channels
            .iter()
            .flat_map(|c| c.original.times.iter().copied())
            .collect();
        times.sort_by(f32::total_cmp);
        times.dedup();
        let mut r = Self {
            tolerance,
            tuning,
            cursors: vec![0; channels.len()],
            channels,
            parents: skeleton.parents().collect(),
            rest: skeleton.joints().iter().map(|j| j.rest_local).collect(),
            chan_of,
            times,
            original: Vec::new(),
            local: vec![Transform::IDENTITY; n],
            model: vec![Mat4::IDENTITY; n],
        };
        r.set_local_tolerances()?;
        Ok(r)
    }

    /// Evaluates the current tracks at every union time; `f(time index, local, model)`.
    fn for_each_frame(
        &mut self,
        mut f: impl FnMut(usize, &[Transform], &[Mat4]),
    ) -> Result<(), ReduceError> {
        self.cursors.fill(0);
        for (ti, &t) in self.times.iter().enumerate() {
            self.local.copy_from_slice(&self.rest);
            for (chan, cursor) in self.channels.iter().zip(self.cursors.iter_mut()) {
                let Some(local) = self.local.get_mut(chan.joint) else {
                    continue;
                };
                let track = chan.current();
                match chan.kind {
                    Kind::Translation => local.translation = sample_vec3(track, t, cursor),
                    Kind::Scale => local.scale = sample_vec3(track, t, cursor),
                    Kind::Rotation => local.rotation = sample_quat(track, t, cursor),
                }
            }
            LocalToModelJob {
                parents: &self.parents,
                local: &self.local,
                root_model: Mat4::IDENTITY,
                model: &mut self.model,
            }
            .run()?;
            f(ti, &self.local, &self.model);
        }
        Ok(())
    }

    /// Step 1: local tolerances from the original motion's lever arms and scales.
    fn set_local_tolerances(&mut self) -> Result<(), ReduceError> {
        let n = self.parents.len();
        let parents = self.parents.clone();
        // lever[j]: farthest descendant from j; parent_norm[j]: largest column length of the
        // parent's model matrix (its scale); min_scale[j]: smallest |scale| component of j.
        let mut lever = vec![0.0f32; n];
        let mut bone = vec![0.0f32; n];
        let mut parent_norm: Vec<f32> = parents
            .iter()
            .map(|p| if p.is_some() { 0.0 } else { 1.0 })
            .collect();
        let mut min_scale = vec![f32::INFINITY; n];
        let mut original = Vec::with_capacity(self.times.len() * n);
        self.for_each_frame(|_, local, model| {
            let base = original.len();
            original.extend(model.iter().map(|m| m.w_axis.truncate()));
            let pos = &original[base..];
            for d in 0..n {
                let p = pos[d];
                let mut cur = parents[d];
                if let Some(pi) = cur {
                    bone[d] = bone[d].max(p.distance(pos[pi.get()]));
                    let m = model[pi.get()];
                    let norm = m
                        .x_axis
                        .truncate()
                        .length()
                        .max(m.y_axis.truncate().length())
                        .max(m.z_axis.truncate().length());
                    parent_norm[d] = parent_norm[d].max(norm);
                }
                while let Some(a) = cur {
                    let a = a.get();
                    lever[a] = lever[a].max(p.distance(pos[a]));
                    cur = parents[a];
                }
                min_scale[d] = min_scale[d].min(local[d].scale.abs().min_element());
            }
        })?;
        self.original = original;
        for j in 0..n {
            if lever[j] == 0.0 {
                // A leaf: as if its bone went on (see `reduce`'s documentation).
                lever[j] = bone[j];
            }
        }
        // Budget split: count the reducible channels that move each joint (translations on
        // the path root..j, rotations and scales on its strict ancestors), plus j's own
        // rotation and scale for the point beyond a leaf; a channel's share is one over the
        // square root of the largest count in its subtree (see the module documentation).
        let reducible = |j: usize, kind: Kind| {
            self.chan_of[j][kind.slot()]
                .and_then(|c| self.channels.get(c))
                .is_some_and(|c| c.reducible) as u32
        };
        let mut moving = vec![0u32; n];
        let mut full = vec![0u32; n];
        for j in 0..n {
            let above = parents[j].map_or(0, |p| full[p.get()]);
            moving[j] = above + reducible(j, Kind::Translation);
            full[j] = moving[j] + reducible(j, Kind::Rotation) + reducible(j, Kind::Scale);
        }
        let mut share = full;
        for j in (0..n).rev() {
            if let Some(p) = parents[j] {
                share[p.get()] = share[p.get()].max(share[j]);
            }
        }
        let tol = self.tolerance;
        for chan in &mut self.channels {
            let j = chan.joint;
            let sensitivity = match chan.kind {
                Kind::Translation => parent_norm[j],
                Kind::Rotation => lever[j],
                Kind::Scale => lever[j] / min_scale[j],
            };
            let count = (share[j].max(1) as f32).sqrt();
            chan.eps = if tol == 0.0 {
                0.0
            } else if sensitivity.is_nan() {
                // 0/0: a zero scale with no lever moves nothing.
                f32::INFINITY
            } else {
                // sensitivity 0 moves nothing: any error is allowed (eps = +inf).
                self.tuning.budget_scale * tol / (sensitivity * count)
            };
        }
        Ok(())
    }

    /// Steps 2 and 3. Returns the measured maximum error.
    fn run(&mut self) -> Result<f32, ReduceError> {
        let tol = self.tolerance;
        let mut dirty = vec![true; self.channels.len()];
        let mut round = 0;
        loop {
            for (chan, dirty) in self.channels.iter_mut().zip(dirty.iter_mut()) {
                if std::mem::take(dirty) && chan.reducible {
                    chan.reduced = Some(simplify(chan));
                }
            }
            let errors = self.joint_errors()?;
            let max_error = errors.iter().copied().fold(0.0f32, f32::max);
            if max_error <= tol {
                return Ok(max_error);
            }
            // Per channel, the strongest tightening any failing joint below it asks for.
            // A failing joint whose reduced channels are all at zero tolerance (or that
            // has had its rounds) gets those channels restored instead.
            round += 1;
            let mut factor = vec![1.0f32; self.channels.len()];
            let mut restore = vec![false; self.channels.len()];
            let mut above = Vec::new();
            for (d, &err) in errors.iter().enumerate() {
                if err <= tol {
                    continue;
                }
                above.clear();
                let mut cur = Some(d);
                while let Some(a) = cur {
                    for kind in [Kind::Translation, Kind::Rotation, Kind::Scale] {
                        // A joint's own rotation and scale do not move it.
                        if kind != Kind::Translation && a == d {
                            continue;
                        }
                        if let Some(c) = self.chan_of[a][kind.slot()] {
                            if self.channels[c].reduced.is_some() {
                                above.push(c);
                            }
                        }
                    }
                    cur = self.parents[a].map(JointIndex::get);
                }
                let can_tighten = round < self.tuning.tighten_rounds
                    && above.iter().any(|&c| self.channels[c].eps > 0.0);
                let f = (0.9 * tol / err).min(0.5);
                for &c in &above {
                    if can_tighten {
                        factor[c] = factor[c].min(f);
                    } else {
                        restore[c] = true;
                    }
                }
            }
            let mut changed = false;
            for (ci, chan) in self.channels.iter_mut().enumerate() {
                if chan.reduced.is_none() {
                    continue;
                }
                if restore[ci] {
                    chan.reduced = None;
                    chan.reducible = false;
                    changed = true;
                } else if factor[ci] < 1.0 && chan.eps > 0.0 {
                    if !chan.eps.is_finite() {
                        chan.eps = tol;
                    }
                    chan.eps *= factor[ci];
                    dirty[ci] = true;
                    changed = true;
                }
            }
            if !changed {
                // Unreachable in exact arithmetic (a failing joint always has a reduced
                // channel above it); restoring everything reproduces the clip exactly.
                for chan in &mut self.channels {
                    chan.reduced = None;
                    chan.reducible = false;
                }
            }
        }
    }

    /// Per joint: the largest model-space distance to the original over every union time.
    fn joint_errors(&mut self) -> Result<Vec<f32>, ReduceError> {
        let n = self.parents.len();
        let mut errors = vec![0.0f32; n];
        let original = std::mem::take(&mut self.original);
        let result = self.for_each_frame(|ti, _, model| {
            let base = ti * n;
            for (j, (m, e)) in model.iter().zip(errors.iter_mut()).enumerate() {
                if let Some(o) = original.get(base + j) {
                    *e = e.max(m.w_axis.truncate().distance(*o));
                }
            }
        });
        self.original = original;
        result.map(|()| errors)
    }
}

/// Step 2: Douglas–Peucker on one LINEAR channel against `chan.eps`. Keeps the first and
/// last keys; a key goes when the interpolation between the kept keys around it is within
/// `eps` of its value (Euclidean distance; for rotations, the angle between them).
fn simplify(chan: &Channel) -> Track {
    let track = chan.original;
    let times = &track.times;
    let n = times.len();
    let mut keep = vec![false; n];
    if let (Some(first), Some(last)) = (keep.first_mut(), n.checked_sub(1)) {
        *first = true;
        keep[last] = true;
    }
    // Rotation: compare chords |q1 - q2| = 2 sin(θ/4) instead of angles (no asin per key).
    let limit = match chan.kind {
        Kind::Rotation => 2.0 * (chan.eps.min(std::f32::consts::TAU) / 4.0).sin(),
        Kind::Translation | Kind::Scale => chan.eps,
    };
    let vectors: Vec<Vec3> = match chan.kind {
        Kind::Rotation => Vec::new(),
        Kind::Translation | Kind::Scale => {
            track.values.chunks_exact(3).map(Vec3::from_slice).collect()
        }
    };
    // The worst original key strictly between keys a and b when interpolating from a to b:
    // (key, error), (a, 0) when there is none. Same arithmetic as the sampler.
    let worst = |a: usize, b: usize| -> (usize, f32) {
        let (ta, tb) = (times[a], times[b]);
        let mut worst = (a, 0.0f32);
        match chan.kind {
            Kind::Rotation => {
                let seg = Slerp::new(chan.quats[a], chan.quats[b]);
                let inner = times[a + 1..b].iter().zip(&chan.quats[a + 1..b]);
                for (k, (&t, &o)) in (a + 1..).zip(inner) {
                    let q = Vec4::from(seg.at((t - ta) / (tb - ta)));
                    let o = Vec4::from(o);
                    let e = (q - o).length().min((q + o).length());
                    if e > worst.1 {
                        worst = (k, e);
                    }
                }
            }
            Kind::Translation | Kind::Scale => {
                let (va, vb) = (vectors[a], vectors[b]);
                let inner = times[a + 1..b].iter().zip(&vectors[a + 1..b]);
                for (k, (&t, &v)) in (a + 1..).zip(inner) {
                    let e = lerp3(va, vb, (t - ta) / (tb - ta)).distance(v);
                    if e > worst.1 {
                        worst = (k, e);
                    }
                }
            }
        }
        worst
    };
    let mut stack = vec![(0usize, n.saturating_sub(1))];
    while let Some((a, b)) = stack.pop() {
        let (k, e) = worst(a, b);
        if e > limit {
            keep[k] = true;
            stack.push((a, k));
            stack.push((k, b));
        }
    }
    // Douglas–Peucker splits at the worst key, which is not always a key the result needs
    // (e.g. inside a run of equal values): one greedy pass drops every kept key whose two
    // kept neighbours already reproduce all original keys between them.
    let kept: Vec<usize> = (0..n).filter(|&k| keep[k]).collect();
    let mut anchor = 0usize;
    for w in kept.windows(2).skip(1) {
        let (k, next) = (w[0], w[1]);
        if worst(anchor, next).1 <= limit {
            keep[k] = false;
        } else {
            anchor = k;
        }
    }
    let comps = if chan.kind == Kind::Rotation { 4 } else { 3 };
    let mut out = Track {
        target: track.target,
        interpolation: track.interpolation,
        times: Vec::new(),
        values: Vec::new(),
    };
    for ((&t, value), _) in times
        .iter()
        .zip(track.values.chunks_exact(comps))
        .zip(&keep)
        .filter(|(_, &k)| k)
    {
        out.times.push(t);
        out.values.extend_from_slice(value);
    }
    out
}

#[cfg(test)]
mod tests;
