//! `rigport ik`: IK handles over time, solved per frame and baked into a clip.

use std::io::Write;

use anyhow::{bail, Context as _, Result};
use rigport_eval::ik::{
    IkEffector, IkHandle, IkMethod, IkProblem, IkReport, IkScratch, IkSettings, IkSolveJob, Lambda,
};
use rigport_eval::sample::{bake, ChannelMask};
use rigport_eval::Pose;
use rigport_model::glam::Vec3;
use rigport_model::{Transform, Warning};
use serde::Serialize;

use super::Context;
use crate::cli::IkArgs;
use crate::handles;
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

/// What a solve needs besides the skeleton and the handles file.
pub struct IkOptions {
    /// The solver.
    pub method: IkMethod,
    /// Frame rate override.
    pub fps: Option<f32>,
    /// Convergence distance (default 1e-4 of the skeleton height).
    pub tolerance: Option<f32>,
    /// Iterations per frame.
    pub max_iterations: u32,
    /// Sub-step distance.
    pub substep: Option<f32>,
    /// Whether roots may translate.
    pub free_root: bool,
}

/// Solves the handles of `handles_path` on `skeleton` frame by frame (warm start from the
/// previous frame) and bakes the poses into a clip named after the file.
///
/// # Errors
/// Bad handles file or settings, or a problem the solver rejects.
pub fn solve(
    ctx: &Context,
    skeleton: &rigport_model::Skeleton,
    handles_path: &std::path::Path,
    opts: &IkOptions,
) -> Result<(rigport_model::Clip, Summary, Vec<Warning>)> {
    let mut warnings = Vec::new();
    let method = opts.method;
    let file = handles::load(handles_path, skeleton)?;
    let fps = opts.fps.or(file.fps).unwrap_or(30.0);
    if !(fps.is_finite() && fps > 0.0) {
        bail!("--fps {fps}: expected a positive frame rate");
    }
    let tracks = file.tracks;
    let rest_points = handles::rest_effectors(skeleton, &tracks);
    let height = {
        let rest = skeleton.model_rest_matrices();
        let (lo, hi) = rest.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), m| (lo.min(m.w_axis.truncate()), hi.max(m.w_axis.truncate())),
        );
        (hi - lo).max_element().max(f32::MIN_POSITIVE)
    };
    let tolerance = opts.tolerance.unwrap_or(1e-4 * height);
    if !(tolerance.is_finite() && tolerance > 0.0) {
        bail!("--tolerance {tolerance}: expected a distance > 0");
    }
    let settings = IkSettings {
        method,
        max_iterations: opts.max_iterations,
        tolerance,
        substep: opts.substep,
        free_root_translation: opts.free_root,
        ..IkSettings::default()
    };
    settings.validate().context("invalid IK settings")?;
    let effectors: Vec<IkEffector> = tracks
        .iter()
        .map(|t| IkEffector {
            joint: t.joint,
            local_offset: t.offset,
        })
        .collect();
    let problem =
        IkProblem::new(skeleton, &effectors, None, &[]).context("cannot set up the IK problem")?;
    let end = tracks
        .iter()
        .filter_map(|t| t.times.last().copied())
        .fold(0.0f32, f32::max);
    let frame_count = (end * fps).round() as usize + 1;
    let times: Vec<f32> = (0..frame_count)
        .map(|k| (k as f32 / fps).min(end))
        .collect();
    let mut pose = Pose::rest(skeleton);
    let mut scratch = IkScratch::new(&problem);
    let mut report = IkReport::new(&problem);
    let mut frames: Vec<Transform> = Vec::with_capacity(frame_count * skeleton.len());
    let mut residuals = vec![Vec::with_capacity(frame_count); tracks.len()];
    let mut iterations = 0u64;
    let mut targets: Vec<IkHandle> = tracks
        .iter()
        .map(|t| IkHandle::new(t.joint, Vec3::ZERO))
        .collect();
    ctx.step("solving", || -> Result<()> {
        for &t in &times {
            for (h, track) in tracks.iter().enumerate() {
                targets[h].target = handles::target_at(track, t, rest_points[h]);
                targets[h].weight = track.weight;
            }
            IkSolveJob {
                problem: &problem,
                targets: &targets,
                settings: &settings,
                pose: &mut pose.local,
                scratch: &mut scratch,
                report: &mut report,
            }
            .run()
            .with_context(|| format!("IK solve at {t} s"))?;
            iterations += u64::from(report.iterations);
            for (h, r) in report.residuals.iter().enumerate() {
                residuals[h].push(*r);
            }
            frames.extend_from_slice(&pose.local);
        }
        Ok(())
    })?;

    let n = skeleton.len();
    let mut mask = ChannelMask::none(n);
    for j in problem.movable() {
        mask.rotation[j.get()] = true;
    }
    if opts.free_root {
        for r in skeleton.roots() {
            mask.translation[r.get()] = true;
        }
    }
    let name = handles_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "ik".into());
    let clip = bake(&name, &times, &frames, &mask).context("cannot bake the solved poses")?;

    let summary = Summary {
        clip: name.clone(),
        solver: method.name(),
        frames: frame_count,
        fps,
        tolerance,
        mean_iterations: iterations as f32 / frame_count as f32,
        handles: tracks
            .iter()
            .zip(&residuals)
            .map(|(t, r)| {
                let (worst_frame, max) = r
                    .iter()
                    .copied()
                    .enumerate()
                    .fold((0, 0.0f32), |a, (i, v)| if v > a.1 { (i, v) } else { a });
                HandleSummary {
                    joint: t.name.clone(),
                    max_residual: max,
                    mean_residual: r.iter().sum::<f32>() / r.len().max(1) as f32,
                    worst_frame,
                    worst_time: times[worst_frame],
                    frames_over_tolerance: r.iter().filter(|&&v| v > tolerance).count(),
                }
            })
            .collect(),
    };
    let over: usize = summary
        .handles
        .iter()
        .map(|h| h.frames_over_tolerance)
        .sum();
    if over > 0 {
        warnings.push(Warning::Incomplete {
            location: handles_path.display().to_string(),
            message: format!(
                "{over} handle-frames end farther than the tolerance {tolerance:.3e} from their targets (unreachable or not converged; best effort kept)"
            ),
        });
    }
    Ok((clip, summary, warnings))
}

/// Runs `ik`.
pub fn run(ctx: &Context, args: &IkArgs) -> Result<()> {
    output::format_of(&args.output.output)?;
    let opts = IkOptions {
        method: method(args)?,
        fps: args.fps,
        tolerance: args.tolerance,
        max_iterations: args.max_iterations,
        substep: args.substep,
        free_root: args.free_root,
    };
    let (_plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    let mut asset = imported.asset;
    let mut warnings = imported.warnings;
    let (clip, summary, solve_warnings) = solve(ctx, &asset.skeleton, &args.handles, &opts)?;
    warnings.extend(solve_warnings);
    asset.clips.insert(0, clip);
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
    }
    Ok(())
}
