//! A rig compiled once from an [`Asset`], then evaluated for any number of poses.

use glam::{Mat4, Vec3};
use rigport_model::{Asset, JointIndex};

use crate::dqs::DqsPalette;
use crate::morph::{morph_positions, MorphWeights};
use crate::skinning::{PackedInfluences, SkinFramesJob};
use crate::{skinning_matrices, EvalError, LocalToModelJob, Pose};
use rigport_model::SkinningMethod;

/// An asset checked and prepared for evaluation: parent array, per-mesh skin data.
///
/// Data-dependent checks (sizes, indices) happen in [`Rig::new`], not per pose; each skin's
/// influences are packed there once ([`PackedInfluences`]).
pub struct Rig<'a> {
    asset: &'a Asset,
    parents: Vec<Option<JointIndex>>,
    /// Per mesh: the index of its skin binding, if skinned.
    mesh_skin: Vec<Option<usize>>,
    /// Per skin binding: its influences, packed for the skinning loops.
    packed: Vec<PackedInfluences>,
    /// Each mesh's default morph weights, for a pose evaluated without a clip's.
    rest_weights: MorphWeights,
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
    /// Per skin binding: scratch for dual quaternion skinning, kept so that evaluating
    /// another pose reuses it.
    pub dqs_palettes: Vec<DqsPalette>,
    /// Scratch: a mesh's morphed shape before it is skinned or placed.
    morphed: Vec<Vec3>,
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
        let mut packed = Vec::with_capacity(asset.skins.len());
        for (si, skin) in asset.skins.iter().enumerate() {
            let mesh = asset.meshes.get(skin.mesh.get());
            let (Some(slot), Some(mesh)) = (mesh_skin.get_mut(skin.mesh.get()), mesh) else {
                return Err(EvalError::Index {
                    what: "skin mesh",
                    index: skin.mesh.get(),
                });
            };
            *slot = Some(si);
            if let Some(j) = skin.joints.iter().find(|j| j.get() >= parents.len()) {
                return Err(EvalError::Index {
                    what: "skin palette",
                    index: j.get(),
                });
            }
            if skin.inv_bind.len() != skin.joints.len() {
                return Err(EvalError::Length {
                    what: "skin inv_bind",
                    expected: skin.joints.len(),
                    found: skin.inv_bind.len(),
                });
            }
            let p = PackedInfluences::new(&skin.influences);
            if p.vertex_count() != mesh.positions.len() {
                return Err(EvalError::Length {
                    what: "skin influences",
                    expected: mesh.positions.len(),
                    found: p.vertex_count(),
                });
            }
            if p.joint_bound() > skin.joints.len() {
                return Err(EvalError::Index {
                    what: "influences",
                    index: p.joint_bound() - 1,
                });
            }
            packed.push(p);
        }
        Ok(Self {
            asset,
            parents,
            mesh_skin,
            packed,
            rest_weights: MorphWeights::rest(asset),
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

    /// Evaluates `pose` with linear blend skinning: [`Rig::evaluate_with`] and
    /// [`SkinningMethod::Lbs`].
    ///
    /// # Errors
    /// If the pose has the wrong number of joints.
    pub fn evaluate(&self, pose: &Pose, out: &mut RigOutput) -> Result<(), EvalError> {
        self.evaluate_with(pose, SkinningMethod::Lbs, out)
    }

    /// Evaluates `pose` with each mesh's default morph weights: [`Rig::evaluate_frame`]
    /// with [`MorphWeights::rest`].
    ///
    /// # Errors
    /// If the pose has the wrong number of joints.
    pub fn evaluate_with(
        &self,
        pose: &Pose,
        method: SkinningMethod,
        out: &mut RigOutput,
    ) -> Result<(), EvalError> {
        self.evaluate_frame(pose, &self.rest_weights, method, out)
    }

    /// The morph weights [`Rig::evaluate_with`] uses: each mesh's defaults. Clone them and
    /// [`MorphWeights::sample`] a clip into the copy to evaluate its frames.
    pub fn rest_weights(&self) -> &MorphWeights {
        &self.rest_weights
    }

    /// Evaluates one frame: joint matrices, skinning matrices and the positions of every
    /// mesh, morphed by `weights` (glTF and UsdSkel apply morph targets before the skin),
    /// then skinned with `method`. Unskinned meshes attached to a joint move rigidly with
    /// it. `out`'s buffers are resized on first use and reused afterwards.
    ///
    /// # Errors
    /// If the pose has the wrong number of joints.
    pub fn evaluate_frame(
        &self,
        pose: &Pose,
        weights: &MorphWeights,
        method: SkinningMethod,
        out: &mut RigOutput,
    ) -> Result<(), EvalError> {
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
        out.dqs_palettes
            .resize_with(asset.skins.len(), DqsPalette::default);
        if method == SkinningMethod::Dqs {
            for (skin, palette) in asset.skins.iter().zip(out.dqs_palettes.iter_mut()) {
                if palette.joint_capacity() < skin.joints.len() || palette.frame_capacity() < 1 {
                    *palette = DqsPalette::new(skin.joints.len(), 1);
                }
            }
        }
        for (mi, mesh) in asset.meshes.iter().enumerate() {
            let dst = &mut out.positions[mi];
            dst.resize(mesh.positions.len(), Vec3::ZERO);
            let shape = if morph_positions(
                &mesh.positions,
                &mesh.morph_targets,
                weights.mesh(mi),
                &mut out.morphed,
            ) {
                out.morphed.as_slice()
            } else {
                mesh.positions.as_slice()
            };
            if let Some(si) = self.mesh_skin[mi] {
                SkinFramesJob {
                    method,
                    influences: &self.packed[si],
                    rest_positions: shape,
                    frame_skin_matrices: &out.skin_matrices[si],
                    out_positions: dst,
                    palette: &mut out.dqs_palettes[si],
                }
                .run()?;
            } else {
                let m = mesh
                    .attached_to
                    .map_or(Mat4::IDENTITY, |j| out.joint_model[j.get()]);
                for (d, p) in dst.iter_mut().zip(shape) {
                    *d = m.transform_point3(*p);
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3Swizzles};
    use rigport_model::{
        Influence, Influences, Joint, Mesh, MeshIndex, Skeleton, SkinBinding, Transform,
    };

    /// A limb along +X: joint 0 at the origin, joint 1 at x = 1; a ring of vertices of
    /// radius 0.25 around the elbow, weighted half to each joint.
    fn limb() -> Asset {
        let skeleton = Skeleton::new(vec![
            Joint {
                name: "upper".into(),
                parent: None,
                rest_local: Transform::IDENTITY,
            },
            Joint {
                name: "lower".into(),
                parent: Some(JointIndex(0)),
                rest_local: Transform::from_translation(Vec3::X),
            },
        ])
        .unwrap();
        let positions: Vec<Vec3> = (0..8)
            .map(|i| {
                let a = i as f32 * std::f32::consts::TAU / 8.0;
                Vec3::new(1.0, 0.25 * a.cos(), 0.25 * a.sin())
            })
            .collect();
        let n = positions.len();
        let inv_bind = skeleton
            .model_rest_matrices()
            .iter()
            .map(|m| m.inverse())
            .collect();
        Asset {
            skeleton,
            meshes: vec![Mesh {
                positions,
                source_vertex: (0..n as u32).collect(),
                ..Mesh::default()
            }],
            skins: vec![SkinBinding {
                method: Default::default(),
                mesh: MeshIndex(0),
                joints: vec![JointIndex(0), JointIndex(1)],
                inv_bind,
                influences: Influences::from_rows((0..n).map(|_| {
                    [
                        Influence {
                            joint: 0,
                            weight: 0.5,
                        },
                        Influence {
                            joint: 1,
                            weight: 0.5,
                        },
                    ]
                })),
            }],
            ..Asset::default()
        }
    }

    #[test]
    fn twisting_collapses_lbs_but_not_dqs() {
        let asset = limb();
        let rig = Rig::new(&asset).unwrap();
        let mut pose = Pose::rest(&asset.skeleton);
        let mut out = RigOutput::default();
        rig.evaluate_with(&pose, SkinningMethod::Dqs, &mut out)
            .unwrap();
        assert_eq!(out.positions[0], asset.meshes[0].positions);
        // Twist the lower joint 180° about the bone axis: the candy-wrapper case.
        pose.local[1].rotation = Quat::from_rotation_x(std::f32::consts::PI);
        rig.evaluate(&pose, &mut out).unwrap();
        let lbs_radius = out.positions[0]
            .iter()
            .map(|p| p.yz().length())
            .fold(0.0f32, f32::max);
        assert!(
            lbs_radius < 1e-6,
            "LBS collapses the ring onto the axis: {lbs_radius}"
        );
        rig.evaluate_with(&pose, SkinningMethod::Dqs, &mut out)
            .unwrap();
        for p in &out.positions[0] {
            assert!(
                (p.yz().length() - 0.25).abs() < 1e-5,
                "DQS keeps the radius: {p}"
            );
            assert!((p.x - 1.0).abs() < 1e-5, "{p}");
        }
    }

    #[test]
    fn rejects_influences_that_do_not_fit_the_mesh_or_palette() {
        let mut asset = limb();
        asset.skins[0].influences = Influences::from_rows([[Influence {
            joint: 0,
            weight: 1.0,
        }]]);
        assert!(matches!(
            Rig::new(&asset),
            Err(EvalError::Length {
                what: "skin influences",
                expected: 8,
                found: 1
            })
        ));
        let mut asset = limb();
        asset.skins[0].influences = Influences::from_rows((0..8).map(|_| {
            [Influence {
                joint: 2,
                weight: 1.0,
            }]
        }));
        assert_eq!(
            Rig::new(&asset).err(),
            Some(EvalError::Index {
                what: "influences",
                index: 2
            })
        );
    }
}
