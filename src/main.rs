//! The `rigport` command line: a thin shell over the rigport crates.
//!
//! Arguments are parsed into [`cli::Cli`], each subcommand resolves them into a plan and
//! calls into `rigport-import`, `rigport-eval` and `rigport-export`. Errors are printed once,
//! with their whole cause chain, and mapped to the exit codes documented in `--help`.

mod cli;
mod commands;
mod exit;
mod handles;
mod input;
mod keys;
mod npz;
mod output;
mod pose;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = cli::Cli::parse();
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
