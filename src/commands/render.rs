//! `rigport render`: pictures of a rig or clip (PNG contact sheet or GIF/APNG animation),
//! drawn on the CPU by `rigport-render`, optionally with IK handle targets as markers.

use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};
use rigport_render::{Markers, Projection, RenderOptions, SkinningChoice, View};

use super::Context;
use crate::exit::OutputError;
use crate::{handles, input};

/// The GIF frame rate when `--fps` is not given.
const DEFAULT_GIF_FPS: f32 = 25.0;

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
    pub input: crate::cli::InputArgs,
    /// The picture to write: .png (contact sheet), .gif or .apng (animation).
    #[arg(long, short, value_name = "OUT.png|OUT.gif|OUT.apng")]
    pub output: PathBuf,
    /// The clip to draw (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Sample the clip at F frames per second (default: its key times for .png, 25 for
    /// animations).
    #[arg(long, value_name = "F")]
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
    #[arg(long, value_enum)]
    pub skinning: Option<SkinningArg>,
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

/// `--skinning`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SkinningArg {
    /// Linear blend skinning.
    Lbs,
    /// Dual quaternion skinning.
    Dqs,
    /// Both, side by side.
    Both,
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

/// The kind of picture, by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Png,
    Gif,
    Apng,
}

/// Runs `render`.
pub fn run(ctx: &Context, args: &RenderArgs) -> Result<()> {
    let ext = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let format = match ext.as_str() {
        "png" => Format::Png,
        "gif" => Format::Gif,
        "apng" => Format::Apng,
        _ => bail!(
            "{}: unknown picture format; expected .png (contact sheet), .gif or .apng (animation)",
            args.output.display()
        ),
    };
    let (plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    ctx.report(&imported.warnings)?;
    let asset = &imported.asset;
    let options = RenderOptions {
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
        skinning: match args.skinning {
            Some(SkinningArg::Lbs) => SkinningChoice::Lbs,
            Some(SkinningArg::Dqs) => SkinningChoice::Dqs,
            Some(SkinningArg::Both) => SkinningChoice::Both,
            None => match asset.skins.first().map(|s| s.method) {
                Some(rigport_model::SkinningMethod::Dqs) => SkinningChoice::Dqs,
                _ => SkinningChoice::Lbs,
            },
        },
        skeleton: !args.no_skeleton,
        frame_counter: !args.no_frame_counter,
    };
    // Read before rendering, so a bad file fails fast and writes nothing.
    let targets = match &args.handles {
        Some(path) => {
            let file = handles::load(path, &asset.skeleton)?;
            Some(handles::Targets::new(&asset.skeleton, file.tracks))
        }
        None => None,
    };
    let markers = targets.as_ref().map(|t| t as &dyn Markers);
    let clip =
        rigport_render::find_clip(asset, args.clip.as_deref()).with_context(|| plan.label())?;
    let fps = match (format, args.fps) {
        (Format::Gif | Format::Apng, None) => Some(DEFAULT_GIF_FPS),
        (_, fps) => fps,
    };
    let range = args.frames.map(|r| (r.start, r.end));
    let frames = rigport_render::frame_list(asset, clip, fps, range)
        .with_context(|| format!("{}: cannot sample the clip", plan.label()))?;
    if frames.is_empty() {
        bail!(
            "{}: --frames keeps no frame (the clip has {} at this rate)",
            plan.label(),
            rigport_render::frame_list(asset, clip, fps, None)?.len()
        );
    }
    let bytes = ctx
        .step("rendering", || match format {
            Format::Png => {
                rigport_render::render_sheet_png(asset, clip, &frames, markers, &options)
            }
            Format::Gif => rigport_render::render_gif(
                asset,
                clip,
                &frames,
                markers,
                rigport_render::gif_delay_cs(fps.unwrap_or(DEFAULT_GIF_FPS)),
                &options,
            ),
            Format::Apng => rigport_render::render_apng(
                asset,
                clip,
                &frames,
                markers,
                rigport_render::apng_delay_ms(fps.unwrap_or(DEFAULT_GIF_FPS)),
                &options,
            ),
        })
        .with_context(|| format!("{}: cannot render", plan.label()))?;
    rigport_export::write_atomic(&args.output, &bytes).with_context(|| OutputError {
        path: args.output.display().to_string(),
    })?;
    if !ctx.quiet {
        let what = match clip {
            Some(c) => format!("clip {:?}", c.name),
            None => "rest pose".into(),
        };
        eprintln!(
            "wrote {} ({what}, {} frame(s){})",
            args.output.display(),
            if format == Format::Png {
                frames.len().min(rigport_render::SHEET_FRAMES)
            } else {
                frames.len()
            },
            if format == Format::Png && frames.len() > rigport_render::SHEET_FRAMES {
                format!(" of {}", frames.len())
            } else {
                String::new()
            }
        );
    }
    Ok(())
}
