//! One module per subcommand; `run` checks the outputs and dispatches. Command modules use
//! [`crate::context`], never this module or each other.

mod animate;
pub mod bake;
mod batch;
mod cloth;
mod convert;
mod demo;
mod eval;
mod footlock;
mod ik;
mod inspect;
pub mod render;
mod retarget;
mod retime;
mod sequence;

use std::path::{Path, PathBuf};

use anyhow::Result;

use crate::cli::{Cli, Command, InputArgs};
use crate::context::Context;
use crate::exit::UsageError;
use crate::output;

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    let ctx = Context {
        quiet: cli.quiet,
        deny_warnings: cli.deny_warnings,
        captured: None,
    };
    match cli.command {
        Command::Batch(args) => batch::run(&ctx, &args, run_command),
        Command::BatchReport(args) => batch::report(&ctx, &args),
        command => run_command(ctx, command),
    }
}

/// Runs one command (also each item of `batch`, with a capturing context).
fn run_command(ctx: Context, command: Command) -> Result<()> {
    check_outputs(&command)?;
    match command {
        Command::Convert(args) => convert::run(&ctx, &args),
        Command::Inspect(args) => inspect::run(&ctx, &args),
        Command::Eval(args) => eval::run(&ctx, &args),
        Command::Demo(args) => demo::run(&ctx, &args),
        Command::Animate(args) => animate::run(&ctx, &args),
        Command::Retime(args) => retime::run(&ctx, &args),
        Command::Retarget(args) => retarget::run(&ctx, &args),
        Command::Sequence(args) => sequence::run(&ctx, &args),
        Command::Ik(args) => ik::run(&ctx, &args),
        Command::Footlock(args) => footlock::run(&ctx, &args),
        Command::Bake(args) => bake::run(&ctx, &args),
        Command::Cloth(args) => cloth::run(&ctx, &args),
        Command::Render(args) => render::run(&ctx, &args),
        Command::Batch(_) | Command::BatchReport(_) => {
            Err(UsageError("a batch item cannot be a batch".into()).into())
        }
    }
}

/// Checks every command's output before any work (see [`output::check_outputs`]): a
/// special file, an input given as output, or (for `bake`) a format the command does not
/// write fail at once, not after a long computation.
fn check_outputs(command: &Command) -> Result<()> {
    let with_files = |input: &InputArgs, files: &[&PathBuf]| {
        let mut all = output::input_files(input);
        all.extend(files.iter().map(|f| f.to_path_buf()));
        all
    };
    let (out, inputs): (&Path, Vec<PathBuf>) = match command {
        Command::Inspect(_) | Command::Demo(_) | Command::Batch(_) | Command::BatchReport(_) => {
            return Ok(())
        }
        Command::Convert(a) => (&a.output.output, with_files(&a.input, &[])),
        Command::Animate(a) => (&a.output.output, with_files(&a.input, &[&a.keys])),
        Command::Retime(a) => (&a.output.output, with_files(&a.input, &[])),
        Command::Retarget(a) => {
            let mut files: Vec<&PathBuf> = a.onto.iter().collect();
            files.extend(&a.map);
            (&a.output.output, with_files(&a.input, &files))
        }
        Command::Sequence(a) => (&a.output.output, with_files(&a.input, &[])),
        Command::Ik(a) => (&a.output.output, with_files(&a.input, &[&a.handles])),
        Command::Footlock(a) => (&a.output.output, with_files(&a.input, &[])),
        Command::Bake(a) => {
            if !output::format_of(&a.output)?.is_gltf() {
                return Err(UsageError(format!(
                    "{}: bake writes glTF (.glb/.gltf); a .usda declares DQS directly (`rigport convert --skinning dqs`)",
                    a.output.display()
                ))
                .into());
            }
            (&a.output, with_files(&a.input, &[]))
        }
        Command::Cloth(a) => {
            let garment = PathBuf::from(&a.garment);
            let files: Vec<&PathBuf> = garment.is_file().then_some(&garment).into_iter().collect();
            (&a.output, with_files(&a.input, &files))
        }
        Command::Eval(a) => {
            output::require_npz(&a.output)?;
            let pose: Vec<&PathBuf> = a.pose.iter().collect();
            (&a.output, with_files(&a.input, &pose))
        }
        Command::Render(a) => {
            render::format_of(&a.output)?;
            let handles: Vec<&PathBuf> = a.handles.iter().collect();
            (&a.output, with_files(&a.input, &handles))
        }
    };
    if !matches!(command, Command::Eval(_) | Command::Render(_)) {
        output::format_of(out)?;
    }
    output::check_outputs(&[out], &inputs)
}
