//! Skinning: linear blend skinning (LBS), the method switch, and the fast multi-frame path
//! shared with dual quaternion skinning ([`crate::dqs`]).
//!
//! Two ways in:
//! - [`LbsJob`] and [`crate::dqs::DqsJob`] skin one frame straight from the model's
//!   [`Influences`] (CSR rows of any length), positions and normals; `validate()` checks
//!   every index, `run()` calls it and then allocates nothing.
//! - [`PackedInfluences`] is built once per mesh (setup: indices checked, zero weights
//!   dropped, the heaviest joint first, fixed width when no vertex has more than 8
//!   influences) and drives [`SkinFramesJob`] / [`skin_frames`]: positions for any number
//!   of frames, each vertex's influences read once per block of up to 16 frames, with
//!   specialized loops per width (1..=8) and SIMD-friendly glam types.
//!
//! Both have rayon variants (`par_run`, [`par_skin_frames`]) that split the vertices into
//! chunks and run serially below a grain size, as UsdSkel does.
//!
//! LBS follows UsdSkel's `classicLinear` (`_SkinPointsLBS` in OpenUSD's
//! `pxr/usd/usdSkel/utils.cpp`): `p' = Σ wᵢ Mᵢ p` over the non-zero weights, used as given
//! (not renormalized). rigport's own rule: a vertex with no influence, or only zero
//! weights, keeps its rest position (UsdSkel would move it to the origin).
//!
//! # Files (each depends only on those above it)
//! - `common.rs`: what the kernels share: [`skinning_matrices`], the checks a job runs
//!   once, the split into vertex chunks, DQS's per-frame joint data;
//! - `simd.rs`: the AVX2 + FMA kernels, used by the portable loops when the CPU has them;
//! - `lbs.rs`: [`LbsJob`] and the LBS loops of the multi-frame path;
//! - `dqs.rs`: dual quaternion skinning ([`dqs::DqsJob`], [`dqs::DqsPalette`]), also
//!   `rigport_eval::dqs`;
//! - `frames.rs`: [`PackedInfluences`], [`SkinFramesJob`] and the method switch
//!   ([`rigport_model::SkinningMethod`]).
//!
//! [`Influences`]: rigport_model::Influences

mod common;
pub mod dqs;
mod frames;
mod lbs;
mod simd;
#[cfg(test)]
mod tests;

/// Re-exported so callers can size the thread pool the `par_*` entry points run in
/// (`rayon::ThreadPoolBuilder::new().num_threads(2).build()?.install(|| ...)`).
pub use rayon;

pub use self::common::skinning_matrices;
pub use self::frames::{par_skin_frames, skin_frames, PackedInfluences, SkinFramesJob};
pub use self::lbs::LbsJob;
