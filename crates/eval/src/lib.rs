//! The rigport rig evaluator: forward kinematics, poses and skinning.
//!
//! Each step is a *job* in the ozz-animation sense: a struct of documented inputs and
//! caller-owned output slices with `validate()` (sizes and references, checked once) and
//! `run()` (no allocation). The evaluator knows no file format; skinning sees matrices and
//! influences, not a skeleton. Parallelism is the caller's choice.
#![warn(missing_docs)]

pub mod bake;
pub mod bone_mesh;
pub mod cloth;
mod error;
pub mod fk;
pub mod footlock;
pub mod ik;
pub mod keyed;
pub mod pose;
pub mod reduce;
pub mod refit;
pub mod retarget;
pub mod retime;
pub mod rig;
pub mod sample;
pub mod sequence;
pub mod skinning;

pub use dqs::{DqsJob, DqsPalette};
pub use error::EvalError;
pub use fk::LocalToModelJob;
pub use pose::Pose;
pub use rig::{Rig, RigOutput};
pub use skinning::dqs;
pub use skinning::{
    par_skin_frames, skin_frames, skinning_matrices, LbsJob, PackedInfluences, SkinFramesJob,
    SkinningMethod,
};
