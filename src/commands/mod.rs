//! One module per subcommand, each with its arguments and a `run` that calls one pipeline
//! function; `run` dispatches. Command modules use [`crate::context`] and
//! [`crate::args`], never this module or each other.

pub mod animate;
pub mod bake;
pub mod batch;
pub mod cloth;
pub mod combine;
pub mod convert;
pub mod demo;
pub mod eval;
pub mod footlock;
pub mod ik;
pub mod inspect;
pub mod render;
pub mod retarget;
pub mod retime;
pub mod sequence;
pub mod skin;
pub mod verify;

use std::ffi::OsString;

use anyhow::Result;
use clap::Parser as _;

use crate::cli::{Cli, Command};
use crate::context::{Captured, Context};
use crate::exit::UsageError;

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    let ctx = Context::new(cli.quiet, cli.deny_warnings, None);
    match cli.command {
        Command::Batch(args) => batch::run(&ctx, &args, run_item),
        Command::BatchReport(args) => batch::report(&ctx, &args),
        command => run_command(ctx, command),
    }
}

/// Parses and runs one `batch` item's command line (see [`batch::RunItem`]).
fn run_item(
    argv: Vec<OsString>,
    deny_warnings: bool,
    captured: Captured,
) -> Result<Result<()>, String> {
    let cli = match Cli::try_parse_from(argv) {
        Ok(cli) => cli,
        Err(e) => return Err(e.to_string()),
    };
    let ctx = Context::new(true, deny_warnings || cli.deny_warnings, Some(captured));
    Ok(run_command(ctx, cli.command))
}

/// Runs one command (also each item of `batch`, with a capturing context).
fn run_command(ctx: Context, command: Command) -> Result<()> {
    match command {
        Command::Convert(args) => convert::run(&ctx, &args),
        Command::Inspect(args) => inspect::run(&ctx, &args),
        Command::Eval(args) => eval::run(&ctx, &args),
        Command::Demo(args) => demo::run(&ctx, &args),
        Command::Animate(args) => animate::run(&ctx, &args),
        Command::Retime(args) => retime::run(&ctx, &args),
        Command::Retarget(args) => retarget::run(&ctx, &args),
        Command::Combine(args) => combine::run(&ctx, &args),
        Command::Sequence(args) => sequence::run(&ctx, &args),
        Command::Ik(args) => ik::run(&ctx, &args),
        Command::Footlock(args) => footlock::run(&ctx, &args),
        Command::Bake(args) => bake::run(&ctx, &args),
        Command::Cloth(args) => cloth::run(&ctx, &args),
        Command::Render(args) => render::run(&ctx, &args),
        Command::Skin(args) => skin::run(&ctx, &args),
        Command::Verify(args) => verify::run(&ctx, &args),
        Command::Batch(_) | Command::BatchReport(_) => {
            Err(UsageError("a batch item cannot be a batch".into()).into())
        }
    }
}
