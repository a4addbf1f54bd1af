//! `rigport ik`: IK handles over time (`HANDLES.json`), solved per frame and baked into a
//! clip placed first.
//!
//! [`run`] is the whole pipeline; [`crate::ik()`] is the same function.

use std::path::PathBuf;

use rigport_ik::clip::{ClipSolveOptions, solve_clip_on};
use serde::Serialize;

use crate::load::Input;
use crate::outputs::check_request;
use crate::progress::{Progress, step};
use crate::write::{Output, write_output};
use crate::{PipelineError, Report};

/// What `ik` solves, and where it writes.
///
/// ```
/// use rigport_ik::clip::ClipSolveOptions;
/// use rigport_pipeline::ik::IkOptions;
/// use rigport_pipeline::{ik, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let handles = dir.path().join("nod.json");
/// std::fs::write(&handles, r#"{"fps": 4, "handles": [{"joint": "bone_2", "relative": true,
///     "keys": [{"time": 0, "position": [0, 0, 0]}, {"time": 0.5, "position": [0, -0.05, 0]}]}]}"#)?;
/// let f = "../../fixtures/pinocchio/branch";
/// let input = Input::new(vec![format!("{f}.obj").into(), format!("{f}_skeleton.out").into(),
///     format!("{f}_attachment.out").into()]);
/// // Without `json`, the residuals come back as a table, one row per handle.
/// let options = IkOptions {
///     handles,
///     solve: ClipSolveOptions::default(),
///     json: false,
///     output: Output::new(dir.path().join("nod.glb")),
/// };
/// let report = ik(&input, &options, &Silent)?;
/// assert!(report.summary.as_deref().is_some_and(|t| t.contains("bone_2")));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct IkOptions {
    /// The `HANDLES.json` file; its stem names the clip.
    pub handles: PathBuf,
    /// The solver and its settings.
    pub solve: ClipSolveOptions,
    /// Give the report as JSON ([`Report::output`]) rather than a summary.
    pub json: bool,
    /// The output file and how it is written.
    pub output: Output,
}

/// Per-handle residual summary.
#[derive(Serialize)]
struct HandleSummary {
    joint: String,
    max_residual: f32,
    mean_residual: f32,
    worst_frame: usize,
    worst_time: f32,
    frames_over_tolerance: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    reached: Option<Vec<bool>>,
}

/// The whole report (JSON).
#[derive(Serialize)]
struct Summary {
    clip: String,
    solver: &'static str,
    frames: usize,
    fps: f32,
    tolerance: f32,
    mean_iterations: f32,
    handles: Vec<HandleSummary>,
}

/// Reads `input` and the handles, solves them into a clip placed first, and writes the
/// rig; the residuals come back as a table or as JSON.
///
/// ```
/// use rigport_ik::clip::ClipSolveOptions;
/// use rigport_pipeline::ik::IkOptions;
/// use rigport_pipeline::{ik, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let handles = dir.path().join("reach.handles.json");
/// std::fs::write(&handles, r#"{"fps": 10, "handles": [{"joint": "bone_2", "relative": true,
///     "keys": [{"time": 0, "position": [0, 0, 0]}, {"time": 1, "position": [0.1, -0.1, 0]}]}]}"#)?;
/// let f = "../../fixtures/pinocchio/branch";
/// let input = Input::new(vec![format!("{f}.obj").into(), format!("{f}_skeleton.out").into(),
///     format!("{f}_attachment.out").into()]);
/// let options = IkOptions {
///     handles,
///     solve: ClipSolveOptions::default(),
///     json: true,
///     output: Output::new(dir.path().join("reach.glb")),
/// };
/// let report = ik(&input, &options, &Silent)?;
/// let json: serde_json::Value = serde_json::from_str(report.output.as_deref().unwrap_or(""))?;
/// assert_eq!(json["frames"], 11);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// The handles file's errors (with their JSON path); a failed solve; as the import and
/// [`write_output`].
pub fn run(
    input: &Input,
    options: &IkOptions,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    check_request(input, &options.output.path, &[&options.handles])?;
    let (_plan, imported) = input.load_single(progress, "reading input")?;
    let (mut asset, mut warnings) = (imported.asset, imported.warnings);
    let handles = rigport_import::json::handles::read(&options.handles, &asset.skeleton)?;
    rigport_import::json::handles::check_base(&options.handles, &handles, &asset.clips)?;
    let name = options
        .handles
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "ik".into());
    let solved = step(progress, "solving", || {
        solve_clip_on(
            &asset.skeleton,
            &asset.clips,
            &handles,
            &options.solve,
            &name,
            &options.handles.display().to_string(),
        )
    })
    .map_err(PipelineError::failed)?;
    warnings.extend(solved.warnings.iter().cloned());
    let summary = Summary {
        clip: name,
        solver: solved.solver,
        frames: solved.frames,
        fps: solved.fps,
        tolerance: solved.tolerance,
        mean_iterations: solved.mean_iterations,
        handles: solved
            .handles
            .iter()
            .map(|h| HandleSummary {
                joint: h.joint.clone(),
                max_residual: h.max_residual,
                mean_residual: h.mean_residual,
                worst_frame: h.worst_frame,
                worst_time: h.worst_time,
                frames_over_tolerance: h.frames_over_tolerance,
                reached: h.reached.clone(),
            })
            .collect(),
    };
    asset.clips.insert(0, solved.clip);
    let line = write_output(asset, warnings, &options.output, &input.budget, progress)?;
    let mut report = Report::logged(line);
    if options.json {
        let text = serde_json::to_string_pretty(&summary)
            .map_err(|e| PipelineError::step("cannot write the report as JSON", e))?;
        report.output = Some(text + "\n");
    } else {
        let mut out = format!(
            "{} frames at {} fps, solver {}, {:.1} iterations per frame, tolerance {:.3e}\n",
            summary.frames, summary.fps, summary.solver, summary.mean_iterations, summary.tolerance
        );
        out += "| handle | max residual | mean residual | worst frame | frames over tolerance |\n";
        out += "| --- | ---: | ---: | ---: | ---: |\n";
        for h in &summary.handles {
            out += &format!(
                "| {} | {:.3e} | {:.3e} | {} ({:.3} s) | {} |\n",
                h.joint,
                h.max_residual,
                h.mean_residual,
                h.worst_frame,
                h.worst_time,
                h.frames_over_tolerance
            );
        }
        for line in solved.handles.iter().filter_map(|h| h.reached_summary()) {
            out += &line;
            out.push('\n');
        }
        report.summary = Some(out);
    }
    Ok(report)
}
