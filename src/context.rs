//! What every command shares: quiet and deny-warnings settings, warning reports and
//! spinners.

use anyhow::Result;
use rigport_model::Warning;

use crate::exit::DeniedWarnings;

/// Settings every command shares.
pub struct Context {
    /// Print nothing but errors and warnings.
    pub quiet: bool,
    /// Fail on warnings.
    pub deny_warnings: bool,
    /// When set (`batch` items), warnings are collected here instead of printed.
    pub captured: Option<std::sync::Arc<std::sync::Mutex<Vec<String>>>>,
}

impl Context {
    /// Prints warnings (and notes) to stderr; with `--deny-warnings`, fails if there is any
    /// warning. Notes ([`Warning::Note`]: facts, nothing lost or repaired) never fail.
    pub fn report(&self, warnings: &[Warning]) -> Result<()> {
        let mut count = 0;
        if let Some(captured) = &self.captured {
            let mut captured = captured.lock().unwrap_or_else(|e| e.into_inner());
            for w in warnings {
                count += usize::from(!w.is_note());
                captured.push(w.labelled());
            }
        }
        // `warning[W003]: file:4: repaired: ...`, `note[N001]: ...` (codes: docs/WARNINGS.md).
        for w in warnings.iter().filter(|_| self.captured.is_none()) {
            if w.is_note() {
                if !self.quiet {
                    eprintln!("{}", w.labelled());
                }
            } else {
                count += 1;
                eprintln!("{}", w.labelled());
            }
        }
        if self.deny_warnings && count > 0 {
            return Err(DeniedWarnings { count }.into());
        }
        Ok(())
    }

    /// Runs `f` under a spinner on stderr (shown only on a terminal, never with --quiet).
    pub fn step<T>(&self, message: &str, f: impl FnOnce() -> T) -> T {
        let bar = self.spinner();
        bar.set_message(message.to_string());
        let out = f();
        bar.finish_and_clear();
        out
    }

    /// A spinner on stderr for a library's progress messages (hidden unless on a terminal
    /// and without --quiet: then no thread at all).
    pub fn spinner(&self) -> indicatif::ProgressBar {
        use std::io::IsTerminal;
        if self.quiet || !std::io::stderr().is_terminal() {
            return indicatif::ProgressBar::hidden();
        }
        let bar = indicatif::ProgressBar::new_spinner();
        bar.enable_steady_tick(std::time::Duration::from_millis(100));
        bar
    }
}
