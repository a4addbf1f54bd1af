//! `rigport eval`'s pipeline: a rig posed (rest or a `POSE.json`) or a clip sampled, each
//! frame skinned, and the result as the bytes of an `.npz` dump
//! (`rigport_export::npz::EvalDump`).
//!
//! ```
//! use rigport_pipeline::{dump, load, MemoryBudget};
//!
//! let plan = load::Source::Bvh("../../fixtures/bvh/end_sites.bvh".into());
//! let asset = load::load(&plan, true, &MemoryBudget::UNLIMITED)?.asset;
//! let opts = dump::DumpOptions { fps: Some(10.0), ..dump::DumpOptions::default() };
//! let out = dump::eval_dump(&asset, &plan.label(), &opts, "out.npz", &MemoryBudget::UNLIMITED)?;
//! assert_eq!(&out.bytes[..2], b"PK");
//! assert!(out.clip.is_some());
//! # Ok::<(), rigport_pipeline::PipelineError>(())
//! ```

use std::path::Path;

use rigport_eval::sample::{CompiledClip, FrameGrid, SampleJob};
use rigport_eval::skinning::SkinningMethod;
use rigport_eval::{Pose, Rig, RigOutput};
use rigport_export::npz::EvalDump;
use rigport_model::{Asset, MemoryBudget};

use crate::{clip_names, PipelineError};

/// What to evaluate.
#[derive(Clone, Copy, Debug, Default)]
pub struct DumpOptions<'a> {
    /// A `POSE.json` to evaluate instead of a clip.
    pub pose: Option<&'a Path>,
    /// The clip to sample (default: the first; none: the rest pose).
    pub clip: Option<&'a str>,
    /// Sample at this rate (default: the clip's key times).
    pub fps: Option<f32>,
    /// Limit the influences per vertex as a glTF would (`rigport_export::gltf_influences`).
    pub max_influences: Option<usize>,
    /// The skinning method (default: the first skin's own).
    pub skinning: Option<SkinningMethod>,
}

/// An evaluated dump.
#[derive(Clone, Debug)]
pub struct Dump {
    /// The `.npz` bytes.
    pub bytes: Vec<u8>,
    /// The clip sampled, `None` for a single pose.
    pub clip: Option<String>,
}

/// Estimated peak bytes of a dump of `frames` frames: positions (f32 x 3 per vertex) and
/// two 4x4 f32 matrices per joint, held as values and again as the `.npz` bytes (measured:
/// a 676 MB dump at a 1.59 GB peak).
fn dump_memory(frames: usize, vertices: usize, joints: usize) -> u64 {
    let per_frame = (vertices as u64)
        .saturating_mul(12)
        .saturating_add((joints as u64).saturating_mul(128));
    (frames as u64).saturating_mul(per_frame).saturating_mul(5) / 2
}

/// Evaluates `asset` as `opts` asks and builds the dump; `label` names the asset in
/// messages and `output` the file in the memory check.
///
/// # Errors
/// Nothing to skin, an unknown clip, a frame rate that is not positive, a pose file's
/// errors, over `budget`, or a clip that does not fit the skeleton.
pub fn eval_dump(
    asset: &Asset,
    label: &str,
    opts: &DumpOptions<'_>,
    output: impl AsRef<Path>,
    budget: &MemoryBudget,
) -> Result<Dump, PipelineError> {
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
        && asset.meshes.iter().all(|m| m.attached_to.is_none())
    {
        return Err(PipelineError::Invalid(format!(
            "{label}: nothing to skin: the rig has no skin weights and no mesh attached to a joint"
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
    let mut posed = RigOutput::default();
    let clip = match (opts.pose, opts.clip) {
        (Some(_), _) => None,
        (None, Some(name)) => {
            Some(asset.clips.iter().find(|c| c.name == name).ok_or_else(|| {
                PipelineError::Invalid(format!(
                    "{label}: no clip named {name:?}; clips: {}",
                    clip_names(asset)
                ))
            })?)
        }
        (None, None) => asset.clips.first(),
    };
    match clip {
        None => {
            if opts.fps.is_some() {
                return Err(PipelineError::Invalid(format!(
                    "{label}: --fps needs a clip to sample; the rig has none"
                )));
            }
            let mut pose = Pose::rest(&asset.skeleton);
            if let Some(path) = opts.pose {
                pose.apply(&rigport_import::json::pose::read(path, &asset.skeleton)?);
            }
            rig.evaluate_with(&pose, method, &mut posed)?;
            dump.push(0.0, &posed.joint_model, &posed.positions);
        }
        Some(clip) => {
            let compiled = CompiledClip::new(clip, &asset.skeleton).map_err(|e| {
                PipelineError::step(format!("clip {:?} does not fit the skeleton", clip.name), e)
            })?;
            let times = match opts.fps {
                None => compiled.key_times(),
                Some(fps) => {
                    if !(fps.is_finite() && fps > 0.0) {
                        return Err(PipelineError::Invalid(format!(
                            "--fps {fps}: expected a positive frame rate"
                        )));
                    }
                    FrameGrid::new(compiled.start(), compiled.end(), fps)?.into_times()
                }
            };
            let vertices: usize = asset.meshes.iter().map(|m| m.positions.len()).sum();
            budget.check(
                format_args!(
                    "{}: {} frames of {vertices} vertices and {} joints",
                    output.as_ref().display(),
                    times.len(),
                    asset.skeleton.len()
                ),
                dump_memory(times.len(), vertices, asset.skeleton.len()),
            )?;
            let rest = Pose::rest(&asset.skeleton);
            let mut pose = rest.clone();
            for &t in &times {
                SampleJob {
                    clip: &compiled,
                    time: t,
                    rest: &rest.local,
                    output: &mut pose.local,
                }
                .run()?;
                rig.evaluate_with(&pose, method, &mut posed)?;
                dump.push(t, &posed.joint_model, &posed.positions);
            }
        }
    }
    let bytes = (dump.finish(clip.is_some()).finish())
        .map_err(|e| PipelineError::output(output.as_ref(), e))?;
    Ok(Dump {
        bytes,
        clip: clip.map(|c| c.name.clone()),
    })
}
