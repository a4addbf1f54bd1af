//! IK over time: handle tracks ([`HandleSet`], e.g. from `HANDLES.json`) solved frame by
//! frame on a fixed-rate grid and baked into a clip.

use glam::Vec3;
use rigport_model::{Clip, HandleSet, HandleTrack, Skeleton, Transform, Warning};

use super::{
    IkEffector, IkError, IkHandle, IkMethod, IkProblem, IkReport, IkScratch, IkSettings,
    IkSolveJob, Lambda,
};
use crate::sample::{bake, ChannelMask, FrameGrid, SampleError};
use crate::EvalError;
use crate::Pose;

/// How [`solve_clip`] solves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipSolveOptions {
    /// The solver.
    pub method: IkMethod,
    /// Frames per second; `None`: the handles' own rate, else 30.
    pub fps: Option<f32>,
    /// Convergence distance (asset length unit); `None`: 1e-4 of the skeleton's rest
    /// height (largest extent of its joints' rest positions).
    pub tolerance: Option<f32>,
    /// Iterations per frame.
    pub max_iterations: u32,
    /// Sub-step distance ([`IkSettings::substep`]).
    pub substep: Option<f32>,
    /// Whether roots above the handles may translate.
    pub free_root: bool,
}

impl Default for ClipSolveOptions {
    /// Adaptive DLS, the handles' frame rate, the default tolerance, 100 iterations, no
    /// sub-steps, fixed roots.
    fn default() -> Self {
        Self {
            method: IkMethod::Dls {
                lambda: Lambda::Adaptive,
            },
            fps: None,
            tolerance: None,
            max_iterations: 100,
            substep: None,
            free_root: false,
        }
    }
}

/// How close one handle came to its targets over the clip.
#[derive(Clone, Debug, PartialEq)]
pub struct HandleResidual {
    /// The handle joint's name.
    pub joint: String,
    /// Largest distance from effector to target over all frames.
    pub max_residual: f32,
    /// Mean distance over all frames.
    pub mean_residual: f32,
    /// The frame of the largest distance (the first if several).
    pub worst_frame: usize,
    /// Its time, seconds.
    pub worst_time: f32,
    /// Frames that end farther than the tolerance.
    pub frames_over_tolerance: usize,
}

/// A solved clip and how well it fits.
#[derive(Clone, Debug, PartialEq)]
pub struct SolvedClip {
    /// The clip: rotation tracks on every movable joint (and root translations with
    /// [`ClipSolveOptions::free_root`]), one `LINEAR` key per frame.
    pub clip: Clip,
    /// The solver's name.
    pub solver: &'static str,
    /// Frames solved.
    pub frames: usize,
    /// Frames per second.
    pub fps: f32,
    /// The convergence distance used.
    pub tolerance: f32,
    /// Mean iterations per frame.
    pub mean_iterations: f32,
    /// One entry per handle, in handle order.
    pub handles: Vec<HandleResidual>,
    /// An [`Warning::Incomplete`] when some handle-frames miss their targets.
    pub warnings: Vec<Warning>,
}

/// Why a clip could not be solved.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ClipSolveError {
    /// The frame rate is not finite and positive.
    #[error("frame rate {0}: expected a positive number")]
    Fps(f32),
    /// The tolerance is not finite and positive.
    #[error("tolerance {0}: expected a distance > 0")]
    Tolerance(f32),
    /// The frame grid would be too large ([`crate::sample::MAX_FRAMES`]).
    #[error(transparent)]
    Frames(EvalError),
    /// A setting is out of range.
    #[error("invalid IK settings")]
    Settings(#[source] IkError),
    /// The handles do not make a problem on this skeleton.
    #[error("cannot set up the IK problem")]
    Setup(#[source] IkError),
    /// A frame's solve failed.
    #[error("IK solve at {time} s")]
    Solve {
        /// The frame's time, seconds.
        time: f32,
        /// Why.
        #[source]
        source: IkError,
    },
    /// The solved poses could not be baked.
    #[error("cannot bake the solved poses")]
    Bake(#[source] SampleError),
}

/// The target of `track` at time `t` (seconds): linear between keys, held before the first
/// and after the last.
pub fn handle_position(track: &HandleTrack, t: f32) -> Vec3 {
    let n = track.times.len();
    let (Some(&first), Some(&last)) = (track.positions.first(), track.positions.last()) else {
        return Vec3::NAN;
    };
    if n <= 1 || t <= track.times[0] {
        return first;
    }
    if t >= track.times[n - 1] {
        return last;
    }
    let k = track.times.partition_point(|&x| x <= t) - 1;
    let u = (t - track.times[k]) / (track.times[k + 1] - track.times[k]);
    // glam's lerp (`a * (1 - u) + b * u`), not the clip sampler's `a + (b - a) * u`: the
    // handles have always been interpolated this way, and solved clips depend on the bits.
    track.positions[k].lerp(track.positions[k + 1], u)
}

/// The model-space targets of a handle set over time, as [`solve_clip`] solves for them
/// (`rigport render --handles` draws them as markers).
#[derive(Clone, Debug, PartialEq)]
pub struct HandleTargets {
    tracks: Vec<HandleTrack>,
    rest_effectors: Vec<Vec3>,
}

impl HandleTargets {
    /// The targets of `tracks` (resolved against `skeleton`).
    pub fn new(skeleton: &Skeleton, tracks: Vec<HandleTrack>) -> Self {
        let rest = skeleton.model_rest_matrices();
        let rest_effectors = tracks
            .iter()
            .map(|t| {
                rest.get(t.joint.get())
                    .map_or(Vec3::NAN, |m| m.transform_point3(t.offset))
            })
            .collect();
        Self {
            tracks,
            rest_effectors,
        }
    }

    /// The tracks, in order.
    pub fn tracks(&self) -> &[HandleTrack] {
        &self.tracks
    }

    /// Track `h`'s model-space target at time `t`: its position, plus the effector's
    /// model-space rest position when the track is `relative`. NaN for a bad `h`.
    pub fn target(&self, h: usize, t: f32) -> Vec3 {
        match (self.tracks.get(h), self.rest_effectors.get(h)) {
            (Some(track), Some(&rest)) => {
                let p = handle_position(track, t);
                if track.relative {
                    rest + p
                } else {
                    p
                }
            }
            _ => Vec3::NAN,
        }
    }

    /// Appends every track's target at time `t` to `out`, in track order.
    pub fn targets_at(&self, t: f32, out: &mut Vec<Vec3>) {
        out.extend((0..self.tracks.len()).map(|h| self.target(h, t)));
    }
}

/// Solves `handles` on `skeleton` frame by frame (warm start from the previous frame) on
/// the [`FrameGrid`] at `options.fps` from 0 to the last handle key (included), and bakes
/// the poses into a clip `name`.
/// `label` names the handles' source in warnings.
///
/// # Errors
/// A bad frame rate (or one needing more than [`crate::sample::MAX_FRAMES`] frames) or
/// tolerance, settings out of range, handles that do not fit the
/// skeleton, a failed frame, poses that cannot be baked.
///
/// ```
/// use rigport_eval::ik::clip::{solve_clip, ClipSolveOptions};
/// use rigport_model::glam::Vec3;
/// use rigport_model::{HandleSet, HandleTrack};
///
/// let rig = rigport_demo::character(1);
/// let skeleton = rigport_import::pinocchio::PinocchioSkeleton {
///     positions: rig.joint_positions.clone(),
///     parents: rig.joint_parents.clone(),
/// };
/// let asset = rigport_import::pinocchio::assemble(
///     "demo", rig.mesh, &skeleton, Some(&rig.joint_names), &rig.bone_weights, None,
/// )?
/// .asset;
/// let hand = asset.skeleton.find("fingertip_l").expect("the demo has a left hand");
/// let handles = HandleSet {
///     fps: Some(10.0),
///     tracks: vec![HandleTrack {
///         joint: hand,
///         name: "fingertip_l".into(),
///         offset: Vec3::ZERO,
///         weight: 1.0,
///         relative: true,
///         times: vec![0.0, 1.0],
///         positions: vec![Vec3::ZERO, Vec3::new(-0.1, 0.1, 0.1)],
///     }],
/// };
/// let solved = solve_clip(&asset.skeleton, &handles, &ClipSolveOptions::default(), "reach", "doc")?;
/// assert_eq!(solved.frames, 11);
/// assert_eq!(solved.clip.duration(), 1.0);
/// assert!(solved.handles[0].max_residual < 1e-3);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn solve_clip(
    skeleton: &Skeleton,
    handles: &HandleSet,
    options: &ClipSolveOptions,
    name: &str,
    label: &str,
) -> Result<SolvedClip, ClipSolveError> {
    let fps = options.fps.or(handles.fps).unwrap_or(30.0);
    if !(fps.is_finite() && fps > 0.0) {
        return Err(ClipSolveError::Fps(fps));
    }
    let tracks = HandleTargets::new(skeleton, handles.tracks.clone());
    let height = {
        let rest = skeleton.model_rest_matrices();
        let (lo, hi) = rest.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), m| (lo.min(m.w_axis.truncate()), hi.max(m.w_axis.truncate())),
        );
        (hi - lo).max_element().max(f32::MIN_POSITIVE)
    };
    let tolerance = options.tolerance.unwrap_or(1e-4 * height);
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(ClipSolveError::Tolerance(tolerance));
    }
    let settings = IkSettings {
        method: options.method,
        max_iterations: options.max_iterations,
        tolerance,
        substep: options.substep,
        free_root_translation: options.free_root,
        ..IkSettings::default()
    };
    settings.validate().map_err(ClipSolveError::Settings)?;
    let effectors: Vec<IkEffector> = handles
        .tracks
        .iter()
        .map(|t| IkEffector {
            joint: t.joint,
            local_offset: t.offset,
        })
        .collect();
    let problem = IkProblem::new(skeleton, &effectors, None, &[]).map_err(ClipSolveError::Setup)?;
    let end = handles
        .tracks
        .iter()
        .filter_map(|t| t.times.last().copied())
        .fold(0.0f32, f32::max);
    let times = FrameGrid::new(0.0, end, fps)
        .map_err(ClipSolveError::Frames)?
        .into_times();
    let frame_count = times.len();
    let mut pose = Pose::rest(skeleton);
    let mut scratch = IkScratch::new(&problem);
    let mut report = IkReport::new(&problem);
    let mut frames: Vec<Transform> = Vec::with_capacity(frame_count * skeleton.len());
    let mut residuals = vec![Vec::with_capacity(frame_count); handles.tracks.len()];
    let mut iterations = 0u64;
    let mut targets: Vec<IkHandle> = handles
        .tracks
        .iter()
        .map(|t| IkHandle::new(t.joint, Vec3::ZERO))
        .collect();
    for &t in &times {
        for (h, (target, track)) in targets.iter_mut().zip(&handles.tracks).enumerate() {
            target.target = tracks.target(h, t);
            target.weight = track.weight;
        }
        IkSolveJob {
            problem: &problem,
            targets: &targets,
            settings: &settings,
            pose: &mut pose.local,
            scratch: &mut scratch,
            report: &mut report,
        }
        .run()
        .map_err(|source| ClipSolveError::Solve { time: t, source })?;
        iterations += u64::from(report.iterations);
        for (r, &v) in residuals.iter_mut().zip(&report.residuals) {
            r.push(v);
        }
        frames.extend_from_slice(&pose.local);
    }

    let mut mask = ChannelMask::none(skeleton.len());
    for j in problem.movable() {
        mask.rotation[j.get()] = true;
    }
    if options.free_root {
        for r in skeleton.roots() {
            mask.translation[r.get()] = true;
        }
    }
    let clip = bake(name, &times, &frames, &mask).map_err(ClipSolveError::Bake)?;
    let residuals: Vec<HandleResidual> = handles
        .tracks
        .iter()
        .zip(&residuals)
        .map(|(t, r)| {
            let (worst_frame, max) = r
                .iter()
                .copied()
                .enumerate()
                .fold((0, 0.0f32), |a, (i, v)| if v > a.1 { (i, v) } else { a });
            HandleResidual {
                joint: t.name.clone(),
                max_residual: max,
                mean_residual: r.iter().sum::<f32>() / r.len().max(1) as f32,
                worst_frame,
                worst_time: times.get(worst_frame).copied().unwrap_or(0.0),
                frames_over_tolerance: r.iter().filter(|&&v| v > tolerance).count(),
            }
        })
        .collect();
    let over: usize = residuals.iter().map(|h| h.frames_over_tolerance).sum();
    let mut warnings = Vec::new();
    if over > 0 {
        warnings.push(Warning::Incomplete {
            location: label.to_string(),
            message: format!(
                "{over} handle-frames end farther than the tolerance {tolerance:.3e} from their targets (unreachable or not converged; best effort kept)"
            ),
        });
    }
    Ok(SolvedClip {
        clip,
        solver: options.method.name(),
        frames: frame_count,
        fps,
        tolerance,
        mean_iterations: iterations as f32 / frame_count as f32,
        handles: residuals,
        warnings,
    })
}
