//! `rigport animate`: keyframe a rig from a JSON file of poses (`rigport_pipeline::animate`).

use std::path::PathBuf;

use anyhow::Result;
use rigport_pipeline::animate::AnimateOptions;

use crate::args::{InputArgs, OutputArgs};
use crate::context::Context;

/// `rigport animate`.
#[derive(Debug, clap::Args)]
pub struct AnimateArgs {
    /// The rig.
    #[command(flatten)]
    pub input: InputArgs,
    /// The keyframes (see below).
    #[arg(long, value_name = "KEYS.json")]
    pub keys: PathBuf,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `animate`.
pub fn run(ctx: &Context, args: &AnimateArgs) -> Result<()> {
    let options = AnimateOptions {
        keys: args.keys.clone(),
        output: args.output.to_output(),
    };
    ctx.run(|progress| rigport_pipeline::animate(&args.input.to_input(), &options, progress))
}
