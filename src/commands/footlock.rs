//! `rigport footlock`: hold mocap feet still during their ground contacts.

use std::io::Write;

use anyhow::{bail, Context as _, Result};
use rigport_ik::footlock::{footlock, resolve_feet, up_in_model, FootlockOptions, PinAt};
use serde_json::json;

use crate::cli::FootlockArgs;
use crate::context::Context;
use crate::{input, output};

/// Runs `footlock`.
pub fn run(ctx: &Context, args: &FootlockArgs) -> Result<()> {
    output::format_of(&args.output.output)?;
    let defaults = FootlockOptions::default();
    let options = FootlockOptions {
        height: args.height.unwrap_or(defaults.height),
        speed: args.speed.unwrap_or(defaults.speed),
        blend: args.blend.unwrap_or(defaults.blend),
        max_stretch: args.max_stretch.unwrap_or(defaults.max_stretch),
        pin_at: if args.pin_first {
            PinAt::First
        } else {
            PinAt::Mean
        },
        ..defaults
    };
    options.validate()?;
    let (plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    let mut asset = imported.asset;
    let mut warnings = imported.warnings;
    let index = asset
        .clip_index(args.clip.as_deref())
        .with_context(|| plan.label())?;
    let Some(index) = index else {
        bail!("{}: the rig has no clip to clean", plan.label());
    };
    let (legs, found_by) = resolve_feet(&asset.skeleton, &args.feet)
        .with_context(|| format!("{}: cannot find the feet", plan.label()))?;
    let clip = &asset.clips[index];
    let locked = ctx
        .step("locking feet", || {
            let up = up_in_model(&asset.frame);
            footlock(&asset.skeleton, clip, &legs, up, &options)
        })
        .with_context(|| format!("cannot lock the feet of clip {:?}", clip.name))?;
    let mut rows = Vec::new();
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
            "start_time": c.start_time, "end_time": c.end_time})
                })
                .collect();
            let windows: Vec<_> = f
                .contacts
                .iter()
                .map(|c| format!("{} {:.3}-{:.3} s", c.joint, c.start_time, c.end_time))
                .collect();
            rows.push(format!(
                "| {} | {} | {:.2e} / {:.2e} | {:.2e} / {:.2e} | {:.2}% |",
                f.label,
                windows.join(", "),
                f.before.max,
                f.before.mean,
                f.after.max,
                f.after.mean,
                100.0 * f.stretch
            ));
            json!({"label": f.label, "ankle": f.ankle, "toe": f.toe, "contacts": contacts,
            "slide_before": {"max": f.before.max, "mean": f.before.mean},
            "slide_after": {"max": f.after.max, "mean": f.after.mean},
            "stretch": f.stretch, "unreached_frames": f.unreached})
        })
        .collect();
    let report = json!({"clip": clip.name, "frames": locked.frames, "fps": locked.fps,
        "height": locked.height, "feet_found_by": found_by, "feet": feet});
    warnings.extend(locked.warnings);
    asset.clips[index] = locked.clip;
    output::reduce_clips(&mut asset, &args.output, &mut warnings)?;
    output::write_asset(ctx, &asset, warnings, &args.output)?;

    let mut out = std::io::stdout().lock();
    if args.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
    } else if !ctx.quiet {
        writeln!(
            out,
            "{} frames at {} fps, skeleton height {:.4}, feet: {found_by}; slides in heights",
            locked.frames, locked.fps, locked.height
        )?;
        writeln!(
            out,
            "| foot | contacts | slide before max / mean | after max / mean | stretch |"
        )?;
        writeln!(
            out,
            "| --- | --- | ---: | ---: | ---: |\n{}",
            rows.join("\n")
        )?;
    }
    Ok(())
}
