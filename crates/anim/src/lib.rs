//! rigport clip edits: the offline jobs that make and change clips, on top of the runtime
//! evaluator (`rigport-eval`).
//!
//! - [`keyed`]: keys (a pose per time) to a clip;
//! - [`retime`]: time warps with slerp, speed changes and resampling;
//! - [`sequence`]: trims, concatenation with blends, loops;
//! - [`reduce`]: key reduction whose error is bounded in world space;
//! - [`root_motion`]: the hips' travel over the ground removed (in place) or moved onto a
//!   root joint.
//!
//! Like the evaluator, these jobs know no file format.
#![warn(missing_docs)]

pub mod keyed;
pub mod reduce;
pub mod retime;
pub mod root_motion;
pub mod sequence;
