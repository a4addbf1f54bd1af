//! A rig compiled once from an [`Asset`], then evaluated for any number of poses.

use glam::{Mat4, Vec3};
use rigport_model::{Asset, JointIndex};

use crate::{skinning_matrices, EvalError, LbsJob, LocalToModelJob, Pose};

/// An asset checked and prepared for evaluation: parent array, per-mesh skin data.
///
/// Data-dependent checks (sizes, indices) happen in [`Rig::new`], not per pose.
pub struct Rig<'a> {
    asset: &'a Asset,
    parents: Vec<Option<JointIndex>>,
    /// Per mesh: the index of its skin binding, if skinned.
    mesh_skin: Vec<Option<usize>>,
}

/// Buffers for one evaluated pose, owned by the caller and reused across poses.
#[derive(Clone, Debug, Default)]
pub struct RigOutput {
    /// Model-space matrix per joint.
    pub joint_model: Vec<Mat4>,
    /// Per skin binding: the skinning matrix per palette joint.
    pub skin_matrices: Vec<Vec<Mat4>>,
    /// Per mesh: posed model-space positions, one per mesh vertex.
    pub positions: Vec<Vec<Vec3>>,
}

impl<'a> Rig<'a> {
    /// Compiles an asset.
    ///
    /// # Errors
    /// If the asset's skeleton or skins do not fit together (an [`Asset::validate`]d asset
    /// always compiles).
    pub fn new(asset: &'a Asset) -> Result<Self, EvalError> {
        let parents: Vec<_> = asset.skeleton.parents().collect();
        let mut mesh_skin = vec![None; asset.meshes.len()];
        for (si, skin) in asset.skins.iter().enumerate() {
            let slot = mesh_skin.get_mut(skin.mesh.get()).ok_or(EvalError::Index {
                what: "skin mesh",
                index: skin.mesh.get(),
            })?;
            *slot = Some(si);
            if let Some(j) = skin.joints.iter().find(|j| j.get() >= parents.len()) {
                return Err(EvalError::Index {
                    what: "skin palette",
                    index: j.get(),
                });
            }
        }
        Ok(Self {
            asset,
            parents,
            mesh_skin,
        })
    }

    /// The asset.
    pub fn asset(&self) -> &Asset {
        self.asset
    }

    /// The skin binding of mesh `mesh`, if it is skinned.
    pub fn skin_of_mesh(&self, mesh: usize) -> Option<usize> {
        self.mesh_skin.get(mesh).copied().flatten()
    }

    /// Evaluates `pose`: joint matrices, skinning matrices and linear-blend-skinned
    /// positions of every mesh. Unskinned meshes attached to a joint move rigidly with it.
    ///
    /// # Errors
    /// If the pose has the wrong number of joints.
    pub fn evaluate(&self, pose: &Pose, out: &mut RigOutput) -> Result<(), EvalError> {
        let asset = self.asset;
        out.joint_model.resize(self.parents.len(), Mat4::IDENTITY);
        LocalToModelJob {
            parents: &self.parents,
            local: &pose.local,
            root_model: Mat4::IDENTITY,
            model: &mut out.joint_model,
        }
        .run()?;
        out.skin_matrices.resize_with(asset.skins.len(), Vec::new);
        for (skin, mats) in asset.skins.iter().zip(out.skin_matrices.iter_mut()) {
            mats.resize(skin.joints.len(), Mat4::IDENTITY);
            skinning_matrices(&out.joint_model, &skin.joints, &skin.inv_bind, mats)?;
        }
        out.positions.resize_with(asset.meshes.len(), Vec::new);
        for (mi, mesh) in asset.meshes.iter().enumerate() {
            let dst = &mut out.positions[mi];
            dst.resize(mesh.positions.len(), Vec3::ZERO);
            if let Some(si) = self.mesh_skin[mi] {
                LbsJob {
                    skin_matrices: &out.skin_matrices[si],
                    influences: &asset.skins[si].influences,
                    rest_positions: &mesh.positions,
                    rest_normals: None,
                    out_positions: dst,
                    out_normals: None,
                }
                .run()?;
            } else {
                let m = mesh
                    .attached_to
                    .map_or(Mat4::IDENTITY, |j| out.joint_model[j.get()]);
                for (d, p) in dst.iter_mut().zip(&mesh.positions) {
                    *d = m.transform_point3(*p);
                }
            }
        }
        Ok(())
    }
}
