//! The rigport runtime evaluator: forward kinematics, poses, clip sampling, morph targets,
//! the `Rig`, and skinning (LBS and DQS).
//!
//! This is the runtime core, as ozz-animation separates its runtime from its offline
//! libraries: clip edits are in `rigport-anim`, IK, foot locking and retargeting in
//! `rigport-ik`, and the deformation bakes (DQS correctives, cloth, influence refit) in
//! `rigport-deform`. Each of those depends on this crate, never the other way.
//!
//! Each step is a *job* in the ozz-animation sense: a struct of documented inputs and
//! caller-owned output slices with `validate()` (sizes and references, checked once) and
//! `run()` (no allocation). The evaluator knows no file format; skinning sees matrices and
//! influences, not a skeleton. Parallelism is the caller's choice.
#![warn(missing_docs)]

mod error;
pub mod fk;
pub mod morph;
pub mod pose;
pub mod rig;
pub mod sample;
pub mod skinning;
#[cfg(any(test, feature = "test-support"))]
#[doc(hidden)]
pub mod test_support;

pub use dqs::{DqsJob, DqsPalette};
pub use error::EvalError;
pub use fk::LocalToModelJob;
pub use morph::MorphWeights;
pub use pose::Pose;
pub use rig::{Rig, RigOutput};
pub use skinning::dqs;
pub use skinning::{
    par_skin_frames, skin_frames, skinning_matrices, LbsJob, PackedInfluences, SkinFramesJob,
};
