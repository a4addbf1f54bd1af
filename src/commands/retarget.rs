//! `rigport retarget`: put a motion onto another rig (`rigport_pipeline::retarget`).

use std::path::PathBuf;

use anyhow::Result;
use rigport_anim::root_motion::RootMotionOptions;
use rigport_ik::retarget::RetargetOptions;
use rigport_pipeline::load::Inputs;
use rigport_pipeline::retarget::RetargetRequest;

use crate::args::{InputArgs, OutputArgs};
use crate::context::Context;

/// `rigport retarget`.
#[derive(Debug, clap::Args)]
pub struct RetargetArgs {
    /// The motion (a .bvh, an .asf with --motion/.amc, a glTF with clips).
    #[command(flatten)]
    pub input: InputArgs,
    /// The rig to put it on: files or a folder, as for inputs.
    #[arg(long, value_name = "RIG", required = true, num_args = 1..)]
    pub onto: Vec<PathBuf>,
    /// A joint map (see below); default: joint for joint by name, else by the body roles
    /// both skeletons' structure shows.
    #[arg(long, value_name = "MAP.json")]
    pub map: Option<PathBuf>,
    /// The clip to retarget (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Plant the target's feet during their ground contacts (foot locking).
    #[arg(long)]
    pub plant_feet: bool,
    /// Turn the arms so the wrists follow the source's, scaled like the hips.
    #[arg(long)]
    pub match_hands: bool,
    /// Retarget even when the joint map leaves a limb of the motion unmapped or puts it on
    /// a limb of another role (a warning, W004, rather than an error).
    #[arg(long)]
    pub allow_partial: bool,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
    #[command(flatten)]
    pub root_motion: RootMotionOptions,
}

/// Runs `retarget`.
pub fn run(ctx: &Context, args: &RetargetArgs) -> Result<()> {
    let input = args.input.to_input();
    let mut onto = input.clone();
    onto.files = Inputs::new(args.onto.clone());
    let request = RetargetRequest {
        onto,
        clip: args.clip.clone(),
        map: args.map.clone(),
        options: RetargetOptions {
            plant_feet: args.plant_feet,
            match_hands: args.match_hands,
            allow_partial: args.allow_partial,
            ..RetargetOptions::default()
        },
        json: args.json,
        output: args.output.to_output(),
        root_motion: args.root_motion,
    };
    ctx.run(|progress| rigport_pipeline::retarget(&input, &request, progress))
}
