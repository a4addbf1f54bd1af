//! `rigport convert`: a rig (and its motion) to glTF or USD.
//!
//! [`run`] is the whole pipeline; [`crate::convert()`] is the same function.

use rigport_anim::root_motion::RootMotionOptions;

use crate::compact::CompactReport;
use crate::load::{Input, single_plan};
use crate::outputs::check_request;
use crate::progress::{Progress, step};
use crate::write::{Output, write_output_report};
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
/// convert(&input, &ConvertOptions { output, ..Default::default() }, &Silent)?;
/// let text = std::fs::read_to_string(&out)?;
/// assert!(text.contains("upAxis = \"Z\"") && text.contains("metersPerUnit = 0.01"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct ConvertOptions {
    /// The output file and how it is written.
    pub output: Output,
    /// The clips' root motion: kept (the default), removed, or extracted onto a root joint
    /// ([`crate::root_motion`]).
    pub root_motion: RootMotionOptions,
    /// Put what reducing the clips did ([`crate::compact::CompactReport`]) in the report's
    /// `output` as JSON (`null` when the clips are not reduced).
    pub json: bool,
}

/// Reads `input`, changes its root motion if asked, and writes it to `options.output`.
///
/// ```
/// use rigport_anim::root_motion::{RootMotion, RootMotionOptions};
/// use rigport_pipeline::{convert, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("walk.usda");
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let report = convert(&input, &convert::ConvertOptions { output: Output::new(&out), ..Default::default() }, &Silent)?;
/// assert!(report.log[0].starts_with("wrote "));
/// assert!(std::fs::read_to_string(&out)?.starts_with("#usda 1.0"));
/// // The travel moved onto a root joint above the hips, reported per clip.
/// let root_motion = RootMotionOptions { mode: RootMotion::Extract, ..Default::default() };
/// let options = convert::ConvertOptions { output: Output::new(&out), root_motion, json: false };
/// let report = convert(&input, &options, &Silent)?;
/// assert!(report.log[1].starts_with("root motion extracted"), "{:?}", report.log);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As the import and [`write_output_report`]; the output is checked before any work.
pub fn run(
    input: &Input,
    options: &ConvertOptions,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    check_request(input, &options.output.path, &[])?;
    let plan = single_plan(&input.files)?;
    let imported = step(progress, &format!("reading {}", plan.label()), || {
        input.load(&plan, progress)
    })?;
    convert_imported(input, imported, options, progress)
}

/// The rest of [`run`] for an asset already imported from `input` (the Python bindings
/// open once, then write): the output checked, the root motion changed if asked, and the
/// asset written to `options.output`. [`run`] is this after its import, so both write the
/// same bytes.
///
/// ```
/// use rigport_pipeline::convert::{convert_imported, ConvertOptions};
/// use rigport_pipeline::{load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let (_, imported) = input.load_single(&Silent, "reading")?;
/// let options = ConvertOptions { output: Output::new(dir.path().join("walk.glb")), ..Default::default() };
/// let report = convert_imported(&input, imported, &options, &Silent)?;
/// assert!(report.log[0].starts_with("wrote "));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As [`run`], but for the import.
pub fn convert_imported(
    input: &Input,
    mut imported: rigport_import::Imported,
    options: &ConvertOptions,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    check_request(input, &options.output.path, &[])?;
    let moved = crate::root_motion::apply(&mut imported.asset, &options.root_motion)?;
    let (line, compacted) = write_output_report(
        imported.asset,
        imported.warnings,
        &options.output,
        &input.budget,
        progress,
    )?;
    let mut report = Report::logged(line);
    if options.json {
        let json = serde_json::to_string_pretty(&compacted)
            .map_err(|e| PipelineError::step("cannot write the report", e))?;
        report.output = Some(json);
    } else {
        report
            .log
            .extend(compacted.iter().flat_map(CompactReport::lines));
    }
    report.log.extend(moved.iter().flat_map(|m| m.lines()));
    Ok(report)
}
