//! `rigport sequence`: clips one after another, crossfaded, optionally looping.

use anyhow::{bail, Context as _, Result};
use rigport_anim::sequence::{concatenate, make_loop};
use rigport_model::{Clip, Skeleton, Track, TrackTarget, Warning};

use crate::cli::SequenceArgs;
use crate::context::Context;
use crate::{input, output};

/// Moves `clip` from skeleton `from` onto `to` by joint name. Tracks of joints `to` lacks
/// and morph-weight tracks (meshes are not carried over) are dropped and counted.
fn remap(clip: &Clip, from: &Skeleton, to: &Skeleton) -> (Clip, usize) {
    let mut dropped = 0;
    let tracks: Vec<Track> = clip
        .tracks
        .iter()
        .filter_map(|t| {
            let joint = |j: rigport_model::JointIndex| to.find(&from.joint(j).name);
            let target = match t.target {
                TrackTarget::Translation(j) => joint(j).map(TrackTarget::Translation),
                TrackTarget::Rotation(j) => joint(j).map(TrackTarget::Rotation),
                TrackTarget::Scale(j) => joint(j).map(TrackTarget::Scale),
                TrackTarget::MorphWeights(_) => None,
            };
            if target.is_none() {
                dropped += 1;
            }
            target.map(|target| Track {
                target,
                ..t.clone()
            })
        })
        .collect();
    (
        Clip {
            name: clip.name.clone(),
            tracks,
        },
        dropped,
    )
}

/// Runs `sequence`.
pub fn run(ctx: &Context, args: &SequenceArgs) -> Result<()> {
    output::format_of(&args.output.output)?;
    let plans = input::plans(&args.input)?;
    let mut loaded = Vec::with_capacity(plans.len());
    for plan in &plans {
        let imported = ctx.step(&format!("reading {}", plan.label()), || {
            input::load(plan, &args.input)
        })?;
        loaded.push((plan, imported));
    }
    let (first_plan, first) = &loaded[0];
    let skeleton = &first.asset.skeleton;
    let mut warnings = first.warnings.clone();
    let mut clips = Vec::new();
    for (plan, imported) in &loaded {
        if imported.asset.clips.is_empty() {
            bail!("{}: has no clip to sequence", plan.label());
        }
        if !std::ptr::eq(*plan, *first_plan) {
            warnings.extend(imported.warnings.iter().cloned());
        }
        for clip in &imported.asset.clips {
            let (clip, dropped) = remap(clip, &imported.asset.skeleton, skeleton);
            if dropped > 0 {
                warnings.push(Warning::Incomplete {
                    location: format!("{} clip {:?}", plan.label(), clip.name),
                    message: format!(
                        "{dropped} track(s) animate joints or meshes that {} lacks; dropped",
                        first_plan.label()
                    ),
                });
            }
            clips.push(clip);
        }
    }
    if let Some(fps) = args.fps {
        if !(fps.is_finite() && fps > 0.0) {
            bail!("--fps {fps}: expected a positive frame rate");
        }
    }
    let refs: Vec<&Clip> = clips.iter().collect();
    let mut sequence = concatenate(&refs, skeleton, args.crossfade, args.fps)
        .context("cannot sequence the clips")?;
    if args.looping {
        sequence = make_loop(&sequence, skeleton, args.crossfade.max(1))
            .context("cannot make the sequence loop")?;
    }
    sequence.name = clips
        .iter()
        .map(|c| c.name.as_str())
        .collect::<Vec<_>>()
        .join("+");
    let mut asset = first.asset.clone();
    asset.clips = vec![sequence];
    output::reduce_clips(&mut asset, &args.output, &mut warnings)?;
    output::write_asset(ctx, &asset, warnings, &args.output)
}
