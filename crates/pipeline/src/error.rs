//! The one error of the pipelines, [`PipelineError`], and the messages it carries.

use std::error::Error as StdError;

use rigport_model::budget::OverBudget;

use crate::progress;

/// Why a pipeline step failed. [`PipelineError::is_usage`] and [`PipelineError::is_output`]
/// tell the CLI's exit codes apart (usage 2, output 3, else input 1).
///
/// ```
/// use rigport_pipeline::{convert, convert::ConvertOptions, load::Input, progress::Silent};
/// use rigport_pipeline::{write::Output, PipelineError};
///
/// let input = Input::new(vec!["../../fixtures/bvh/missing.bvh".into()]);
/// let options = ConvertOptions { output: Output::new("walk.glb"), ..Default::default() };
/// match convert(&input, &options, &Silent) {
///     Err(PipelineError::Import(e)) => assert!(e.to_string().contains("missing.bvh"), "{e}"),
///     other => panic!("expected an import error, got {other:?}"),
/// }
/// ```
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
    /// Units given for an input contradict the unit its file states (a usage error).
    #[error(transparent)]
    Units(#[from] UnitsConflict),
    /// The inputs are readable but do not make what was asked (the message says why).
    #[error("{0}")]
    Invalid(String),
    /// The caller refused the warnings ([`progress::Progress::warnings`]); nothing was
    /// written.
    #[error(transparent)]
    Denied(#[from] progress::Denied),
    /// A job of the library crates failed (its own message says why).
    #[error(transparent)]
    Failed(Box<dyn StdError + Send + Sync>),
}

impl PipelineError {
    /// Whether this is a usage error (the CLI exits 2).
    ///
    /// ```
    /// use rigport_pipeline::{convert, convert::ConvertOptions, load::Input, progress::Silent};
    ///
    /// // rigport writes .usda, .usdc and .usdz, not the ambiguous .usd.
    /// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
    /// let options = ConvertOptions { output: rigport_pipeline::write::Output::new("walk.usd"), ..Default::default() };
    /// assert!(convert(&input, &options, &Silent).unwrap_err().is_usage());
    /// ```
    pub fn is_usage(&self) -> bool {
        matches!(self, Self::Usage(_) | Self::Units(_))
    }

    /// Whether a retarget failed on a partial joint map
    /// (`rigport_ik::retarget::RetargetError::PartialMap`), which a caller may allow.
    ///
    /// ```
    /// assert!(!rigport_pipeline::PipelineError::Invalid("no".into()).is_partial_map());
    /// ```
    pub fn is_partial_map(&self) -> bool {
        use rigport_ik::retarget::RetargetError;
        let mut cur: Option<&(dyn StdError + 'static)> = Some(self);
        while let Some(e) = cur {
            if let Some(RetargetError::PartialMap(_)) = e.downcast_ref::<RetargetError>() {
                return true;
            }
            cur = e.source();
        }
        false
    }

    /// A job's own error, shown as it is.
    pub(crate) fn failed(e: impl StdError + Send + Sync + 'static) -> Self {
        Self::Failed(Box::new(e))
    }

    /// Whether an output failed (the CLI exits 3).
    ///
    /// ```
    /// use rigport_pipeline::{convert, convert::ConvertOptions, load::Input, progress::Silent};
    ///
    /// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
    /// let out = tempfile::tempdir()?.path().join("gone/walk.glb");
    /// let options = ConvertOptions { output: rigport_pipeline::write::Output::new(out), ..Default::default() };
    /// assert!(convert(&input, &options, &Silent).unwrap_err().is_output());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
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

/// Units given that contradict the unit a file states.
///
/// ```
/// use rigport_pipeline::units::InputUnits;
/// use rigport_pipeline::{convert, convert::ConvertOptions, load::Input, progress::Silent};
///
/// // A glTF states metres; centimetres given contradict it.
/// let input = Input {
///     units: Some(InputUnits::MetersPerUnit(0.01)),
///     ..Input::new(vec!["../../fixtures/gltf/skin_basic.glb".into()])
/// };
/// let dir = tempfile::tempdir()?;
/// let options = ConvertOptions { output: rigport_pipeline::write::Output::new(dir.path().join("a.glb")), ..Default::default() };
/// let err = convert(&input, &options, &Silent).unwrap_err();
/// assert!(err.is_usage() && err.to_string().contains("states 1 m per unit"), "{err}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, thiserror::Error)]
#[error("{file} states {stated} m per unit; the units given say {given}")]
pub struct UnitsConflict {
    /// The input.
    pub file: String,
    /// Metres per unit the file states.
    pub stated: f64,
    /// Metres per unit given.
    pub given: f64,
}

/// An error with its causes, `: `-separated (as the CLI prints errors).
///
/// ```
/// use rigport_pipeline::{chain, convert, convert::ConvertOptions, load::Input, progress::Silent};
///
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let out = tempfile::tempdir()?.path().join("gone/walk.glb");
/// let options = ConvertOptions { output: rigport_pipeline::write::Output::new(&out), ..Default::default() };
/// let err = convert(&input, &options, &Silent).unwrap_err();
/// // The error names the output; its cause says why.
/// let text = chain(&err);
/// assert!(text.starts_with(&format!("cannot write {}: ", out.display())), "{text}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
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
