//! `rigport eval`: pose a rig and dump the skinned result as `.npz`
//! (`rigport_pipeline::eval`).

use std::path::PathBuf;

use anyhow::Result;
use rigport_model::SkinningMethod;
use rigport_pipeline::eval::EvalOptions;

use crate::args::{frame_rate, InputArgs};
use crate::context::Context;

/// `rigport eval`.
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// The rig.
    #[command(flatten)]
    pub input: InputArgs,
    /// The pose (see below); the rest pose when absent.
    #[arg(long, value_name = "POSE.json")]
    pub pose: Option<PathBuf>,
    /// The .npz dump to write.
    #[arg(long = "out", short = 'o', value_name = "DUMP.npz")]
    pub output: PathBuf,
    /// Skin with the influences a glTF export with this limit writes (1 to 8) instead of
    /// all of them: shows what a viewer of that file computes.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    pub max_influences: Option<u8>,
    /// The clip to play (default: the first).
    #[arg(long, value_name = "NAME", conflicts_with = "pose")]
    pub clip: Option<String>,
    /// Sample the clip at F frames per second (default: at its own key times).
    #[arg(long, value_name = "F", conflicts_with = "pose", value_parser = frame_rate)]
    pub fps: Option<f32>,
    /// Skinning method (default: the one the source declares for its skin, LBS unless a
    /// USD mesh says `dualQuaternion`).
    #[arg(long, value_enum)]
    pub skinning: Option<SkinningMethod>,
}

/// Runs `eval`.
pub fn run(ctx: &Context, args: &EvalArgs) -> Result<()> {
    let options = EvalOptions {
        pose: args.pose.clone(),
        clip: args.clip.clone(),
        fps: args.fps,
        max_influences: args.max_influences.map(usize::from),
        skinning: args.skinning,
        output: args.output.clone(),
    };
    ctx.run(|progress| rigport_pipeline::eval(&args.input.to_input(), &options, progress))
}
