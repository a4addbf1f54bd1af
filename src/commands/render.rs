//! `rigport render`: pictures of a rig or clip (PNG contact sheet or GIF/APNG animation),
//! drawn on the CPU (`rigport_pipeline::render`), optionally with IK handle targets as
//! markers.

use std::path::PathBuf;

use anyhow::Result;
use rigport_model::SkinningMethod;
use rigport_pipeline::render::RenderRequest;
use rigport_render::{Projection, RenderOptions, View};

use crate::args::{frame_rate, InputArgs};
use crate::context::Context;

/// `rigport render` arguments.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "A .png output is a contact sheet: a grid of up to 16 frames evenly \
chosen from the sampled ones. A .gif output is a looping animation of every sampled frame \
(default 25 fps; the frame delay follows --fps, at least 0.02 s); .apng likewise, in full \
colour. All frames share one camera \
framed on the bounds of all of them. A rig without clips renders its rest pose.

--handles HANDLES.json (the file `rigport ik` takes; see `rigport ik --help`) draws each \
handle's target at each frame's time as a magenta crosshair over the mesh and skeleton; \
`relative` positions are offsets from the effector's rest position, as for `rigport ik`. \
The targets take part in the framing, so one away from the body is in the picture too.

--camera perspective frames the same bounds with a 35 deg (vertical) pinhole camera on the \
view axis through their centre, as far away as needed for their nearest face to be drawn \
at the orthographic scale, so everything fits inside the margin."
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
    #[arg(long, value_name = "a..b", value_parser = parse_range)]
    pub frames: Option<FrameRange>,
    /// Size of one view in pixels (`--skinning both` pictures are twice as wide).
    #[arg(long, value_name = "WxH", default_value = "512x512", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Where the camera looks from: front (+Z), side (+X), top (+Y) or three-quarter.
    #[arg(long, value_enum, default_value_t = ViewArg::Front)]
    pub view: ViewArg,
    /// Orthographic (parallel) or perspective (35 deg field of view) projection.
    #[arg(long, value_enum, default_value_t = CameraArg::Ortho)]
    pub camera: CameraArg,
    /// Draw the targets of these IK handles (HANDLES.json, as `rigport ik` reads it) as
    /// markers, at each frame's time.
    #[arg(long, value_name = "HANDLES.json")]
    pub handles: Option<PathBuf>,
    /// Skinning method; `both` draws LBS (left) and DQS (right) with the same camera.
    /// Default: the method the source declares for its skin (LBS unless a USD mesh says
    /// `dualQuaternion`).
    #[arg(long, value_name = "lbs|dqs|both", value_parser = render_skinning)]
    pub skinning: Option<&'static [SkinningMethod]>,
    /// Do not draw the skeleton over the mesh.
    #[arg(long)]
    pub no_skeleton: bool,
    /// Do not draw the frame number.
    #[arg(long)]
    pub no_frame_counter: bool,
}

/// A half-open range of frame indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    /// First index kept.
    pub start: usize,
    /// First index not kept; `None`: through the last.
    pub end: Option<usize>,
}

/// `--view`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ViewArg {
    /// From +Z looking towards -Z.
    Front,
    /// From +X.
    Side,
    /// From +Y, looking down.
    Top,
    /// From the front-right, slightly above.
    ThreeQuarter,
}

/// `--camera`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CameraArg {
    /// Orthographic: sizes do not change with depth.
    Ortho,
    /// Perspective, 35 deg vertical field of view.
    Perspective,
}

/// `rigport render --skinning`: one method, or `both` (LBS left, DQS right).
fn render_skinning(s: &str) -> Result<&'static [SkinningMethod], String> {
    match s {
        "both" => Ok(rigport_render::LBS_AND_DQS),
        "lbs" => Ok(&[SkinningMethod::Lbs]),
        "dqs" => Ok(&[SkinningMethod::Dqs]),
        _ => Err(format!("{s:?}: expected lbs, dqs or both")),
    }
}

fn parse_range(s: &str) -> Result<FrameRange, String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("{s:?}: expected a..b"))?;
    let num = |t: &str| -> Result<Option<usize>, String> {
        if t.is_empty() {
            return Ok(None);
        }
        t.parse()
            .map(Some)
            .map_err(|_| format!("{t:?}: expected a frame index"))
    };
    let start = num(a)?.unwrap_or(0);
    let end = num(b)?;
    if end.is_some_and(|e| e <= start) {
        return Err(format!("{s:?}: the range is empty"));
    }
    Ok(FrameRange { start, end })
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("{s:?}: expected WxH, e.g. 512x512"))?;
    let px = |t: &str| -> Result<u32, String> {
        match t.parse::<u32>() {
            Ok(v) if (1..=16384).contains(&v) => Ok(v),
            _ => Err(format!("{t:?}: expected 1 to 16384 pixels")),
        }
    };
    Ok((px(w)?, px(h)?))
}

/// Runs `render`.
pub fn run(ctx: &Context, args: &RenderArgs) -> Result<()> {
    let request = RenderRequest {
        options: RenderOptions {
            width: args.size.0,
            height: args.size.1,
            view: match args.view {
                ViewArg::Front => View::Front,
                ViewArg::Side => View::Side,
                ViewArg::Top => View::Top,
                ViewArg::ThreeQuarter => View::ThreeQuarter,
            },
            projection: match args.camera {
                CameraArg::Ortho => Projection::Orthographic,
                CameraArg::Perspective => Projection::PERSPECTIVE,
            },
            skinning: &[],
            skeleton: !args.no_skeleton,
            frame_counter: !args.no_frame_counter,
        },
        skinning: args.skinning,
        clip: args.clip.clone(),
        fps: args.fps,
        frames: args.frames.map(|r| (r.start, r.end)),
        handles: args.handles.clone(),
        output: args.output.clone(),
    };
    ctx.run(|progress| rigport_pipeline::render(&args.input.to_input(), &request, progress))
}
