//! `rigport retarget`: put a motion onto another rig.

use std::io::Write;

use anyhow::{bail, Context as _, Result};
use rigport_eval::footlock::up_in_model;
use rigport_eval::retarget::{auto_map, retarget, JointMap, RetargetInput, RetargetOptions};
use serde_json::json;

use crate::cli::{InputArgs, RetargetArgs};
use crate::context::Context;
use crate::{input, output};
use rigport_pipeline::clip_names;

/// Runs `retarget`.
pub fn run(ctx: &Context, args: &RetargetArgs) -> Result<()> {
    output::format_of(&args.output.output)?;
    let (plan, source) = ctx.step("reading motion", || input::load_single(&args.input))?;
    let rig_args = InputArgs {
        inputs: args.onto.clone(),
        mesh: None,
        skeleton: None,
        attachment: None,
        motion: Vec::new(),
        amc_fps: None,
        no_bone_mesh: args.input.no_bone_mesh,
    };
    let (rig_plan, target) = ctx.step("reading rig", || input::load_single(&rig_args))?;
    let (source, mut asset) = (source.asset, target.asset);
    let mut warnings = target.warnings;
    let clip = match &args.clip {
        Some(name) => source.clips.iter().find(|c| &c.name == name),
        None => source.clips.first(),
    };
    let Some(clip) = clip else {
        bail!(
            "{}: no clip {}; clips: {}",
            plan.label(),
            args.clip
                .as_deref()
                .map_or("to retarget".into(), |n| format!("named {n:?}")),
            clip_names(&source)
        );
    };
    let (source_up, target_up) = (up_in_model(&source.frame), up_in_model(&asset.frame));
    let map = match &args.map {
        Some(path) => {
            let file = rigport_import::json::map::read(path, &source.skeleton, &asset.skeleton)?;
            JointMap::from_pairs(&source.skeleton, &file.pairs, file.pelvis, "file")
                .with_context(|| format!("{}: no pairs", path.display()))?
        }
        None => auto_map(&source.skeleton, &asset.skeleton, source_up, target_up)
            .with_context(|| format!("{} onto {}", plan.label(), rig_plan.label()))?,
    };
    let options = RetargetOptions {
        plant_feet: args.plant_feet,
        match_hands: args.match_hands,
        ..RetargetOptions::default()
    };
    let run_input = RetargetInput {
        source: &source.skeleton,
        source_up,
        clip,
        target: &asset.skeleton,
        target_up,
        map: &map,
    };
    let done = ctx
        .step("retargeting", || retarget(&run_input, &options))
        .with_context(|| {
            format!(
                "cannot retarget clip {:?} onto {}",
                clip.name,
                rig_plan.label()
            )
        })?;
    let r = &done.report;
    warnings.extend(done.warnings);
    asset.clips = vec![done.clip];
    output::reduce_clips(&mut asset, &args.output, &mut warnings)?;
    output::write_asset(ctx, &asset, warnings, &args.output)?;

    let limbs: Vec<_> = r
        .limbs
        .iter()
        .map(|l| {
            json!({"limb": l.label, "target": l.target, "source": l.source,
        "length": l.length, "max_error": l.max_error, "mean_error": l.mean_error})
        })
        .collect();
    let feet: Vec<_> = r.feet.iter().map(|f| json!({"label": f.label, "ankle": f.ankle, "contacts": f.contacts.len(),
        "slide_before": {"max": f.before.max, "mean": f.before.mean}, "slide_after": {"max": f.after.max, "mean": f.after.mean},
        "unreached_frames": f.unreached})).collect();
    let pairs: Vec<_> = r
        .pairs
        .iter()
        .map(|(s, t, role)| json!({"source": s, "target": t, "role": role}))
        .collect();
    let hands: Vec<_> = r
        .hands
        .iter()
        .map(|(l, e)| json!({"label": l, "max_error": e}))
        .collect();
    let report = json!({"clip": clip.name, "map": r.map, "pairs": pairs, "unmapped": r.unmapped, "reference": r.reference,
        "scale_vertical": r.scale_vertical, "scale_horizontal": r.scale_horizontal, "frames": r.frames,
        "height": r.height, "limbs": limbs, "feet": feet, "planted": r.planted, "hands": hands});
    let mut out = std::io::stdout().lock();
    if args.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
    } else if !ctx.quiet {
        writeln!(out, "{}", r.summary())?;
    }
    Ok(())
}
