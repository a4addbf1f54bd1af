//! rigport's pipelines: each command's whole pipeline, callable from Rust. The CLI
//! (`src/`) parses its arguments, calls one of these functions and prints the [`Report`];
//! `rigport batch` and anyone embedding rigport call the same functions.
//!
//! Every command is `rigport_pipeline::COMMAND(input, options, &dyn Progress) ->
//! Result<Report, PipelineError>`, one module each: [`convert()`], [`inspect()`],
//! [`eval()`], [`animate()`], [`retime()`], [`sequence()`], [`ik()`], [`footlock()`],
//! [`retarget()`], [`combine()`], [`bake()`], [`cloth()`], [`skin()`], [`render()`], [`verify()`], and [`demo()`]
//! (no input).
//! Each checks its output before any work, and gives [`progress::Progress::warnings`]
//! everything lossy before writing, so a caller can refuse it ([`progress::Silent`] shows
//! nothing and accepts all).
//!
//! The steps they share:
//! - [`load`]: [`load::Input`] (the files as named, the bone-mesh setting, the memory
//!   budget); inputs are resolved into assets the way the CLI does, imported under the
//!   budget, and a skeleton-only asset gets a bone mesh;
//! - [`mod@write`]: [`write::Output`] and [`write::write_output`]: key reduction, the
//!   memory check, the influence fit (`truncate` or `refit`) and the writer chosen by the
//!   output's extension;
//! - [`memory`]: this process's memory budget;
//! - [`numbers`]: the one check of each kind of number an option takes (frame rate,
//!   distance, ...), the CLI's value parsers;
//! - [`root_motion`]: the clips' travel kept, removed (in place) or moved onto a root
//!   joint, for `convert`, `retarget` and `retime`;
//! - [`units`]: the units of inputs that state none, and the warning for a skeleton too
//!   tall for metres;
//! - private to the crate: the output checks made before any work (an output must not be
//!   an input, a special file or a `.gltf` link), the `.npz` dump `eval` writes, and what
//!   `inspect` lists.
//!
//! A motion converted to a USD package, then listed:
//!
//! ```
//! use rigport_pipeline::{convert::ConvertOptions, inspect::InspectOptions};
//! use rigport_pipeline::{convert, inspect, load::Input, progress::Silent, write::Output};
//!
//! let dir = tempfile::tempdir()?;
//! let usdz = dir.path().join("walk.usdz");
//! let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
//! convert(&input, &ConvertOptions { output: Output::new(&usdz), ..Default::default() }, &Silent)?;
//! let listing = inspect(&Input::new(vec![usdz]), &InspectOptions { json: true }, &Silent)?;
//! let json: serde_json::Value = serde_json::from_str(listing.output.as_deref().unwrap_or(""))?;
//! assert_eq!(json[0]["joints"].as_array().map(Vec::len), Some(9));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod animate;
mod asset_report;
pub mod bake;
pub mod cloth;
pub mod combine;
pub mod compact;
pub mod convert;
pub mod demo;
mod dump;
mod error;
pub mod eval;
pub mod footlock;
pub mod ik;
pub mod inspect;
mod keys;
pub mod load;
pub mod memory;
pub mod numbers;
mod outputs;
pub mod progress;
pub mod render;
mod report;
pub mod retarget;
pub mod retime;
pub mod root_motion;
pub mod sequence;
pub mod skin;
pub mod units;
pub mod verify;
mod weights;
pub mod write;

pub use animate::run as animate;
pub use bake::run as bake;
pub use cloth::run as cloth;
pub use combine::run as combine;
pub use convert::run as convert;
pub use demo::run as demo;
pub use eval::run as eval;
pub use footlock::run as footlock;
pub use ik::run as ik;
pub use inspect::run as inspect;
pub use render::run as render;
pub use report::Report;
pub use retarget::run as retarget;
pub use retime::run as retime;
pub use sequence::run as sequence;
pub use skin::run as skin;
pub use verify::run as verify;

pub use error::{PipelineError, chain};
pub use rigport_model::budget::{MemoryBudget, OverBudget};
