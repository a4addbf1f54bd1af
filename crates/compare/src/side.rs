//! One side of a comparison: an asset compiled into a [`Rig`], evaluated in the
//! comparison frame (a model -> frame matrix: +Y up metres, and for the candidate the
//! placement found undone) at the times asked, into caller-owned [`Posed`] buffers.

use glam::{DMat4, DQuat, DVec3, Mat4};
use rigport_eval::sample::{CompiledClip, SampleJob};
use rigport_eval::{LocalToModelJob, MorphWeights, Pose, Rig, RigOutput};
use rigport_model::{Asset, JointIndex, SkinningMethod};

use crate::CompareError;

/// An asset ready to be evaluated in the comparison frame.
pub struct Side<'a> {
    asset: &'a Asset,
    rig: Rig<'a>,
    to_frame: DMat4,
    method: SkinningMethod,
    rest: Pose,
    parents: Vec<Option<JointIndex>>,
}

/// One evaluated frame in the comparison frame: per joint its position and rotation, per
/// mesh its vertices.
#[derive(Clone, Debug, Default)]
pub struct Posed {
    /// Joint origins (metres).
    pub joint_positions: Vec<DVec3>,
    /// Joint rotations (scale taken out).
    pub joint_rotations: Vec<DQuat>,
    /// Per mesh, its vertices (metres).
    pub positions: Vec<Vec<DVec3>>,
}

/// Scratch reused across frames.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    pose: Option<Pose>,
    weights: Option<MorphWeights>,
    out: RigOutput,
}

impl<'a> Side<'a> {
    /// `asset` seen through `to_frame` (model space -> the comparison frame), skinned
    /// with its first skin's method.
    ///
    /// # Errors
    /// The asset cannot be evaluated.
    pub fn new(asset: &'a Asset, to_frame: DMat4) -> Result<Self, CompareError> {
        let method = asset.skins.first().map(|s| s.method).unwrap_or_default();
        Ok(Self {
            asset,
            rig: Rig::new(asset)?,
            to_frame,
            method,
            rest: Pose::rest(&asset.skeleton),
            parents: asset.skeleton.parents().collect(),
        })
    }

    /// The asset.
    pub fn asset(&self) -> &'a Asset {
        self.asset
    }

    /// Model space -> comparison frame.
    pub fn to_frame(&self) -> DMat4 {
        self.to_frame
    }

    /// The same asset seen through `to_frame` instead.
    pub fn with_frame(mut self, to_frame: DMat4) -> Self {
        self.to_frame = to_frame;
        self
    }

    /// Evaluates the rest pose (`clip` `None`) or `clip` at `time` into `out`; vertices
    /// only when `vertices` (joints alone are a forward-kinematics pass).
    ///
    /// # Errors
    /// The clip does not fit the skeleton, or the pose cannot be evaluated.
    pub fn evaluate(
        &self,
        clip: Option<&CompiledClip<'_>>,
        time: f32,
        vertices: bool,
        scratch: &mut Scratch,
        out: &mut Posed,
    ) -> Result<(), CompareError> {
        let asset = self.asset();
        let pose = scratch.pose.get_or_insert_with(|| self.rest.clone());
        let weights = scratch
            .weights
            .get_or_insert_with(|| self.rig.rest_weights().clone());
        let rest = &self.rest;
        match clip {
            Some(clip) => {
                SampleJob {
                    clip,
                    time,
                    rest: &rest.local,
                    output: &mut pose.local,
                }
                .run()?;
                weights.sample(clip, time)?;
            }
            None => {
                pose.local.clone_from(&rest.local);
                weights.clone_from(self.rig.rest_weights());
            }
        }
        if vertices {
            self.rig
                .evaluate_frame(pose, weights, self.method, &mut scratch.out)?;
        } else {
            let model = &mut scratch.out.joint_model;
            model.resize(self.parents.len(), Mat4::IDENTITY);
            LocalToModelJob {
                parents: &self.parents,
                local: &pose.local,
                root_model: Mat4::IDENTITY,
                model,
            }
            .run()?;
        }
        out.joint_positions.clear();
        out.joint_rotations.clear();
        for m in &scratch.out.joint_model {
            let world = self.to_frame * m.as_dmat4();
            let (_, rotation, position) = world.to_scale_rotation_translation();
            out.joint_positions.push(position);
            out.joint_rotations.push(rotation.normalize());
        }
        if vertices {
            out.positions.resize_with(asset.meshes.len(), Vec::new);
            for (dst, src) in out.positions.iter_mut().zip(&scratch.out.positions) {
                dst.clear();
                dst.extend(
                    src.iter()
                        .map(|p| self.to_frame.transform_point3(p.as_dvec3())),
                );
            }
        }
        Ok(())
    }
}
