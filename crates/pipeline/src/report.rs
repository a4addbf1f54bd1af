//! What a command's pipeline returns for its caller to show.

use rigport_model::Warning;

/// What a command did, for its caller to show.
///
/// ```
/// let report = rigport_pipeline::Report::logged("wrote a.glb".into());
/// assert_eq!(report.log, ["wrote a.glb"]);
/// assert!(report.summary.is_none() && report.output.is_none());
/// ```
/// The CLI prints `log` to standard error and
/// `summary` to standard output unless it is quiet, `notices` to standard error and
/// `output` to standard output always.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// Lines about the work done, in order ("wrote out.glb: 32 joints, ...").
    pub log: Vec<String>,
    /// The command's human-readable result (a table of contacts, limbs or handles).
    pub summary: Option<String>,
    /// The command's product when it is text (the JSON report asked for, `inspect`'s
    /// listing).
    pub output: Option<String>,
    /// What was skipped, and why (shown even when quiet).
    pub notices: Vec<String>,
    /// Warnings that are part of the product (`inspect` lists each asset's), not given to
    /// [`crate::progress::Progress::warnings`].
    pub warnings: Vec<Warning>,
}

impl Report {
    /// A report of one log line.
    pub fn logged(line: String) -> Self {
        Self {
            log: vec![line],
            ..Self::default()
        }
    }
}
