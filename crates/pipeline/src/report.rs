//! What a command's pipeline returns for its caller to show.

use rigport_model::Warning;

/// What a command did, for its caller to show.
///
/// ```
/// use rigport_pipeline::{convert, convert::ConvertOptions, inspect, inspect::InspectOptions};
/// use rigport_pipeline::{load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// // `convert` says what it wrote; `inspect`'s listing is its product.
/// let options = ConvertOptions { output: Output::new(dir.path().join("walk.glb")), ..Default::default() };
/// let converted = convert(&input, &options, &Silent)?;
/// assert!(converted.log[0].starts_with("wrote ") && converted.output.is_none());
/// let listed = inspect(&input, &InspectOptions { json: false }, &Silent)?;
/// assert!(listed.log.is_empty() && listed.output.is_some());
/// # Ok::<(), Box<dyn std::error::Error>>(())
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
    pub(crate) fn logged(line: String) -> Self {
        Self {
            log: vec![line],
            ..Self::default()
        }
    }
}
