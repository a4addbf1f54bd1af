//! `rigport retime`: resample, speed up, warp, reverse or trim a clip.

use anyhow::{bail, Context as _, Result};
use rigport_anim::retime::{retime, Retime, WarpCurve};
use rigport_anim::sequence::trim;
use rigport_model::{Clip, Warning};

use crate::cli::RetimeArgs;
use crate::context::Context;
use crate::{input, output};

/// Parses `START..END` seconds.
fn parse_range(text: &str) -> Result<(f32, f32)> {
    let parse = |s: &str| -> Result<f32> {
        let v: f32 = s
            .trim()
            .parse()
            .with_context(|| format!("--trim {text:?}: {s:?} is not a number of seconds"))?;
        if !v.is_finite() {
            bail!("--trim {text:?}: {s:?} is not finite");
        }
        Ok(v)
    };
    let (a, b) = text
        .split_once("..")
        .with_context(|| format!("--trim {text:?}: expected START..END, e.g. 0.5..2"))?;
    Ok((parse(a)?, parse(b)?))
}

fn keys_of(clip: &Clip) -> usize {
    clip.tracks.iter().map(|t| t.times.len()).max().unwrap_or(0)
}

/// Runs `retime`.
pub fn run(ctx: &Context, args: &RetimeArgs) -> Result<()> {
    output::format_of(&args.output.output)?;
    let how = if let Some(n) = args.frames {
        if n < 2 {
            bail!("--frames {n}: a clip needs at least 2 frames");
        }
        Retime::Frames(n)
    } else if let Some(fps) = args.fps {
        if !(fps.is_finite() && fps > 0.0) {
            bail!("--fps {fps}: expected a positive frame rate");
        }
        Retime::Fps(fps)
    } else if let Some(s) = args.speed {
        if !(s.is_finite() && s > 0.0) {
            bail!("--speed {s}: expected a positive factor (use --reverse to play backwards)");
        }
        Retime::Speed(s)
    } else if let Some(w) = &args.warp {
        Retime::Warp(WarpCurve::parse(w).with_context(|| format!("--warp {w:?}"))?)
    } else if args.reverse {
        Retime::Reverse
    } else {
        // --trim (clap requires one of the group).
        let text = args.trim.as_deref().unwrap_or_default();
        let (start, end) = parse_range(text)?;
        return run_with(ctx, args, |clip, skeleton| {
            trim(clip, skeleton, start, end).with_context(|| format!("--trim {text:?}"))
        });
    };
    run_with(ctx, args, |clip, skeleton| {
        retime(clip, skeleton, &how).map_err(anyhow::Error::from)
    })
}

fn run_with(
    ctx: &Context,
    args: &RetimeArgs,
    op: impl Fn(&Clip, &rigport_model::Skeleton) -> Result<Clip>,
) -> Result<()> {
    let (plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    let mut asset = imported.asset;
    let mut warnings = imported.warnings;
    let index = asset
        .clip_index(args.clip.as_deref())
        .with_context(|| plan.label())?;
    let Some(index) = index else {
        bail!("{}: the rig has no clip to retime", plan.label());
    };
    let before = &asset.clips[index];
    let after = op(before, &asset.skeleton)
        .with_context(|| format!("cannot retime clip {:?}", before.name))?;
    warnings.push(Warning::Note {
        location: format!("clip {:?}", before.name),
        message: format!(
            "retimed: {:.4} s with {} keys -> {:.4} s with {} keys",
            before.duration(),
            keys_of(before),
            after.duration(),
            keys_of(&after)
        ),
    });
    asset.clips[index] = after;
    output::reduce_clips(&mut asset, &args.output, &mut warnings)?;
    output::write_asset(ctx, &asset, warnings, &args.output)
}
