//! rigport's pipelines: each command's whole pipeline, callable from Rust. The CLI
//! (`src/`) parses its arguments, calls one of these functions and prints the [`Report`];
//! `rigport batch` and anyone embedding rigport call the same functions.
//!
//! Every command is `rigport_pipeline::COMMAND(input, options, &dyn Progress) ->
//! Result<Report, PipelineError>`, one module each: [`convert()`], [`inspect()`],
//! [`eval()`], [`animate()`], [`retime()`], [`sequence()`], [`ik()`], [`footlock()`],
//! [`retarget()`], [`bake()`], [`cloth()`], [`render()`], and [`demo()`] (no input).
//! Each checks its output before any work, and gives [`progress::Progress::warnings`]
//! everything lossy before writing, so a caller can refuse it ([`progress::Silent`] shows
//! nothing and accepts all).
//!
//! The steps they share:
//! - [`load`]: [`load::Input`] (the files as named, the bone-mesh setting, the memory
//!   budget); resolve inputs into assets the way the CLI does, import one under the budget,
//!   and give a skeleton-only asset a bone mesh;
//! - [`outputs`]: the output format by extension, and the checks made before any work (an
//!   output must not be an input, a special file or a `.gltf` link);
//! - [`mod@write`]: [`write::Output`] and [`write::write_output`]: key reduction, the
//!   memory check, the influence fit (`truncate` or `refit`) and the writer chosen by the
//!   output's extension;
//! - [`memory`]: this process's memory budget and the import check;
//! - [`dump`]: a rig posed or sampled, skinned and written as an `.npz` dump;
//! - [`asset_report`]: what `inspect` lists.
//!
//! A whole `convert`, from a BVH file to a `.usda`:
//!
//! ```
//! use rigport_pipeline::{load, write, MemoryBudget};
//!
//! let dir = tempfile::tempdir()?;
//! let out = dir.path().join("walk.usda");
//! let inputs = load::Inputs::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
//! let plan = load::single_plan(&inputs)?;
//! let imported = load::load(&plan, true, &MemoryBudget::UNLIMITED)?;
//! let format = rigport_pipeline::outputs::format_of(&out)?;
//! let prepared = write::prepare(&imported.asset, &out, format, &write::WriteOptions::default())?;
//! prepared.write()?;
//! assert!(std::fs::read_to_string(&out)?.starts_with("#usda 1.0"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod animate;
pub mod asset_report;
pub mod bake;
pub mod cloth;
pub mod convert;
pub mod demo;
pub mod dump;
mod error;
pub mod eval;
pub mod footlock;
pub mod ik;
pub mod inspect;
mod keys;
pub mod load;
pub mod memory;
pub mod outputs;
pub mod progress;
pub mod render;
mod report;
pub mod retarget;
pub mod retime;
pub mod sequence;
pub mod write;

pub use animate::run as animate;
pub use bake::run as bake;
pub use cloth::run as cloth;
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

pub use error::{chain, PipelineError};
pub use rigport_model::budget::{MemoryBudget, OverBudget};
