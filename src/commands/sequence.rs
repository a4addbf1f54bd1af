//! `rigport sequence`: clips one after another, crossfaded, optionally looping
//! (`rigport_pipeline::sequence`).

use anyhow::Result;
use rigport_pipeline::sequence::SequenceOptions;

use crate::args::{frame_rate, InputArgs, OutputArgs};
use crate::context::Context;

/// `rigport sequence`.
#[derive(Debug, clap::Args)]
pub struct SequenceArgs {
    /// The rigs whose clips play one after another (the first rig's skeleton and meshes
    /// are written; the others' clips are matched to it by joint name). A rig with several
    /// clips contributes all of them, in order.
    #[command(flatten)]
    pub input: InputArgs,
    /// Frames over which each clip blends into the next (slerp).
    #[arg(long, default_value_t = 0, value_name = "FRAMES")]
    pub crossfade: usize,
    /// Make the result loop seamlessly (its end blends into its start over --crossfade
    /// frames, at least one).
    #[arg(long = "loop")]
    pub looping: bool,
    /// Frame rate of the result (default: the first clip's).
    #[arg(long, value_name = "F", value_parser = frame_rate)]
    pub fps: Option<f32>,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `sequence`.
pub fn run(ctx: &Context, args: &SequenceArgs) -> Result<()> {
    let options = SequenceOptions {
        crossfade: args.crossfade,
        fps: args.fps,
        looping: args.looping,
        output: args.output.to_output(),
    };
    ctx.run(|progress| rigport_pipeline::sequence(&args.input.to_input(), &options, progress))
}
