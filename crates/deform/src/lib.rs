//! rigport deformation bakes, on top of the runtime evaluator (`rigport-eval`):
//!
//! - [`bake`]: dual-quaternion skinning baked into corrective morph targets (per frame,
//!   compressed by PCA), so any glTF viewer shows DQS;
//! - [`cloth`]: garments simulated on a skinned body (position-based dynamics, capsule
//!   colliders) and baked into morph targets;
//! - [`refit`]: influences refit to at most K per vertex over a pose set;
//! - [`weights`]: automatic skin weights by bone heat (Pinocchio's attachment step).
//!
//! Like the evaluator, these jobs know no file format.
#![warn(missing_docs)]

pub mod bake;
pub mod cloth;
pub mod refit;
pub mod weights;
