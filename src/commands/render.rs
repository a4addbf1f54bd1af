//! `rigport render`: pictures of a rig or clip (PNG contact sheet or GIF/APNG animation),
//! drawn on the CPU by `rigport-render`, optionally with IK handle targets as markers.

use anyhow::{bail, Context as _, Result};
use rigport_ik::clip::HandleTargets;
use rigport_model::SkinningMethod;
use rigport_render::{Markers, Projection, RenderOptions, View};

use crate::cli::{CameraArg, RenderArgs, ViewArg};
use crate::context::Context;
use crate::exit::{OutputError, UsageError};
use crate::input;

/// The GIF frame rate when `--fps` is not given.
const DEFAULT_GIF_FPS: f32 = 25.0;

/// The kind of picture, by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Format {
    Png,
    Gif,
    Apng,
}

/// The picture format `path`'s extension asks for.
///
/// # Errors
/// Any other extension ([`UsageError`], exit code 2).
pub(crate) fn format_of(path: &std::path::Path) -> Result<Format> {
    Ok(match crate::output::extension(path).as_str() {
        "png" => Format::Png,
        "gif" => Format::Gif,
        "apng" => Format::Apng,
        _ => {
            return Err(UsageError(format!(
            "{}: unknown picture format; expected .png (contact sheet), .gif or .apng (animation)",
            path.display()
        ))
            .into())
        }
    })
}

/// Runs `render`.
pub fn run(ctx: &Context, args: &RenderArgs) -> Result<()> {
    let format = format_of(&args.output)?;
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
            Some(methods) => methods,
            None => match asset.skins.first().map(|s| s.method) {
                Some(SkinningMethod::Dqs) => &[SkinningMethod::Dqs],
                _ => &[SkinningMethod::Lbs],
            },
        },
        skeleton: !args.no_skeleton,
        frame_counter: !args.no_frame_counter,
    };
    // Read before rendering, so a bad file fails fast and writes nothing.
    let targets = match &args.handles {
        Some(path) => {
            let file = rigport_import::json::handles::read(path, &asset.skeleton)?;
            Some(HandleTargets::new(&asset.skeleton, file.tracks))
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
