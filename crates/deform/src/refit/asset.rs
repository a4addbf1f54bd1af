//! The refit of a whole asset: every skin whose vertices carry more than K influences is
//! refitted to K over a pose set, and the deviation of truncation and of the refit from
//! the full-weight deformation is measured over the same set.
//!
//! The pose set: the asset's clips sampled at their key times (at most
//! [`MAX_CLIP_POSES`] poses, spread evenly over all clips' keys) when it has clips;
//! otherwise [`range_of_motion`] with [`ROM_RANDOM_POSES`] random poses of
//! [`ROM_BENT_JOINTS`] joints each, seed [`ROM_SEED`]. The bind pose needs no place in the
//! set: any convex weights reproduce it exactly (see the module docs).

use std::num::NonZeroUsize;

use glam::Mat4;
use rigport_model::{Asset, Influences};

use super::{deviation, range_of_motion, truncate_row, Deviation, RefitJob};
use rigport_eval::sample::{CompiledClip, SampleError, SampleJob};
use rigport_eval::{skinning_matrices, EvalError, Pose};

/// Most clip poses a refit fits to (clips with more keys are sampled evenly).
pub const MAX_CLIP_POSES: usize = 256;
/// Random poses of the range-of-motion set for rigs without clips (160 combined bends, so
/// that the fit holds on poses outside the set; the held-out figures are in BENCHMARKS.md).
pub const ROM_RANDOM_POSES: usize = 160;
/// Joints bent together in each random range-of-motion pose.
pub const ROM_BENT_JOINTS: usize = 2;
/// Seed of the range-of-motion set.
pub const ROM_SEED: u64 = 1;

/// Where the poses of a refit came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PoseSet {
    /// The asset's clips, at their key times.
    Clips,
    /// [`range_of_motion`] (the asset has no clip).
    RangeOfMotion,
}

/// One skin's refit and what it changed.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinRefit {
    /// The skin (index into `Asset::skins`).
    pub skin: usize,
    /// Vertices whose row differs from the truncated one.
    pub changed: usize,
    /// Deviation of truncate-and-renormalize from the full weights, over the pose set.
    pub truncated: Deviation,
    /// Deviation of the refit from the full weights, over the pose set.
    pub refit: Deviation,
    /// Bounding-box diagonal of the skinned mesh at rest (to read deviations relative).
    pub diagonal: f64,
}

/// What [`refit_asset`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct AssetRefit {
    /// The pose set's source.
    pub pose_set: PoseSet,
    /// Poses fitted to.
    pub poses: usize,
    /// One entry per skin that had more than K influences on some vertex (others are left
    /// as they are).
    pub skins: Vec<SkinRefit>,
}

/// Why a refit could not run.
#[derive(Debug, thiserror::Error)]
pub enum RefitError {
    /// A clip does not fit the skeleton.
    #[error(transparent)]
    Sample(#[from] SampleError),
    /// A pose or skin does not fit.
    #[error(transparent)]
    Eval(#[from] EvalError),
}

/// Refits every skin of `asset` with more than `k` influences on a vertex to at most `k`
/// per vertex (see [`RefitJob`]), in place, and reports the deviations.
///
/// ```
/// # use std::num::NonZeroUsize;
/// # use rigport_deform::refit::asset::refit_asset;
/// let mut asset = rigport_model::Asset::default();
/// let report = refit_asset(&mut asset, NonZeroUsize::new(4).unwrap())?;
/// assert!(report.skins.is_empty()); // no skin, nothing to refit
/// # Ok::<(), rigport_deform::refit::asset::RefitError>(())
/// ```
///
/// # Errors
/// A clip or skin that does not fit the skeleton.
pub fn refit_asset(asset: &mut Asset, k: NonZeroUsize) -> Result<AssetRefit, RefitError> {
    let needs: Vec<usize> = (0..asset.skins.len())
        .filter(|&s| asset.skins[s].influences.max_per_vertex() > k.get())
        .collect();
    let (pose_set, poses) = if asset.clips.is_empty() {
        let poses = range_of_motion(&asset.skeleton, ROM_RANDOM_POSES, ROM_BENT_JOINTS, ROM_SEED);
        (PoseSet::RangeOfMotion, poses)
    } else {
        (PoseSet::Clips, clip_poses(asset)?)
    };
    let mut report = AssetRefit {
        pose_set,
        poses: poses.len(),
        skins: Vec::new(),
    };
    if needs.is_empty() {
        return Ok(report);
    }
    let models: Vec<Vec<Mat4>> = poses
        .iter()
        .map(|p| p.model_matrices(&asset.skeleton))
        .collect::<Result<_, _>>()?;
    for s in needs {
        let skin = &asset.skins[s];
        let n = skin.joints.len();
        let mut matrices = Vec::with_capacity(models.len() * n);
        let mut palette = vec![Mat4::IDENTITY; n];
        for model in &models {
            skinning_matrices(model, &skin.joints, &skin.inv_bind, &mut palette)?;
            matrices.extend_from_slice(&palette);
        }
        let positions = &asset.meshes[skin.mesh.get()].positions;
        let refit = RefitJob {
            positions,
            influences: &skin.influences,
            pose_matrices: &matrices,
            palette_len: n,
            max_influences: k,
        }
        .run()?;
        let truncated =
            Influences::from_rows(skin.influences.rows().map(|row| truncate_row(row, k.get())));
        let d_truncated = deviation(positions, &skin.influences, &truncated, &matrices, n)?;
        let d_refit = deviation(positions, &skin.influences, &refit.influences, &matrices, n)?;
        let diagonal = positions
            .iter()
            .fold(None, |acc: Option<(glam::Vec3, glam::Vec3)>, &p| {
                Some(acc.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))))
            })
            .map_or(0.0, |(lo, hi)| f64::from((hi - lo).length()));
        report.skins.push(SkinRefit {
            skin: s,
            changed: refit.changed,
            truncated: d_truncated,
            refit: d_refit,
            diagonal,
        });
        asset.skins[s].influences = refit.influences;
    }
    Ok(report)
}

/// The clip poses: every clip's key times, thinned evenly to at most [`MAX_CLIP_POSES`].
fn clip_poses(asset: &Asset) -> Result<Vec<Pose>, RefitError> {
    let rest = Pose::rest(&asset.skeleton);
    let compiled: Vec<CompiledClip> = asset
        .clips
        .iter()
        .map(|clip| CompiledClip::new(clip, &asset.skeleton))
        .collect::<Result<_, _>>()?;
    let samples: Vec<(usize, f32)> = compiled
        .iter()
        .enumerate()
        .flat_map(|(c, clip)| clip.key_times().into_iter().map(move |t| (c, t)))
        .collect();
    let step = samples.len().div_ceil(MAX_CLIP_POSES).max(1);
    let mut poses = Vec::new();
    for &(c, time) in samples.iter().step_by(step) {
        let mut pose = rest.clone();
        SampleJob {
            clip: &compiled[c],
            time,
            rest: &rest.local,
            output: &mut pose.local,
        }
        .run()?;
        poses.push(pose);
    }
    Ok(poses)
}
