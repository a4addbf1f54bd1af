//! Key reduction with a bound on model-space error: of joints, and of points fixed to them.
//!
//! [`reduce_clip`] removes keys from LINEAR joint tracks while, at every original key time,
//! the model-space position of every joint, and of *virtual points* fixed in each joint's
//! frame (at a distance per joint: ACL's "shell distance", 3 cm or a skinned mesh's reach),
//! stays within a tolerance of the unreduced clip's. [`reduce`] is the joints-only form.
//! It works in three steps, as ozz-animation's optimizer does:
//!
//! 1. Each reducible track gets a *local* tolerance (metres of translation, radians of
//!    rotation, scale units) derived from the model-space tolerance and propagated down
//!    the hierarchy, so a parent's error is paid for by its children: a rotation error `θ`
//!    at a joint moves a descendant (or one of its own virtual points) at distance `r` by
//!    at most `2 r sin(θ/2) <= r θ`; a translation error `δ` moves the joint and its
//!    subtree by at most `|parent scale| δ`; a scale error `δ` moves a point by at most
//!    `r δ / |scale|`. The budget is shared by the `N` reducible tracks on the longest
//!    chain through the track: each gets `1/√N` of it, not `1/N`, because the errors of
//!    different tracks rarely line up (verification catches the frames where they do, and
//!    `1/N` kept about 1.6 times as many keys on random 30-joint motion for the same
//!    tolerance).
//! 2. Per track, the smaller of key removal and a lower uniform rate within its local
//!    tolerance (`simplify`), with the same interpolation a viewer uses (lerp,
//!    shortest-path slerp), on the values as written (16-bit rotations when asked).
//! 3. Verification by forward kinematics at every original key time. Where a joint's error
//!    exceeds the tolerance, the local tolerances of every reduced track above it shrink and
//!    step 2 repeats; after a few rounds, tracks of chains that still fail are restored
//!    whole. Restoring every track reproduces the clip exactly, so the loop always ends with
//!    the bound met.

use glam::{Mat4, Vec3};
use rigport_model::{Clip, JointIndex, Skeleton, Track, Transform};

use rigport_eval::LocalToModelJob;

mod channel;
mod codec;
mod cubic;
mod curve;
mod error;
mod loosen;
pub mod metric;
mod rate;
mod simplify;

pub use codec::{Codec, RotationAtBits, RotationBits};
pub use error::{ReduceError, TrackProblem};

use channel::{collect_channels, Channel, Kind};
use codec::cubic_as_written;
use curve::{sample_quat, sample_vec3};
use simplify::simplify;

/// What [`reduce`] and [`reduce_clip`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct ReduceStats {
    /// Keys over every track of the clip before reduction (all tracks, including those kept
    /// as they are).
    pub keys_before: usize,
    /// Keys over every track of the reduced clip.
    pub keys_after: usize,
    /// The largest distance, in the skeleton's length unit, between a joint's (or one of its
    /// virtual points') model-space position in the reduced and in the original clip, over
    /// every joint and every original key time. At most the tolerance.
    pub max_error: f32,
    /// The mean over joints and original key times of that distance (the largest of a
    /// joint's points at each time).
    pub mean_error: f32,
    /// Whether the error was measured on values as [`ReduceOptions::codec`] stores them:
    /// `false` when asked but the codec alone would exceed the tolerance, so the values
    /// must be written exactly (as floats).
    pub coded: bool,
    /// With a codec that has [`Codec::rotation_bits`]: per track of the reduced clip, the
    /// bits per component its rotations were measured with and must be written with (0:
    /// the codec's default). Empty otherwise.
    pub rotation_bits: Vec<u8>,
}

/// What [`reduce_clip`] holds to.
#[derive(Clone, Debug, Default)]
pub struct ReduceOptions {
    /// The largest model-space distance allowed, in the skeleton's length unit.
    pub tolerance: f32,
    /// Per joint (by index), the distance of its virtual points from the joint, in the
    /// skeleton's length unit: three points on the joint's local axes (in its model-space
    /// frame, scale included), checked besides the joint itself. Empty or shorter than the
    /// skeleton: no virtual points (0) for the joints left out, and a leaf's rotation held
    /// at one parent-bone length instead, unverified ([`reduce`]).
    pub point_distance: Vec<f32>,
    /// How the writer stores LINEAR and STEP key values (`None`: exactly), so that the
    /// error is measured on what a reader gets ([`Codec::I16`]: 16-bit rotations).
    pub codec: Option<Codec>,
    /// Also try a lower uniform rate per track (every k-th key), kept when it needs fewer
    /// bytes than key removal (a key's value without a time of its own).
    pub uniform_rate: bool,
    /// Also try CUBICSPLINE fits per track (original values at kept keys, Hermite tangents
    /// fitted to the keys between), kept when they need fewer bytes than LINEAR keys: for
    /// glTF outputs (USD time samples interpolate linearly).
    pub cubic: bool,
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

/// [`reduce`] with virtual points, 16-bit rotations and a uniform rate as `options` asks:
/// every joint and every virtual point stays within `options.tolerance` of the unreduced
/// clip at every original key time, as the values are written.
///
/// ```
/// use rigport_anim::reduce::{reduce_clip, Codec, ReduceOptions};
/// use rigport_model::glam::{Quat, Vec3};
/// use rigport_model::{Clip, Interpolation, Joint, JointIndex, Skeleton, Track, TrackTarget, Transform};
///
/// let joint = |name: &str, parent: Option<u32>, y: f32| Joint {
///     name: name.into(),
///     parent: parent.map(JointIndex),
///     rest_local: Transform { translation: Vec3::new(0.0, y, 0.0), ..Transform::IDENTITY },
/// };
/// let skeleton = Skeleton::new(vec![joint("hip", None, 0.0), joint("knee", Some(0), 0.5)]).expect("valid");
/// // A slow swing of the hip at 120 keys per second.
/// let times: Vec<f32> = (0..121).map(|k| k as f32 / 120.0).collect();
/// let values = times.iter().flat_map(|t| Quat::from_rotation_z(0.5 * t).to_array()).collect();
/// let track = Track { target: TrackTarget::Rotation(JointIndex(0)),
///     interpolation: Interpolation::Linear, times, values };
/// let clip = Clip { name: "swing".into(), tracks: vec![track] };
/// let options = ReduceOptions { tolerance: 0.001, point_distance: vec![0.03; 2],
///     codec: Some(Codec::I16), uniform_rate: true, cubic: false };
/// let (reduced, stats) = reduce_clip(&clip, &skeleton, &options)?;
/// assert!(stats.keys_after < 10 && stats.max_error <= 0.001 && stats.coded);
/// assert_eq!(reduced.tracks[0].times.last(), Some(&1.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As [`reduce`].
pub fn reduce_clip(
    clip: &Clip,
    skeleton: &Skeleton,
    options: &ReduceOptions,
) -> Result<(Clip, ReduceStats), ReduceError> {
    reduce_impl(clip, skeleton, options, Tuning::DEFAULT)
}

/// How much of a rotation track's local tolerance its rounding may take when the codec lets
/// the reducer pick the bits: three times it. The local tolerances are a worst case (each
/// track's rounding and each removed key at its limit, on the same frame, in the same
/// direction); verification measures the real error and the tightening raises the bits of
/// the tracks above a joint that fails. With meshopt, on 57 Bandai Namco clips (the
/// corpus's three and 54 drawn from the dataset), against gltfpack -cc: 0.966 of its total
/// size at twice (4 files over it, the worst by 2.0%), 0.965 at three times (none over,
/// the worst at 0.994), 0.964 at four times (none over, the worst at 0.997).
const BITS_SHARE: f32 = 3.0;

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
        tighten_rounds: 20,
    };
}

/// [`reduce`] with explicit [`Tuning`].
fn reduce_with(
    clip: &Clip,
    skeleton: &Skeleton,
    tolerance: f32,
    tuning: Tuning,
) -> Result<(Clip, ReduceStats), ReduceError> {
    let options = ReduceOptions {
        tolerance,
        ..ReduceOptions::default()
    };
    reduce_impl(clip, skeleton, &options, tuning)
}

/// [`reduce_clip`] with explicit [`Tuning`].
fn reduce_impl(
    clip: &Clip,
    skeleton: &Skeleton,
    options: &ReduceOptions,
    tuning: Tuning,
) -> Result<(Clip, ReduceStats), ReduceError> {
    let tolerance = options.tolerance;
    if !tolerance.is_finite() || tolerance < 0.0 {
        return Err(ReduceError::Tolerance { tolerance });
    }
    let keys_before: usize = clip.tracks.iter().map(|t| t.times.len()).sum();
    let mut codec = options.codec;
    let mut reducer = loop {
        let channels = collect_channels(
            clip,
            skeleton,
            codec.as_ref(),
            options.uniform_rate,
            options.cubic,
        )?;
        let mut reducer = Reducer::new(skeleton, options, tuning, channels)?;
        // The codec's rounding is the one error that restoring tracks cannot undo: measure
        // it alone first, and write exact values when it does not fit.
        if codec.is_some() && reducer.errors()?.0.iter().any(|&e| e > tolerance) {
            codec = None;
            continue;
        }
        reducer.set_local_tolerances();
        if codec.is_some_and(|c| c.rotation_bits.is_some()) {
            for chan in &mut reducer.channels {
                chan.choose_bits(BITS_SHARE);
            }
        }
        break reducer;
    };
    let (max_error, mean_error) = reducer.run()?;
    let mut out = clip.clone();
    for chan in &reducer.channels {
        if let (Some(kept), Some(slot)) = (&chan.kept, out.tracks.get_mut(chan.track)) {
            *slot = match &chan.fitted {
                Some(cubic) => cubic.clone(),
                None => pick_keys(chan.original, kept),
            };
        }
    }
    let keys_after = out.tracks.iter().map(|t| t.times.len()).sum();
    let mut rotation_bits = Vec::new();
    if codec.is_some_and(|c| c.rotation_bits.is_some()) {
        rotation_bits = vec![0u8; out.tracks.len()];
        for chan in &reducer.channels {
            if let (Some(bits), Some(slot)) = (chan.bits, rotation_bits.get_mut(chan.track)) {
                *slot = bits;
            }
        }
    }
    Ok((
        out,
        ReduceStats {
            keys_before,
            keys_after,
            max_error,
            mean_error,
            coded: codec.is_some(),
            rotation_bits,
        },
    ))
}

/// The keys `kept` (increasing indices) of a LINEAR or STEP track.
fn pick_keys(track: &Track, kept: &[usize]) -> Track {
    let comps = track.values.len() / track.times.len().max(1);
    let mut out = Track {
        target: track.target,
        interpolation: track.interpolation,
        times: Vec::with_capacity(kept.len()),
        values: Vec::with_capacity(kept.len() * comps),
    };
    for &k in kept {
        if let (Some(&t), Some(v)) = (
            track.times.get(k),
            track.values.get(k * comps..(k + 1) * comps),
        ) {
            out.times.push(t);
            out.values.extend_from_slice(v);
        }
    }
    out
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
    /// Per joint: the distance of its virtual points (0: none).
    points: Vec<f32>,
    /// Whether any joint has virtual points (a joint's own rotation then moves its points).
    with_points: bool,
    /// Sorted union of every channel's key times.
    times: Vec<f32>,
    /// Original model-space points, `times.len() * joints * 4`, time-major: per joint the
    /// joint, then its virtual points on x, y and z.
    original: Vec<Vec3>,
    /// What the original motion says about each joint's reach, for step 1.
    reach: Reach,
    /// Scratch for forward kinematics.
    local: Vec<Transform>,
    model: Vec<Mat4>,
    cursors: Vec<usize>,
}

/// Per joint, from the original motion: `lever` the farthest descendant (or virtual
/// point), `bone` the longest distance to the parent, `parent_norm` the largest column
/// length of the parent's model matrix (its scale), `min_scale` the smallest `|scale|`
/// component.
#[derive(Default)]
struct Reach {
    lever: Vec<f32>,
    bone: Vec<f32>,
    parent_norm: Vec<f32>,
    min_scale: Vec<f32>,
}

/// The joint and its three virtual points at `r` on its local axes, in model space.
fn points_of(m: &Mat4, r: f32) -> [Vec3; 4] {
    let p = m.w_axis.truncate();
    [
        p,
        p + m.x_axis.truncate() * r,
        p + m.y_axis.truncate() * r,
        p + m.z_axis.truncate() * r,
    ]
}

impl<'a> Reducer<'a> {
    fn new(
        skeleton: &Skeleton,
        options: &ReduceOptions,
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
        let points: Vec<f32> = (0..n)
            .map(|j| {
                options
                    .point_distance
                    .get(j)
                    .copied()
                    .unwrap_or(0.0)
                    .max(0.0)
            })
            .collect();
        let mut r = Self {
            tolerance: options.tolerance,
            tuning,
            cursors: vec![0; channels.len()],
            channels,
            parents: skeleton.parents().collect(),
            rest: skeleton.joints().iter().map(|j| j.rest_local).collect(),
            chan_of,
            with_points: points.iter().any(|&d| d > 0.0),
            points,
            times,
            original: Vec::new(),
            reach: Reach::default(),
            local: vec![Transform::IDENTITY; n],
            model: vec![Mat4::IDENTITY; n],
        };
        r.measure_original()?;
        Ok(r)
    }

    /// Evaluates the tracks at every union time, the original ones (`original`) or as a
    /// reader sees them now; `f(time index, local, model)`.
    fn for_each_frame(
        &mut self,
        original: bool,
        mut f: impl FnMut(usize, &[Transform], &[Mat4]),
    ) -> Result<(), ReduceError> {
        self.cursors.fill(0);
        for (ti, &t) in self.times.iter().enumerate() {
            self.local.copy_from_slice(&self.rest);
            for (chan, cursor) in self.channels.iter().zip(self.cursors.iter_mut()) {
                let Some(local) = self.local.get_mut(chan.joint) else {
                    continue;
                };
                let track = if original {
                    chan.original
                } else {
                    chan.current()
                };
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

    /// The original motion's points and reach.
    fn measure_original(&mut self) -> Result<(), ReduceError> {
        let n = self.parents.len();
        let parents = self.parents.clone();
        let radius = self.points.clone();
        let mut reach = Reach {
            lever: vec![0.0f32; n],
            bone: vec![0.0f32; n],
            parent_norm: parents
                .iter()
                .map(|p| if p.is_some() { 0.0 } else { 1.0 })
                .collect(),
            min_scale: vec![f32::INFINITY; n],
        };
        let mut original = Vec::with_capacity(self.times.len() * n * 4);
        self.for_each_frame(true, |_, local, model| {
            let base = original.len();
            for (m, &r) in model.iter().zip(&radius) {
                original.extend(points_of(m, r));
            }
            let pos = |j: usize| original[base + 4 * j];
            for d in 0..n {
                let p = pos(d);
                let mut cur = parents[d];
                if let Some(pi) = cur {
                    reach.bone[d] = reach.bone[d].max(p.distance(pos(pi.get())));
                    let m = model[pi.get()];
                    let norm = m
                        .x_axis
                        .truncate()
                        .length()
                        .max(m.y_axis.truncate().length())
                        .max(m.z_axis.truncate().length());
                    reach.parent_norm[d] = reach.parent_norm[d].max(norm);
                }
                let own = (1..4).map(|k| original[base + 4 * d + k].distance(p));
                reach.lever[d] = own.fold(reach.lever[d], f32::max);
                while let Some(a) = cur {
                    let a = a.get();
                    reach.lever[a] = reach.lever[a].max(p.distance(pos(a)));
                    cur = parents[a];
                }
                reach.min_scale[d] = reach.min_scale[d].min(local[d].scale.abs().min_element());
            }
        })?;
        self.original = original;
        self.reach = reach;
        Ok(())
    }

    /// Step 1: local tolerances from the original motion's lever arms and scales.
    fn set_local_tolerances(&mut self) {
        let n = self.parents.len();
        let parents = &self.parents;
        let Reach {
            lever,
            bone,
            parent_norm,
            min_scale,
        } = &self.reach;
        let mut lever = lever.clone();
        for j in 0..n {
            if lever[j] == 0.0 {
                // A leaf without virtual points: as if its bone went on (see `reduce`).
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
    }

    /// Steps 2 and 3. Returns the measured maximum error.
    fn run(&mut self) -> Result<(f32, f32), ReduceError> {
        let errors = self.tighten()?;
        self.loosen(errors)
    }

    /// Re-simplifies the channels marked `dirty` (step 2).
    fn simplify_dirty(&mut self, dirty: &mut [bool]) {
        for (chan, dirty) in self.channels.iter_mut().zip(dirty.iter_mut()) {
            if std::mem::take(dirty) && chan.reducible {
                let (kept, cubic) = simplify(chan);
                chan.reduced = Some(match &cubic {
                    Some(track) => chan
                        .codec
                        .and_then(|codec| {
                            cubic_as_written(track, chan.kind == Kind::Rotation, &codec)
                        })
                        .unwrap_or_else(|| track.clone()),
                    None => pick_keys(chan.as_written.as_ref().unwrap_or(chan.original), &kept),
                });
                chan.fitted = cubic;
                chan.kept = Some(kept);
            }
        }
    }

    /// Steps 2 and 3 until the bound holds. Returns the per-joint errors and their mean.
    fn tighten(&mut self) -> Result<(Vec<f32>, f32), ReduceError> {
        let tol = self.tolerance;
        let mut dirty = vec![true; self.channels.len()];
        let mut round = 0;
        loop {
            self.simplify_dirty(&mut dirty);
            let (errors, mean) = self.errors()?;
            let max_error = errors.iter().copied().fold(0.0f32, f32::max);
            if max_error <= tol {
                return Ok((errors, mean));
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
                        // A joint's own rotation and scale move its virtual points only.
                        if kind != Kind::Translation && a == d && !self.with_points {
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
                let f = (0.9 * tol / err).min(0.75);
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
                    chan.kept = None;
                    chan.fitted = None;
                    chan.reducible = false;
                    // Restored whole at the default precision, as measured before step 1.
                    chan.default_bits();
                    changed = true;
                } else if factor[ci] < 1.0 && chan.eps > 0.0 {
                    if !chan.eps.is_finite() {
                        chan.eps = tol;
                    }
                    chan.eps *= factor[ci];
                    if chan.bits.is_some() {
                        chan.choose_bits(BITS_SHARE);
                    }
                    dirty[ci] = true;
                    changed = true;
                }
            }
            if !changed {
                // Unreachable in exact arithmetic (a failing joint always has a reduced
                // channel above it); restoring everything reproduces the clip exactly.
                for chan in &mut self.channels {
                    chan.reduced = None;
                    chan.kept = None;
                    chan.fitted = None;
                    chan.reducible = false;
                    chan.default_bits();
                }
            }
        }
    }

    /// Per joint: the largest model-space distance of the joint or one of its virtual
    /// points to the original, over every union time; and the mean over joints and times of
    /// the largest of a joint's points.
    fn errors(&mut self) -> Result<(Vec<f32>, f32), ReduceError> {
        let n = self.parents.len();
        let mut errors = vec![0.0f32; n];
        let mut sum = 0.0f64;
        let original = std::mem::take(&mut self.original);
        let radius = std::mem::take(&mut self.points);
        let result = self.for_each_frame(false, |ti, _, model| {
            let base = ti * n * 4;
            for (j, ((m, e), &r)) in model.iter().zip(errors.iter_mut()).zip(&radius).enumerate() {
                let at = base + 4 * j;
                let Some(was) = original.get(at..at + 4) else {
                    continue;
                };
                // Without virtual points the joint alone (its points coincide with it).
                let worst = if r > 0.0 {
                    let now = points_of(m, r);
                    now.iter()
                        .zip(was)
                        .map(|(a, b)| a.distance(*b))
                        .fold(0.0f32, f32::max)
                } else {
                    m.w_axis.truncate().distance(was[0])
                };
                sum += f64::from(worst);
                *e = e.max(worst);
            }
        });
        self.original = original;
        self.points = radius;
        let samples = (self.times.len() * n).max(1);
        result.map(|()| (errors, (sum / samples as f64) as f32))
    }
}

#[cfg(test)]
mod tests;
