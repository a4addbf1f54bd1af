//! Why a reduction could not run.

use rigport_eval::EvalError;
use rigport_model::JointIndex;

/// Why [`reduce`](super::reduce) could not run.
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
    /// A reduced clip's track animates another property than the original's track of the
    /// same index ([`super::metric::point_error`]).
    #[error("clip {clip:?} track {track}: not the original's track {track}")]
    Mismatch {
        /// Clip name.
        clip: String,
        /// Track index in the clip.
        track: usize,
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
