//! USD layers for rigport, with no rig semantics: the `.usda` text format parsed into a
//! [`Layer`] (`lex`, [`parse`]), one layer composed into prims ([`stage`]), typed reads of
//! values ([`values`]), the binary crate format (`.usdc`) read into the same [`Layer`]
//! ([`crate_file`]), and `.usdz` packages read ([`usdz`]).
//!
//! The dependencies inside the crate go one way: `precision` and `lex` <- [`parse`] <-
//! [`stage`] <- [`values`]; [`crate_file`] uses [`parse`]'s layer;
//! [`usdz`] uses both encodings.
#![warn(missing_docs)]

pub mod crate_file;
mod error;
mod lex;
pub mod parse;
mod precision;
pub mod stage;
pub mod usdz;
pub mod values;

pub use error::{utf8, Location, Problem, UsdError};
pub use parse::Layer;
pub use usdz::read_layer;
