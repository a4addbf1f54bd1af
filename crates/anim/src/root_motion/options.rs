//! The options, report and errors of [`super::root_motion`].

use rigport_eval::sample::SampleError;
use rigport_model::{JointIndex, SkeletonProblem};

/// The name of the joint [`RootMotion::Extract`] adds above the hips (`root_1`, ... when
/// the skeleton has one of that name).
pub const ROOT_NAME: &str = "root";

/// The default smoothing window (seconds): 0, the hips' own ground position, so an
/// in-place clip holds them over one point (a walk's hips sway 2-5% of the leg length about
/// any smoothed path; a window of about one gait cycle, 1 s, keeps that sway).
pub const DEFAULT_WINDOW_S: f32 = 0.0;

/// What happens to the hips' travel over the ground.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum RootMotion {
    /// No change at all.
    #[default]
    Keep,
    /// The travel is removed: the clip plays in place.
    InPlace,
    /// The travel moves onto a root joint above the hips.
    Extract,
}

/// How [`super::root_motion`] changes an asset's clips. With the `clap` feature, command
/// lines flatten it into their arguments (`root-motion`, `root-yaw`, `root-window`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct RootMotionOptions {
    /// Keep the clips' travel over the ground (the default), remove it (in-place: the hips'
    /// smoothed path taken out, their sway about it kept) or extract it (onto a root joint
    /// above the hips, or onto the existing top joint).
    #[cfg_attr(feature = "clap", arg(long = "root-motion", value_enum, default_value_t = RootMotion::Keep))]
    pub mode: RootMotion,
    /// Remove (or extract) the smoothed heading too, not only the ground-plane position.
    #[cfg_attr(feature = "clap", arg(long = "root-yaw"))]
    pub yaw: bool,
    /// The path's smoothing window in seconds (finite, >= 0; 0 follows the hips exactly).
    #[cfg_attr(feature = "clap", arg(long = "root-window", value_name = "S", default_value_t = DEFAULT_WINDOW_S))]
    pub window_s: f32,
}

impl Default for RootMotionOptions {
    fn default() -> Self {
        Self {
            mode: RootMotion::Keep,
            yaw: false,
            window_s: DEFAULT_WINDOW_S,
        }
    }
}

/// The travel of one clip's smoothed hips path.
#[derive(Clone, Debug, PartialEq)]
pub struct Travel {
    /// The clip's name.
    pub clip: String,
    /// Length of the smoothed ground-plane path, in the asset's length unit.
    pub distance: f32,
    /// The clip's duration (first to last key), seconds.
    pub duration_s: f32,
    /// `distance / duration_s` (0 for a clip of no duration), units per second.
    pub speed: f32,
    /// The smoothed heading's change from the first key to the last, degrees,
    /// counter-clockwise seen from above.
    pub turn_deg: f32,
}

/// What [`root_motion`](super::root_motion) did.
#[derive(Clone, Debug, PartialEq)]
pub struct RootMotionReport {
    /// One per clip, in clip order (empty for [`RootMotion::Keep`]).
    pub travel: Vec<Travel>,
    /// The joint that carries the travel after [`RootMotion::Extract`] (index in the
    /// changed skeleton); `None` otherwise.
    pub root: Option<JointIndex>,
    /// Whether a joint was added (then every joint index from `root` on moved up by one).
    pub added_joint: bool,
}

/// Why root motion could not be changed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RootMotionError {
    /// The hips index is not a joint of the skeleton.
    #[error("joint {hips} is not in the skeleton ({joints} joints)")]
    NoSuchJoint {
        /// The index given.
        hips: usize,
        /// The skeleton's joint count.
        joints: usize,
    },
    /// A smoothing window that is negative or not finite.
    #[error("smoothing window {window_s} s is not a finite number >= 0")]
    BadWindow {
        /// The window, seconds.
        window_s: f32,
    },
    /// A clip does not fit the skeleton.
    #[error("the clip does not fit the skeleton")]
    Clip(#[source] SampleError),
    /// Sampling the clip failed (e.g. too many samples).
    #[error("cannot sample the clip")]
    Sample(#[source] SampleError),
    /// The root joint could not be added.
    #[error("cannot add a root joint: {0:?}")]
    Skeleton(Vec<SkeletonProblem>),
}
