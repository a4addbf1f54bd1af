//! rigport exporters: a rig [`Asset`](rigport_model::Asset) to glTF 2.0 (`.glb` or
//! `.gltf` + `.bin`) and to USD (`.usda` text, `.usdc` crate, `.usdz` package).
//!
//! glTF output follows the glTF 2.0 specification and is checked against Khronos
//! glTF-Validator: zero errors and zero warnings is the bar; USD output passes usd-core's
//! validators. Bytes are deterministic: the same asset and options always give the same
//! file. Each writer uses its format's own frame: the glTF writer converts the asset's
//! units and up axis ([`rigport_model::SceneFrame`]) to +Y up in metres; the USD writer
//! states the `upAxis` and `metersPerUnit` that match the data it writes.
//!
//! Lossy steps (influences beyond the per-vertex limit, renormalized weight rows, vertices
//! without influence, tracks glTF cannot hold) succeed and are reported as
//! [`Warning`](rigport_model::Warning)s; an asset that breaks the model's rules is rejected
//! with every problem listed.
//!
//! ```
//! use rigport_export::{to_glb, GltfOptions};
//! use rigport_model::{glam::Vec3, Asset, Mesh};
//!
//! let asset = Asset {
//!     meshes: vec![Mesh {
//!         positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
//!         triangles: vec![[0, 1, 2]],
//!         source_vertex: vec![0, 1, 2],
//!         ..Default::default()
//!     }],
//!     ..Default::default()
//! };
//! let out = to_glb(&asset, &GltfOptions::default())?;
//! assert_eq!(&out.glb[..4], b"glTF");
//! assert_eq!(out.glb.len() % 4, 0);
//! assert!(out.warnings.is_empty());
//! # Ok::<(), rigport_export::ExportError>(())
//! ```
#![warn(missing_docs)]

mod checks;
mod error;
pub mod estimate;
mod gltf;
mod labels;
pub mod npz;
mod usd;

#[cfg(test)]
mod test_assets;

pub use error::{ExportError, Problem};
pub use gltf::meshopt::{
    encoded_bytes as meshopt_encoded_bytes, rotation_as_written as meshopt_rotation_as_written,
    rotations_as_written_bits as meshopt_rotations_as_written_bits,
    vector_as_written as meshopt_vector_as_written,
    vector_as_written_16 as meshopt_vector_as_written_16,
};
pub use gltf::weights::gltf_influences;
pub use gltf::{
    prepare_gltf, to_glb, to_gltf, write_gltf, Exported, ExportedSplit, GltfOptions, ImageFile,
    PreparedGltf,
};
pub use rigport_atomic::{
    check_output, remove_temp_files, write_atomic, write_atomic_with, NotRegularFile,
};
pub use usd::{prepare_usd, to_usda, ExportedUsd, PreparedUsd, UsdOptions};
