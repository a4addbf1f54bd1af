//! `rigport verify`: whether a candidate file plays like a reference file, in any two
//! formats rigport reads, and where it does not.
//!
//! Both are loaded as every command loads its input, seen +Y up in metres (as
//! [`rigport_model::SceneFrame::model_to_gltf`] defines it), and evaluated by
//! `rigport-eval` (skin, morph weights, clips) at the same times; `rigport-compare` pairs
//! their vertices and measures the deviations. Joints pair by name (the retarget naming
//! rule), meshes and clips by name then order, vertices by index or source vertex when
//! those agree at rest, else by nearest rest position. A candidate that is the reference
//! scaled, turned or moved as a whole (a unit, an up axis, a placement: fitted on the
//! paired joints at rest) or whose clip plays at a time offset is reported as exactly
//! that, with what deviates beyond it.
//!
//! [`run`] is the whole pipeline; [`crate::verify()`] is the same function.

mod findings;
mod options;
mod pairing;
mod picture;
mod text;

pub use options::{Clips, DEFAULT_TOLERANCE, Times, VerifyOptions};

use crate::load::Input;
use crate::outputs::{check_not_read, extension};
use crate::progress::{Progress, step};
use crate::{PipelineError, Report};

/// The verdict and the report.
///
/// ```
/// use rigport_pipeline::verify::{VerifyOptions, run};
/// use rigport_pipeline::{load::Input, progress::Silent};
///
/// let bvh = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let same = run(&bvh, &VerifyOptions::new(bvh.clone()), &Silent)?;
/// assert!(same.passed, "{:?}", same.report.summary);
/// # Ok::<(), rigport_pipeline::PipelineError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Verification {
    /// Whether the candidate plays like the reference within the tolerance: nothing on
    /// one side only, no placement or time offset, every deviation within it.
    pub passed: bool,
    /// The report: text in `summary`, or JSON in `output`; the picture in `log`.
    pub report: Report,
}

/// Compares `options.candidate` with `reference`.
///
/// ```
/// use rigport_pipeline::verify::{VerifyOptions, run};
/// use rigport_pipeline::{convert, convert::ConvertOptions, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let usdz = dir.path().join("walk.usdz");
/// let bvh = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// convert(&bvh, &ConvertOptions { output: Output::new(&usdz), ..Default::default() }, &Silent)?;
/// let verdict = run(&bvh, &VerifyOptions::new(Input::new(vec![usdz])), &Silent)?;
/// assert!(verdict.passed, "{:?}", verdict.report.summary);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// A picture that is not `.png` (a usage error) or that is an input; either input
/// unreadable; a clip not in the reference; a side that cannot be evaluated; an
/// unwritable picture.
pub fn run(
    reference: &Input,
    options: &VerifyOptions,
    progress: &dyn Progress,
) -> Result<Verification, PipelineError> {
    if let Some(picture) = &options.picture {
        if extension(picture) != "png" {
            return Err(PipelineError::Usage(format!(
                "{}: the picture is a PNG; use the .png extension",
                picture.display()
            )));
        }
        let candidate_files = options.candidate.read_files();
        let extra: Vec<&std::path::Path> = candidate_files.iter().map(|p| p.as_path()).collect();
        check_not_read(reference, picture, &extra)?;
    }
    let (ref_plan, ref_in) = reference.load_single(progress, "reading the reference")?;
    progress.warnings(&ref_in.warnings)?;
    let (cand_plan, cand_in) = options
        .candidate
        .load_single(progress, "reading the candidate")?;
    progress.warnings(&cand_in.warnings)?;
    let labels = (ref_plan.label(), cand_plan.label());
    let findings = step(progress, "comparing", || {
        findings::compare(&ref_in.asset, &cand_in.asset, labels, options)
    })?;
    let mut report = Report::default();
    let mut marks = Vec::new();
    if let Some(path) = &options.picture {
        marks = step(progress, "drawing", || picture::write(&findings, path))?;
        report.log.push(format!(
            "wrote {} ({} vertices ringed)",
            path.display(),
            marks.len()
        ));
    }
    if options.json {
        report.output = Some(text::json(&findings, &marks));
    } else {
        report.summary = Some(text::summary(&findings));
    }
    Ok(Verification {
        passed: findings.passed(),
        report,
    })
}
