//! Chain-aware IK per frame ([`ChainSolver`]): handle chains (`root`), pins, orientation
//! targets, analytic two-bone handles with poles, limits, a locked or free root, and
//! layering over an input pose. [`super::clip::solve_clip_on`] runs it over a clip.
//!
//! # One frame
//! The pose starts as the input pose (the base clip's sample, or rest). Then:
//! 1. the iterative handles (the clip's method, e.g. DLS) are solved together over the
//!    union of their chains: each handle moves the joints from its `root` (or the
//!    skeleton's root) down to its joint's parent, plus the joint itself when it has an
//!    offset or an orientation target; pins weigh [`PIN_WEIGHT`] times a keyed handle;
//! 2. each two-bone handle is solved analytically ([`super::two_bone`]) on the result, in
//!    handle order with pins last, then its root and mid joints are clamped into their
//!    limits and, with an orientation target, its joint is turned to that model-space
//!    rotation (then clamped too).
//!
//! Joints outside every chain keep the input pose bit for bit. With the root locked (the
//! default), the skeleton's root joints are in no chain. Limits are projections: after
//! every iterative update and after each analytic solve each limited joint's rotation
//! relative to rest is clamped per Euler angle ([`JointLimit::project`]), so no frame leaves
//! its limits; a clamped two-bone solve reports `reached = false`.
//!
//! Pins are hard in this sense: the two-bone pins are solved last, so nothing moves them
//! afterwards, and iterative pins outweigh keyed handles so far that a shared joint yields
//! to the pin.

use glam::{Mat4, Quat, Vec3};
use rigport_model::{
    find_clip, Clip, HandleSet, HandleSolver, HandleTrack, JointIndex, RootMotion, Skeleton,
    Transform, Warning,
};

use super::handles::{
    lerp_keys, ClipSolveError, ClipSolveOptions, HandleResidual, HandleTargets, SolvedClip,
};
use super::two_bone::{apply_correction, TwoBoneIkJob};
use super::{axis_angle, IkSolveJob, JointLimit};
use super::{IkEffector, IkError, IkHandle, IkProblem, IkReport, IkScratch, IkSettings};
use rigport_eval::sample::{bake, ChannelMask, CompiledClip, FrameGrid, SampleJob};
use rigport_eval::LocalToModelJob;

/// How much more an iterative pin weighs than a keyed handle of weight 1.
pub const PIN_WEIGHT: f32 = 1000.0;

/// What one frame did, per handle (handle order).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameReport {
    /// Distance from effector to target at the end of the frame (asset length unit).
    pub residuals: Vec<f32>,
    /// Angle to the rotation target, radians (0 without one).
    pub orientation_residuals_rad: Vec<f32>,
    /// Two-bone handles: whether the analytic solve reached the target (and no limit
    /// clamped it); `None` for iterative handles.
    pub reached: Vec<Option<bool>>,
    /// Iterations of the iterative solve.
    pub iterations: u32,
}

/// A two-bone handle's joints.
#[derive(Clone, Copy, Debug)]
struct TwoBone {
    handle: usize,
    root: usize,
    mid: usize,
    tip: usize,
}

/// The iterative part: a problem over the iterative handles' chains.
struct Iterative {
    problem: IkProblem,
    scratch: IkScratch,
    report: IkReport,
    settings: IkSettings,
    /// Per problem handle: the track index.
    handles: Vec<usize>,
    targets: Vec<IkHandle>,
}

/// A compiled chain-aware solve for one skeleton and handle set; see the module docs.
/// Allocates when built, not per frame.
pub struct ChainSolver {
    parents: Vec<Option<JointIndex>>,
    rest_rotation: Vec<Quat>,
    tracks: HandleTargets,
    /// Per track: (key times, rotations) of its rotation keys.
    rotation_keys: Vec<(Vec<f32>, Vec<Quat>)>,
    /// Per track: the pinned position and rotation (pins only).
    pins: Vec<Option<(Vec3, Option<Quat>)>>,
    /// Per track: the effector's rest position (model space), for relative poles.
    rest_effectors: Vec<Vec3>,
    iterative: Option<Iterative>,
    two_bone: Vec<TwoBone>,
    limits: Vec<Option<JointLimit>>,
    /// Per joint: whether some chain moves it (the output clip's rotation tracks).
    moved: Vec<bool>,
    model: Vec<Mat4>,
}

/// The rotation of a model matrix (rotation times uniform scale).
fn rotation_of(m: &Mat4) -> Quat {
    let (_, r, _) = m.to_scale_rotation_translation();
    r.normalize()
}

impl ChainSolver {
    /// Compiles the solve. `first_input` is the input pose at the first frame (pins keep
    /// what it gives them); `settings` are the iterative solver's (its
    /// `free_root_translation` also unlocks the roots' rotations).
    ///
    /// # Errors
    /// [`IkError`] from setting up the iterative problem (bad limits), or
    /// [`IkError::Length`] when `first_input` does not fit the skeleton.
    pub fn new(
        skeleton: &Skeleton,
        handles: &HandleSet,
        settings: &IkSettings,
        first_input: &[Transform],
    ) -> Result<Self, IkError> {
        let n = skeleton.len();
        if first_input.len() != n {
            return Err(IkError::Length {
                what: "first_input",
                expected: n,
                found: first_input.len(),
            });
        }
        let parents: Vec<Option<JointIndex>> = skeleton.parents().collect();
        let free = settings.free_root_translation;
        let locked = |j: usize| !free && parents.get(j).is_some_and(Option::is_none);
        let mut limits: Vec<Option<JointLimit>> = vec![None; n];
        for l in skeleton.limits().iter().chain(&handles.limits) {
            if let Some(slot) = limits.get_mut(l.joint.get()) {
                *slot = Some(JointLimit::from(l));
            }
        }
        let mut model = vec![Mat4::IDENTITY; n];
        LocalToModelJob {
            parents: &parents,
            local: first_input,
            root_model: Mat4::IDENTITY,
            model: &mut model,
        }
        .run()
        .map_err(|_| IkError::Length {
            what: "first_input",
            expected: n,
            found: first_input.len(),
        })?;
        let rest = skeleton.model_rest_matrices();
        let effector = |m: &[Mat4], t: &HandleTrack| {
            m.get(t.joint.get())
                .map_or(Vec3::NAN, |m| m.transform_point3(t.offset))
        };
        let pins = handles
            .tracks
            .iter()
            .map(|t| {
                t.pin.then(|| {
                    let rot = t
                        .orient
                        .then(|| model.get(t.joint.get()).map(rotation_of))
                        .flatten();
                    (effector(&model, t), rot)
                })
            })
            .collect();
        let rest_effectors = handles.tracks.iter().map(|t| effector(&rest, t)).collect();
        let rotation_keys = handles
            .tracks
            .iter()
            .map(|t| {
                t.times
                    .iter()
                    .zip(&t.rotations)
                    .filter_map(|(&time, q)| q.map(|q| (time, q)))
                    .unzip()
            })
            .collect();

        // Chains.
        let mut moved = vec![false; n];
        let ancestors_to = |j: usize, top: Option<JointIndex>| {
            let mut out = Vec::new();
            let mut cur = parents.get(j).copied().flatten();
            while let Some(p) = cur {
                out.push(p.get());
                if Some(p) == top {
                    break;
                }
                cur = parents.get(p.get()).copied().flatten();
            }
            out
        };
        let mut movable = Vec::new();
        let mut iter_handles = Vec::new();
        let mut two_bone = Vec::new();
        for (h, t) in handles.tracks.iter().enumerate() {
            let j = t.joint.get();
            match t.solver {
                HandleSolver::TwoBone => {
                    let mid = parents.get(j).copied().flatten();
                    let root = mid.and_then(|m| parents.get(m.get()).copied().flatten());
                    if let (Some(mid), Some(root)) = (mid, root) {
                        let chain = TwoBone {
                            handle: h,
                            root: root.get(),
                            mid: mid.get(),
                            tip: j,
                        };
                        moved[chain.root] = true;
                        moved[chain.mid] = true;
                        if !t.rotations.is_empty() || t.orient {
                            moved[j] = true;
                        }
                        two_bone.push(chain);
                    }
                }
                HandleSolver::Iterative => {
                    iter_handles.push(h);
                    let mut chain = ancestors_to(j, t.root);
                    if t.offset != Vec3::ZERO || !t.rotations.is_empty() || t.orient {
                        chain.push(j);
                    }
                    for a in chain.into_iter().filter(|&a| !locked(a)) {
                        moved[a] = true;
                        movable.push(JointIndex(a as u32));
                    }
                }
            }
        }
        // Pins last among the two-bone handles.
        two_bone.sort_by_key(|c| handles.tracks[c.handle].pin);
        let iterative = if iter_handles.is_empty() {
            None
        } else {
            let effectors: Vec<IkEffector> = iter_handles
                .iter()
                .map(|&h| IkEffector {
                    joint: handles.tracks[h].joint,
                    local_offset: handles.tracks[h].offset,
                })
                .collect();
            let limit_list: Vec<(JointIndex, JointLimit)> = limits
                .iter()
                .enumerate()
                .filter_map(|(j, l)| l.map(|l| (JointIndex(j as u32), l)))
                .collect();
            let problem = IkProblem::new(skeleton, &effectors, Some(&movable), &limit_list)?;
            let targets = iter_handles
                .iter()
                .map(|&h| IkHandle::new(handles.tracks[h].joint, Vec3::ZERO))
                .collect();
            Some(Iterative {
                scratch: IkScratch::new(&problem),
                report: IkReport::new(&problem),
                problem,
                settings: *settings,
                handles: iter_handles,
                targets,
            })
        };
        Ok(Self {
            rest_rotation: skeleton
                .joints()
                .iter()
                .map(|j| j.rest_local.rotation)
                .collect(),
            parents,
            tracks: HandleTargets::new(skeleton, handles.tracks.clone()),
            rotation_keys,
            pins,
            rest_effectors,
            iterative,
            two_bone,
            limits,
            moved,
            model,
        })
    }

    /// Per joint: whether some handle's chain may rotate it (the other joints keep their
    /// input rotation).
    pub fn moved(&self) -> &[bool] {
        &self.moved
    }

    /// A report sized for this solver.
    pub fn report(&self) -> FrameReport {
        let h = self.tracks.tracks().len();
        FrameReport {
            residuals: vec![0.0; h],
            orientation_residuals_rad: vec![0.0; h],
            reached: vec![None; h],
            iterations: 0,
        }
    }

    /// Handle `h`'s position target at time `t` (model space).
    pub fn target(&self, h: usize, t: f32) -> Vec3 {
        match self.pins.get(h) {
            Some(Some((p, _))) => *p,
            _ => self.tracks.target(h, t),
        }
    }

    /// Handle `h`'s rotation target at time `t` (model space), if it has one.
    pub fn rotation_target(&self, h: usize, t: f32) -> Option<Quat> {
        if let Some(Some((_, rot))) = self.pins.get(h) {
            return *rot;
        }
        let (times, quats) = self.rotation_keys.get(h)?;
        let n = times.len();
        let (first, last) = (quats.first()?, quats.last()?);
        if n == 1 || t <= times[0] {
            return Some(*first);
        }
        if t >= times[n - 1] {
            return Some(*last);
        }
        let k = times.partition_point(|&x| x <= t).saturating_sub(1);
        let (a, b) = (quats.get(k)?, quats.get(k + 1)?);
        let u = (t - times[k]) / (times[k + 1] - times[k]);
        Some(a.slerp(*b, u).normalize())
    }

    /// Handle `h`'s pole target at time `t` (model space), if it has one.
    fn pole_target(&self, h: usize, t: f32) -> Option<Vec3> {
        let track = self.tracks.tracks().get(h)?;
        if track.poles.is_empty() {
            return None;
        }
        let p = if track.pin {
            *track.poles.first()?
        } else {
            lerp_keys(&track.times, &track.poles, t)
        };
        Some(if track.relative {
            self.rest_effectors.get(h).copied().unwrap_or(Vec3::ZERO) + p
        } else {
            p
        })
    }

    fn forward(&mut self, pose: &[Transform]) -> Result<(), IkError> {
        LocalToModelJob {
            parents: &self.parents,
            local: pose,
            root_model: Mat4::IDENTITY,
            model: &mut self.model,
        }
        .run()
        .map_err(|_| IkError::Length {
            what: "pose",
            expected: self.parents.len(),
            found: pose.len(),
        })
    }

    /// Clamps joint `j`'s local rotation into its limit; whether it changed.
    fn clamp(&self, pose: &mut [Transform], j: usize) -> bool {
        let (Some(Some(limit)), Some(&rest)) = (self.limits.get(j), self.rest_rotation.get(j))
        else {
            return false;
        };
        let Some(local) = pose.get_mut(j) else {
            return false;
        };
        let q = (rest * limit.project(rest.conjugate() * local.rotation)).normalize();
        let changed = axis_angle(q.conjugate() * local.rotation).1 > 1e-5;
        local.rotation = q;
        changed
    }

    /// Solves one frame at time `t` (seconds): `pose` is the input pose in, the solved pose
    /// out (one local transform per joint). Allocates nothing.
    ///
    /// # Errors
    /// [`IkError`] for a pose of the wrong length or non-finite input.
    pub fn solve_frame(
        &mut self,
        t: f32,
        pose: &mut [Transform],
        report: &mut FrameReport,
    ) -> Result<(), IkError> {
        report.iterations = 0;
        let tracks = self.tracks.tracks().len();
        if let Some(mut it) = self.iterative.take() {
            for (target, &h) in it.targets.iter_mut().zip(&it.handles) {
                let track = &self.tracks.tracks()[h];
                target.target = self.target(h, t);
                target.weight = if track.pin {
                    PIN_WEIGHT * track.weight
                } else {
                    track.weight
                };
                target.orientation = self.rotation_target(h, t);
            }
            let result = IkSolveJob {
                problem: &it.problem,
                targets: &it.targets,
                settings: &it.settings,
                pose,
                scratch: &mut it.scratch,
                report: &mut it.report,
            }
            .run();
            report.iterations = it.report.iterations;
            self.iterative = Some(it);
            result?;
        }
        for c in 0..self.two_bone.len() {
            let chain = self.two_bone[c];
            let h = chain.handle;
            let Some(track) = self.tracks.tracks().get(h) else {
                continue;
            };
            let (offset, weight, soften, twist_deg) =
                (track.offset, track.weight, track.soften, track.twist_deg);
            self.forward(pose)?;
            let (root, mid) = (self.model[chain.root], self.model[chain.mid]);
            let tip = self.model[chain.tip] * Mat4::from_translation(offset);
            let target = self.target(h, t);
            let mut job = TwoBoneIkJob::new(root, mid, tip, target);
            if let Some(pole) = self.pole_target(h, t) {
                job.pole = pole - root.w_axis.truncate();
                job.mid_axis = TwoBoneIkJob::bend_axis(root, mid, tip, job.pole);
            }
            job.twist_rad = twist_deg.to_radians();
            job.soften = soften.clamp(0.0, 1.0);
            job.weight = weight.clamp(0.0, 1.0);
            let out = job.run().map_err(|_| IkError::NonFiniteTarget {
                handle: h,
                what: "position",
            })?;
            apply_correction(&mut pose[chain.root], out.root_correction);
            apply_correction(&mut pose[chain.mid], out.mid_correction);
            let clamped = self.clamp(pose, chain.root) | self.clamp(pose, chain.mid);
            if let Some(q) = self.rotation_target(h, t) {
                self.forward(pose)?;
                let parent = rotation_of(&self.model[chain.mid]);
                let wanted = (parent.conjugate() * q).normalize();
                let local = &mut pose[chain.tip];
                local.rotation = local.rotation.slerp(wanted, job.weight).normalize();
                self.clamp(pose, chain.tip);
            }
            if let Some(r) = report.reached.get_mut(h) {
                *r = Some(out.reached && !clamped);
            }
        }
        self.forward(pose)?;
        for h in 0..tracks {
            let Some(track) = self.tracks.tracks().get(h) else {
                continue;
            };
            let m = self.model[track.joint.get()];
            let target = self.target(h, t);
            if let Some(r) = report.residuals.get_mut(h) {
                *r = m.transform_point3(track.offset).distance(target);
            }
            if let Some(r) = report.orientation_residuals_rad.get_mut(h) {
                *r = self.rotation_target(h, t).map_or(0.0, |q| {
                    axis_angle(rotation_of(&m).conjugate() * q.normalize()).1
                });
            }
        }
        Ok(())
    }
}

/// The chain-aware clip solve behind [`super::clip::solve_clip_on`].
pub(super) fn solve_chains(
    skeleton: &Skeleton,
    clips: &[Clip],
    handles: &HandleSet,
    options: &ClipSolveOptions,
    name: &str,
    label: &str,
) -> Result<SolvedClip, ClipSolveError> {
    let base = match &handles.base {
        None => None,
        Some(b) => find_clip(clips, Some(b))
            .map_err(ClipSolveError::UnknownBase)?
            .map(|i| &clips[i]),
    };
    let compiled = base
        .map(|c| CompiledClip::new(c, skeleton))
        .transpose()
        .map_err(ClipSolveError::Base)?;
    let fps = options
        .fps
        .or(handles.fps)
        .or_else(|| compiled.as_ref().and_then(CompiledClip::fps))
        .unwrap_or(30.0);
    if !(fps.is_finite() && fps > 0.0) {
        return Err(ClipSolveError::Fps(fps));
    }
    let rest = skeleton.model_rest_matrices();
    let (lo, hi) = rest.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), m| (lo.min(m.w_axis.truncate()), hi.max(m.w_axis.truncate())),
    );
    let height = (hi - lo).max_element().max(f32::MIN_POSITIVE);
    let tolerance = options.tolerance.unwrap_or(1e-4 * height);
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(ClipSolveError::Tolerance(tolerance));
    }
    let free = options.free_root || handles.root_motion == Some(RootMotion::Free);
    let settings = IkSettings {
        method: options.method,
        max_iterations: options.max_iterations,
        tolerance,
        substep: options.substep,
        free_root_translation: free,
        ..IkSettings::default()
    };
    settings.validate().map_err(ClipSolveError::Settings)?;
    let end = handles
        .tracks
        .iter()
        .filter_map(|t| t.times.last().copied())
        .chain(compiled.as_ref().map(CompiledClip::end))
        .fold(0.0f32, f32::max);
    let times = FrameGrid::new(0.0, end, fps)
        .map_err(ClipSolveError::Frames)?
        .into_times();
    let rest_local: Vec<Transform> = skeleton.joints().iter().map(|j| j.rest_local).collect();
    let mut input = rest_local.clone();
    let sample = |t: f32, out: &mut [Transform]| -> Result<(), ClipSolveError> {
        match &compiled {
            Some(c) => SampleJob {
                clip: c,
                time: t,
                rest: &rest_local,
                output: out,
            }
            .run()
            .map_err(ClipSolveError::Base),
            None => {
                out.copy_from_slice(&rest_local);
                Ok(())
            }
        }
    };
    sample(times.first().copied().unwrap_or(0.0), &mut input)?;
    let mut solver =
        ChainSolver::new(skeleton, handles, &settings, &input).map_err(ClipSolveError::Setup)?;
    let mut report = solver.report();
    let h_count = handles.tracks.len();
    let mut frames: Vec<Transform> = Vec::with_capacity(times.len() * skeleton.len());
    let mut residuals = vec![Vec::with_capacity(times.len()); h_count];
    let mut orientation = vec![0.0f32; h_count];
    let mut reached: Vec<Option<Vec<bool>>> = handles
        .tracks
        .iter()
        .map(|t| (t.solver == HandleSolver::TwoBone).then(Vec::new))
        .collect();
    let mut iterations = 0u64;
    for &t in &times {
        sample(t, &mut input)?;
        solver
            .solve_frame(t, &mut input, &mut report)
            .map_err(|source| ClipSolveError::Solve { time: t, source })?;
        iterations += u64::from(report.iterations);
        for h in 0..h_count {
            residuals[h].push(report.residuals[h]);
            orientation[h] = orientation[h].max(report.orientation_residuals_rad[h].to_degrees());
            if let (Some(list), Some(r)) = (reached[h].as_mut(), report.reached[h]) {
                list.push(r);
            }
        }
        frames.extend_from_slice(&input);
    }
    let mut mask = match base {
        Some(c) => ChannelMask::of_clip(c, skeleton.len()),
        None => ChannelMask::none(skeleton.len()),
    };
    for (j, &m) in solver.moved().iter().enumerate() {
        mask.rotation[j] |= m;
    }
    if free {
        for r in skeleton.roots() {
            mask.translation[r.get()] = true;
            mask.rotation[r.get()] = true;
        }
    }
    let clip = bake(name, &times, &frames, &mask).map_err(ClipSolveError::Bake)?;
    let summaries: Vec<HandleResidual> = handles
        .tracks
        .iter()
        .enumerate()
        .map(|(h, t)| HandleResidual {
            max_orientation_residual_deg: orientation[h],
            reached: reached[h].take(),
            ..HandleResidual::from_frames(&t.name, &residuals[h], &times, tolerance)
        })
        .collect();
    let over: usize = summaries.iter().map(|h| h.frames_over_tolerance).sum();
    let mut warnings = Vec::new();
    if over > 0 {
        warnings.push(Warning::Incomplete {
            location: label.to_string(),
            message: format!(
                "{over} handle-frames end farther than the tolerance {tolerance:.3e} from their targets (unreachable, limited or not converged; best effort kept)"
            ),
        });
    }
    Ok(SolvedClip {
        clip,
        solver: options.method.name(),
        frames: times.len(),
        fps,
        tolerance,
        mean_iterations: iterations as f32 / times.len().max(1) as f32,
        handles: summaries,
        warnings,
    })
}
