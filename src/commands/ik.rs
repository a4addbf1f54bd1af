//! `rigport ik`: IK handles over time, solved per frame and baked into a clip.

use std::io::Write;

use anyhow::{bail, Result};
use rigport_ik::clip::{solve_clip_on, ClipSolveOptions};
use rigport_ik::{IkMethod, Lambda};
use serde::Serialize;

use crate::cli::IkArgs;
use crate::context::Context;
use crate::{input, output};

/// Per-handle residual summary.
#[derive(Serialize)]
pub struct HandleSummary {
    joint: String,
    max_residual: f32,
    mean_residual: f32,
    worst_frame: usize,
    worst_time: f32,
    frames_over_tolerance: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    reached: Option<Vec<bool>>,
}

/// The whole report (`--json`).
#[derive(Serialize)]
pub struct Summary {
    clip: String,
    solver: &'static str,
    frames: usize,
    fps: f32,
    tolerance: f32,
    mean_iterations: f32,
    handles: Vec<HandleSummary>,
}

fn method(args: &IkArgs) -> Result<IkMethod> {
    let Some(m) = IkMethod::from_name(&args.solver) else {
        bail!(
            "--solver {:?}: expected one of dls, pinv, transpose, ccd, fabrik",
            args.solver
        );
    };
    Ok(match (m, args.lambda) {
        (IkMethod::Dls { .. }, Some(l)) => {
            if !(l.is_finite() && l >= 0.0) {
                bail!("--lambda {l}: expected a damping >= 0");
            }
            IkMethod::Dls {
                lambda: Lambda::Fixed(l),
            }
        }
        (_, Some(_)) => bail!("--lambda applies to --solver dls only"),
        (m, None) => m,
    })
}

/// Runs `ik`.
pub fn run(ctx: &Context, args: &IkArgs) -> Result<()> {
    output::format_of(&args.output.output)?;
    let opts = ClipSolveOptions {
        method: method(args)?,
        fps: args.fps,
        tolerance: args.tolerance,
        max_iterations: args.max_iterations,
        substep: args.substep,
        free_root: args.free_root,
    };
    if let Some(fps) = opts.fps {
        if !(fps.is_finite() && fps > 0.0) {
            bail!("--fps {fps}: expected a positive frame rate");
        }
    }
    if let Some(t) = opts.tolerance {
        if !(t.is_finite() && t > 0.0) {
            bail!("--tolerance {t}: expected a distance > 0");
        }
    }
    let (_plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    let mut asset = imported.asset;
    let mut warnings = imported.warnings;
    let handles = rigport_import::json::handles::read(&args.handles, &asset.skeleton)?;
    rigport_import::json::handles::check_base(&args.handles, &handles, &asset.clips)?;
    let name = args
        .handles
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "ik".into());
    let solved = ctx.step("solving", || {
        solve_clip_on(
            &asset.skeleton,
            &asset.clips,
            &handles,
            &opts,
            &name,
            &args.handles.display().to_string(),
        )
    })?;
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
    output::reduce_clips(&mut asset, &args.output, &mut warnings)?;
    output::write_asset(ctx, &asset, warnings, &args.output)?;

    let mut out = std::io::stdout().lock();
    if args.json {
        let text = serde_json::to_string_pretty(&summary)?;
        writeln!(out, "{text}")?;
    } else if !ctx.quiet {
        writeln!(
            out,
            "{} frames at {} fps, solver {}, {:.1} iterations per frame, tolerance {:.3e}",
            summary.frames, summary.fps, summary.solver, summary.mean_iterations, summary.tolerance
        )?;
        writeln!(
            out,
            "| handle | max residual | mean residual | worst frame | frames over tolerance |"
        )?;
        writeln!(out, "| --- | ---: | ---: | ---: | ---: |")?;
        for h in &summary.handles {
            writeln!(
                out,
                "| {} | {:.3e} | {:.3e} | {} ({:.3} s) | {} |",
                h.joint,
                h.max_residual,
                h.mean_residual,
                h.worst_frame,
                h.worst_time,
                h.frames_over_tolerance
            )?;
        }
        for line in solved.handles.iter().filter_map(|h| h.reached_summary()) {
            writeln!(out, "{line}")?;
        }
    }
    Ok(())
}
