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
mod signals;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    raise_malloc_mmap_threshold();
    let cli = cli::Cli::parse();
    match &cli.command {
        // Items run side by side on `--jobs` threads: each gets its share of the budget.
        cli::Command::Batch(args) => memory::set_shared(cli.max_memory, args.jobs.unwrap_or(0)),
        _ => memory::set(cli.max_memory),
    }
    if !matches!(cli.command, cli::Command::Inspect(_)) {
        signals::remove_temp_files_on_interrupt();
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

/// Allocates and frees one 8 MiB block, untouched, before any real work.
///
/// glibc's malloc serves each block of 128 KiB or more with its own `mmap` and returns it
/// with `munmap` on free: a conversion reads a file, fills value arrays and builds the
/// output through several such blocks, each paying two system calls and fresh-page faults,
/// and every `munmap` after a helper thread has run also interrupts the other cores to
/// flush their TLBs. Freeing an mmapped block raises glibc's dynamic threshold to that
/// block's size (`M_MMAP_THRESHOLD`, glibc `malloc.c`), so from then on blocks up to 8 MiB
/// come from the heap, which keeps and reuses freed memory. Measured on the kick BVH
/// (BENCHMARKS.md, 300 interleaved runs): 7% less wall and 8% less CPU time per
/// `rigport convert`. Other allocators ignore this; it costs one `mmap` and one `munmap`
/// of pages never touched.
fn raise_malloc_mmap_threshold() {
    drop(std::hint::black_box(Vec::<u8>::with_capacity(8 << 20)));
}
