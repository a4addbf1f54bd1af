//! rigport's comparison of two rigs as they play: one side per asset ([`side::Side`],
//! evaluated by `rigport-eval` in a common frame), the correspondence of their vertices
//! ([`vertex_map`]), per-clip deviations of vertices and joints ([`deviation`], over the
//! frames of [`frames`]), and what explains a candidate that is the reference moved,
//! turned or scaled ([`similarity`]) or played with a time offset
//! ([`frames::find_time_offset`]).
//!
//! Like the evaluator it builds on, it knows no file format: callers load both assets,
//! pair meshes, joints and clips by name, and say which frame each is seen in.
//!
//! ```
//! use rigport_compare::side::{Posed, Scratch, Side};
//! use rigport_compare::glam::DMat4;
//! use rigport_model::{Asset, Mesh, glam::Vec3};
//!
//! let mesh = Mesh { positions: vec![Vec3::ZERO, Vec3::X], ..Mesh::default() };
//! let asset = Asset { meshes: vec![mesh], ..Asset::default() };
//! // Seen in centimetres.
//! let side = Side::new(&asset, DMat4::from_scale(rigport_compare::glam::DVec3::splat(100.0)))?;
//! let mut posed = Posed::default();
//! side.evaluate(None, 0.0, true, &mut Scratch::default(), &mut posed)?;
//! assert_eq!(posed.positions[0][1].x, 100.0);
//! # Ok::<(), rigport_compare::CompareError>(())
//! ```
#![warn(missing_docs)]

pub mod deviation;
pub mod frames;
pub mod side;
pub mod similarity;
pub mod vertex_map;

pub use glam;

/// Why two rigs could not be compared.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// A side cannot be evaluated.
    #[error(transparent)]
    Eval(#[from] rigport_eval::EvalError),
    /// A clip cannot be sampled.
    #[error(transparent)]
    Sample(#[from] rigport_eval::sample::SampleError),
}
