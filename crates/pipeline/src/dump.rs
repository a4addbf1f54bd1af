//! `rigport eval`'s pipeline: a rig posed (rest or a `POSE.json`) or a clip sampled, each
//! frame skinned, and the result as an `.npz` dump (`rigport_export::npz::EvalDump`):
//! written to a file in memory bounded whatever the clip's length ([`eval_dump_to`]).

use std::io::{BufWriter, Write as _};
use std::path::Path;

use rigport_eval::sample::{CompiledClip, FrameGrid, SampleJob};
use rigport_eval::{Pose, Rig, RigOutput};
use rigport_export::npz::EvalArrays;
use rigport_export::npz::{EvalDump, SPILL_LIMIT};
use rigport_model::SkinningMethod;
use rigport_model::{Asset, MemoryBudget, RestRotation};

use crate::PipelineError;

/// What to evaluate: a pose, or a clip sampled at its keys or a rate; the influences
/// limited or not; the skinning method. `rigport eval` and the Python bindings' `evaluate`
/// and `pose` take it.
///
/// ```
/// use rigport_pipeline::eval::{Evaluation, PoseSource};
///
/// // A clip named "walk" sampled at 30 frames per second, skinned with DQS.
/// let request = Evaluation {
///     clip: Some("walk"),
///     fps: Some(30.0),
///     skinning: Some(rigport_model::SkinningMethod::Dqs),
///     ..Evaluation::default()
/// };
/// assert!(request.pose.is_none() && request.max_influences.is_none());
/// // A pose given as rotations already read (none: every joint at rest).
/// let rest = Evaluation { pose: Some(PoseSource::Rotations(&[])), ..Evaluation::default() };
/// assert!(rest.pose.is_some());
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct Evaluation<'a> {
    /// A pose to evaluate instead of a clip.
    pub pose: Option<PoseSource<'a>>,
    /// The clip to sample (default: the first; none: the rest pose).
    pub clip: Option<&'a str>,
    /// Sample at this rate (default: the clip's key times).
    pub fps: Option<f32>,
    /// Sample at these times, in seconds (instead of a rate or the key times).
    pub times: Option<&'a [f32]>,
    /// Limit the influences per vertex as a glTF would (`rigport_export::gltf_influences`).
    pub max_influences: Option<usize>,
    /// The skinning method (default: the first skin's own).
    pub skinning: Option<SkinningMethod>,
}

/// Where a pose comes from: a `POSE.json` file, or its rotations already read (from a
/// dictionary, `rigport_import::json::pose::parse`).
///
/// ```
/// use rigport_pipeline::eval::PoseSource;
///
/// let file = PoseSource::File(std::path::Path::new("rest.json"));
/// assert!(matches!(file, PoseSource::File(_)));
/// ```
#[derive(Clone, Copy, Debug)]
pub enum PoseSource<'a> {
    /// A `POSE.json`, read against the rig's skeleton.
    File(&'a Path),
    /// Rotations in each joint's rest frame.
    Rotations(&'a [RestRotation]),
}

/// A dump written to its file.
#[derive(Clone, Debug)]
pub(crate) struct DumpInfo {
    /// The clip sampled, `None` for a single pose.
    pub clip: Option<String>,
}

/// Bytes of one frame's arrays: positions (f32 x 3 per vertex) and two 4x4 f32 matrices
/// per joint.
fn frame_bytes(vertices: usize, joints: usize) -> u64 {
    (vertices as u64)
        .saturating_mul(12)
        .saturating_add((joints as u64).saturating_mul(128))
}

/// Estimated peak bytes of a dump of `frames` frames streamed to its file: each per-frame
/// array in memory up to [`SPILL_LIMIT`], the frame times, three frames' worth of scratch
/// (the evaluator's output, the dump's rows, the skinning's work) and the copy buffers
/// (1 MiB each for reading a spill back and for writing the file).
fn streamed_memory(frames: usize, vertices: usize, joints: usize) -> u64 {
    let frames = frames as u64;
    let held = |bytes_per_frame: u64| {
        frames
            .saturating_mul(bytes_per_frame)
            .min(SPILL_LIMIT as u64)
    };
    let spills = held(4)
        .saturating_add(held((vertices as u64).saturating_mul(12)))
        .saturating_add(held((joints as u64).saturating_mul(64)).saturating_mul(2));
    spills
        .saturating_add(frames.saturating_mul(4))
        .saturating_add(frame_bytes(vertices, joints).saturating_mul(3))
        .saturating_add(2 << 20)
}

/// Evaluates `asset` as `opts` asks and writes the dump to `output` atomically
/// (`rigport_export::write_atomic_with`); `label` names the asset in messages. Memory
/// stays bounded whatever the clip's length: the per-frame arrays beyond
/// [`SPILL_LIMIT`] bytes each wait in unnamed temporary files in `output`'s folder, and
/// the `.npz` is streamed from them.
///
/// # Errors
/// Nothing to skin, an unknown clip, a frame rate that is not positive, a pose file's
/// errors, over `budget`, or a clip that does not fit the skeleton;
/// [`PipelineError::Output`] when `output` is not a regular file
/// (or absent), or a temporary file or the output cannot be written (nothing is left
/// behind then).
pub(crate) fn eval_dump_to(
    asset: &Asset,
    label: &str,
    opts: &Evaluation<'_>,
    output: impl AsRef<Path>,
    budget: &MemoryBudget,
) -> Result<DumpInfo, PipelineError> {
    let output = output.as_ref();
    let target =
        rigport_export::check_output(output).map_err(|e| PipelineError::output(output, e))?;
    // The temporary files go where the output goes: its folder is on the disk meant to
    // hold that many bytes, while the system's temporary folder may be a tmpfs in memory.
    let dir = match target.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let (dump, clip) = evaluate(asset, label, opts, budget, Some((output, dir)))?;
    let npz = dump.finish(clip.is_some());
    rigport_export::write_atomic_with(output, |file| {
        npz.write_to(BufWriter::with_capacity(1 << 20, file))?
            .flush()
    })
    .map_err(|e| PipelineError::output(output, e))?;
    Ok(DumpInfo { clip })
}

/// The arrays of `asset` evaluated as `opts` asks, in memory, with the name of the clip
/// sampled (`None` for a pose): the same frames, in the same rows, as the `.npz` that
/// [`eval_dump_to`] writes.
///
/// # Errors
/// As [`eval_dump_to`], but for the output's.
pub(crate) fn eval_arrays(
    asset: &Asset,
    label: &str,
    opts: &Evaluation<'_>,
    budget: &MemoryBudget,
) -> Result<(EvalArrays, Option<String>), PipelineError> {
    let (dump, clip) = evaluate(asset, label, opts, budget, None)?;
    let arrays = dump
        .into_arrays()
        .map_err(|e| PipelineError::step(format!("{label}: the evaluated frames"), e))?;
    Ok((arrays, clip))
}

/// The dump filled with the frames and the name of the clip sampled. With `spill`
/// (`(output, folder)`), the frames beyond [`SPILL_LIMIT`] bytes per array wait in unnamed
/// temporary files in the folder; without, they stay in memory.
fn evaluate(
    asset: &Asset,
    label: &str,
    opts: &Evaluation<'_>,
    budget: &MemoryBudget,
    spill: Option<(&Path, &Path)>,
) -> Result<(EvalDump, Option<String>), PipelineError> {
    let mut limited = None;
    if let Some(max) = opts.max_influences {
        let mut copy = asset.clone();
        for skin in &mut copy.skins {
            skin.influences = rigport_export::gltf_influences(&asset.skeleton, skin, max);
        }
        limited = Some(copy);
    }
    let asset = limited.as_ref().unwrap_or(asset);
    if !asset.meshes.is_empty()
        && asset.skins.is_empty()
        && asset
            .meshes
            .iter()
            .all(|m| m.attached_to.is_none() && m.morph_targets.is_empty())
    {
        return Err(PipelineError::Invalid(format!(
            "{label}: nothing to skin: the rig has no skin weights, no mesh attached to a joint and no morph targets"
        )));
    }
    let method = (opts.skinning)
        .unwrap_or_else(|| asset.skins.first().map(|s| s.method).unwrap_or_default());
    let method_name = match method {
        SkinningMethod::Lbs => "lbs",
        SkinningMethod::Dqs => "dqs",
    };
    let rig = Rig::new(asset).map_err(|e| PipelineError::step("the rig cannot be evaluated", e))?;
    let mut dump = EvalDump::new(asset, |m| rig.skin_of_mesh(m), method_name);
    // Beyond [`SPILL_LIMIT`] bytes per array, the frames wait in unnamed temporary files
    // in the spill folder.
    let output = match spill {
        Some((output, dir)) => {
            dump = dump.spill_into(dir);
            output
        }
        None => Path::new(label),
    };
    let spill_err = |e| PipelineError::output(output, e);
    let mut posed = RigOutput::default();
    let clip = match opts.pose {
        Some(_) => None,
        None => asset
            .clip(opts.clip)
            .map_err(|e| PipelineError::Invalid(format!("{label}: {e}")))?,
    };
    match clip {
        None => {
            if opts.fps.is_some() || opts.times.is_some() {
                return Err(PipelineError::Invalid(format!(
                    "{label}: a sampling rate or sample times need a clip to sample; the rig has none"
                )));
            }
            let mut pose = Pose::rest(&asset.skeleton);
            match opts.pose {
                Some(PoseSource::File(path)) => {
                    pose.apply(&rigport_import::json::pose::read(path, &asset.skeleton)?);
                }
                Some(PoseSource::Rotations(rotations)) => pose.apply(rotations),
                None => {}
            }
            rig.evaluate_with(&pose, method, &mut posed)?;
            dump.push(0.0, &posed.joint_model, &posed.positions)
                .map_err(spill_err)?;
        }
        Some(clip) => {
            let compiled = CompiledClip::new(clip, &asset.skeleton).map_err(|e| {
                PipelineError::step(format!("clip {:?} does not fit the skeleton", clip.name), e)
            })?;
            let times = match (opts.times, opts.fps) {
                (Some(_), Some(_)) => {
                    return Err(PipelineError::Usage(
                        "give sample times or a sampling rate, not both".into(),
                    ));
                }
                (Some(times), None) => {
                    if let Some(t) = times.iter().find(|t| !t.is_finite()) {
                        return Err(PipelineError::Invalid(format!(
                            "sample time {t}: expected a finite number of seconds"
                        )));
                    }
                    times.to_vec()
                }
                (None, None) => compiled.key_times(),
                (None, Some(fps)) => {
                    if !(fps.is_finite() && fps > 0.0) {
                        return Err(PipelineError::Invalid(format!(
                            "frame rate {fps}: expected a positive number"
                        )));
                    }
                    FrameGrid::new(compiled.start(), compiled.end(), fps)?.into_times()
                }
            };
            let vertices: usize = asset.meshes.iter().map(|m| m.positions.len()).sum();
            let joints = asset.skeleton.len();
            let needed = match spill {
                Some(_) => streamed_memory(times.len(), vertices, joints),
                // Held whole: every frame's arrays, and their copy as values.
                None => frame_bytes(vertices, joints)
                    .saturating_add(4)
                    .saturating_mul(times.len() as u64)
                    .saturating_mul(2),
            };
            budget.check(
                format_args!(
                    "{}: {} frames of {vertices} vertices and {joints} joints",
                    output.display(),
                    times.len(),
                ),
                needed,
            )?;
            let rest = Pose::rest(&asset.skeleton);
            let mut pose = rest.clone();
            let mut weights = rig.rest_weights().clone();
            for &t in &times {
                // Rotations as stored, as the viewers compose them (16-bit keys are not
                // quite unit length).
                SampleJob {
                    clip: &compiled,
                    time: t,
                    rest: &rest.local,
                    output: &mut pose.local,
                }
                .run_as_stored()?;
                weights.sample(&compiled, t)?;
                rig.evaluate_frame(&pose, &weights, method, &mut posed)?;
                dump.push(t, &posed.joint_model, &posed.positions)
                    .map_err(spill_err)?;
            }
        }
    }
    Ok((dump, clip.map(|c| c.name.clone())))
}
