//! `rigport retarget`'s pipeline: a source asset's clip put onto a target rig through a
//! joint map (a `MAP.json` file, or the body roles both skeletons' structure shows), with
//! the report as JSON.
//!
//! [`run`] is the whole pipeline; [`crate::retarget()`] is the same function.

use std::path::Path;

use rigport_anim::root_motion::RootMotionOptions;
use rigport_ik::footlock::up_in_model;
use rigport_ik::retarget::{JointMap, Limb, RetargetInput, RetargetOptions, auto_map, retarget};
use rigport_ik::retarget::{RetargetReport, Retargeted};
use rigport_model::{Asset, Clip, Warning};
use serde_json::{Value, json};

use crate::load::Input;
use crate::progress::{Progress, step};
use crate::write::{Output, write_output};
use crate::{PipelineError, Report};

/// What `retarget` puts onto which rig, and where it writes.
///
/// ```
/// use rigport_pipeline::retarget::RetargetRequest;
/// use rigport_pipeline::{load::Input, progress::Silent, retarget, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let bvh = "../../fixtures/bvh/end_sites.bvh";
/// // A joint map file that does not exist fails before anything is written.
/// let out = dir.path().join("onto.glb");
/// let request = RetargetRequest {
///     onto: Input::new(vec![bvh.into()]),
///     clip: None,
///     map: Some(dir.path().join("missing_map.json")),
///     options: Default::default(),
///     json: false,
///     output: Output::new(&out),
///     root_motion: Default::default(),
/// };
/// assert!(retarget(&Input::new(vec![bvh.into()]), &request, &Silent).is_err());
/// assert!(!out.exists());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct RetargetRequest {
    /// The rig the motion goes onto (read like any input).
    pub onto: Input,
    /// The source clip (the first when `None`).
    pub clip: Option<String>,
    /// A `MAP.json` (default: [`auto_map`]: by name, else by body structure).
    pub map: Option<std::path::PathBuf>,
    /// Planting and hand matching.
    pub options: RetargetOptions,
    /// Give the report as JSON ([`Report::output`]) rather than a summary.
    pub json: bool,
    /// The output file and how it is written.
    pub output: Output,
    /// The retargeted clip's root motion, changed on the rig ([`crate::root_motion`]);
    /// the travel is in the report (`"root_motion"` in JSON).
    pub root_motion: RootMotionOptions,
}

/// Reads the motion (`input`) and the rig (`request.onto`), puts the clip onto the rig,
/// and writes the rig with it; the report comes back as a summary or as JSON.
///
/// ```
/// use rigport_anim::root_motion::{RootMotion, RootMotionOptions};
/// use rigport_pipeline::retarget::RetargetRequest;
/// use rigport_pipeline::{load::Input, progress::Silent, retarget, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let bvh = "../../fixtures/bvh/end_sites.bvh";
/// let request = RetargetRequest {
///     onto: Input::new(vec![bvh.into()]),
///     clip: None,
///     map: None,
///     options: Default::default(),
///     json: true,
///     output: Output::new(dir.path().join("onto.glb")),
///     // The travel moved onto a root joint, and listed in the report.
///     root_motion: RootMotionOptions { mode: RootMotion::Extract, ..Default::default() },
/// };
/// let report = retarget(&Input::new(vec![bvh.into()]), &request, &Silent)?;
/// let json: serde_json::Value = serde_json::from_str(report.output.as_deref().unwrap_or(""))?;
/// assert!(json["frames"].as_u64().is_some());
/// assert_eq!(json["root_motion"]["mode"], "extract");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// No such clip, a bad map file (with its JSON path), no joints in common, or a failed
/// solve; as the imports and [`write_output`].
pub fn run(
    input: &Input,
    request: &RetargetRequest,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    let mut read = request.onto.read_files();
    read.extend(request.map.iter().cloned());
    let read: Vec<&std::path::Path> = read.iter().map(std::path::PathBuf::as_path).collect();
    crate::outputs::check_request(input, &request.output.path, &read)?;
    let (plan, source) = input.load_single(progress, "reading motion")?;
    let (rig_plan, target) = request.onto.load_single(progress, "reading rig")?;
    let done = step(progress, "retargeting", || {
        onto(
            &source.asset,
            target.asset,
            request.clip.as_deref(),
            request.map.as_deref(),
            &request.options,
        )
    })
    .map_err(|e| PipelineError::step(format!("{} onto {}", plan.label(), rig_plan.label()), e))?;
    let mut json = request.json.then(|| report_json(&done));
    let summary = done.report.summary();
    let (mut asset, mut warnings) = (done.asset, target.warnings);
    warnings.extend(done.warnings);
    let moved = crate::root_motion::apply(&mut asset, &request.root_motion)?;
    if let (Some(Value::Object(json)), Some(moved)) = (&mut json, &moved) {
        json.insert("root_motion".into(), moved.json());
    }
    let line = write_output(asset, warnings, &request.output, &input.budget, progress)?;
    let mut report = Report::logged(line);
    report.log.extend(moved.iter().flat_map(|m| m.lines()));
    match json {
        Some(json) => {
            let text = serde_json::to_string_pretty(&json)
                .map_err(|e| PipelineError::step("cannot write the report as JSON", e))?;
            report.output = Some(text + "\n");
        }
        None => report.summary = Some(summary + "\n"),
    }
    Ok(report)
}

/// A retargeted rig.
pub(crate) struct Done {
    /// The target rig with the retargeted clip as its only clip.
    pub asset: Asset,
    /// The source clip's name.
    pub clip: String,
    /// The map used and the figures (limb errors, foot slide, hands).
    pub report: RetargetReport,
    /// Notes (unmapped joints, feet without contacts, hands out of reach).
    pub warnings: Vec<Warning>,
}

/// Puts `source`'s clip named `clip` (or its first) onto `target`, mapped by `map_file`
/// or by [`auto_map`].
///
/// # Errors
/// No such clip, or as [`clip_onto`].
pub(crate) fn onto(
    source: &Asset,
    mut target: Asset,
    clip: Option<&str>,
    map_file: Option<&Path>,
    options: &RetargetOptions,
) -> Result<Done, PipelineError> {
    let found = source
        .clip(clip)
        .map_err(|e| PipelineError::Invalid(e.to_string()))?;
    let Some(found) = found else {
        return Err(PipelineError::Invalid(
            "no clip to retarget; the source has none".into(),
        ));
    };
    let done = clip_onto(source, found, &target, map_file, options)?;
    target.clips = vec![done.clip];
    Ok(Done {
        asset: target,
        clip: found.name.clone(),
        report: done.report,
        warnings: done.warnings,
    })
}

/// Puts `found` (a clip of `source`) onto `target`'s skeleton, mapped by `map_file` or by
/// [`auto_map`]; `target` itself is left as it is (`combine` puts many clips on one rig).
///
/// # Errors
/// A bad map file (with its JSON path), no joints in common, or a failed solve
/// ([`PipelineError::Json`], [`PipelineError::Step`]).
pub(crate) fn clip_onto(
    source: &Asset,
    found: &Clip,
    target: &Asset,
    map_file: Option<&Path>,
    options: &RetargetOptions,
) -> Result<Retargeted, PipelineError> {
    let (source_up, target_up) = (up_in_model(&source.frame), up_in_model(&target.frame));
    let map = match map_file {
        Some(path) => {
            let file = rigport_import::json::map::read(path, &source.skeleton, &target.skeleton)?;
            JointMap::from_pairs(&source.skeleton, &file.pairs, file.pelvis, "file")
                .ok_or_else(|| PipelineError::Invalid(format!("{}: no pairs", path.display())))?
        }
        None => auto_map(
            &source.skeleton,
            &target.skeleton,
            source_up,
            target_up,
            Some(found),
        )
        .map_err(|e| PipelineError::step("no joint map", e))?,
    };
    let input = RetargetInput {
        source: &source.skeleton,
        source_up,
        clip: found,
        target: &target.skeleton,
        target_up,
        map: &map,
    };
    retarget(&input, options)
        .map_err(|e| PipelineError::step(format!("cannot retarget clip {:?}", found.name), e))
}

/// The report of `done` as JSON (`rigport retarget --json`).
pub(crate) fn report_json(done: &Done) -> Value {
    let r = &done.report;
    let limbs: Vec<_> = (r.limbs.iter())
        .map(|l| {
            json!({"limb": l.label, "target": l.target, "source": l.source, "length": l.length,
                "max_error": l.max_error, "mean_error": l.mean_error})
        })
        .collect();
    let feet: Vec<_> = (r.feet.iter())
        .map(|f| {
            json!({"label": f.label, "ankle": f.ankle, "contacts": f.contacts.len(),
                "slide_before": {"max": f.before.max, "mean": f.before.mean},
                "slide_after": {"max": f.after.max, "mean": f.after.mean},
                "unreached_frames": f.unreached})
        })
        .collect();
    let pairs: Vec<_> = (r.pairs.iter())
        .map(|(s, t, role)| json!({"source": s, "target": t, "role": role}))
        .collect();
    let roles: Vec<_> = (r.roles.iter())
        .map(|row| {
            json!({"role": row.role, "limb": Limb::of(row.role).map(Limb::label),
                "source": row.source, "target": row.target, "driven_by": row.driven_by})
        })
        .collect();
    let hands: Vec<_> = (r.hands.iter())
        .map(|(l, e)| json!({"label": l, "max_error": e}))
        .collect();
    json!({"clip": done.clip, "map": r.map, "pairs": pairs, "roles": roles, "unmapped": r.unmapped,
        "reference": r.reference, "scale_vertical": r.scale_vertical,
        "scale_horizontal": r.scale_horizontal, "frames": r.frames, "height": r.height,
        "limbs": limbs, "feet": feet, "planted": r.planted, "hands": hands})
}
