//! `rigport.Report`: what a command did (the pipeline's `Report`).

use pyo3::prelude::*;

use crate::errors::PyProgress;

/// What a command did: the lines the CLI prints.
#[pyclass(frozen, module = "rigport")]
pub struct Report {
    /// Lines about the work done ("wrote out.glb ...").
    #[pyo3(get)]
    log: Vec<String>,
    /// The command's human-readable result (a table), or None.
    #[pyo3(get)]
    summary: Option<String>,
    /// The command's product when it is text (a JSON report, `inspect`'s listing), or
    /// None.
    #[pyo3(get)]
    output: Option<String>,
    /// What was skipped, and why.
    #[pyo3(get)]
    notices: Vec<String>,
    /// Warnings that are part of the product (`inspect` lists each asset's), as printed.
    #[pyo3(get)]
    warnings: Vec<String>,
    /// The notes (`note[N001]: ...`) met on the way.
    #[pyo3(get)]
    notes: Vec<String>,
    /// `verify`'s verdict: whether the candidate matched; None for other commands.
    #[pyo3(get)]
    passed: Option<bool>,
}

impl Report {
    /// The pipeline's `report`, with the notes `progress` met.
    pub fn new(report: rigport_pipeline::Report, progress: &PyProgress) -> Self {
        Self {
            log: report.log,
            summary: report.summary,
            output: report.output,
            notices: report.notices,
            warnings: report.warnings.iter().map(|w| w.labelled()).collect(),
            notes: progress.notes.lock().map(|n| n.clone()).unwrap_or_default(),
            passed: None,
        }
    }

    /// This report with `verify`'s verdict.
    pub fn with_verdict(self, passed: bool) -> Self {
        Self {
            passed: Some(passed),
            ..self
        }
    }
}

#[pymethods]
impl Report {
    fn __repr__(&self) -> String {
        format!("<rigport.Report {:?}>", self.log)
    }
}
