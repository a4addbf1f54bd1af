//! `rigport retarget`: put a motion onto another rig (`rigport_pipeline::retarget`).

use std::io::Write;

use anyhow::{Context as _, Result};
use rigport_ik::retarget::RetargetOptions;

use crate::cli::{InputArgs, RetargetArgs};
use crate::context::Context;
use crate::{input, output};

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
    let options = RetargetOptions {
        plant_feet: args.plant_feet,
        match_hands: args.match_hands,
        ..RetargetOptions::default()
    };
    let done = ctx
        .step("retargeting", || {
            rigport_pipeline::retarget::onto(
                &source.asset,
                target.asset,
                args.clip.as_deref(),
                args.map.as_deref(),
                &options,
            )
        })
        .with_context(|| format!("{} onto {}", plan.label(), rig_plan.label()))?;
    let json = args
        .json
        .then(|| rigport_pipeline::retarget::report_json(&done));
    let summary = done.report.summary();
    let (mut asset, mut warnings) = (done.asset, target.warnings);
    warnings.extend(done.warnings);
    output::reduce_clips(&mut asset, &args.output, &mut warnings)?;
    output::write_asset(ctx, &asset, warnings, &args.output)?;
    let mut out = std::io::stdout().lock();
    if let Some(report) = json {
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
    } else if !ctx.quiet {
        writeln!(out, "{summary}")?;
    }
    Ok(())
}
