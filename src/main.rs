//! The `rigport` command line: a thin shell over the rigport crates.
//!
//! Arguments are parsed into [`cli::Cli`]; each subcommand converts its arguments into one
//! `rigport-pipeline` call and prints the report. Errors are printed once, with their whole
//! cause chain, and mapped to the exit codes documented in `--help`.

mod args;
mod cli;
mod commands;
mod context;
mod exit;

use std::process::ExitCode;

use clap::Parser;
use rigport_pipeline::memory::{install, process_budget, shared_budget};

const BATCH_SHARE: &str = "the batch's --jobs items in flight";

fn main() -> ExitCode {
    rigport_pipeline::memory::raise_malloc_mmap_threshold();
    let cli = cli::Cli::parse();
    let whole = process_budget(cli.max_memory, "--max-memory");
    install(match &cli.command {
        // Items run side by side on `--jobs` threads: each gets its share of the budget.
        cli::Command::Batch(a) => shared_budget(whole, a.jobs.unwrap_or(0), BATCH_SHARE),
        _ => whole,
    });
    if !matches!(cli.command, cli::Command::Inspect(_)) {
        rigport_atomic::interrupt::remove_temp_files_on_interrupt();
    }
    match commands::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            if exit::is_broken_pipe(&err) {
                return ExitCode::SUCCESS;
            }
            eprintln!("error: {err:#}");
            ExitCode::from(exit::code_for(&err))
        }
    }
}
