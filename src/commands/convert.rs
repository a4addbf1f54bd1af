//! `rigport convert`: a rig (and its motion) to glTF or USD (`rigport_pipeline::convert`).

use anyhow::{bail, Result};
use rigport_anim::root_motion::RootMotionOptions;
use rigport_pipeline::convert::ConvertOptions;
use rigport_pipeline::progress::Progress as _;

use crate::args::{frame_rate, InputArgs, OutputArgs};
use crate::context::Context;

/// `rigport convert`.
#[derive(Debug, clap::Args)]
pub struct ConvertArgs {
    /// The rig.
    #[command(flatten)]
    pub input: InputArgs,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
    #[command(flatten)]
    pub root_motion: RootMotionOptions,
    /// Print what --reduce-tolerance did as JSON on standard output (keys, bytes, errors).
    #[arg(long)]
    pub json: bool,
    /// Deprecated: the frame rate of AMC motions, now `--amc-fps` (kept for one release).
    #[arg(long, value_name = "FPS", hide = true, value_parser = frame_rate)]
    pub fps: Option<f32>,
}

/// Runs `convert`.
pub fn run(ctx: &Context, args: &ConvertArgs) -> Result<()> {
    let mut input = args.input.to_input();
    if let Some(fps) = args.fps {
        if input.files.amc_fps.is_some() {
            bail!("give the AMC frame rate once: --amc-fps (--fps is its deprecated name)");
        }
        input.files.amc_fps = Some(fps);
        ctx.info("note: --fps is deprecated for convert: the AMC frame rate is --amc-fps (--fps means a sampling rate everywhere else)");
    }
    let options = ConvertOptions {
        output: args.output.to_output(),
        root_motion: args.root_motion,
        json: args.json,
    };
    ctx.run(|progress| rigport_pipeline::convert(&input, &options, progress))
}
