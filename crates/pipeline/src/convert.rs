//! `rigport convert`: a rig (and its motion) to glTF or USD.
//!
//! ```
//! use rigport_pipeline::{convert, load::Input, progress::Silent, write::Output};
//!
//! let dir = tempfile::tempdir()?;
//! let out = dir.path().join("walk.usda");
//! let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
//! let report = convert(&input, &convert::ConvertOptions { output: Output::new(&out) }, &Silent)?;
//! assert!(report.log[0].starts_with("wrote "));
//! assert!(std::fs::read_to_string(&out)?.starts_with("#usda 1.0"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::load::{single_plan, Input};
use crate::outputs::check_request;
use crate::progress::{step, Progress};
use crate::write::{write_output, Output};
use crate::{PipelineError, Report};

/// What `convert` writes.
#[derive(Clone, Debug, Default)]
pub struct ConvertOptions {
    /// The output file and how it is written.
    pub output: Output,
}

/// Reads `input` and writes it to `options.output`.
///
/// # Errors
/// As the import and [`write_output`]; the output is checked before any work.
pub fn run(
    input: &Input,
    options: &ConvertOptions,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    check_request(input, &options.output.path, &[])?;
    let plan = single_plan(&input.files)?;
    let imported = step(progress, &format!("reading {}", plan.label()), || {
        input.load(&plan)
    })?;
    let line = write_output(
        imported.asset,
        imported.warnings,
        &options.output,
        &input.budget,
        progress,
    )?;
    Ok(Report::logged(line))
}
