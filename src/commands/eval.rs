//! `rigport eval`: pose a rig and dump the skinned result as `.npz`.

use anyhow::{Context as _, Result};
use rigport_eval::sample::{CompiledClip, FrameGrid, SampleJob};
use rigport_eval::skinning::SkinningMethod;
use rigport_eval::{Pose, Rig, RigOutput};
use rigport_export::npz::EvalDump;

use crate::cli::{EvalArgs, Skinning};
use crate::context::{clip_names, Context};
use crate::exit::OutputError;
use crate::input;

/// Estimated peak bytes of a dump of `frames` frames: positions (f32 x 3 per vertex) and
/// two 4x4 f32 matrices per joint, held as values and again as the `.npz` bytes (measured:
/// a 676 MB dump at a 1.59 GB peak).
fn dump_memory(frames: usize, vertices: usize, joints: usize) -> u64 {
    let per_frame = (vertices as u64)
        .saturating_mul(12)
        .saturating_add((joints as u64).saturating_mul(128));
    (frames as u64).saturating_mul(per_frame).saturating_mul(5) / 2
}

/// Runs `eval`.
pub fn run(ctx: &Context, args: &EvalArgs) -> Result<()> {
    let (plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    ctx.report(&imported.warnings)?;
    let mut limited = None;
    if let Some(max) = args.max_influences {
        let mut asset = imported.asset.clone();
        for skin in &mut asset.skins {
            skin.influences =
                rigport_export::gltf_influences(&imported.asset.skeleton, skin, usize::from(max));
        }
        limited = Some(asset);
    }
    let asset = limited.as_ref().unwrap_or(&imported.asset);
    if !asset.meshes.is_empty()
        && asset.skins.is_empty()
        && asset.meshes.iter().all(|m| m.attached_to.is_none())
    {
        anyhow::bail!(
            "{}: nothing to skin: the rig has no skin weights and no mesh attached to a joint",
            plan.label()
        );
    }
    // --skinning, else the method the source declares for its (first) skin.
    let method = match args.skinning {
        Some(Skinning::Lbs) => SkinningMethod::Lbs,
        Some(Skinning::Dqs) => SkinningMethod::Dqs,
        None => asset.skins.first().map(|s| s.method).unwrap_or_default(),
    };
    let method_name = match method {
        SkinningMethod::Lbs => "lbs",
        SkinningMethod::Dqs => "dqs",
    };
    let rig = Rig::new(asset).context("the rig cannot be evaluated")?;
    let mut dump = EvalDump::new(asset, |m| rig.skin_of_mesh(m), method_name);
    let mut posed = RigOutput::default();
    let clip = match (&args.pose, &args.clip) {
        (Some(_), _) => None,
        (None, Some(name)) => Some(asset.clips.iter().find(|c| &c.name == name).ok_or_else(
            || {
                anyhow::anyhow!(
                    "{}: no clip named {name:?}; clips: {}",
                    plan.label(),
                    clip_names(asset)
                )
            },
        )?),
        (None, None) => asset.clips.first(),
    };
    let frames = clip.is_some();
    match clip {
        None => {
            if args.fps.is_some() {
                anyhow::bail!(
                    "{}: --fps needs a clip to sample; the rig has none",
                    plan.label()
                );
            }
            let pose = match &args.pose {
                Some(path) => {
                    let mut pose = Pose::rest(&asset.skeleton);
                    pose.apply(&rigport_import::json::pose::read(path, &asset.skeleton)?);
                    pose
                }
                None => Pose::rest(&asset.skeleton),
            };
            rig.evaluate_with(&pose, method, &mut posed)?;
            dump.push(0.0, &posed.joint_model, &posed.positions);
        }
        Some(clip) => {
            let compiled = CompiledClip::new(clip, &asset.skeleton)
                .with_context(|| format!("clip {:?} does not fit the skeleton", clip.name))?;
            let times = match args.fps {
                None => compiled.key_times(),
                Some(fps) => {
                    if !(fps.is_finite() && fps > 0.0) {
                        anyhow::bail!("--fps {fps}: expected a positive frame rate");
                    }
                    FrameGrid::new(compiled.start(), compiled.end(), fps)?.into_times()
                }
            };
            let vertices: usize = asset.meshes.iter().map(|m| m.positions.len()).sum();
            crate::memory::budget().check(
                format_args!(
                    "{}: {} frames of {vertices} vertices and {} joints",
                    args.output.display(),
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
    let bytes = dump.finish(frames).finish().with_context(|| OutputError {
        path: args.output.display().to_string(),
    })?;
    rigport_export::write_atomic(&args.output, &bytes).with_context(|| OutputError {
        path: args.output.display().to_string(),
    })?;
    if !ctx.quiet {
        let what = match clip {
            Some(c) => format!(", clip {:?}", c.name),
            None => String::new(),
        };
        eprintln!(
            "wrote {} ({} joints, {} meshes{what})",
            args.output.display(),
            asset.skeleton.len(),
            asset.meshes.len()
        );
    }
    Ok(())
}
