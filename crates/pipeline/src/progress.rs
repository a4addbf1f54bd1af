//! How a pipeline tells its caller what it is doing: steps (a spinner's message), counted
//! work (a progress bar), lines for the user, and the warnings gathered before an output
//! is written, which the caller may refuse (the CLI's deny-warnings setting): then nothing
//! is written.

use rigport_model::Warning;

/// What a pipeline reports while it runs. Every method has a default that shows nothing
/// and accepts every warning.
///
/// ```
/// use std::sync::Mutex;
/// use rigport_pipeline::progress::Progress;
/// use rigport_pipeline::{convert, convert::ConvertOptions, load::Input, write::Output};
///
/// /// Remembers the steps it is told of.
/// #[derive(Default)]
/// struct Steps(Mutex<Vec<String>>);
///
/// impl Progress for Steps {
///     fn step(&self, message: &str) {
///         self.0.lock().unwrap().push(message.to_string());
///     }
/// }
///
/// let dir = tempfile::tempdir()?;
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let options = ConvertOptions { output: Output::new(dir.path().join("walk.glb")), ..Default::default() };
/// let steps = Steps::default();
/// convert(&input, &options, &steps)?;
/// let steps = steps.0.into_inner().unwrap();
/// assert!(steps[0].starts_with("reading "), "{steps:?}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub trait Progress: Sync {
    /// A step starts (`message`: what it does); it lasts until [`Progress::step_done`].
    fn step(&self, message: &str) {
        let _ = message;
    }

    /// The current step is done.
    fn step_done(&self) {}

    /// `done` of `total` units of counted work (e.g. simulated frames) are done.
    fn count(&self, what: &str, done: usize, total: usize) {
        let _ = (what, done, total);
    }

    /// A line for the user that is neither a warning nor the result (e.g. a note about
    /// influences).
    fn info(&self, line: &str) {
        let _ = line;
    }

    /// The warnings and notes gathered before an output is written, given once per
    /// output. An error refuses them: the pipeline stops and writes nothing.
    ///
    /// # Errors
    /// [`Denied`] when the caller refuses the warnings.
    fn warnings(&self, warnings: &[Warning]) -> Result<(), Denied> {
        let _ = warnings;
        Ok(())
    }
}

/// Shows nothing and accepts every warning (tests, scripts, bindings).
///
/// ```
/// use rigport_model::Warning;
/// use rigport_pipeline::progress::{Progress, Silent};
///
/// let warning = Warning::Note { location: "walk.bvh".into(), message: "a note".into() };
/// assert!(Silent.warnings(&[warning]).is_ok());
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {}

/// The caller refused the warnings ([`Progress::warnings`]): nothing was written.
///
/// ```
/// use rigport_model::Warning;
/// use rigport_pipeline::progress::{Denied, Progress};
/// use rigport_pipeline::{convert, convert::ConvertOptions, load::Input, write::Output, PipelineError};
///
/// /// Refuses every list of warnings, notes included.
/// struct Strict;
///
/// impl Progress for Strict {
///     fn warnings(&self, warnings: &[Warning]) -> Result<(), Denied> {
///         Err(Denied { count: warnings.len() })
///     }
/// }
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("walk.glb");
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let err = convert(&input, &ConvertOptions { output: Output::new(&out), ..Default::default() }, &Strict).unwrap_err();
/// assert!(matches!(err, PipelineError::Denied(_)), "{err}");
/// assert!(!out.exists(), "nothing is written");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{count} warning(s) reported and refused")]
pub struct Denied {
    /// How many warnings (notes not counted).
    pub count: usize,
}

/// Runs `f` as one step of `progress` named `message`.
pub(crate) fn step<T>(progress: &dyn Progress, message: &str, f: impl FnOnce() -> T) -> T {
    progress.step(message);
    let out = f();
    progress.step_done();
    out
}
