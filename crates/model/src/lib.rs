//! Plain rig data for rigport: skeletons, meshes, sparse skin influences, clips, and the
//! materials and images meshes are drawn with.
//!
//! This crate holds data and the rules that make it valid; it does no I/O. Every importer
//! produces an [`Asset`], the evaluator reads one, every exporter writes one.
//! The conventions every value follows are written down once, in [`conventions`].
#![warn(missing_docs)]

mod asset;
pub mod budget;
mod clip;
pub mod conventions;
mod format;
mod frame;
mod handle;
mod index;
mod insert_joint;
pub mod interp;
mod keyed;
mod material;
mod mesh;
pub mod quantize;
mod skeleton;
mod skin;
mod transform;
mod warning;

pub use asset::{find_clip, Asset, AssetError, NoSuchClip};
pub use budget::{MemoryBudget, OverBudget};
pub use clip::{Clip, Interpolation, Track, TrackTarget};
pub use format::{Compression, OutputFormat, OutputFormatError};
pub use frame::{SceneFrame, UpAxis};
pub use handle::{HandleSet, HandleSolver, HandleTrack, RootMotion, RotationLimit};
pub use index::{JointIndex, MeshIndex};
pub use keyed::{PoseKey, PoseKeys, RestRotation};
pub use material::{
    AlphaMode, Image, ImageIndex, MagFilter, Material, MaterialIndex, MinFilter, Sampler,
    TextureRef, Wrap,
};
pub use mesh::{Mesh, MorphTarget};
pub use skeleton::{parents_first_order, Joint, Skeleton, SkeletonProblem};
pub use skin::{Influence, Influences, InfluencesFit, SkinBinding, SkinningMethod};
pub use transform::Transform;
pub use warning::{Warning, WARNING_CODES};

/// Re-exported so downstream crates use the same math types.
pub use glam;
