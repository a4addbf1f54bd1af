//! `rigport render`: pictures of a rig or clip (PNG contact sheet or GIF/APNG animation),
//! drawn on the CPU (`rigport_pipeline::render`), optionally with IK handle targets as
//! markers.

use std::path::PathBuf;

use anyhow::Result;
use rigport_model::SkinningMethod;
use std::str::FromStr as _;

use rigport_pipeline::render::{
    picture_size, projection, skinning_methods, FrameRange, RenderRequest,
};
use rigport_render::{Projection, RenderOptions, View};

use crate::args::{frame_rate, InputArgs};
use crate::context::Context;

/// `rigport render` arguments.
#[derive(Debug, clap::Args)]
#[command(
    after_help = include_str!("../../docs/help/render.txt")
)]
pub struct RenderArgs {
    /// The rig.
    #[command(flatten)]
    pub input: InputArgs,
    /// The picture to write: .png (contact sheet), .gif or .apng (animation).
    #[arg(long, short, value_name = "OUT.png|OUT.gif|OUT.apng")]
    pub output: PathBuf,
    /// The clip to draw (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Sample the clip at F frames per second (default: its key times for .png, 25 for
    /// animations).
    #[arg(long, value_name = "F", value_parser = frame_rate)]
    pub fps: Option<f32>,
    /// Keep sampled frames a..b (0-based, b excluded; `a..` and `..b` work too).
    #[arg(long, value_name = "a..b", value_parser = FrameRange::from_str)]
    pub frames: Option<FrameRange>,
    /// Size of one view in pixels (`--skinning both` pictures are twice as wide).
    #[arg(long, value_name = "WxH", default_value = "512x512", value_parser = picture_size)]
    pub size: (u32, u32),
    /// Where the camera looks from: front (+Z), side (+X), top (+Y) or three-quarter.
    #[arg(long, value_enum, default_value_t = View::Front)]
    pub view: View,
    /// Projection: ortho (parallel) or perspective (35 deg vertical field of view).
    #[arg(long, value_name = "ortho|perspective", default_value = "ortho", value_parser = projection)]
    pub camera: Projection,
    /// Draw the targets of these IK handles (HANDLES.json, as `rigport ik` reads it) as
    /// markers, at each frame's time.
    #[arg(long, value_name = "HANDLES.json")]
    pub handles: Option<PathBuf>,
    /// Skinning method; `both` draws LBS (left) and DQS (right) with the same camera.
    /// Default: the method the source declares for its skin (LBS unless a USD mesh says
    /// `dualQuaternion`).
    #[arg(long, value_name = "lbs|dqs|both", value_parser = skinning_methods)]
    pub skinning: Option<&'static [SkinningMethod]>,
    /// Do not draw the skeleton over the mesh.
    #[arg(long)]
    pub no_skeleton: bool,
    /// Do not draw the frame number.
    #[arg(long)]
    pub no_frame_counter: bool,
}

/// Runs `render`.
pub fn run(ctx: &Context, args: &RenderArgs) -> Result<()> {
    let request = RenderRequest {
        options: RenderOptions {
            width: args.size.0,
            height: args.size.1,
            view: args.view,
            projection: args.camera,
            skinning: &[],
            skeleton: !args.no_skeleton,
            frame_counter: !args.no_frame_counter,
        },
        skinning: args.skinning,
        clip: args.clip.clone(),
        fps: args.fps,
        frames: args.frames,
        handles: args.handles.clone(),
        output: args.output.clone(),
    };
    ctx.run(|progress| rigport_pipeline::render(&args.input.to_input(), &request, progress))
}
