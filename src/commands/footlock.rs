//! `rigport footlock`: hold mocap feet still during their ground contacts
//! (`rigport_pipeline::footlock`).

use anyhow::Result;
use rigport_ik::footlock::{FootlockOptions, PinAt};
use rigport_pipeline::footlock::FootlockRequest;

use crate::args::{InputArgs, OutputArgs};
use crate::context::Context;

/// `rigport footlock`.
#[derive(Debug, clap::Args)]
pub struct FootlockArgs {
    /// The rig with its motion.
    #[command(flatten)]
    pub input: InputArgs,
    /// The clip to clean (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// A foot: its ankle joint and, optionally, its toe joint (repeat for each foot).
    #[arg(long = "foot", value_name = "ANKLE[,TOE]")]
    pub feet: Vec<String>,
    /// Contact height: above a joint's lowest point, in skeleton heights (default 0.01).
    #[arg(long, value_name = "H")]
    pub height: Option<f32>,
    /// Contact speed: skeleton heights per second (default 0.2). A clip where no foot
    /// slows under it gets warning W006 (a clip played at the wrong frame rate, say).
    #[arg(long, value_name = "V")]
    pub speed: Option<f32>,
    /// Seconds over which a leg eases into and out of a contact (default 0.1).
    #[arg(long, value_name = "S")]
    pub blend: Option<f32>,
    /// Pin each contact where it starts (default: at the joint's mean position over it).
    #[arg(long)]
    pub pin_first: bool,
    /// How much longer a leg may grow to reach a pin, as a fraction of its length (default
    /// 0.02: 2%; 0 keeps bone lengths and lets such frames slide). Pins are placed within
    /// this reach, and the frames at a contact's ends that it cannot reach are left out.
    #[arg(long, value_name = "F")]
    pub max_stretch: Option<f32>,
    /// Soft IK: the fraction of the leg's length, short of full extension, over which its
    /// reach is eased so the knee never snaps straight (default 0.02; 0 turns it off).
    #[arg(long, value_name = "F")]
    pub soft: Option<f32>,
    /// The most the knee angle may change per second beyond the source's own change, in
    /// degrees per second (default 1200: 10° a frame at 120 fps).
    #[arg(long, value_name = "DEG_PER_S")]
    pub max_knee_speed: Option<f32>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `footlock`.
pub fn run(ctx: &Context, args: &FootlockArgs) -> Result<()> {
    let defaults = FootlockOptions::default();
    let request = FootlockRequest {
        clip: args.clip.clone(),
        feet: args.feet.clone(),
        options: FootlockOptions {
            height: args.height.unwrap_or(defaults.height),
            speed: args.speed.unwrap_or(defaults.speed),
            blend: args.blend.unwrap_or(defaults.blend),
            max_stretch: args.max_stretch.unwrap_or(defaults.max_stretch),
            soft: args.soft.unwrap_or(defaults.soft),
            max_knee_speed_deg: args.max_knee_speed.unwrap_or(defaults.max_knee_speed_deg),
            pin_at: if args.pin_first {
                PinAt::First
            } else {
                PinAt::Mean
            },
            ..defaults
        },
        json: args.json,
        output: args.output.to_output(),
    };
    ctx.run(|progress| rigport_pipeline::footlock(&args.input.to_input(), &request, progress))
}
