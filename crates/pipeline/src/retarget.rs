//! `rigport retarget`'s pipeline: a source asset's clip put onto a target rig through a
//! joint map (a `MAP.json` file or the built-in maps chosen by name), with the report as
//! JSON.
//!
//! ```
//! use rigport_pipeline::{load, retarget, MemoryBudget};
//!
//! let open = |path: &str| -> Result<_, rigport_pipeline::PipelineError> {
//!     let plan = load::single_plan(&load::Inputs::new(vec![path.into()]))?;
//!     Ok(load::load(&plan, true, &MemoryBudget::UNLIMITED)?.asset)
//! };
//! let walk = open("../../fixtures/bvh/end_sites.bvh")?;
//! let rig = walk.clone();
//! let done = retarget::onto(&walk, rig, None, None, &Default::default())?;
//! assert_eq!(done.asset.clips.len(), 1);
//! assert!(retarget::report_json(&done)["frames"].as_u64().is_some());
//! # Ok::<(), rigport_pipeline::PipelineError>(())
//! ```

use std::path::Path;

use rigport_ik::footlock::up_in_model;
use rigport_ik::retarget::RetargetReport;
use rigport_ik::retarget::{auto_map, retarget, JointMap, RetargetInput, RetargetOptions};
use rigport_model::{Asset, Warning};
use serde_json::{json, Value};

use crate::load::Input;
use crate::progress::{step, Progress};
use crate::write::{write_output, Output};
use crate::{PipelineError, Report};

/// What `retarget` puts onto which rig, and where it writes.
#[derive(Clone, Debug)]
pub struct RetargetRequest {
    /// The rig the motion goes onto (read like any input).
    pub onto: Input,
    /// The source clip (the first when `None`).
    pub clip: Option<String>,
    /// A `MAP.json` (default: the built-in maps, chosen by joint names).
    pub map: Option<std::path::PathBuf>,
    /// Planting and hand matching.
    pub options: RetargetOptions,
    /// Give the report as JSON ([`Report::output`]) rather than a summary.
    pub json: bool,
    /// The output file and how it is written.
    pub output: Output,
}

/// Reads the motion (`input`) and the rig (`request.onto`), puts the clip onto the rig,
/// and writes the rig with it; the report comes back as a summary or as JSON.
///
/// # Errors
/// As [`onto`], the imports and [`write_output`].
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
    let json = request.json.then(|| report_json(&done));
    let summary = done.report.summary();
    let (asset, mut warnings) = (done.asset, target.warnings);
    warnings.extend(done.warnings);
    let line = write_output(asset, warnings, &request.output, &input.budget, progress)?;
    let mut report = Report::logged(line);
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
pub struct Done {
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
/// or by the built-in maps.
///
/// # Errors
/// No such clip, a bad map file (with its JSON path), no joints in common, or a failed
/// solve ([`PipelineError::Invalid`], [`PipelineError::Json`], [`PipelineError::Step`]).
pub fn onto(
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
    let (source_up, target_up) = (up_in_model(&source.frame), up_in_model(&target.frame));
    let map = match map_file {
        Some(path) => {
            let file = rigport_import::json::map::read(path, &source.skeleton, &target.skeleton)?;
            JointMap::from_pairs(&source.skeleton, &file.pairs, file.pelvis, "file")
                .ok_or_else(|| PipelineError::Invalid(format!("{}: no pairs", path.display())))?
        }
        None => auto_map(&source.skeleton, &target.skeleton, source_up, target_up)
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
    let done = retarget(&input, options)
        .map_err(|e| PipelineError::step(format!("cannot retarget clip {:?}", found.name), e))?;
    target.clips = vec![done.clip];
    Ok(Done {
        asset: target,
        clip: found.name.clone(),
        report: done.report,
        warnings: done.warnings,
    })
}

/// The report of `done` as JSON (`rigport retarget --json`).
pub fn report_json(done: &Done) -> Value {
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
    let hands: Vec<_> = (r.hands.iter())
        .map(|(l, e)| json!({"label": l, "max_error": e}))
        .collect();
    json!({"clip": done.clip, "map": r.map, "pairs": pairs, "unmapped": r.unmapped,
        "reference": r.reference, "scale_vertical": r.scale_vertical,
        "scale_horizontal": r.scale_horizontal, "frames": r.frames, "height": r.height,
        "limbs": limbs, "feet": feet, "planted": r.planted, "hands": hands})
}
