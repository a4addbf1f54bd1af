//! How a pipeline tells its caller what it is doing: steps (a spinner's message), counted
//! work (a progress bar), lines for the user, and the warnings gathered before an output
//! is written, which the caller may refuse (the CLI's deny-warnings setting): then nothing
//! is written.
//!
//! ```
//! use rigport_pipeline::progress::{Progress, Silent};
//!
//! // A caller that shows nothing and accepts every warning.
//! let progress: &dyn Progress = &Silent;
//! assert!(progress.warnings(&[]).is_ok());
//! ```

use rigport_model::Warning;

/// What a pipeline reports while it runs. Every method has a default that shows nothing
/// and accepts every warning.
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
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {}

/// The caller refused the warnings ([`Progress::warnings`]): nothing was written.
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
