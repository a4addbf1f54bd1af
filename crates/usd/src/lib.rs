//! USD layers for rigport, with no rig semantics: a layer as typed data ([`layer`]), the
//! `.usda` text format parsed into a [`Layer`] (`lex`, [`parse`]), one layer composed into
//! prims ([`stage`]), typed reads of values ([`values`]), the binary crate format (`.usdc`)
//! read into the same [`Layer`] ([`crate_file`]) and written from one ([`crate_write`]),
//! and `.usdz` packages read and written ([`usdz`]).
//!
//! Writers describe a layer once, as typed calls to a [`sink::LayerSink`]: the
//! [`printer::UsdaPrinter`] streams them as `.usda` text, the [`sink::LayerBuilder`] makes
//! them a [`Layer`] for the crate writer, so `.usdc` is never text printed and parsed back.
//!
//! The dependencies inside the crate go one way: [`layer`] <- `precision` and `lex` <-
//! [`parse`] <- [`stage`] <- [`values`]; [`sink`] <- [`printer`]; [`crate_file`] and
//! [`crate_write`] use the [`layer`]; [`usdz`] uses both encodings.
//!
//! ```
//! use std::path::Path;
//! let text = "#usda 1.0\n(\n    upAxis = \"Z\"\n)\n\ndef Xform \"A\"\n{\n    double3 xformOp:translate = (1, 2, 3)\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}\n";
//! let layer = rigport_usd::parse::parse(text, Path::new("a.usda")).unwrap();
//! let usdc = rigport_usd::crate_write::write(&layer, Path::new("a.usda")).unwrap();
//! let back = rigport_usd::read_layer(&usdc, Path::new("a.usdc")).unwrap();
//! assert_eq!(back.root.children[0].name, "A");
//! ```
#![warn(missing_docs)]

pub mod crate_file;
pub mod crate_write;
mod error;
pub mod layer;
mod lex;
pub mod parse;
mod precision;
pub mod printer;
pub mod sink;
pub mod stage;
pub mod usdz;
pub mod values;

pub use error::{
    utf8, CrateProblem, Location, Nesting, PackageProblem, Problem, UsdError, WriteProblem,
};
pub use layer::Layer;
pub use usdz::read_layer;
