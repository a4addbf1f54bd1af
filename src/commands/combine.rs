//! `rigport combine`: a rig and its clip library in one file (`rigport_pipeline::combine`).

use std::path::PathBuf;

use anyhow::Result;
use rigport_anim::root_motion::RootMotionOptions;
use rigport_ik::retarget::RetargetOptions;
use rigport_pipeline::combine::{self, CombineRequest};

use crate::args::{frame_rate, InputArgs, OutputArgs};
use crate::context::Context;

/// `rigport combine`.
#[derive(Debug, clap::Args)]
pub struct CombineArgs {
    /// RIG (unless --mesh/--skeleton/--attachment name it), then each MOTION: a file or a
    /// folder (BVH, ASF with AMC, glTF, USD, FBX, COLLADA clips; an .amc alone goes with the
    /// .asf before it, or with an .asf RIG).
    #[command(flatten)]
    pub input: InputArgs,
    /// Name a motion file's clip: FILE=NAME (FILE as given, its file name or its stem).
    #[arg(long = "name", value_name = "FILE=NAME", value_parser = combine::parse_name)]
    pub names: Vec<(String, String)>,
    /// A joint map for the retargeted motions (as `retarget --map`).
    #[arg(long, value_name = "MAP.json")]
    pub map: Option<PathBuf>,
    /// Plant the rig's feet during their ground contacts (foot locking).
    #[arg(long)]
    pub plant_feet: bool,
    /// Resample every clip at this rate (default: each keeps its key times).
    #[arg(long, value_parser = frame_rate)]
    pub fps: Option<f32>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub output: OutputArgs,
    #[command(flatten)]
    pub root_motion: RootMotionOptions,
}

/// Runs `combine`.
pub fn run(ctx: &Context, args: &CombineArgs) -> Result<()> {
    let (rig, motions) = combine::split_inputs(args.input.to_input());
    let request = CombineRequest {
        motions,
        names: args.names.clone(),
        map: args.map.clone(),
        options: RetargetOptions {
            plant_feet: args.plant_feet,
            ..RetargetOptions::default()
        },
        fps: args.fps,
        json: args.json,
        output: args.output.to_output(),
        root_motion: args.root_motion,
    };
    ctx.run(|progress| rigport_pipeline::combine(&rig, &request, progress))
}
