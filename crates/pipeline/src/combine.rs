//! `rigport combine`: a rig and its clip library in one file. Each motion (a file or a
//! folder of BVH, ASF/AMC, glTF, USD, FBX or COLLADA clips) becomes named clips on the
//! rig's skeleton: taken as they are when the motion's skeleton is the rig's (the same
//! joints and rest pose, within the tolerances of `combine/same.rs`: rest translations
//! within 1e-4 of the rig's size, rotations within 1e-4 rad), retargeted otherwise
//! ([`crate::retarget()`]'s engine, map and foot planting).
//!
//! The rig is read once; the motions are read and retargeted in parallel (rayon), and
//! their clips kept in the order the motions are given (a folder's files in sorted order),
//! so the output's bytes do not depend on the thread count. Names come from the file stem
//! (a file of one clip) or the clips' own names (a file of several); a repeated name gets
//! `_2`, `_3`, ... and a warning (W003). A motion that fails to read stops the command
//! (nothing is written), its file named.
//!
//! [`run`] is the whole pipeline; [`crate::combine()`] is the same function.

mod motions;
mod names;
mod rows;
mod same;

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;
use rigport_anim::retime::{Retime, retime};
use rigport_anim::root_motion::RootMotionOptions;
use rigport_ik::footlock::{Leg, footlock};
use rigport_ik::retarget::{RetargetOptions, target_legs};
use rigport_import::detect::DetectError;
use rigport_model::glam::Vec3;
use rigport_model::{Asset, Clip, Warning};
use serde_json::json;

use crate::load::Input;
use crate::progress::Progress;
use crate::write::{Output, write_output};
use crate::{PipelineError, Report};
use motions::Motion;
use rows::{How, Row};

/// What `combine` puts onto the rig, and where it writes.
///
/// ```
/// use rigport_pipeline::combine::CombineRequest;
/// use rigport_pipeline::write::Output;
///
/// let request = CombineRequest {
///     motions: vec!["walk.bvh".into(), "mocap/".into()],
///     names: vec![("walk.bvh".into(), "stroll".into())],
///     ..CombineRequest::new(Output::new("library.glb"))
/// };
/// assert_eq!(request.fps, None);
/// ```
#[derive(Clone, Debug, Default)]
pub struct CombineRequest {
    /// The motion files and folders, in order.
    pub motions: Vec<PathBuf>,
    /// Clip names given per motion file (`FILE`, `NAME`): `FILE` is the path as given,
    /// its file name or its stem; a file of several clips names them `NAME_<clip>`.
    pub names: Vec<(String, String)>,
    /// A `MAP.json` for the retargeted motions (default: by name, else by body roles).
    pub map: Option<PathBuf>,
    /// Planting and hand matching of retargeted clips (planting also of taken ones).
    pub options: RetargetOptions,
    /// Resample every clip at this rate (frames per second); `None` keeps each clip's
    /// key times.
    pub fps: Option<f32>,
    /// Give the report as JSON ([`Report::output`]) rather than a table.
    pub json: bool,
    /// The output file and how it is written (key reduction included).
    pub output: Output,
    /// The clips' root motion ([`crate::root_motion`]).
    pub root_motion: RootMotionOptions,
}

impl CombineRequest {
    /// No motions yet, written to `output` with the defaults.
    ///
    /// ```
    /// let request = rigport_pipeline::combine::CombineRequest::new(
    ///     rigport_pipeline::write::Output::new("library.usdz"));
    /// assert!(request.motions.is_empty() && !request.json);
    /// ```
    pub fn new(output: Output) -> Self {
        Self {
            output,
            ..Self::default()
        }
    }
}

/// Splits inputs given as `RIG MOTION...` into the rig's input and the motions: the rig
/// is the first path, or the Pinocchio files named explicitly (then every path is a
/// motion); AMC files given for the rig's `.asf` are motions too.
///
/// ```
/// use rigport_pipeline::{combine::split_inputs, load::Input};
///
/// let (rig, motions) = split_inputs(Input::new(vec!["07-walk.asf".into(), "07_05-walk.amc".into()]));
/// assert_eq!(rig.files.paths, [std::path::PathBuf::from("07-walk.asf")]);
/// assert_eq!(motions, [std::path::PathBuf::from("07_05-walk.amc")]);
/// ```
pub fn split_inputs(mut input: Input) -> (Input, Vec<PathBuf>) {
    let files = &mut input.files;
    let mut motions = std::mem::take(&mut files.paths);
    if files.mesh.is_none() && files.skeleton.is_none() && files.attachment.is_none() {
        files.paths = motions.drain(..1.min(motions.len())).collect();
    }
    motions.append(&mut files.motions);
    (input, motions)
}

/// A clip name given for a motion file as `FILE=NAME` (split at the last `=`).
///
/// ```
/// use rigport_pipeline::combine::parse_name;
///
/// assert_eq!(parse_name("walk.bvh=stroll"), Ok(("walk.bvh".into(), "stroll".into())));
/// assert!(parse_name("walk.bvh").is_err());
/// ```
///
/// # Errors
/// No `=`.
pub fn parse_name(text: &str) -> Result<(String, String), String> {
    let (file, name) = text.rsplit_once('=').ok_or("expected FILE=NAME")?;
    Ok((file.to_string(), name.to_string()))
}

/// One motion's clips on the rig, with their rows (unnamed yet) and warnings.
struct Gathered {
    clips: Vec<(Clip, Row, names::Unnamed)>,
    warnings: Vec<Warning>,
}

/// Reads the rig (`rig`, one asset with a skeleton) and every motion of `request`, puts
/// each motion's clips on the rig, and writes the rig with all of them.
///
/// ```
/// use rigport_pipeline::combine::CombineRequest;
/// use rigport_pipeline::{combine, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let bvh = "../../fixtures/bvh/end_sites.bvh";
/// let request = CombineRequest {
///     // The same clip twice: the second is renamed `end_sites_2`.
///     motions: vec![bvh.into(), bvh.into()],
///     json: true,
///     ..CombineRequest::new(Output::new(dir.path().join("both.glb")))
/// };
/// let report = combine(&Input::new(vec![bvh.into()]), &request, &Silent)?;
/// let json: serde_json::Value = serde_json::from_str(report.output.as_deref().unwrap_or(""))?;
/// assert_eq!(json["clips"][1]["clip"], "end_sites_2");
/// assert_eq!(json["clips"][0]["how"], "taken");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// A rig without a skeleton, no motion, or a name given for no motion file (usage
/// errors); a motion that cannot be read or has no clip (naming it); a failed retarget;
/// as [`write_output`].
pub fn run(
    rig: &Input,
    request: &CombineRequest,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    // The AMC frame rate is for the motions' AMC files when the rig is no `.asf`.
    let fps_without_asf = matches!(
        crate::load::single_plan(&rig.files),
        Err(PipelineError::Detect(DetectError::FpsWithoutAsf))
    );
    let amc_fps = rig.files.amc_fps;
    let mut rig = rig.clone();
    if fps_without_asf {
        rig.files.amc_fps = None;
    }
    let rig = &rig;
    let rig_plan = crate::load::single_plan(&rig.files)?;
    let motions = motions::expand(&request.motions, &rig_plan, amc_fps)?;
    let mut read: Vec<PathBuf> = motions.iter().flat_map(|m| m.source.files()).collect();
    read.extend(request.map.iter().cloned());
    let read: Vec<&std::path::Path> = read.iter().map(PathBuf::as_path).collect();
    crate::outputs::check_request(rig, &request.output.path, &read)?;
    let (_, loaded) = rig.load_single(progress, "reading rig")?;
    let (mut asset, mut warnings) = (loaded.asset, loaded.warnings);
    if asset.skeleton.is_empty() {
        return Err(PipelineError::Usage(format!(
            "{}: the rig has no skeleton to put clips on",
            rig_plan.label()
        )));
    }
    let up = asset.frame.up_in_model();
    let legs = target_legs(&asset.skeleton, up);
    let reading = Input {
        bone_mesh: false,
        ..rig.clone()
    };
    let done = AtomicUsize::new(0);
    let gathered: Vec<Result<Gathered, PipelineError>> = motions
        .par_iter()
        .map(|motion| {
            let result = gather(motion, &reading, &asset, &legs, up, request);
            let n = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress.count("combining motions", n, motions.len());
            result
        })
        .collect();
    progress.step_done();
    let (mut clips, mut rows, mut unnamed) = (Vec::new(), Vec::new(), Vec::new());
    for result in gathered {
        let g = result?;
        warnings.extend(g.warnings);
        for (clip, row, name) in g.clips {
            clips.push(clip);
            rows.push(row);
            unnamed.push(name);
        }
    }
    let (names, renamed) = names::name_clips(&unnamed, &request.names)?;
    warnings.extend(renamed);
    for ((clip, row), name) in clips.iter_mut().zip(&mut rows).zip(names) {
        clip.name.clone_from(&name);
        row.name = name;
    }
    asset.clips = clips;
    let moved = crate::root_motion::apply(&mut asset, &request.root_motion)?;
    let line = write_output(asset, warnings, &request.output, &rig.budget, progress)?;
    let mut report = Report::logged(line);
    report.log.extend(moved.iter().flat_map(|m| m.lines()));
    if request.json {
        let mut value = json!({"rig": rig_plan.label(), "output": request.output.path,
            "clips": rows::json(&rows)});
        if let Some(moved) = &moved {
            value["root_motion"] = moved.json();
        }
        let text = serde_json::to_string_pretty(&value)
            .map_err(|e| PipelineError::step("cannot write the report as JSON", e))?;
        report.output = Some(text + "\n");
    } else {
        report.summary = Some(rows::summary(&rows));
    }
    Ok(report)
}

/// Reads `motion` and puts each of its clips on `rig`: taken when the skeletons are the
/// same ([`same::same_skeleton`]), else retarget; planted when asked; resampled when asked.
///
/// # Errors
/// The import's; a motion given as a file without clips; a failed retarget or planting.
fn gather(
    motion: &Motion,
    input: &Input,
    rig: &Asset,
    legs: &[Leg],
    up: Vec3,
    request: &CombineRequest,
) -> Result<Gathered, PipelineError> {
    let label = motion.source.label();
    let imported = input.load(&motion.source, &crate::progress::Silent)?;
    let (source, mut warnings) = (imported.asset, imported.warnings);
    if source.clips.is_empty() {
        if motion.from_folder {
            warnings.push(Warning::Note {
                location: label,
                message: "no clip: passed over".into(),
            });
            return Ok(Gathered {
                clips: Vec::new(),
                warnings,
            });
        }
        return Err(PipelineError::Invalid(format!(
            "{label}: no clip to combine"
        )));
    }
    let taken = same::same_skeleton(rig, &source);
    let options = &request.options;
    let mut clips = Vec::new();
    for (index, found) in source.clips.iter().enumerate() {
        let (mut clip, slide, planted) = if taken {
            let locked = measure(rig, legs, up, found, request);
            let slide = locked.as_ref().map(|l| slides(&l.feet));
            match locked {
                Some(locked) if options.plant_feet => {
                    warnings.extend(locked.warnings);
                    (locked.clip, slide, true)
                }
                None if options.plant_feet => {
                    return Err(PipelineError::Invalid(format!(
                        "{label}: cannot plant the feet of clip {:?}: the rig shows no legs, or the clip has fewer than two frames",
                        found.name
                    )));
                }
                _ => (found.clone(), slide, false),
            }
        } else {
            let done =
                crate::retarget::clip_onto(&source, found, rig, request.map.as_deref(), options)
                    .map_err(|e| in_motion(&label, e))?;
            warnings.extend(done.warnings);
            let slide = match (done.report.planted, done.report.feet.is_empty()) {
                (true, _) => Some(slides(&done.report.feet)),
                (false, true) => None,
                (false, false) => measure(rig, legs, up, &done.clip, request)
                    .map(|l| (slides(&done.report.feet).0, slides(&l.feet).1)),
            };
            (done.clip, slide, done.report.planted)
        };
        if let Some(fps) = request.fps {
            clip = retime(&clip, &rig.skeleton, &Retime::Fps(fps)).map_err(|e| {
                PipelineError::step(format!("{label}: cannot resample clip {:?}", found.name), e)
            })?;
        }
        let row = Row {
            name: String::new(),
            source: motion
                .file_of(index, source.clips.len())
                .display()
                .to_string(),
            source_clip: found.name.clone(),
            how: if taken { How::Taken } else { How::Retargeted },
            frames: (clip.tracks.iter())
                .map(|t| t.times.len())
                .max()
                .unwrap_or(0),
            duration_s: clip.duration(),
            slide,
            planted,
        };
        let unnamed = names::Unnamed {
            file: motion.file_of(index, source.clips.len()),
            own: found.name.clone(),
            index,
            of: if matches!(motion.source, rigport_import::detect::Source::AsfAmc { .. }) {
                1
            } else {
                source.clips.len()
            },
        };
        clips.push((clip, row, unnamed));
    }
    Ok(Gathered { clips, warnings })
}

/// The feet of `clip` on the rig locked as `retarget --plant-feet` locks them (`None`
/// without legs, or for a clip too short).
fn measure(
    rig: &Asset,
    legs: &[Leg],
    up: Vec3,
    clip: &Clip,
    request: &CombineRequest,
) -> Option<rigport_ik::footlock::Footlocked> {
    if legs.is_empty() {
        return None;
    }
    footlock(&rig.skeleton, clip, legs, up, &request.options.footlock).ok()
}

/// The worst slide over the feet, before and after planting (rig heights).
fn slides(feet: &[rigport_ik::footlock::FootReport]) -> (f32, f32) {
    feet.iter().fold((0.0, 0.0), |(b, a), f| {
        (f32::max(b, f.before.max), f32::max(a, f.after.max))
    })
}

/// `err` with the motion's file named in front of a step's message.
fn in_motion(label: &str, err: PipelineError) -> PipelineError {
    match err {
        PipelineError::Step { message, source } => PipelineError::Step {
            message: format!("{label}: {message}"),
            source,
        },
        PipelineError::Invalid(message) => PipelineError::Invalid(format!("{label}: {message}")),
        err => err,
    }
}
