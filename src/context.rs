//! What every command shares: quiet and deny-warnings settings, warning reports, spinners,
//! and small message helpers.

use anyhow::Result;
use rigport_model::{Asset, Warning};

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
        use std::io::IsTerminal;
        // No spinner thread at all unless someone can see it.
        if self.quiet || !std::io::stderr().is_terminal() {
            return f();
        }
        let bar = indicatif::ProgressBar::new_spinner();
        bar.set_message(message.to_string());
        bar.enable_steady_tick(std::time::Duration::from_millis(100));
        let out = f();
        bar.finish_and_clear();
        out
    }
}

/// The clip names of an asset, for messages.
pub fn clip_names(asset: &Asset) -> String {
    if asset.clips.is_empty() {
        return "none".into();
    }
    asset
        .clips
        .iter()
        .map(|c| format!("{:?}", c.name))
        .collect::<Vec<_>>()
        .join(", ")
}
