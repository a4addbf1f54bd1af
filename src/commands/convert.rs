//! `rigport convert`: a rig (and its motion) to glTF or USD.

use anyhow::Result;

use crate::cli::ConvertArgs;
use crate::context::Context;
use crate::{input, output};

/// Runs `convert`.
pub fn run(ctx: &Context, args: &ConvertArgs) -> Result<()> {
    output::format_of(&args.output.output)?;
    let mut input_args = args.input.clone();
    if args.fps.is_some() {
        if input_args.amc_fps.is_some() {
            anyhow::bail!("give the AMC frame rate once: --fps or --amc-fps");
        }
        input_args.amc_fps = args.fps;
    }
    let plan = input::single_plan(&input_args)?;
    let imported = ctx.step(&format!("reading {}", plan.label()), || {
        input::load(&plan, &input_args)
    })?;
    let mut asset = imported.asset;
    let mut warnings = imported.warnings;
    output::reduce_clips(&mut asset, &args.output, &mut warnings)?;
    output::write_asset(ctx, &asset, warnings, &args.output)
}
