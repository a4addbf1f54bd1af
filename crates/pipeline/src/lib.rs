//! rigport's pipelines: what a command does between parsing its arguments and printing,
//! callable from Rust. The CLI (`src/`) and anyone embedding rigport call the same code.
//!
//! - [`load`]: resolve inputs into assets the way the CLI does, import one under the
//!   memory budget, and give a skeleton-only asset a bone mesh;
//! - [`outputs`]: the output format by extension, and the checks made before any work (an
//!   output must not be an input, a special file or a `.gltf` link);
//! - [`write`]: the influence fit (`truncate` or `refit`), key reduction, the memory check
//!   and the writer chosen by the output's extension;
//! - [`memory`]: this process's memory budget and the import check;
//! - [`demo`]: the built-in demo character, written with its pictures;
//! - [`dump`]: a rig posed or sampled, skinned and written as an `.npz` dump;
//! - [`retarget`]: a clip put onto another rig, and its report as JSON.
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

pub mod demo;
pub mod dump;
pub mod load;
pub mod memory;
pub mod outputs;
pub mod retarget;
pub mod write;

use std::error::Error as StdError;

pub use rigport_model::budget::{MemoryBudget, OverBudget};

/// Why a pipeline step failed. [`PipelineError::is_usage`] and [`PipelineError::is_output`]
/// tell the CLI's exit codes apart (usage 2, output 3, else input 1).
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// The request cannot be carried out as given (an output extension rigport does not
    /// write, an output that is one of the inputs); the message says what to change.
    #[error("{0}")]
    Usage(String),
    /// An output could not be written or is not writable.
    #[error("cannot write {path}")]
    Output {
        /// The output path, as given.
        path: String,
        /// Why.
        #[source]
        source: Box<dyn StdError + Send + Sync>,
    },
    /// The step would use more memory than the budget allows.
    #[error(transparent)]
    Budget(#[from] OverBudget),
    /// The inputs do not group into assets.
    #[error(transparent)]
    Detect(#[from] rigport_import::detect::DetectError),
    /// An input could not be imported.
    #[error(transparent)]
    Import(#[from] rigport_import::ImportError),
    /// A step failed on valid inputs: the message names the step and the asset.
    #[error("{message}")]
    Step {
        /// What failed.
        message: String,
        /// Why.
        #[source]
        source: Box<dyn StdError + Send + Sync>,
    },
    /// The built-in demo failed (a rigport bug).
    #[error(transparent)]
    Demo(#[from] rigport_demo::DemoError),
    /// An asset could not be exported.
    #[error(transparent)]
    Export(#[from] rigport_export::ExportError),
    /// A pose or keys file is invalid (the message names the JSON path).
    #[error(transparent)]
    Json(#[from] rigport_import::json::JsonError),
    /// Evaluating a pose failed.
    #[error(transparent)]
    Eval(#[from] rigport_eval::EvalError),
    /// Sampling a clip failed.
    #[error(transparent)]
    Sample(#[from] rigport_eval::sample::SampleError),
    /// An influence refit failed.
    #[error(transparent)]
    Refit(#[from] rigport_deform::refit::asset::RefitError),
    /// The inputs are readable but do not make what was asked (the message says why).
    #[error("{0}")]
    Invalid(String),
}

impl PipelineError {
    /// Whether this is a usage error (the CLI exits 2).
    pub fn is_usage(&self) -> bool {
        matches!(self, Self::Usage(_))
    }

    /// Whether an output failed (the CLI exits 3).
    pub fn is_output(&self) -> bool {
        matches!(self, Self::Output { .. })
    }

    /// An output error for `path`.
    pub(crate) fn output(
        path: &std::path::Path,
        source: impl Into<Box<dyn StdError + Send + Sync>>,
    ) -> Self {
        Self::Output {
            path: path.display().to_string(),
            source: source.into(),
        }
    }

    /// A failed step.
    pub(crate) fn step(
        message: impl Into<String>,
        source: impl Into<Box<dyn StdError + Send + Sync>>,
    ) -> Self {
        Self::Step {
            message: message.into(),
            source: source.into(),
        }
    }
}

/// An error with its causes, `: `-separated (as the CLI prints errors).
pub fn chain(err: &(dyn StdError + 'static)) -> String {
    let mut text = err.to_string();
    let mut source = err.source();
    while let Some(e) = source {
        text.push_str(": ");
        text.push_str(&e.to_string());
        source = e.source();
    }
    text
}

/// A plain message as an error source.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct Message(pub String);
