//! What every command shares: quiet and deny-warnings settings, spinners and progress bars
//! for the pipelines' steps ([`Progress`]), warning reports, and the printing of a
//! pipeline's [`Report`].

use std::io::Write as _;
use std::sync::{Arc, Mutex};

use anyhow::Result;
use rigport_model::Warning;
use rigport_pipeline::progress::{Denied, Progress};
use rigport_pipeline::{PipelineError, Report};

/// Where a `batch` item's warnings are collected instead of printed.
pub type Captured = Arc<Mutex<Vec<String>>>;

/// Settings every command shares.
pub struct Context {
    /// Print nothing but errors and warnings.
    pub quiet: bool,
    /// Fail on warnings.
    pub deny_warnings: bool,
    /// When set (`batch` items), warnings are collected here instead of printed.
    pub captured: Option<Captured>,
    /// The spinner or bar of the step under way.
    bar: Mutex<Option<indicatif::ProgressBar>>,
}

impl Context {
    /// A context; `captured` collects the warnings instead of printing them.
    pub fn new(quiet: bool, deny_warnings: bool, captured: Option<Captured>) -> Self {
        Self {
            quiet,
            deny_warnings,
            captured,
            bar: Mutex::new(None),
        }
    }

    /// Prints warnings (and notes) to stderr; with `--deny-warnings`, refuses them if there
    /// is any warning. Notes ([`Warning::Note`]: facts, nothing lost or repaired) never
    /// fail.
    fn show(&self, warnings: &[Warning]) -> Result<(), Denied> {
        let count = warnings.iter().filter(|w| !w.is_note()).count();
        // `warning[W003]: file:4: repaired: ...`, `note[N001]: ...` (codes: docs/WARNINGS.md).
        for line in warnings
            .iter()
            .map(|w| (w.is_note(), crate::exit::warning_line(w)))
        {
            match &self.captured {
                Some(captured) => captured
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push(line.1),
                None if !line.0 || !self.quiet => eprintln!("{}", line.1),
                None => {}
            }
        }
        if self.deny_warnings && count > 0 {
            return Err(Denied { count });
        }
        Ok(())
    }

    /// Runs a pipeline with this context as its [`Progress`], then prints its report:
    /// `log` to stderr and `summary` to stdout unless quiet, `notices` to stderr and
    /// `output` to stdout always.
    ///
    /// # Errors
    /// The pipeline's error, worded for the command line ([`crate::exit::command_line`]).
    pub fn run(
        &self,
        pipeline: impl FnOnce(&dyn Progress) -> Result<Report, PipelineError>,
    ) -> Result<()> {
        let result = pipeline(self);
        self.step_done();
        let report = result.map_err(crate::exit::command_line)?;
        for line in &report.notices {
            eprintln!("{line}");
        }
        if !self.quiet {
            for line in &report.log {
                eprintln!("{line}");
            }
        }
        let mut out = std::io::stdout().lock();
        if let Some(summary) = report.summary.as_ref().filter(|_| !self.quiet) {
            out.write_all(summary.as_bytes())?;
        }
        if let Some(text) = &report.output {
            out.write_all(text.as_bytes())?;
        }
        out.flush()?;
        Ok(())
    }

    /// Whether bars and spinners are drawn: on a terminal, without --quiet.
    fn draws(&self) -> bool {
        use std::io::IsTerminal;
        !self.quiet && self.captured.is_none() && std::io::stderr().is_terminal()
    }

    /// A bar of `total` steps drawn with indicatif's `template`; hidden unless [`Self::draws`].
    pub fn bar(&self, total: usize, template: &str) -> indicatif::ProgressBar {
        if !self.draws() {
            return indicatif::ProgressBar::hidden();
        }
        let style = indicatif::ProgressStyle::with_template(template)
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
        indicatif::ProgressBar::new(total as u64).with_style(style)
    }

    fn set_bar(&self, bar: Option<indicatif::ProgressBar>) {
        let mut slot = self.bar.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(old) = slot.take() {
            old.finish_and_clear();
        }
        *slot = bar;
    }
}

impl Progress for Context {
    fn step(&self, message: &str) {
        if !self.draws() {
            return;
        }
        let bar = indicatif::ProgressBar::new_spinner();
        bar.enable_steady_tick(std::time::Duration::from_millis(100));
        bar.set_message(message.to_string());
        self.set_bar(Some(bar));
    }

    fn step_done(&self) {
        self.set_bar(None);
    }

    fn count(&self, what: &str, done: usize, total: usize) {
        if !self.draws() {
            return;
        }
        let mut slot = self.bar.lock().unwrap_or_else(|e| e.into_inner());
        // A step's spinner (no length) gives way to the bar.
        if let Some(spinner) = slot.take_if(|b| b.length().is_none()) {
            spinner.finish_and_clear();
        }
        let template = format!("{what} {{bar:30}} {{pos}}/{{len}}, ETA {{eta}}");
        let bar = slot.get_or_insert_with(|| self.bar(total, &template));
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    }

    fn info(&self, line: &str) {
        if !self.quiet {
            eprintln!("{line}");
        }
    }

    fn warnings(&self, warnings: &[Warning]) -> Result<(), Denied> {
        self.show(warnings)
    }
}
