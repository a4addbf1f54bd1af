//! `rigport render`: pictures of a rig or clip (a PNG contact sheet, or a GIF or APNG
//! animation), drawn on the CPU by `rigport-render`, optionally with IK handle targets as
//! markers.
//!
//! [`run`] is the whole pipeline; [`crate::render()`] is the same function.

use std::path::{Path, PathBuf};

use rigport_ik::clip::HandleTargets;
use rigport_model::SkinningMethod;
use rigport_render::{Markers, RenderOptions};

use crate::load::Input;
use crate::outputs::{check_not_read, extension};
use crate::progress::{Progress, step};
use crate::{PipelineError, Report};

/// The GIF and APNG frame rate when none is given.
pub(crate) const DEFAULT_ANIMATION_FPS: f32 = 25.0;

/// The kind of picture, by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PictureFormat {
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
    pub(crate) fn of_path(path: &Path) -> Result<Self, PipelineError> {
        Ok(match extension(path).as_str() {
            "png" => Self::Png,
            "gif" => Self::Gif,
            "apng" => Self::Apng,
            _ => {
                return Err(PipelineError::Usage(format!(
                    "{}: unknown picture format; expected .png (contact sheet), .gif or .apng (animation)",
                    path.display()
                )));
            }
        })
    }
}

/// A half-open range of sampled frames, `a..b` (0-based, `b` excluded; `a..` and `..b`
/// too).
///
/// ```
/// use rigport_pipeline::render::FrameRange;
///
/// assert_eq!("2..7".parse(), Ok(FrameRange { start: 2, end: Some(7) }));
/// assert_eq!("..3".parse(), Ok(FrameRange { start: 0, end: Some(3) }));
/// assert!("5..2".parse::<FrameRange>().is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    /// First index kept.
    pub start: usize,
    /// First index not kept; `None`: through the last.
    pub end: Option<usize>,
}

impl std::str::FromStr for FrameRange {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
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
        Ok(Self { start, end })
    }
}

/// A picture size `WxH`, each 1 to 16384 pixels.
///
/// ```
/// assert_eq!(rigport_pipeline::render::picture_size("640x480"), Ok((640, 480)));
/// assert!(rigport_pipeline::render::picture_size("0x10").is_err());
/// ```
///
/// # Errors
/// Anything else, saying what is expected.
pub fn picture_size(s: &str) -> Result<(u32, u32), String> {
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

/// A projection by name: `ortho` (parallel) or `perspective` (35 deg vertical field of
/// view, [`rigport_render::Projection::PERSPECTIVE`]).
///
/// ```
/// use rigport_render::Projection;
///
/// assert_eq!(rigport_pipeline::render::projection("ortho"), Ok(Projection::Orthographic));
/// assert_eq!(rigport_pipeline::render::projection("perspective"), Ok(Projection::PERSPECTIVE));
/// ```
///
/// # Errors
/// Any other name.
pub fn projection(s: &str) -> Result<rigport_render::Projection, String> {
    match s {
        "ortho" => Ok(rigport_render::Projection::Orthographic),
        "perspective" => Ok(rigport_render::Projection::PERSPECTIVE),
        _ => Err(format!("{s:?}: expected ortho or perspective")),
    }
}

/// Skinning methods by name: `lbs`, `dqs`, or `both` ([`rigport_render::LBS_AND_DQS`]:
/// LBS on the left, DQS on the right).
///
/// ```
/// use rigport_model::SkinningMethod;
///
/// assert_eq!(rigport_pipeline::render::skinning_methods("dqs"), Ok(&[SkinningMethod::Dqs][..]));
/// assert_eq!(rigport_pipeline::render::skinning_methods("both").map(<[_]>::len), Ok(2));
/// ```
///
/// # Errors
/// Any other name.
pub fn skinning_methods(s: &str) -> Result<&'static [SkinningMethod], String> {
    match s {
        "both" => Ok(rigport_render::LBS_AND_DQS),
        "lbs" => Ok(&[SkinningMethod::Lbs]),
        "dqs" => Ok(&[SkinningMethod::Dqs]),
        _ => Err(format!("{s:?}: expected lbs, dqs or both")),
    }
}

/// What `render` draws, and where it writes.
///
/// ```
/// use rigport_pipeline::render::RenderRequest;
/// use rigport_pipeline::{load::Input, progress::Silent, render};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("walk.gif");
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// // An animation (the extension chooses GIF) at 20 frames per second.
/// let request = RenderRequest {
///     options: rigport_render::RenderOptions { width: 48, height: 48, ..Default::default() },
///     skinning: None,
///     clip: Some("end_sites".into()),
///     fps: Some(20.0),
///     frames: None,
///     handles: None,
///     output: out.clone(),
/// };
/// render(&input, &request, &Silent)?;
/// assert_eq!(&std::fs::read(&out)?[..6], b"GIF89a");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
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
    /// Keep these of the sampled frames.
    pub frames: Option<FrameRange>,
    /// A `HANDLES.json` whose targets are drawn as markers.
    pub handles: Option<PathBuf>,
    /// The picture file.
    pub output: PathBuf,
}

/// Reads `input`, samples the clip and draws the pictures into `request.output`.
///
/// ```
/// use rigport_pipeline::render::RenderRequest;
/// use rigport_pipeline::{load::Input, progress::Silent, render};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("walk.png");
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let request = RenderRequest {
///     options: rigport_render::RenderOptions { width: 64, height: 64, ..Default::default() },
///     skinning: None,
///     clip: None,
///     fps: None,
///     frames: None,
///     handles: None,
///     output: out.clone(),
/// };
/// render(&input, &request, &Silent)?;
/// assert_eq!(&std::fs::read(&out)?[1..4], b"PNG");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
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
    let extra: Vec<&std::path::Path> = request.handles.iter().map(|p| p.as_path()).collect();
    check_not_read(input, output, &extra)?;
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
        rigport_render::frame_list(asset, clip, fps, request.frames.map(|r| (r.start, r.end)))
            .map_err(cannot_sample)?;
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
