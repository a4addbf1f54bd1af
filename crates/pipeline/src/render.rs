//! `rigport render`: pictures of a rig or clip (a PNG contact sheet, or a GIF or APNG
//! animation), drawn on the CPU by `rigport-render`, optionally with IK handle targets as
//! markers.

use std::path::{Path, PathBuf};

use rigport_ik::clip::HandleTargets;
use rigport_model::SkinningMethod;
use rigport_render::{Markers, RenderOptions};

use crate::load::Input;
use crate::outputs::{check_outputs, extension};
use crate::progress::{step, Progress};
use crate::{PipelineError, Report};

/// The GIF and APNG frame rate when none is given.
pub const DEFAULT_ANIMATION_FPS: f32 = 25.0;

/// The kind of picture, by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PictureFormat {
    /// `.png`: a contact sheet of up to [`rigport_render::SHEET_FRAMES`] frames.
    Png,
    /// `.gif`: a looping animation.
    Gif,
    /// `.apng`: a looping animation in full colour.
    Apng,
}

impl PictureFormat {
    /// The picture format `path`'s extension asks for.
    ///
    /// # Errors
    /// Any other extension (a usage error).
    pub fn of_path(path: &Path) -> Result<Self, PipelineError> {
        Ok(match extension(path).as_str() {
            "png" => Self::Png,
            "gif" => Self::Gif,
            "apng" => Self::Apng,
            _ => {
                return Err(PipelineError::Usage(format!(
                    "{}: unknown picture format; expected .png (contact sheet), .gif or .apng (animation)",
                    path.display()
                )))
            }
        })
    }
}

/// What `render` draws, and where it writes.
#[derive(Clone, Debug)]
pub struct RenderRequest {
    /// Size, view, camera, overlays; `skinning` is replaced by the asset's own method
    /// when [`RenderRequest::skinning`] is `None`.
    pub options: RenderOptions,
    /// The skinning methods, side by side (`None`: the first skin's own).
    pub skinning: Option<&'static [SkinningMethod]>,
    /// The clip (the first when `None`; the rest pose without clips).
    pub clip: Option<String>,
    /// Sample at this rate (default: the key times for a sheet, 25 for animations).
    pub fps: Option<f32>,
    /// Keep the sampled frames `start..end` (0-based, `end` excluded; `None`: to the last).
    pub frames: Option<(usize, Option<usize>)>,
    /// A `HANDLES.json` whose targets are drawn as markers.
    pub handles: Option<PathBuf>,
    /// The picture file.
    pub output: PathBuf,
}

/// Reads `input`, samples the clip and draws the pictures into `request.output`.
///
/// # Errors
/// An unknown picture format (a usage error); a bad handles file; no such clip; a frame
/// range that keeps nothing; as the import; an unwritable output.
pub fn run(
    input: &Input,
    request: &RenderRequest,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    let output = &request.output;
    let format = PictureFormat::of_path(output)?;
    let mut read = input.read_files();
    read.extend(request.handles.iter().cloned());
    check_outputs(&[output], &read)?;
    let (plan, imported) = input.load_single(progress, "reading input")?;
    progress.warnings(&imported.warnings)?;
    let asset = &imported.asset;
    let mut options = request.options;
    options.skinning = match request.skinning {
        Some(methods) => methods,
        None => match asset.skins.first().map(|s| s.method) {
            Some(SkinningMethod::Dqs) => &[SkinningMethod::Dqs],
            _ => &[SkinningMethod::Lbs],
        },
    };
    // Read before rendering, so a bad file fails fast and writes nothing.
    let targets = match &request.handles {
        Some(path) => {
            let file = rigport_import::json::handles::read(path, &asset.skeleton)?;
            Some(HandleTargets::new(&asset.skeleton, file.tracks))
        }
        None => None,
    };
    let markers = targets.as_ref().map(|t| t as &dyn Markers);
    let clip = rigport_render::find_clip(asset, request.clip.as_deref())
        .map_err(|e| PipelineError::step(plan.label(), e))?;
    let fps = match (format, request.fps) {
        (PictureFormat::Gif | PictureFormat::Apng, None) => Some(DEFAULT_ANIMATION_FPS),
        (_, fps) => fps,
    };
    let cannot_sample =
        |e| PipelineError::step(format!("{}: cannot sample the clip", plan.label()), e);
    let frames =
        rigport_render::frame_list(asset, clip, fps, request.frames).map_err(cannot_sample)?;
    if frames.is_empty() {
        let all = rigport_render::frame_list(asset, clip, fps, None).map_err(cannot_sample)?;
        return Err(PipelineError::Invalid(format!(
            "{}: the frame range keeps no frame (the clip has {} at this rate)",
            plan.label(),
            all.len()
        )));
    }
    let animation_fps = fps.unwrap_or(DEFAULT_ANIMATION_FPS);
    let bytes = step(progress, "rendering", || match format {
        PictureFormat::Png => {
            rigport_render::render_sheet_png(asset, clip, &frames, markers, &options)
        }
        PictureFormat::Gif => rigport_render::render_gif(
            asset,
            clip,
            &frames,
            markers,
            rigport_render::gif_delay_cs(animation_fps),
            &options,
        ),
        PictureFormat::Apng => rigport_render::render_apng(
            asset,
            clip,
            &frames,
            markers,
            rigport_render::apng_delay_ms(animation_fps),
            &options,
        ),
    })
    .map_err(|e| PipelineError::step(format!("{}: cannot render", plan.label()), e))?;
    rigport_export::write_atomic(output, &bytes).map_err(|e| PipelineError::output(output, e))?;
    let what = match clip {
        Some(c) => format!("clip {:?}", c.name),
        None => "rest pose".into(),
    };
    let sheet = format == PictureFormat::Png;
    Ok(Report::logged(format!(
        "wrote {} ({what}, {} frame(s){})",
        output.display(),
        if sheet {
            frames.len().min(rigport_render::SHEET_FRAMES)
        } else {
            frames.len()
        },
        if sheet && frames.len() > rigport_render::SHEET_FRAMES {
            format!(" of {}", frames.len())
        } else {
            String::new()
        }
    )))
}
