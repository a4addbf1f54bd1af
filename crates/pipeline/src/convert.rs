//! `rigport convert`: a rig (and its motion) to glTF or USD.
//!
//! [`run`] is the whole pipeline; [`crate::convert()`] is the same function.

use crate::load::{Input, single_plan};
use crate::outputs::check_request;
use crate::progress::{Progress, step};
use crate::write::{Output, write_output};
use crate::{PipelineError, Report};

/// What `convert` writes.
///
/// ```
/// use rigport_model::UpAxis;
/// use rigport_pipeline::write::{Output, WriteOptions};
/// use rigport_pipeline::{convert, convert::ConvertOptions, load::Input, progress::Silent};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("walk.usda");
/// // The stage declares Z up and centimetres, whatever the input's own frame.
/// let options = WriteOptions {
///     up_axis: Some(UpAxis::Z),
///     meters_per_unit: Some(0.01),
///     ..WriteOptions::default()
/// };
/// let output = Output { options, ..Output::new(&out) };
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// convert(&input, &ConvertOptions { output }, &Silent)?;
/// let text = std::fs::read_to_string(&out)?;
/// assert!(text.contains("upAxis = \"Z\"") && text.contains("metersPerUnit = 0.01"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct ConvertOptions {
    /// The output file and how it is written.
    pub output: Output,
}

/// Reads `input` and writes it to `options.output`.
///
/// ```
/// use rigport_pipeline::{convert, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("walk.usda");
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let report = convert(&input, &convert::ConvertOptions { output: Output::new(&out) }, &Silent)?;
/// assert!(report.log[0].starts_with("wrote "));
/// assert!(std::fs::read_to_string(&out)?.starts_with("#usda 1.0"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
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
