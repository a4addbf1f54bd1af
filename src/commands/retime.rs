//! `rigport retime`: resample, speed up, warp, reverse or trim a clip
//! (`rigport_pipeline::retime`).

use anyhow::{Context as _, Result};
use rigport_anim::retime::{Retime, WarpCurve};
use rigport_anim::root_motion::RootMotionOptions;
use rigport_pipeline::retime::{parse_trim, Change, RetimeOptions};

use crate::args::{frame_rate, positive, InputArgs, OutputArgs};
use crate::context::Context;

/// `rigport retime`.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("how").required(true).args(["frames", "fps", "speed", "warp", "reverse", "trim"])))]
pub struct RetimeArgs {
    /// The rig with its clips.
    #[command(flatten)]
    pub input: InputArgs,
    /// Resample to N frames over the same duration.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(2..))]
    pub frames: Option<u64>,
    /// Resample at F frames per second over the same duration.
    #[arg(long, value_name = "F", value_parser = frame_rate)]
    pub fps: Option<f32>,
    /// Play S times as fast (0.5 = half speed, twice as long).
    #[arg(long, value_name = "S", value_parser = positive)]
    pub speed: Option<f32>,
    /// Warp curve: output_seconds:source_seconds keys, monotone, e.g. 0:0,1:0.4,2:2.
    #[arg(long, value_name = "KEYS", allow_hyphen_values = true)]
    pub warp: Option<String>,
    /// Play backwards.
    #[arg(long)]
    pub reverse: bool,
    /// Keep only START..END seconds (times shift to start at 0).
    #[arg(long, value_name = "START..END", value_parser = parse_trim)]
    pub trim: Option<Change>,
    /// The clip to retime (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
    #[command(flatten)]
    pub root_motion: RootMotionOptions,
}

/// Runs `retime`.
pub fn run(ctx: &Context, args: &RetimeArgs) -> Result<()> {
    let change = if let Some(n) = args.frames {
        Change::Retime(Retime::Frames(n as usize))
    } else if let Some(fps) = args.fps {
        Change::Retime(Retime::Fps(fps))
    } else if let Some(s) = args.speed {
        Change::Retime(Retime::Speed(s))
    } else if let Some(w) = &args.warp {
        Change::Retime(Retime::Warp(
            WarpCurve::parse(w).with_context(|| format!("--warp {w:?}"))?,
        ))
    } else if args.reverse {
        Change::Retime(Retime::Reverse)
    } else {
        // --trim (clap requires one of the group).
        args.trim.clone().unwrap_or(Change::Trim {
            start: 0.0,
            end: 0.0,
        })
    };
    let options = RetimeOptions {
        clip: args.clip.clone(),
        change,
        output: args.output.to_output(),
        root_motion: args.root_motion,
    };
    ctx.run(|progress| rigport_pipeline::retime(&args.input.to_input(), &options, progress))
}
