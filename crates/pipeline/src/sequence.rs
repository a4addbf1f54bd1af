//! `rigport sequence`: clips one after another, crossfaded, optionally looping.
//!
//! [`run`] is the whole pipeline; [`crate::sequence()`] is the same function.

use rigport_anim::sequence::{concatenate, make_loop};
use rigport_model::{Clip, Skeleton, Track, TrackTarget, Warning};

use crate::load::Input;
use crate::outputs::check_request;
use crate::progress::{Progress, step};
use crate::write::{Output, write_output};
use crate::{PipelineError, Report};

/// How `sequence` joins the clips, and what it writes.
///
/// ```
/// use rigport_pipeline::sequence::SequenceOptions;
/// use rigport_pipeline::{load::Input, progress::Silent, sequence, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let bvh = "../../fixtures/bvh/end_sites.bvh";
/// let input = Input::new(vec![bvh.into(), bvh.into()]);
/// // Resampled at 30 fps, and the end blends back into the start.
/// let options = SequenceOptions {
///     crossfade: 0,
///     fps: Some(30.0),
///     looping: true,
///     output: Output::new(dir.path().join("loop.glb")),
/// };
/// let report = sequence(&input, &options, &Silent)?;
/// assert!(report.log[0].starts_with("wrote "));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct SequenceOptions {
    /// Frames of crossfade between consecutive clips.
    pub crossfade: usize,
    /// The sequence's frame rate (`None`: the first clip's).
    pub fps: Option<f32>,
    /// Blend the end back into the start.
    pub looping: bool,
    /// The output file and how it is written.
    pub output: Output,
}

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

/// Reads every input, puts their clips one after another on the first input's skeleton
/// (by joint name), and writes the first rig with the sequence as its only clip.
///
/// ```
/// use rigport_pipeline::sequence::SequenceOptions;
/// use rigport_pipeline::{load::Input, progress::Silent, sequence, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("twice.glb");
/// let bvh = "../../fixtures/bvh/end_sites.bvh";
/// let input = Input::new(vec![bvh.into(), bvh.into()]);
/// let options = SequenceOptions { crossfade: 1, fps: None, looping: false, output: Output::new(&out) };
/// let report = sequence(&input, &options, &Silent)?;
/// assert!(report.log[0].contains("1 clips"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// An input without clips; clips that cannot be joined; as the imports and
/// [`write_output`].
pub fn run(
    input: &Input,
    options: &SequenceOptions,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    check_request(input, &options.output.path, &[])?;
    let plans = input.plans()?;
    let mut loaded = Vec::with_capacity(plans.len());
    for plan in &plans {
        let imported = step(progress, &format!("reading {}", plan.label()), || {
            input.load(plan, progress)
        })?;
        loaded.push((plan, imported));
    }
    let (first_plan, first) = &loaded[0];
    let skeleton = &first.asset.skeleton;
    let mut warnings = first.warnings.clone();
    let mut clips = Vec::new();
    for (plan, imported) in &loaded {
        if imported.asset.clips.is_empty() {
            return Err(PipelineError::Invalid(format!(
                "{}: has no clip to sequence",
                plan.label()
            )));
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
    let refs: Vec<&Clip> = clips.iter().collect();
    let mut sequence = concatenate(&refs, skeleton, options.crossfade, options.fps)
        .map_err(|e| PipelineError::step("cannot sequence the clips", e))?;
    if options.looping {
        sequence = make_loop(&sequence, skeleton, options.crossfade.max(1))
            .map_err(|e| PipelineError::step("cannot make the sequence loop", e))?;
    }
    sequence.name = clips
        .iter()
        .map(|c| c.name.as_str())
        .collect::<Vec<_>>()
        .join("+");
    let mut asset = first.asset.clone();
    asset.clips = vec![sequence];
    let line = write_output(asset, warnings, &options.output, &input.budget, progress)?;
    Ok(Report::logged(line))
}
