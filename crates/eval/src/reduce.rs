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

use crate::{EvalError, LocalToModelJob};

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

/// Where `t` falls in a track's keys.
enum Position {
    /// Exactly on key `k`, or held before the first / after the last key.
    Key(usize),
    /// Between key `k` and `k + 1`, at fraction `u` in (0, 1).
    Between(usize, f32),
}

/// Finds `t`, moving `cursor` forward for increasing times (binary search otherwise).
fn locate(times: &[f32], t: f32, cursor: &mut usize) -> Position {
    if times.get(*cursor).is_none_or(|&c| c > t) {
        *cursor = times.partition_point(|&x| x <= t).saturating_sub(1);
    }
    while times.get(*cursor + 1).is_some_and(|&next| next <= t) {
        *cursor += 1;
    }
    let k = *cursor;
    match (times.get(k), times.get(k + 1)) {
        (Some(&t0), Some(&t1)) if t0 < t => Position::Between(k, (t - t0) / (t1 - t0)),
        _ => Position::Key(k),
    }
}

/// `a + (b - a) u`: exact for equal endpoints (glam's `lerp` is not).
fn lerp3(a: Vec3, b: Vec3, u: f32) -> Vec3 {
    a + (b - a) * u
}

/// Shortest-path spherical interpolation of unit quaternions; exact for equal endpoints.
fn slerp(a: Quat, b: Quat, u: f32) -> Quat {
    Slerp::new(a, b).at(u)
}

/// One slerp segment with its angle computed once (the simplifier evaluates many points).
struct Slerp {
    a: Vec4,
    b: Vec4,
    /// Angle between the 4-vectors `a` and `b` (half the rotation angle), radians.
    omega: f32,
    sin_omega: f32,
    equal: bool,
}

impl Slerp {
    fn new(a: Quat, b: Quat) -> Self {
        let a4 = Vec4::from(a);
        let mut b4 = Vec4::from(b);
        if a4.dot(b4) < 0.0 {
            b4 = -b4;
        }
        // The angle from atan2 of chord lengths: accurate at every angle, where acos(dot)
        // loses half the digits near 0.
        let omega = 2.0 * (a4 - b4).length().atan2((a4 + b4).length());
        Self {
            a: a4,
            b: b4,
            omega,
            sin_omega: omega.sin(),
            equal: a == b,
        }
    }

    fn at(&self, u: f32) -> Quat {
        if self.equal {
            return Quat::from_vec4(self.a);
        }
        let v = if self.omega < 1e-3 {
            // Normalized lerp deviates from slerp by O(omega^3) < 1e-9 here.
            self.a + (self.b - self.a) * u
        } else {
            self.a * (((1.0 - u) * self.omega).sin() / self.sin_omega)
                + self.b * ((u * self.omega).sin() / self.sin_omega)
        };
        Quat::from_vec4(v.normalize())
    }
}

/// Three floats at `at` (zero when out of range, which validation rules out).
fn vec3_at(values: &[f32], at: usize) -> Vec3 {
    values.get(at..at + 3).map_or(Vec3::ZERO, Vec3::from_slice)
}

/// The normalized quaternion at `at` of `values` (NaN for a zero quaternion).
fn quat_at(values: &[f32], at: usize) -> Quat {
    let v = values.get(at..at + 4).map_or(Vec4::ZERO, Vec4::from_slice);
    Quat::from_vec4(v / v.length())
}

/// A translation or scale track at time `t`.
fn sample_vec3(track: &Track, t: f32, cursor: &mut usize) -> Vec3 {
    let v = &track.values;
    let cubic = track.interpolation == Interpolation::CubicSpline;
    let stride = if cubic { 9 } else { 3 };
    let value = |k: usize| vec3_at(v, k * stride + if cubic { 3 } else { 0 });
    match locate(&track.times, t, cursor) {
        Position::Key(k) => value(k),
        Position::Between(k, u) => match track.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear => lerp3(value(k), value(k + 1), u),
            Interpolation::CubicSpline => {
                let dt = track.times[k + 1] - track.times[k];
                let out_tangent = vec3_at(v, k * 9 + 6);
                let in_tangent = vec3_at(v, (k + 1) * 9);
                let [h00, h10, h01, h11] = hermite(u);
                value(k) * h00
                    + out_tangent * (dt * h10)
                    + value(k + 1) * h01
                    + in_tangent * (dt * h11)
            }
        },
    }
}

/// A rotation track at time `t`, normalized.
fn sample_quat(track: &Track, t: f32, cursor: &mut usize) -> Quat {
    let v = &track.values;
    let cubic = track.interpolation == Interpolation::CubicSpline;
    let stride = if cubic { 12 } else { 4 };
    let value = |k: usize| quat_at(v, k * stride + if cubic { 4 } else { 0 });
    match locate(&track.times, t, cursor) {
        Position::Key(k) => value(k),
        Position::Between(k, u) => match track.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear => slerp(value(k), value(k + 1), u),
            Interpolation::CubicSpline => {
                // glTF 2.0 Appendix C: Hermite on the raw components, then normalize.
                let raw = |at: usize| v.get(at..at + 4).map_or(Vec4::ZERO, Vec4::from_slice);
                let dt = track.times[k + 1] - track.times[k];
                let [h00, h10, h01, h11] = hermite(u);
                let q = raw(k * 12 + 4) * h00
                    + raw(k * 12 + 8) * (dt * h10)
                    + raw((k + 1) * 12 + 4) * h01
                    + raw((k + 1) * 12) * (dt * h11);
                Quat::from_vec4(q.normalize())
            }
        },
    }
}

/// Cubic Hermite basis at `u` (glTF 2.0 Appendix C): value k, out-tangent k, value k+1,
/// in-tangent k+1.
fn hermite(u: f32) -> [f32; 4] {
    let u2 = u * u;
    let u3 = u2 * u;
    [
        2.0 * u3 - 3.0 * u2 + 1.0,
        u3 - 2.0 * u2 + u,
        -2.0 * u3 + 3.0 * u2,
        u3 - u2,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use rigport_model::{Joint, MeshIndex};

    /// xorshift64*: deterministic test data without a dependency.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
        }
        fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.next()
        }
    }

    /// A random tree: joint i's parent is one of the earlier joints, offsets 0.2–1 long.
    fn random_skeleton(rng: &mut Rng, n: usize) -> Skeleton {
        let joints = (0..n)
            .map(|i| {
                let parent = (i > 0).then(|| JointIndex((rng.next() * i as f32) as u32));
                let dir = Vec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                )
                .normalize_or(Vec3::Y);
                Joint {
                    name: format!("j{i}"),
                    parent,
                    rest_local: Transform {
                        translation: if i == 0 {
                            Vec3::ZERO
                        } else {
                            dir * rng.range(0.2, 1.0)
                        },
                        rotation: Quat::from_rotation_y(rng.range(-1.0, 1.0)),
                        scale: Vec3::ONE,
                    },
                }
            })
            .collect();
        Skeleton::new(joints).unwrap()
    }

    fn quats(qs: impl IntoIterator<Item = Quat>) -> Vec<f32> {
        qs.into_iter().flat_map(|q| q.to_array()).collect()
    }

    /// Smooth random motion at 120 fps: a sum of two sines per axis per joint, a root
    /// translation, a LINEAR scale on one joint and a STEP scale on another.
    fn random_clip(rng: &mut Rng, skeleton: &Skeleton, frames: usize) -> Clip {
        let times: Vec<f32> = (0..frames).map(|f| f as f32 / 120.0).collect();
        let mut tracks = Vec::new();
        for j in 0..skeleton.len() {
            let rest = skeleton.joints()[j].rest_local.rotation;
            let waves: Vec<[f32; 4]> = (0..6)
                .map(|_| {
                    [
                        rng.range(0.05, 0.6),
                        rng.range(0.2, 3.0),
                        rng.range(0.0, 6.3),
                        0.0,
                    ]
                })
                .collect();
            let angles = |t: f32, axis: usize| {
                let w1 = waves[2 * axis];
                let w2 = waves[2 * axis + 1];
                w1[0] * (w1[1] * t + w1[2]).sin() + w2[0] * (w2[1] * 2.0 * t + w2[2]).sin()
            };
            tracks.push(Track {
                target: TrackTarget::Rotation(JointIndex(j as u32)),
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values: quats(times.iter().map(|&t| {
                    rest * Quat::from_euler(
                        glam::EulerRot::ZYX,
                        angles(t, 0),
                        angles(t, 1),
                        angles(t, 2),
                    )
                })),
            });
        }
        tracks.push(Track {
            target: TrackTarget::Translation(JointIndex(0)),
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values: times
                .iter()
                .flat_map(|&t| [0.5 * t, 0.1 * (3.0 * t).sin(), 0.2 * (1.3 * t).cos()])
                .collect(),
        });
        tracks.push(Track {
            target: TrackTarget::Scale(JointIndex(1)),
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values: times
                .iter()
                .flat_map(|&t| {
                    let s = 1.0 + 0.2 * (2.0 * t).sin();
                    [s, s, 1.0 / s]
                })
                .collect(),
        });
        let step_times: Vec<f32> = times.iter().step_by(17).copied().collect();
        tracks.push(Track {
            target: TrackTarget::Scale(JointIndex(2)),
            interpolation: Interpolation::Step,
            values: step_times
                .iter()
                .flat_map(|&t| [1.0 + 0.1 * t, 1.0, 1.0])
                .collect(),
            times: step_times,
        });
        Clip {
            name: "random".into(),
            tracks,
        }
    }

    /// The naive reference: binary search, f64 slerp, recursive FK; STEP and LINEAR only.
    fn naive_positions(clip: &Clip, skeleton: &Skeleton, t: f32) -> Vec<Vec3> {
        let mut local: Vec<Transform> = skeleton.joints().iter().map(|j| j.rest_local).collect();
        let mut done = std::collections::BTreeSet::new();
        for track in &clip.tracks {
            if !done.insert(track.target) {
                continue;
            }
            let c = track.components();
            let times = &track.times;
            let k = times.partition_point(|&x| x <= t).saturating_sub(1);
            let (k0, k1, u) = if t <= times[0] || k + 1 == times.len() || times[k] == t {
                (k, k, 0.0)
            } else {
                (
                    k,
                    k + 1,
                    f64::from((t - times[k]) / (times[k + 1] - times[k])),
                )
            };
            let u = if track.interpolation == Interpolation::Step {
                0.0
            } else {
                u
            };
            let at = |k: usize| -> Vec<f64> {
                track.values[k * c..(k + 1) * c]
                    .iter()
                    .map(|&v| f64::from(v))
                    .collect()
            };
            let (a, b) = (at(k0), at(k1));
            let value: Vec<f64> = if c == 4 {
                let norm = |q: &[f64]| {
                    let l = q.iter().map(|x| x * x).sum::<f64>().sqrt();
                    q.iter().map(|x| x / l).collect::<Vec<f64>>()
                };
                let (a, mut b) = (norm(&a), norm(&b));
                let mut dot: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
                if dot < 0.0 {
                    b.iter_mut().for_each(|x| *x = -*x);
                    dot = -dot;
                }
                let omega = dot.min(1.0).acos();
                if omega < 1e-9 {
                    a
                } else {
                    let (wa, wb) = (
                        ((1.0 - u) * omega).sin() / omega.sin(),
                        (u * omega).sin() / omega.sin(),
                    );
                    a.iter().zip(&b).map(|(x, y)| wa * x + wb * y).collect()
                }
            } else {
                a.iter().zip(&b).map(|(x, y)| x + (y - x) * u).collect()
            };
            let v: Vec<f32> = value.iter().map(|&x| x as f32).collect();
            match track.target {
                TrackTarget::Translation(j) => local[j.get()].translation = Vec3::from_slice(&v),
                TrackTarget::Scale(j) => local[j.get()].scale = Vec3::from_slice(&v),
                TrackTarget::Rotation(j) => {
                    local[j.get()].rotation = Quat::from_slice(&v).normalize()
                }
                TrackTarget::MorphWeights(_) => {}
            }
        }
        fn world(skeleton: &Skeleton, local: &[Transform], j: usize) -> Mat4 {
            let m = local[j].to_mat4();
            match skeleton.joints()[j].parent {
                Some(p) => world(skeleton, local, p.get()) * m,
                None => m,
            }
        }
        (0..skeleton.len())
            .map(|j| world(skeleton, &local, j).w_axis.truncate())
            .collect()
    }

    /// The largest joint position difference at every original key time, measured by the
    /// naive reference.
    fn measured_error(original: &Clip, reduced: &Clip, skeleton: &Skeleton) -> f32 {
        let mut times: Vec<f32> = original
            .tracks
            .iter()
            .filter(|t| !matches!(t.target, TrackTarget::MorphWeights(_)))
            .flat_map(|t| t.times.iter().copied())
            .collect();
        times.sort_by(f32::total_cmp);
        times.dedup();
        let mut worst = 0.0f32;
        for t in times {
            let a = naive_positions(original, skeleton, t);
            let b = naive_positions(reduced, skeleton, t);
            for (p, q) in a.iter().zip(&b) {
                worst = worst.max(p.distance(*q));
            }
        }
        worst
    }

    /// Every reduced track keeps the first and last key and a subset of the original keys,
    /// values bit for bit; non-LINEAR tracks are unchanged.
    fn assert_subset(original: &Clip, reduced: &Clip) {
        assert_eq!(original.tracks.len(), reduced.tracks.len());
        assert_eq!(original.duration(), reduced.duration());
        for (o, r) in original.tracks.iter().zip(&reduced.tracks) {
            assert_eq!((o.target, o.interpolation), (r.target, r.interpolation));
            if o.interpolation != Interpolation::Linear
                || matches!(o.target, TrackTarget::MorphWeights(_))
            {
                assert_eq!(o, r);
                continue;
            }
            assert_eq!(r.times.first(), o.times.first());
            assert_eq!(r.times.last(), o.times.last());
            let c = o.components();
            for (k, t) in r.times.iter().enumerate() {
                let ko = o
                    .times
                    .iter()
                    .position(|x| x == t)
                    .expect("an original time");
                assert_eq!(r.values[k * c..(k + 1) * c], o.values[ko * c..(ko + 1) * c]);
            }
        }
    }

    #[test]
    fn bound_holds_on_random_smooth_clips() {
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        for case in 0..4 {
            let skeleton = random_skeleton(&mut rng, 6 + 3 * case);
            let clip = random_clip(&mut rng, &skeleton, 240);
            for tolerance in [1e-3, 1e-2, 0.05] {
                let (reduced, stats) = reduce(&clip, &skeleton, tolerance).unwrap();
                assert_subset(&clip, &reduced);
                let measured = measured_error(&clip, &reduced, &skeleton);
                // The naive reference slerps in f64: it may differ from the reducer's f32
                // sampling by a few ulps of the skeleton's size (a few units here).
                assert!(
                    measured <= tolerance + 2e-5,
                    "case {case} tol {tolerance}: measured {measured}, stats {stats:?}"
                );
                assert!(
                    (measured - stats.max_error).abs() <= 2e-5,
                    "case {case}: measured {measured} vs reported {}",
                    stats.max_error
                );
                assert!(stats.max_error <= tolerance);
                println!("case {case} tol {tolerance}: {stats:?}");
                // At 1 mm, motion this fast needs most of its 120 fps keys.
                let factor = if tolerance < 0.01 { 1 } else { 3 };
                assert!(
                    stats.keys_after * factor < stats.keys_before,
                    "case {case} tol {tolerance}: smooth motion keeps few keys: {stats:?}"
                );
            }
        }
    }

    #[test]
    fn bound_holds_across_a_sharp_step() {
        // A chain of 4 along +X; the root's translation jumps by 1 between two frames and
        // joint 1's rotation flips by 120 degrees between two others.
        let skeleton = Skeleton::new(
            (0..4)
                .map(|i| Joint {
                    name: format!("j{i}"),
                    parent: (i > 0).then(|| JointIndex(i - 1)),
                    rest_local: Transform::from_translation(if i > 0 {
                        Vec3::X
                    } else {
                        Vec3::ZERO
                    }),
                })
                .collect(),
        )
        .unwrap();
        let times: Vec<f32> = (0..100).map(|f| f as f32 / 30.0).collect();
        let clip = Clip {
            name: "step".into(),
            tracks: vec![
                Track {
                    target: TrackTarget::Translation(JointIndex(0)),
                    interpolation: Interpolation::Linear,
                    times: times.clone(),
                    values: (0..100)
                        .flat_map(|f| [if f < 40 { 0.0 } else { 1.0 }, 0.01 * f as f32, 0.0])
                        .collect(),
                },
                Track {
                    target: TrackTarget::Rotation(JointIndex(1)),
                    interpolation: Interpolation::Linear,
                    times: times.clone(),
                    values: quats((0..100).map(|f| {
                        let a = if f < 70 {
                            0.002 * f as f32
                        } else {
                            2.1 + 0.002 * f as f32
                        };
                        Quat::from_rotation_z(a)
                    })),
                },
            ],
        };
        for tolerance in [1e-4, 1e-2] {
            let (reduced, stats) = reduce(&clip, &skeleton, tolerance).unwrap();
            assert_subset(&clip, &reduced);
            let measured = measured_error(&clip, &reduced, &skeleton);
            assert!(measured <= tolerance + 1e-5, "{measured} {stats:?}");
            // The keys on both sides of each step survive; the ramps between go.
            let tr = &reduced.tracks[0].times;
            assert!(tr.contains(&times[39]) && tr.contains(&times[40]), "{tr:?}");
            let rot = &reduced.tracks[1].times;
            assert!(
                rot.contains(&times[69]) && rot.contains(&times[70]),
                "{rot:?}"
            );
            assert!(tr.len() <= 6 && rot.len() <= 6, "{tr:?} {rot:?}");
        }
    }

    #[test]
    fn tolerance_zero_keeps_every_non_redundant_key() {
        let mut rng = Rng(7);
        let skeleton = random_skeleton(&mut rng, 8);
        let clip = random_clip(&mut rng, &skeleton, 120);
        let (reduced, stats) = reduce(&clip, &skeleton, 0.0).unwrap();
        assert_eq!(reduced, clip, "no key of smooth motion is redundant");
        assert_eq!(stats.keys_before, stats.keys_after);
        assert_eq!(stats.max_error, 0.0);

        // Runs of equal values: only their interior keys go, and the result is exact.
        let mut held = clip.clone();
        let rot = &mut held.tracks[3];
        let first: Vec<f32> = rot.values[40..44].to_vec();
        for k in 10..=30 {
            rot.values[4 * k..4 * k + 4].copy_from_slice(&first);
        }
        let root = held
            .tracks
            .iter_mut()
            .find(|t| t.target == TrackTarget::Translation(JointIndex(0)))
            .unwrap();
        for k in 100..120 {
            let v: Vec<f32> = root.values[300..303].to_vec();
            root.values[3 * k..3 * k + 3].copy_from_slice(&v);
        }
        let (reduced, stats) = reduce(&held, &skeleton, 0.0).unwrap();
        assert_subset(&held, &reduced);
        assert_eq!(stats.keys_before - stats.keys_after, 19 + 18, "{stats:?}");
        assert_eq!(reduced.tracks[3].times.len(), 120 - 19);
        assert!(!reduced.tracks[3].times.contains(&held.tracks[3].times[20]));
        assert_eq!(stats.max_error, 0.0);
        assert_eq!(measured_error(&held, &reduced, &skeleton), 0.0);
    }

    #[test]
    fn linear_ramps_reduce_to_two_keys() {
        let skeleton = Skeleton::new(vec![
            Joint {
                name: "root".into(),
                parent: None,
                rest_local: Transform::IDENTITY,
            },
            Joint {
                name: "arm".into(),
                parent: Some(JointIndex(0)),
                rest_local: Transform::from_translation(Vec3::new(0.0, 2.0, 0.0)),
            },
            Joint {
                name: "hand".into(),
                parent: Some(JointIndex(1)),
                rest_local: Transform::from_translation(Vec3::new(0.0, 1.0, 0.0)),
            },
        ])
        .unwrap();
        let times: Vec<f32> = (0..100).map(|f| f as f32 * 0.01).collect();
        let clip = Clip {
            name: "ramp".into(),
            tracks: vec![
                Track {
                    target: TrackTarget::Translation(JointIndex(0)),
                    interpolation: Interpolation::Linear,
                    times: times.clone(),
                    values: times.iter().flat_map(|&t| [t, 2.0 * t, -3.0 * t]).collect(),
                },
                Track {
                    // Constant angular velocity: slerp between the ends is the same path.
                    // Every other key is stored as -q, the same rotation.
                    target: TrackTarget::Rotation(JointIndex(1)),
                    interpolation: Interpolation::Linear,
                    times: times.clone(),
                    values: quats(times.iter().enumerate().map(|(k, &t)| {
                        let q = Quat::from_rotation_x(1.5 * t);
                        if k % 2 == 1 {
                            -q
                        } else {
                            q
                        }
                    })),
                },
            ],
        };
        let (reduced, stats) = reduce(&clip, &skeleton, 1e-4).unwrap();
        for track in &reduced.tracks {
            assert_eq!(track.times, [times[0], times[99]]);
        }
        assert_eq!((stats.keys_before, stats.keys_after), (200, 4));
        assert!(measured_error(&clip, &reduced, &skeleton) <= 1e-4);
    }

    #[test]
    fn stats_count_every_track_and_other_tracks_are_kept() {
        let mut rng = Rng(99);
        let skeleton = random_skeleton(&mut rng, 5);
        let mut clip = random_clip(&mut rng, &skeleton, 60);
        clip.tracks.push(Track {
            target: TrackTarget::Translation(JointIndex(3)),
            interpolation: Interpolation::CubicSpline,
            times: vec![0.0, 0.25, 0.5],
            values: (0..27).map(|i| (i as f32 * 0.37).sin() * 0.1).collect(),
        });
        clip.tracks.push(Track {
            target: TrackTarget::MorphWeights(MeshIndex(0)),
            interpolation: Interpolation::Linear,
            times: vec![0.0, 0.1, 0.2, 0.3],
            values: vec![0.0, 0.0, 0.0, 0.0],
        });
        // A second track for the same property: kept, not sampled.
        let mut duplicate = clip.tracks[0].clone();
        duplicate.values.iter_mut().for_each(|v| *v = -*v);
        clip.tracks.push(duplicate);
        let (reduced, stats) = reduce(&clip, &skeleton, 0.01).unwrap();
        assert_subset(&clip, &reduced);
        let count = |c: &Clip| c.tracks.iter().map(|t| t.times.len()).sum::<usize>();
        assert_eq!(stats.keys_before, count(&clip));
        assert_eq!(stats.keys_after, count(&reduced));
        assert!(stats.keys_after < stats.keys_before);
        let n = clip.tracks.len();
        assert_eq!(reduced.tracks[n - 1], clip.tracks[n - 1], "duplicate kept");
        assert_eq!(
            reduced.tracks[n - 2],
            clip.tracks[n - 2],
            "morph weights kept"
        );
        assert_eq!(reduced.tracks[n - 3], clip.tracks[n - 3], "cubic kept");
        assert!(
            stats.max_error > 0.0 && stats.max_error <= 0.01,
            "{stats:?}"
        );
    }

    #[test]
    fn verification_tightens_and_restores_until_the_bound_holds() {
        let mut rng = Rng(0x00DE_C0DE);
        let skeleton = random_skeleton(&mut rng, 10);
        let clip = random_clip(&mut rng, &skeleton, 240);
        let tolerance = 0.01;
        let (plain, _) = reduce(&clip, &skeleton, tolerance).unwrap();
        // Local tolerances 50 times too loose: the first round fails, tightening repairs it.
        let loose = Tuning {
            budget_scale: 50.0,
            ..Tuning::DEFAULT
        };
        let (tightened, stats) = reduce_with(&clip, &skeleton, tolerance, loose).unwrap();
        assert_subset(&clip, &tightened);
        assert!(measured_error(&clip, &tightened, &skeleton) <= tolerance + 2e-5);
        assert!(stats.max_error <= tolerance);
        assert_ne!(tightened, plain, "another path to the bound");
        // No tightening allowed: the failing chains come back whole, and the bound holds.
        let no_rounds = Tuning {
            budget_scale: 50.0,
            tighten_rounds: 0,
        };
        let (restored, stats) = reduce_with(&clip, &skeleton, tolerance, no_rounds).unwrap();
        assert_subset(&clip, &restored);
        assert!(measured_error(&clip, &restored, &skeleton) <= tolerance + 2e-5);
        assert!(stats.max_error <= tolerance);
        let whole = restored
            .tracks
            .iter()
            .zip(&clip.tracks)
            .filter(|(r, o)| r.interpolation == Interpolation::Linear && r == o)
            .count();
        assert!(whole > 0, "some tracks restored whole");
        assert!(stats.keys_after < stats.keys_before, "{stats:?}");
    }

    #[test]
    fn bad_inputs_are_reported() {
        let mut rng = Rng(3);
        let skeleton = random_skeleton(&mut rng, 3);
        let clip = random_clip(&mut rng, &skeleton, 10);
        for tolerance in [-1.0, f32::NAN, f32::INFINITY] {
            assert!(matches!(
                reduce(&clip, &skeleton, tolerance),
                Err(ReduceError::Tolerance { .. })
            ));
        }
        let mut bad = clip.clone();
        bad.tracks[1].target = TrackTarget::Rotation(JointIndex(7));
        assert_eq!(
            reduce(&bad, &skeleton, 0.1).unwrap_err(),
            ReduceError::UnknownJoint {
                clip: "random".into(),
                track: 1,
                joint: JointIndex(7),
                joints: 3
            }
        );
        let mut bad = clip.clone();
        bad.tracks[0].values.pop();
        assert!(matches!(
            reduce(&bad, &skeleton, 0.1).unwrap_err(),
            ReduceError::BadTrack {
                track: 0,
                problem: TrackProblem::ValueCount {
                    expected: 40,
                    found: 39
                },
                ..
            }
        ));
        let mut bad = clip.clone();
        bad.tracks[2].values[8..12].fill(0.0);
        assert!(matches!(
            reduce(&bad, &skeleton, 0.1).unwrap_err(),
            ReduceError::BadTrack {
                track: 2,
                problem: TrackProblem::ZeroRotation { key: 2 },
                ..
            }
        ));
        let mut bad = clip.clone();
        bad.tracks[0].times[5] = bad.tracks[0].times[4];
        assert!(matches!(
            reduce(&bad, &skeleton, 0.1).unwrap_err(),
            ReduceError::BadTrack {
                track: 0,
                problem: TrackProblem::Times { key: 5 },
                ..
            }
        ));
        let mut bad = clip;
        bad.tracks[0].times.clear();
        assert!(matches!(
            reduce(&bad, &skeleton, 0.1).unwrap_err(),
            ReduceError::BadTrack {
                track: 0,
                problem: TrackProblem::NoKeys,
                ..
            }
        ));
    }

    #[test]
    fn mocap_sized_clip_is_fast() {
        // 30 joints x 5000 frames at 120 fps, like CMU 131_04-dance.
        let mut rng = Rng(131);
        let skeleton = random_skeleton(&mut rng, 30);
        let clip = random_clip(&mut rng, &skeleton, 5000);
        let start = std::time::Instant::now();
        let (_, stats) = reduce(&clip, &skeleton, 0.01).unwrap();
        let elapsed = start.elapsed();
        println!("30 joints x 5000 frames: {stats:?} in {elapsed:?}");
        assert!(stats.max_error <= 0.01);
        if !cfg!(debug_assertions) {
            assert!(elapsed.as_secs_f32() < 0.5, "{elapsed:?}");
        }
    }
}
