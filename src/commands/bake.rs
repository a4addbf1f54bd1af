//! `rigport bake`: a dual quaternion skinning result baked into an ordinary (LBS) glTF as
//! per-frame corrective morph targets in bind space (FORMATS.md, "glTF 2.0 skins and
//! animation"; the eval side is `rigport_eval::bake`).

use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};
use rigport_eval::bake::{
    compress_correctives, CorrectiveDeltasJob, FrameBakeStats, DEFAULT_MIN_RELATIVE_SCALE,
};
use rigport_eval::dqs::DqsPalette;
use rigport_eval::sample::{CompiledClip, SampleJob};
use rigport_eval::{skinning_matrices, LbsJob, LocalToModelJob, Pose};
use rigport_model::glam::{Mat4, Vec3};
use rigport_model::{
    Asset, Influences, Interpolation, MeshIndex, MorphTarget, Track, TrackTarget, Warning,
};

use super::eval::clip_names;
use super::Context;
use crate::cli::{InputArgs, OutputArgs, Skinning};
use crate::input;
use crate::output::{self, Format};
use rigport_eval::sample::sample_times;

/// `rigport bake` arguments.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "For every sampled frame and skinned vertex, with M the vertex's blended \
    LBS matrix (of the influences the glTF holds), the frame's target holds \
    M^-1 * p_dqs - p_rest, so a viewer's LBS of the morphed vertex lands on the DQS result. \
    Morph weights are animated (LINEAR, one key per frame) so that exactly frame k's target \
    is active at its time."
)]
pub struct BakeArgs {
    /// The rig, with at least one clip.
    #[command(flatten)]
    pub input: InputArgs,
    /// Output file: .glb or .gltf (+ .bin).
    #[arg(long, short, value_name = "OUT")]
    pub output: PathBuf,
    /// The skinning to bake (default: the one the source declares for its skin). `lbs`
    /// needs no correction and writes the plain file.
    #[arg(long, value_enum)]
    pub skinning: Option<Skinning>,
    /// The clip to bake (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Sample the clip at F frames per second (default: at its own key times).
    #[arg(long, value_name = "F")]
    pub fps: Option<f32>,
    /// Corrections no longer than D (bind-space units) are left out of the sparse targets
    /// (default: 1e-6 of the bounding-box diagonal of the skinned meshes).
    #[arg(long, value_name = "D")]
    pub threshold: Option<f32>,
    /// Compress the per-frame targets to K shared targets (PCA) with per-frame weights.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..))]
    pub correctives: Option<u32>,
    /// Influences kept per vertex in the glTF (1 to 8), and used for the DQS being baked.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u8).range(1..=8))]
    pub max_influences: u8,
}

/// One skinned mesh's bake, before it goes into the asset.
struct MeshBake {
    mesh: usize,
    influences: Influences,
    /// `F x J` skinning matrices.
    frame_matrices: Vec<Mat4>,
    joints: usize,
    dqs: Vec<Vec3>,
    deltas: Vec<Vec3>,
    stats: Vec<FrameBakeStats>,
}

/// Runs `bake`.
pub fn run(ctx: &Context, args: &BakeArgs) -> Result<()> {
    if output::format_of(&args.output)? != Format::Gltf {
        bail!(
            "{}: bake writes glTF (.glb/.gltf); a .usda declares DQS directly (`rigport convert --skinning dqs`)",
            args.output.display()
        );
    }
    if let Some(t) = args.threshold {
        if !(t.is_finite() && t >= 0.0) {
            bail!("--threshold {t}: expected a distance >= 0");
        }
    }
    let out_args = OutputArgs {
        output: args.output.clone(),
        max_influences: args.max_influences,
        reduce_tolerance: None,
        // The file itself is LBS; the DQS result lives in its morph targets.
        skinning: Some(Skinning::Lbs),
        up_axis: None,
        meters_per_unit: None,
    };
    let (plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    let mut asset = imported.asset;
    let mut warnings = imported.warnings;
    let skinning = args.skinning.unwrap_or(
        match asset.skins.first().map(|s| s.method).unwrap_or_default() {
            rigport_model::SkinningMethod::Lbs => Skinning::Lbs,
            rigport_model::SkinningMethod::Dqs => Skinning::Dqs,
        },
    );
    if skinning == Skinning::Lbs {
        warnings.push(Warning::Note {
            location: plan.label(),
            message: "--skinning lbs: glTF skins with LBS already, no corrective targets needed; writing the plain file".into(),
        });
        return output::write_asset(ctx, &asset, warnings, &out_args);
    }
    let lines = bake_dqs(
        ctx,
        &plan.label(),
        &mut asset,
        &DqsBakeOptions {
            clip: args.clip.as_deref(),
            fps: args.fps,
            threshold: args.threshold,
            correctives: args.correctives,
            max_influences: args.max_influences,
        },
        &mut warnings,
    )?;
    // The DQS result is baked into the targets: the file itself skins linearly.
    asset
        .skins
        .iter_mut()
        .for_each(|s| s.method = Default::default());
    output::write_asset(ctx, &asset, warnings, &out_args)?;
    if !ctx.quiet {
        for line in &lines {
            eprintln!("{line}");
        }
        let mut size = std::fs::metadata(&args.output).map_or(0, |m| m.len());
        if args
            .output
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf"))
        {
            size += std::fs::metadata(args.output.with_extension("bin")).map_or(0, |m| m.len());
        }
        eprintln!("file size: {size} bytes");
    }
    Ok(())
}

/// What [`bake_dqs`] bakes (the options of `rigport bake --skinning dqs`).
pub(crate) struct DqsBakeOptions<'a> {
    /// The clip to bake (default: the first).
    pub clip: Option<&'a str>,
    /// Sample rate in frames per second (default: the clip's key times).
    pub fps: Option<f32>,
    /// Corrections no longer than this (bind-space units) stay out of the sparse targets
    /// (default: 1e-6 of the skinned meshes' bounding-box diagonal).
    pub threshold: Option<f32>,
    /// Compress to this many shared targets (PCA) instead of one per frame.
    pub correctives: Option<u32>,
    /// Influences per vertex the glTF will hold (1 to 8): the bake inverts exactly the LBS a
    /// viewer computes from them, so the file must be written with the same limit.
    pub max_influences: u8,
}

/// Bakes the DQS result of one clip of `asset` into corrective morph targets (bind space,
/// one per sampled frame or `correctives` shared ones) on every skinned mesh, and a morph
/// weight track on that clip, so a glTF viewer's LBS of the written file lands on DQS.
/// Near-singular fallbacks go into `warnings`; returns one report line per mesh (frames,
/// targets, vertices corrected, the baked-vs-DQS deviation). `label` names the input in
/// messages.
///
/// # Errors
/// No skinned mesh, no such clip (or no clip), a skinned mesh that already has morph
/// targets, a clip that does not fit the skeleton, a bad `fps`, evaluation failures.
pub(crate) fn bake_dqs(
    ctx: &Context,
    label: &str,
    asset: &mut Asset,
    opts: &DqsBakeOptions<'_>,
    warnings: &mut Vec<Warning>,
) -> Result<Vec<String>> {
    if asset.skins.is_empty() {
        bail!("{}: nothing to bake: the rig has no skinned mesh", label);
    }
    let clip_index = match opts.clip {
        Some(name) => asset
            .clips
            .iter()
            .position(|c| c.name == name)
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "{}: no clip named {name:?}; clips: {}",
                    label,
                    clip_names(asset)
                )
            })?,
        None if asset.clips.is_empty() => bail!(
            "{}: the rig has no clip to bake (make one with `rigport animate`)",
            label
        ),
        None => 0,
    };
    for skin in &asset.skins {
        if let Some(mesh) = asset.meshes.get(skin.mesh.get()) {
            if !mesh.morph_targets.is_empty() {
                bail!(
                    "{}: mesh {:?} already has morph targets; baking correctives on top of them is not supported",
                    label,
                    mesh.name
                );
            }
        }
    }

    let times = {
        let clip = &asset.clips[clip_index];
        let compiled = CompiledClip::new(clip, &asset.skeleton)
            .with_context(|| format!("clip {:?} does not fit the skeleton", clip.name))?;
        let times = match opts.fps {
            None => compiled.key_times(),
            Some(fps) => {
                if !(fps.is_finite() && fps > 0.0) {
                    bail!("--fps {fps}: expected a positive frame rate");
                }
                sample_times(compiled.start(), compiled.end(), fps)
            }
        };
        // Model-space joint matrices per frame.
        let parents: Vec<_> = asset.skeleton.parents().collect();
        let rest = Pose::rest(&asset.skeleton);
        let mut pose = rest.clone();
        let mut model = vec![Mat4::IDENTITY; parents.len()];
        let mut frame_model = Vec::with_capacity(times.len() * parents.len());
        for &t in &times {
            SampleJob {
                clip: &compiled,
                time: t,
                rest: &rest.local,
                output: &mut pose.local,
            }
            .run()?;
            LocalToModelJob {
                parents: &parents,
                local: &pose.local,
                root_model: Mat4::IDENTITY,
                model: &mut model,
            }
            .run()?;
            frame_model.extend_from_slice(&model);
        }
        (times, frame_model)
    };
    let (times, frame_model) = times;
    let frames = times.len();
    let joint_count = asset.skeleton.len();

    let diagonal = skinned_diagonal(asset);
    let threshold = opts.threshold.unwrap_or(1e-6 * diagonal);
    let mut bakes = Vec::with_capacity(asset.skins.len());
    ctx.step("baking DQS correctives", || -> Result<()> {
        for skin in &asset.skins {
            let mesh = asset
                .meshes
                .get(skin.mesh.get())
                .context("skin refers to a missing mesh")?;
            // Exactly the influences the glTF will hold, so the viewer's LBS is what we invert.
            let influences = rigport_export::gltf_influences(
                &asset.skeleton,
                skin,
                usize::from(opts.max_influences),
            );
            let joints = skin.joints.len();
            let mut frame_matrices = vec![Mat4::IDENTITY; frames * joints];
            for (f, out) in frame_matrices.chunks_exact_mut(joints.max(1)).enumerate() {
                let model = &frame_model[f * joint_count..(f + 1) * joint_count];
                skinning_matrices(model, &skin.joints, &skin.inv_bind, out)?;
            }
            let v = mesh.positions.len();
            let mut bake = MeshBake {
                mesh: skin.mesh.get(),
                influences,
                frame_matrices,
                joints,
                dqs: vec![Vec3::ZERO; frames * v],
                deltas: vec![Vec3::ZERO; frames * v],
                stats: vec![FrameBakeStats::default(); frames],
            };
            CorrectiveDeltasJob {
                influences: &bake.influences,
                rest_positions: &mesh.positions,
                joints,
                frame_skin_matrices: &bake.frame_matrices,
                threshold,
                min_relative_scale: DEFAULT_MIN_RELATIVE_SCALE,
                out_dqs_positions: &mut bake.dqs,
                out_deltas: &mut bake.deltas,
                out_stats: &mut bake.stats,
                palette: &mut DqsPalette::new(joints, 1),
            }
            .run()
            .with_context(|| format!("cannot bake mesh {:?}", mesh.name))?;
            bakes.push(bake);
        }
        Ok(())
    })?;

    let mut lines = Vec::new();
    for bake in &bakes {
        let mesh = &asset.meshes[bake.mesh];
        let v = mesh.positions.len();
        let (targets, weights) = match opts.correctives {
            Some(k) => {
                let c = compress_correctives(&bake.deltas, frames, k as usize)?;
                let targets: Vec<MorphTarget> = c
                    .targets
                    .into_iter()
                    .enumerate()
                    .map(|(i, d)| MorphTarget {
                        name: format!("corrective_{i}"),
                        position_deltas: d,
                        normal_deltas: None,
                    })
                    .collect();
                (targets, c.frame_weights)
            }
            None => {
                let targets = bake
                    .deltas
                    .chunks_exact(v.max(1))
                    .enumerate()
                    .map(|(f, d)| MorphTarget {
                        name: format!("frame_{f}"),
                        position_deltas: d.to_vec(),
                        normal_deltas: None,
                    })
                    .collect();
                // One-hot rows: at frame k's time exactly target k has weight 1.
                let weights = (0..frames)
                    .flat_map(|f| (0..frames).map(move |t| if t == f { 1.0 } else { 0.0 }))
                    .collect();
                (targets, weights)
            }
        };
        let max_error = viewer_error(bake, &mesh.positions, &targets, &weights)?;
        let corrected: Vec<u32> = bake.stats.iter().map(|s| s.corrected).collect();
        let fallback: Vec<String> = bake
            .stats
            .iter()
            .enumerate()
            .filter(|(_, s)| s.singular > 0)
            .map(|(f, s)| format!("{f} ({} vertices)", s.singular))
            .collect();
        let label = if mesh.name.is_empty() {
            format!("mesh {}", bake.mesh)
        } else {
            format!("mesh {:?}", mesh.name)
        };
        if !fallback.is_empty() {
            warnings.push(Warning::Repaired {
                location: label.clone(),
                message: format!(
                    "the blended LBS matrix is near-singular for some vertices, which keep plain LBS (no correction) in frames {}",
                    fallback.join(", ")
                ),
            });
        }
        lines.push(format!(
            "{label}: {frames} frames, {} targets; vertices corrected: max {} of {v} per frame, {} in total; baked LBS vs DQS max deviation {max_error:.3e} ({:.3e} of the diagonal {diagonal:.4})",
            targets.len(),
            corrected.iter().max().copied().unwrap_or(0),
            corrected.iter().map(|&c| u64::from(c)).sum::<u64>(),
            max_error / diagonal.max(f32::MIN_POSITIVE),
        ));
        if !fallback.is_empty() {
            lines.push(format!(
                "{label}: the deviation includes the near-singular vertices left at plain LBS"
            ));
        }
        let track = Track {
            target: TrackTarget::MorphWeights(MeshIndex(bake.mesh as u32)),
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values: weights,
        };
        asset.meshes[bake.mesh].morph_targets = targets;
        asset.clips[clip_index].tracks.push(track);
    }
    Ok(lines)
}

/// The bounding-box diagonal of the skinned meshes' bind positions.
fn skinned_diagonal(asset: &Asset) -> f32 {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for skin in &asset.skins {
        for p in asset
            .meshes
            .get(skin.mesh.get())
            .map_or(&[][..], |m| &m.positions)
        {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
    }
    if lo.x <= hi.x {
        (hi - lo).length()
    } else {
        0.0
    }
}

/// The largest distance, over all frames and vertices, between what a glTF viewer shows
/// (morph with `weights`, then LBS with the limited influences) and rigport's DQS.
fn viewer_error(
    bake: &MeshBake,
    rest: &[Vec3],
    targets: &[MorphTarget],
    weights: &[f32],
) -> Result<f32> {
    let v = rest.len();
    let k = targets.len();
    let mut morphed = vec![Vec3::ZERO; v];
    let mut skinned = vec![Vec3::ZERO; v];
    let mut worst = 0.0f32;
    for (f, mats) in bake
        .frame_matrices
        .chunks_exact(bake.joints.max(1))
        .enumerate()
    {
        morphed.copy_from_slice(rest);
        let w = weights.get(f * k..(f + 1) * k).unwrap_or(&[]);
        for (t, &wt) in targets.iter().zip(w) {
            if wt != 0.0 {
                for (m, d) in morphed.iter_mut().zip(&t.position_deltas) {
                    *m += *d * wt;
                }
            }
        }
        LbsJob {
            skin_matrices: mats,
            influences: &bake.influences,
            rest_positions: &morphed,
            rest_normals: None,
            out_positions: &mut skinned,
            out_normals: None,
        }
        .run()?;
        let dqs = bake.dqs.get(f * v..(f + 1) * v).unwrap_or(&[]);
        for (a, b) in skinned.iter().zip(dqs) {
            worst = worst.max((*a - *b).length());
        }
    }
    Ok(worst)
}
