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
mod memory;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    rigport_pipeline::memory::raise_malloc_mmap_threshold();
    let cli = cli::Cli::parse();
    match &cli.command {
        // Items run side by side on `--jobs` threads: each gets its share of the budget.
        cli::Command::Batch(args) => memory::set_shared(cli.max_memory, args.jobs.unwrap_or(0)),
        _ => memory::set(cli.max_memory),
    }
    if !matches!(cli.command, cli::Command::Inspect(_)) {
        rigport_atomic::remove_temp_files_on_interrupt();
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
