//! The DQS bake of one clip on an asset (what `rigport bake --skinning dqs` and the demo's
//! twist run): sampling, FK, skinning
//! matrices, corrective deltas, optional PCA compression, morph targets and a morph-weight
//! track, and the check of what a glTF viewer will show.

use std::fmt;

use glam::{Mat4, Vec3};
use rigport_model::{
    Asset, Influences, Interpolation, MeshIndex, MorphTarget, NoSuchClip, Skeleton, SkinBinding,
    Track, TrackTarget, Warning,
};

use super::{
    compress_correctives, CorrectiveDeltasJob, FrameBakeStats, DEFAULT_MIN_RELATIVE_SCALE,
};
use rigport_eval::dqs::DqsPalette;
use rigport_eval::sample::{CompiledClip, FrameGrid, SampleError, SampleJob};
use rigport_eval::{skinning_matrices, EvalError, LbsJob, LocalToModelJob, Pose};

/// What [`bake_dqs`] bakes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DqsBakeOptions<'a> {
    /// The clip to bake (default: the first).
    pub clip: Option<&'a str>,
    /// Sample rate in frames per second (default: the clip's key times).
    pub fps: Option<f32>,
    /// Corrections no longer than this (bind-space units) stay out of the sparse targets
    /// (default: 1e-6 of the skinned meshes' bounding-box diagonal).
    pub threshold: Option<f32>,
    /// Compress to this many shared targets (PCA) instead of one per frame.
    pub correctives: Option<u32>,
}

/// Why [`bake_dqs`] failed. `label` names the input.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DqsBakeError {
    /// No skinned mesh.
    #[error("{label}: nothing to bake: the rig has no skinned mesh")]
    NoSkin {
        /// The input.
        label: String,
    },
    /// No clip of that name.
    #[error("{label}: {clip}")]
    NoSuchClip {
        /// The input.
        label: String,
        /// The name asked for, and the clips there are.
        clip: NoSuchClip,
    },
    /// No clip at all.
    #[error("{label}: the rig has no clip to bake (make one with `rigport animate`)")]
    NoClip {
        /// The input.
        label: String,
    },
    /// A skinned mesh has morph targets already.
    #[error("{label}: mesh {mesh:?} already has morph targets; baking correctives on top of them is not supported")]
    HasMorphTargets {
        /// The input.
        label: String,
        /// The mesh's name.
        mesh: String,
    },
    /// The clip does not fit the skeleton.
    #[error("clip {clip:?} does not fit the skeleton")]
    Clip {
        /// The clip's name.
        clip: String,
        /// Why.
        #[source]
        source: SampleError,
    },
    /// Sampling failed.
    #[error(transparent)]
    Sample(#[from] SampleError),
    /// A skin refers to a mesh the asset does not have.
    #[error("skin refers to a missing mesh")]
    MissingMesh,
    /// A mesh's correctives could not be computed.
    #[error("cannot bake mesh {mesh:?}")]
    Mesh {
        /// The mesh's name.
        mesh: String,
        /// Why.
        #[source]
        source: EvalError,
    },
    /// An evaluation step's inputs did not fit.
    #[error(transparent)]
    Eval(#[from] EvalError),
}

/// What the bake did to one skinned mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshBakeReport {
    /// The mesh (`mesh "name"`, or `mesh N` when unnamed).
    pub label: String,
    /// Frames sampled.
    pub frames: usize,
    /// Morph targets written.
    pub targets: usize,
    /// The mesh's vertex count.
    pub vertices: usize,
    /// Most vertices corrected in one frame.
    pub max_corrected: u32,
    /// Vertices corrected, summed over frames.
    pub total_corrected: u64,
    /// Largest distance between the viewer's result (morph, then LBS with the limited
    /// influences) and DQS, over frames and vertices (bind-space units).
    pub max_error: f32,
    /// The skinned meshes' bounding-box diagonal.
    pub diagonal: f32,
    /// Whether some vertices kept plain LBS (near-singular blended matrix).
    pub has_fallback: bool,
}

impl fmt::Display for MeshBakeReport {
    /// One line (two when some vertices kept plain LBS).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} frames, {} targets; vertices corrected: max {} of {} per frame, {} in total; baked LBS vs DQS max deviation {:.3e} ({:.3e} of the diagonal {:.4})",
            self.label,
            self.frames,
            self.targets,
            self.max_corrected,
            self.vertices,
            self.total_corrected,
            self.max_error,
            self.max_error / self.diagonal.max(f32::MIN_POSITIVE),
            self.diagonal,
        )?;
        if self.has_fallback {
            write!(
                f,
                "\n{}: the deviation includes the near-singular vertices left at plain LBS",
                self.label
            )?;
        }
        Ok(())
    }
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

/// Bakes the DQS result of one clip of `asset` into corrective morph targets (bind space,
/// one per sampled frame or `correctives` shared ones) on every skinned mesh, and a morph
/// weight track on that clip, so a glTF viewer's LBS of the written file lands on DQS.
///
/// `influences` gives, per skin, exactly the influences the written file will hold (e.g.
/// the glTF writer's limit to 4 per vertex): the bake inverts the LBS a viewer computes
/// from them, and the DQS being baked uses them too. Near-singular fallbacks go into
/// `warnings`; returns one report per skinned mesh. `label` names the input in messages.
///
/// # Errors
/// No skinned mesh, no such clip (or no clip), a skinned mesh that already has morph
/// targets, a clip that does not fit the skeleton, a bad `fps` or one that would need more
/// than [`rigport_eval::sample::MAX_FRAMES`] frames, evaluation failures.
///
/// ```
/// use rigport_deform::bake::asset::{bake_dqs, DqsBakeOptions};
/// use rigport_model::glam::Quat;
/// use rigport_model::{Clip, PoseKey, PoseKeys, RestRotation};
///
/// let rig = rigport_demo::character(1);
/// let skeleton = rigport_import::pinocchio::PinocchioSkeleton {
///     positions: rig.joint_positions.clone(),
///     parents: rig.joint_parents.clone(),
/// };
/// let mut asset = rigport_import::pinocchio::assemble(
///     "demo", rig.mesh, &skeleton, Some(&rig.joint_names), &rig.bone_weights, None,
/// )?
/// .asset;
/// // The left forearm twists 120 degrees and back over two seconds.
/// let forearm = asset.skeleton.find("hand_l").expect("the demo has a left forearm");
/// let key = |time, deg: f32| PoseKey {
///     time,
///     index: 0,
///     rotations: vec![RestRotation { joint: forearm, rotation: Quat::from_rotation_x(deg.to_radians()) }],
///     translation: None,
/// };
/// let keys = PoseKeys { name: Some("twist".into()), keys: vec![key(0.0, 0.0), key(1.0, 120.0), key(2.0, 0.0)] };
/// asset.clips.push(rigport_anim::keyed::clip(&asset.skeleton, &keys, "twist")?);
/// let mut warnings = Vec::new();
/// let reports = bake_dqs(
///     &mut asset,
///     &DqsBakeOptions { fps: Some(5.0), ..DqsBakeOptions::default() },
///     |_, skin| skin.influences.clone(),
///     "demo",
///     &mut warnings,
/// )?;
/// assert_eq!(reports[0].frames, 11);
/// assert_eq!(asset.meshes[0].morph_targets.len(), 11);
/// assert!(reports[0].max_error < 1e-3 * reports[0].diagonal);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn bake_dqs(
    asset: &mut Asset,
    opts: &DqsBakeOptions<'_>,
    influences: impl Fn(&Skeleton, &SkinBinding) -> Influences,
    label: &str,
    warnings: &mut Vec<Warning>,
) -> Result<Vec<MeshBakeReport>, DqsBakeError> {
    if asset.skins.is_empty() {
        return Err(DqsBakeError::NoSkin {
            label: label.into(),
        });
    }
    let clip_index = asset
        .clip_index(opts.clip)
        .map_err(|clip| DqsBakeError::NoSuchClip {
            label: label.into(),
            clip,
        })?
        .ok_or_else(|| DqsBakeError::NoClip {
            label: label.into(),
        })?;
    for skin in &asset.skins {
        if let Some(mesh) = asset.meshes.get(skin.mesh.get()) {
            if !mesh.morph_targets.is_empty() {
                return Err(DqsBakeError::HasMorphTargets {
                    label: label.into(),
                    mesh: mesh.name.clone(),
                });
            }
        }
    }

    let (times, frame_model) = {
        let clip = &asset.clips[clip_index];
        let compiled =
            CompiledClip::new(clip, &asset.skeleton).map_err(|source| DqsBakeError::Clip {
                clip: clip.name.clone(),
                source,
            })?;
        let times = match opts.fps {
            None => compiled.key_times(),
            Some(fps) => FrameGrid::new(compiled.start(), compiled.end(), fps)?.into_times(),
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
    let frames = times.len();
    let joint_count = asset.skeleton.len();

    let diagonal = skinned_diagonal(asset);
    let threshold = opts.threshold.unwrap_or(1e-6 * diagonal);
    let mut bakes = Vec::with_capacity(asset.skins.len());
    for skin in &asset.skins {
        let mesh = asset
            .meshes
            .get(skin.mesh.get())
            .ok_or(DqsBakeError::MissingMesh)?;
        let influences = influences(&asset.skeleton, skin);
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
        .map_err(|source| DqsBakeError::Mesh {
            mesh: mesh.name.clone(),
            source,
        })?;
        bakes.push(bake);
    }

    let mut reports = Vec::new();
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
        let fallback: Vec<String> = bake
            .stats
            .iter()
            .enumerate()
            .filter(|(_, s)| s.singular > 0)
            .map(|(f, s)| format!("{f} ({} vertices)", s.singular))
            .collect();
        let mesh_label = if mesh.name.is_empty() {
            format!("mesh {}", bake.mesh)
        } else {
            format!("mesh {:?}", mesh.name)
        };
        if !fallback.is_empty() {
            warnings.push(Warning::Repaired {
                location: mesh_label.clone(),
                message: format!(
                    "the blended LBS matrix is near-singular for some vertices, which keep plain LBS (no correction) in frames {}",
                    fallback.join(", ")
                ),
            });
        }
        reports.push(MeshBakeReport {
            label: mesh_label,
            frames,
            targets: targets.len(),
            vertices: v,
            max_corrected: bake.stats.iter().map(|s| s.corrected).max().unwrap_or(0),
            total_corrected: bake.stats.iter().map(|s| u64::from(s.corrected)).sum(),
            max_error,
            diagonal,
            has_fallback: !fallback.is_empty(),
        });
        let track = Track {
            target: TrackTarget::MorphWeights(MeshIndex(bake.mesh as u32)),
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values: weights,
        };
        asset.meshes[bake.mesh].morph_targets = targets;
        asset.clips[clip_index].tracks.push(track);
    }
    Ok(reports)
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
/// (morph with `weights`, then LBS with the limited influences) and the DQS result.
fn viewer_error(
    bake: &MeshBake,
    rest: &[Vec3],
    targets: &[MorphTarget],
    weights: &[f32],
) -> Result<f32, EvalError> {
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
