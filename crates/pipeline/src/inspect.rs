//! `rigport inspect`: what is in each rig, as text or JSON.
//!
//! [`run`] is the whole pipeline; [`crate::inspect()`] is the same function.

use crate::asset_report::AssetReport;
use crate::load::Input;
use crate::progress::{Progress, step};
use crate::{PipelineError, Report};

/// How `inspect` lists.
///
/// ```
/// use rigport_pipeline::inspect::InspectOptions;
/// use rigport_pipeline::{inspect, load::Input, progress::Silent};
///
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let report = inspect(&input, &InspectOptions { json: false }, &Silent)?;
/// assert!(report.output.as_deref().is_some_and(|t| t.contains("joints: 9")));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct InspectOptions {
    /// JSON instead of text.
    pub json: bool,
}

/// Reads every asset of `input` and lists what is in it; each asset's warnings are part of
/// its listing, and all of them are in [`Report::warnings`].
///
/// ```
/// use rigport_pipeline::inspect::InspectOptions;
/// use rigport_pipeline::{inspect, load::Input, progress::Silent};
///
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let report = inspect(&input, &InspectOptions { json: true }, &Silent)?;
/// let json: serde_json::Value = serde_json::from_str(report.output.as_deref().unwrap_or(""))?;
/// assert!(json[0]["joints"].is_array());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As the imports.
pub fn run(
    input: &Input,
    options: &InspectOptions,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    let (mut reports, mut all) = (Vec::new(), Vec::new());
    for plan in input.plans()? {
        let imported = step(progress, &format!("reading {}", plan.label()), || {
            plan.import()
        })?;
        all.extend(imported.warnings.iter().cloned());
        let warnings = imported.warnings.iter().map(|w| w.labelled()).collect();
        reports.push(AssetReport::new(plan.label(), &imported.asset, warnings));
    }
    let mut out = Vec::new();
    if options.json {
        serde_json::to_writer_pretty(&mut out, &reports)
            .map_err(|e| PipelineError::step("cannot list the assets as JSON", e))?;
        out.push(b'\n');
    } else {
        for r in &reports {
            r.write_text(&mut out)
                .map_err(|e| PipelineError::step("cannot list the assets", e))?;
            for w in &r.warnings {
                out.extend_from_slice(format!("  {w}\n").as_bytes());
            }
        }
    }
    Ok(Report {
        output: Some(String::from_utf8_lossy(&out).into_owned()),
        warnings: all,
        ..Report::default()
    })
}
