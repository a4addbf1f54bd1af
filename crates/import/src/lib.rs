//! rigport importers: source files to a [`rigport_model::Asset`].
//!
//! One module per format. Every entry point returns an [`Imported`] (the asset plus the
//! [`Warning`]s of any lossy or repairing step) or an [`ImportError`] that names the file and
//! the line (or JSON path, or byte offset) of the first problem. No entry point panics on
//! any input.
#![warn(missing_docs)]

pub mod csci520;
pub mod demo;
mod error;
pub mod gltf;
pub mod obj;
pub mod pinocchio;

pub use error::{ImportError, Location, Problem};

use rigport_model::{Asset, Warning};

/// An imported asset and what was repaired or lost on the way.
#[derive(Clone, Debug)]
pub struct Imported {
    /// The asset, valid by [`Asset::validate`].
    pub asset: Asset,
    /// Lossy or repairing steps, in the order they happened.
    pub warnings: Vec<Warning>,
}

/// Reads a whole file, mapping failure to an [`ImportError`] that names it.
pub(crate) fn read_file(path: &std::path::Path) -> Result<Vec<u8>, ImportError> {
    std::fs::read(path).map_err(|e| ImportError::new(Location::file(path), Problem::Io(e)))
}
