//! `rigport inspect`: what is in a rig (`rigport_pipeline::inspect`).

use anyhow::Result;
use rigport_pipeline::inspect::InspectOptions;

use crate::args::InputArgs;
use crate::context::Context;

/// `rigport inspect`.
#[derive(Debug, clap::Args)]
pub struct InspectArgs {
    /// The rigs.
    #[command(flatten)]
    pub input: InputArgs,
    /// Print JSON (one object per asset, in an array) for machines.
    #[arg(long)]
    pub json: bool,
}

/// Runs `inspect`. The assets' warnings are part of the listing; with `--deny-warnings`
/// any of them fails the command before anything is printed.
pub fn run(ctx: &Context, args: &InspectArgs) -> Result<()> {
    let options = InspectOptions { json: args.json };
    ctx.run(|progress| {
        let report = rigport_pipeline::inspect(&args.input.to_input(), &options, progress)?;
        if ctx.deny_warnings {
            progress.warnings(&report.warnings)?;
        }
        Ok(report)
    })
}
