//! IK over time: handle tracks ([`HandleSet`], e.g. from `HANDLES.json`) solved frame by
//! frame on a fixed-rate grid and baked into a clip.

use glam::Vec3;
use rigport_model::{Clip, HandleSet, Skeleton, Transform, Warning};

use super::{IkEffector, IkHandle, IkProblem, IkReport, IkScratch, IkSettings, IkSolveJob};
use rigport_eval::sample::{bake, ChannelMask, FrameGrid};
use rigport_eval::Pose;

pub use super::handles::{
    handle_position, ClipSolveError, ClipSolveOptions, HandleResidual, HandleTargets, SolvedClip,
};

/// Solves `handles` on `skeleton` frame by frame (warm start from the previous frame) on
/// the [`FrameGrid`] at `options.fps` from 0 to the last handle key (included), and bakes
/// the poses into a clip `name`.
/// `label` names the handles' source in warnings.
///
/// # Errors
/// A bad frame rate (or one needing more than [`rigport_eval::sample::MAX_FRAMES`] frames) or
/// tolerance, settings out of range, handles that do not fit the
/// skeleton, a failed frame, poses that cannot be baked.
///
/// ```
/// use rigport_ik::clip::{solve_clip, ClipSolveOptions};
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
/// let mut track = HandleTrack::keyed(hand, "fingertip_l", vec![0.0, 1.0], vec![Vec3::ZERO, Vec3::new(-0.1, 0.1, 0.1)]);
/// track.relative = true;
/// let handles = HandleSet { fps: Some(10.0), tracks: vec![track], base: None, root_motion: None, limits: vec![] };
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
    solve_clip_on(skeleton, &[], handles, options, name, label)
}

/// As [`solve_clip`], with the input's clips for a handle set that names a `base` clip.
/// A handle set that uses any chain-aware field ([`HandleSet::uses_chains`]) is solved by
/// [`super::chains::ChainSolver`] frame by frame from the input pose (the base clip's
/// sample at each frame time, or rest), on the grid from 0 to the last key or the base
/// clip's end, at `options.fps`, else the handles' rate, else the base clip's, else 30;
/// the output clip animates the base clip's channels plus the rotations of the joints the
/// chains move. Other handle sets solve exactly as before.
///
/// # Errors
/// As [`solve_clip`]; [`ClipSolveError::UnknownBase`], [`ClipSolveError::Base`].
pub fn solve_clip_on(
    skeleton: &Skeleton,
    clips: &[Clip],
    handles: &HandleSet,
    options: &ClipSolveOptions,
    name: &str,
    label: &str,
) -> Result<SolvedClip, ClipSolveError> {
    if handles.uses_chains() {
        return super::chains::solve_chains(skeleton, clips, handles, options, name, label);
    }
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
        .map(|(t, r)| HandleResidual::from_frames(&t.name, r, &times, tolerance))
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
