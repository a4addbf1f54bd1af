//! `rigport footlock`: hold mocap feet still during their ground contacts.
//!
//! [`run`] is the whole pipeline; [`crate::footlock()`] is the same function.

use rigport_ik::footlock::{FootlockOptions, Footlocked, footlock, resolve_feet, up_in_model};
use serde_json::json;

use crate::load::Input;
use crate::outputs::check_request;
use crate::progress::{Progress, step};
use crate::write::{Output, write_output};
use crate::{PipelineError, Report};

/// What `footlock` cleans, and where it writes.
///
/// ```
/// use rigport_ik::footlock::FootlockOptions;
/// use rigport_pipeline::footlock::FootlockRequest;
/// use rigport_pipeline::{footlock, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let request = FootlockRequest {
///     clip: Some("run".into()),
///     feet: vec!["Hand,Hand_end".into()],
///     options: FootlockOptions::default(),
///     json: true,
///     output: Output::new(dir.path().join("clean.glb")),
/// };
/// let err = footlock(&input, &request, &Silent).unwrap_err();
/// let text = rigport_pipeline::chain(&err);
/// assert!(text.contains("no clip named \"run\""), "{text}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct FootlockRequest {
    /// The clip (the first when `None`).
    pub clip: Option<String>,
    /// The feet as `ANKLE[,TOE]` joint names (found by name when empty).
    pub feet: Vec<String>,
    /// Contact thresholds, blending and stretch.
    pub options: FootlockOptions,
    /// Give the report as JSON ([`Report::output`]) rather than a table.
    pub json: bool,
    /// The output file and how it is written.
    pub output: Output,
}

/// Reads `input`, finds the feet and their contacts in one clip, pins them, and writes the
/// rig; the contacts and slides come back as a table or as JSON.
///
/// ```
/// use rigport_ik::footlock::FootlockOptions;
/// use rigport_pipeline::footlock::FootlockRequest;
/// use rigport_pipeline::{footlock, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("clean.glb");
/// // A skeleton whose joint names say nothing about feet: they must be named.
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let request = FootlockRequest {
///     clip: None,
///     feet: Vec::new(),
///     options: FootlockOptions::default(),
///     json: false,
///     output: Output::new(&out),
/// };
/// let err = footlock(&input, &request, &Silent).unwrap_err();
/// assert!(err.to_string().contains("cannot find the feet"), "{err}");
/// assert!(!out.exists());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// Invalid options; no such clip, or none; feet not found; as the import and
/// [`write_output`].
pub fn run(
    input: &Input,
    request: &FootlockRequest,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    check_request(input, &request.output.path, &[])?;
    let options = &request.options;
    options.validate().map_err(PipelineError::failed)?;
    let (plan, imported) = input.load_single(progress, "reading input")?;
    let (mut asset, mut warnings) = (imported.asset, imported.warnings);
    let index = asset
        .clip_index(request.clip.as_deref())
        .map_err(|e| PipelineError::step(plan.label(), e))?
        .ok_or_else(|| {
            PipelineError::Invalid(format!("{}: the rig has no clip to clean", plan.label()))
        })?;
    let (legs, found_by) = resolve_feet(&asset.skeleton, &request.feet)
        .map_err(|e| PipelineError::step(format!("{}: cannot find the feet", plan.label()), e))?;
    let clip = &asset.clips[index];
    let locked = step(progress, "locking feet", || {
        let up = up_in_model(&asset.frame);
        footlock(&asset.skeleton, clip, &legs, up, options)
    })
    .map_err(|e| PipelineError::step(format!("cannot lock the feet of clip {:?}", clip.name), e))?;
    let json = report_json(&clip.name, &locked, found_by);
    let table = report_table(&locked, found_by);
    warnings.extend(locked.warnings);
    asset.clips[index] = locked.clip;
    let line = write_output(asset, warnings, &request.output, &input.budget, progress)?;
    let mut report = Report::logged(line);
    if request.json {
        let text = serde_json::to_string_pretty(&json)
            .map_err(|e| PipelineError::step("cannot write the report as JSON", e))?;
        report.output = Some(text + "\n");
    } else {
        report.summary = Some(table);
    }
    Ok(report)
}

/// The report as JSON: the clip, and per foot its contacts (joint, frames, times, pin and
/// the joint's slide in the source and the result, in heights), slides, stretch and knee
/// step.
fn report_json(clip: &str, locked: &Footlocked, found_by: &str) -> serde_json::Value {
    let feet: Vec<_> = locked
        .feet
        .iter()
        .map(|f| {
            let contacts: Vec<_> = f
                .contacts
                .iter()
                .map(|c| {
                    json!({
                        "joint": c.joint, "start_frame": c.start_frame, "end_frame": c.end_frame,
                        "start_time": c.start_time, "end_time": c.end_time,
                        "frames": c.end_frame + 1 - c.start_frame,
                        "slide_before": c.slide_before, "slide_after": c.slide_after})
                })
                .collect();
            json!({"label": f.label, "ankle": f.ankle, "toe": f.toe, "contacts": contacts,
            "slide_before": {"max": f.before.max, "mean": f.before.mean},
            "slide_after": {"max": f.after.max, "mean": f.after.mean},
            "stretch": f.stretch, "unreached_frames": f.unreached,
            "knee_step_deg": f.knee_step_deg})
        })
        .collect();
    json!({"clip": clip, "frames": locked.frames, "fps": locked.fps,
        "height": locked.height, "feet_found_by": found_by, "feet": feet})
}

/// The report as text: one line per foot (slides, stretch, knee step), then a table with
/// one row per contact (a long clip has a hundred; a table cell would not hold them).
fn report_table(locked: &Footlocked, found_by: &str) -> String {
    let mut out = format!(
        "{} frames at {} fps, skeleton height {:.4}, feet: {found_by}; slides in heights\n\
         | foot | contacts | slide before max / mean | after max / mean | stretch | knee step beyond source |\n\
         | --- | ---: | ---: | ---: | ---: | ---: |\n",
        locked.frames, locked.fps, locked.height
    );
    for f in &locked.feet {
        out += &format!(
            "| {} | {} | {:.2e} / {:.2e} | {:.2e} / {:.2e} | {:.2}% | {:.1}° |\n",
            f.label,
            f.contacts.len(),
            f.before.max,
            f.before.mean,
            f.after.max,
            f.after.mean,
            100.0 * f.stretch,
            f.knee_step_deg
        );
    }
    if locked.feet.iter().any(|f| !f.contacts.is_empty()) {
        out += "\n| foot | joint | start s | end s | frames | slide before | after |\n\
                | --- | --- | ---: | ---: | ---: | ---: | ---: |\n";
        for f in &locked.feet {
            for c in &f.contacts {
                out += &format!(
                    "| {} | {} | {:.3} | {:.3} | {} | {:.2e} | {:.2e} |\n",
                    f.label,
                    c.joint,
                    c.start_time,
                    c.end_time,
                    c.end_frame + 1 - c.start_frame,
                    c.slide_before,
                    c.slide_after
                );
            }
        }
    }
    out
}
