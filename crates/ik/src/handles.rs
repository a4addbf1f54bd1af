//! What a clip solve takes and gives: options, per-handle residuals, the solved clip,
//! errors, and the handles' targets over time ([`HandleTargets`]). Shared by
//! [`super::clip`] (the solve) and [`super::chains`] (the chain-aware frame solve).

use glam::Vec3;
use rigport_model::{Clip, HandleTrack, NoSuchClip, Skeleton, Warning};

use super::{IkError, IkMethod, Lambda};
use rigport_eval::sample::SampleError;
use rigport_eval::EvalError;

/// How [`solve_clip`](crate::clip::solve_clip) solves.
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
    /// Sub-step distance ([`IkSettings::substep`](crate::IkSettings::substep)).
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
    /// Largest angle to the rotation target over all frames, degrees (0 without one).
    pub max_orientation_residual_deg: f32,
    /// Two-bone handles: per frame, whether the analytic solve reached the target.
    pub reached: Option<Vec<bool>>,
}

impl HandleResidual {
    /// The summary of one handle's per-frame `residuals` at `times` (worst frame, mean,
    /// frames over `tolerance`); no orientation residual and no `reached` flags.
    pub(crate) fn from_frames(
        joint: &str,
        residuals: &[f32],
        times: &[f32],
        tolerance: f32,
    ) -> Self {
        let (worst_frame, max) = residuals
            .iter()
            .copied()
            .enumerate()
            .fold((0, 0.0f32), |a, (i, v)| if v > a.1 { (i, v) } else { a });
        Self {
            joint: joint.to_owned(),
            max_residual: max,
            mean_residual: residuals.iter().sum::<f32>() / residuals.len().max(1) as f32,
            worst_frame,
            worst_time: times.get(worst_frame).copied().unwrap_or(0.0),
            frames_over_tolerance: residuals.iter().filter(|&&v| v > tolerance).count(),
            max_orientation_residual_deg: 0.0,
            reached: None,
        }
    }

    /// For a two-bone handle, one line: `two-bone hand_l: reached in 58/61 frames; not
    /// reached in frames: 30 31 32` (`none` when every frame reached).
    pub fn reached_summary(&self) -> Option<String> {
        let r = self.reached.as_ref()?;
        let missed: Vec<String> = (0..r.len())
            .filter(|&f| !r[f])
            .map(|f| f.to_string())
            .collect();
        let list = if missed.is_empty() {
            "none".to_string()
        } else {
            missed.join(" ")
        };
        Some(format!(
            "two-bone {}: reached in {}/{} frames; not reached in frames: {list}",
            self.joint,
            r.len() - missed.len(),
            r.len()
        ))
    }
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
    /// The frame grid would be too large ([`rigport_eval::sample::MAX_FRAMES`]).
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
    /// The handles' `base` clip is not among the input's clips.
    #[error("the handles' base: {0}")]
    UnknownBase(NoSuchClip),
    /// The base clip does not fit the skeleton.
    #[error("cannot sample the base clip")]
    Base(#[source] SampleError),
}

/// A handle's target positions as a LINEAR translation track of its joint, so the clip
/// sampler interpolates them (linear between keys, held before the first and after the
/// last), as it does every keyframe track.
fn position_track(track: &HandleTrack) -> rigport_model::Track {
    rigport_model::Track {
        target: rigport_model::TrackTarget::Translation(track.joint),
        interpolation: rigport_model::Interpolation::Linear,
        times: track.times.clone(),
        values: track.positions.iter().flat_map(|p| p.to_array()).collect(),
    }
}

/// The target of `track` at time `t` (seconds): linear between keys, held before the first
/// and after the last.
pub fn handle_position(track: &HandleTrack, t: f32) -> Vec3 {
    lerp_keys(&track.times, &track.positions, t)
}

/// Keys `values` at `times` (strictly increasing, same length) at time `t`: linear between
/// keys, held before the first and after the last; NaN without keys.
pub(crate) fn lerp_keys(times: &[f32], values: &[Vec3], t: f32) -> Vec3 {
    let n = times.len().min(values.len());
    let (Some(&first), Some(&last)) = (values.first(), values.get(n.wrapping_sub(1))) else {
        return Vec3::NAN;
    };
    if n <= 1 || t <= times[0] {
        return first;
    }
    if t >= times[n - 1] {
        return last;
    }
    let k = times.partition_point(|&x| x <= t).clamp(1, n - 1) - 1;
    let u = (t - times[k]) / (times[k + 1] - times[k]);
    // glam's lerp (`a * (1 - u) + b * u`), not the clip sampler's `a + (b - a) * u`: the
    // handles have always been interpolated this way, and solved clips depend on the bits.
    values[k].lerp(values[k + 1], u)
}

/// The model-space targets of a handle set over time, as [`solve_clip`](crate::clip::solve_clip) solves for them
/// (`rigport render --handles` draws them as markers).
#[derive(Clone, Debug, PartialEq)]
pub struct HandleTargets {
    tracks: Vec<HandleTrack>,
    /// Per track: its positions as a sampler track ([`position_track`]); `None` when the
    /// track has no keys or its times and positions differ in count.
    positions: Vec<Option<rigport_model::Track>>,
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
        let positions = tracks
            .iter()
            .map(|t| {
                (!t.times.is_empty() && t.times.len() == t.positions.len())
                    .then(|| position_track(t))
            })
            .collect();
        Self {
            tracks,
            positions,
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
        match (
            self.tracks.get(h),
            self.positions.get(h),
            self.rest_effectors.get(h),
        ) {
            (Some(track), Some(Some(positions)), Some(&rest)) => {
                let p = rigport_eval::sample::sample_vec3(positions, t);
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
