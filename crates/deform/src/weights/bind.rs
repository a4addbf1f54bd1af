//! Bone heat for a mesh and any skeleton ([`bind`]): the skin binding a rig would have had.
//!
//! The bones are the skeleton's segments at rest, from each joint to each of its children
//! (a joint with three children has three bones). A bone turns with the joint at its
//! head, so its weights go to that joint; the joints that head no bone (ends, or
//! children where their parent stands) get none. Each joint's inverse bind matrix is its
//! model-space rest transform inverted, so the mesh, given in the skeleton's model space,
//! stays where it is at rest.

use glam::Vec3;
use rigport_model::{Influence, Influences, JointIndex, Mesh, MeshIndex, Skeleton, SkinBinding};

use super::{bone_heat, Bone, HeatOptions, Repairs, WeightsError};

/// A skin binding made by [`bind`], with what bone heat repaired.
#[derive(Clone, Debug, PartialEq)]
pub struct Bound {
    /// The binding of the mesh, palette = the joints that head a bone.
    pub binding: SkinBinding,
    /// What bone heat repaired (see [`Repairs`]).
    pub repairs: Repairs,
    /// How many bones were weighted.
    pub bones: usize,
}

/// The skin binding of `mesh` (index `index` in its asset, positions in `skeleton`'s model
/// space) to `skeleton` by bone heat, LBS; `progress` as [`bone_heat`]'s.
///
/// ```
/// use rigport_deform::weights::{bind, HeatOptions};
/// use rigport_model::glam::{Quat, Vec3};
/// use rigport_model::{Joint, JointIndex, Mesh, MeshIndex, Skeleton, Transform};
///
/// // A two-bone chain along +Y, and a quad strip around it.
/// let joint = |name: &str, parent: Option<u32>, y| Joint {
///     name: name.into(),
///     parent: parent.map(JointIndex),
///     rest_local: Transform { translation: Vec3::Y * y, rotation: Quat::IDENTITY, scale: Vec3::ONE },
/// };
/// let skeleton = Skeleton::new(vec![
///     joint("hip", None, 0.0),
///     joint("knee", Some(0), 1.0),
///     joint("foot", Some(1), 1.0),
/// ]).unwrap();
/// let mut mesh = Mesh::default();
/// for k in 0..=4 {
///     let y = k as f32 * 0.5;
///     mesh.positions.extend([Vec3::new(-0.1, y, 0.0), Vec3::new(0.1, y, 0.0)]);
/// }
/// for k in 0..4u32 {
///     let (a, b) = (2 * k, 2 * k + 2);
///     mesh.triangles.extend([[a, a + 1, b], [b, a + 1, b + 1]]);
/// }
/// let bound = bind(&skeleton, &mesh, MeshIndex(0), &HeatOptions::default(), &|_, _| {}).unwrap();
/// assert_eq!(bound.bones, 2);
/// // The hip and the knee head a bone; the foot none.
/// assert_eq!(bound.binding.joints, [JointIndex(0), JointIndex(1)]);
/// let bottom = bound.binding.influences.vertex(0);
/// assert_eq!(bottom[0].joint, 0, "the bottom follows the hip: {bottom:?}");
/// ```
///
/// # Errors
/// A mesh without faces, a skeleton without bones (fewer than two joints, or every child
/// where its parent stands), a non-finite position.
pub fn bind(
    skeleton: &Skeleton,
    mesh: &Mesh,
    index: MeshIndex,
    options: &HeatOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Bound, WeightsError> {
    let rest = skeleton.model_rest_matrices();
    let at = |j: usize| rest[j].w_axis.truncate();
    let extent = (0..rest.len())
        .map(|j| at(j).length())
        .fold(0.0_f32, f32::max)
        .max(f32::MIN_POSITIVE);
    // One bone per (parent, child) pair of distinct positions; `head_of[b]` its parent.
    let mut bones = Vec::new();
    let mut head_of = Vec::new();
    for (child, parent) in skeleton.parents().enumerate() {
        let Some(parent) = parent else { continue };
        let (head, tail): (Vec3, Vec3) = (at(parent.get()), at(child));
        if head.distance(tail) > 1e-6 * extent {
            bones.push(Bone { head, tail });
            head_of.push(parent.get());
        }
    }
    if bones.is_empty() {
        return Err(WeightsError::NoBones);
    }
    let heat = bone_heat(&mesh.positions, &mesh.triangles, &bones, options, progress)?;
    // The palette: the joints that head a bone, in joint order.
    let mut palette_of = vec![None; skeleton.len()];
    let mut joints = Vec::new();
    for &j in &head_of {
        if palette_of[j].is_none() {
            palette_of[j] = Some(joints.len() as u32);
            joints.push(JointIndex(j as u32));
        }
    }
    let rows = heat.rows.iter().map(|row| {
        let mut out: Vec<Influence> = Vec::with_capacity(row.len());
        for &(bone, weight) in row {
            let joint = palette_of[head_of[bone as usize]].unwrap_or_default();
            match out.iter_mut().find(|i| i.joint == joint) {
                Some(i) => i.weight += weight,
                None => out.push(Influence { joint, weight }),
            }
        }
        out.sort_by(|a, b| b.weight.total_cmp(&a.weight));
        out
    });
    let mut influences = Influences::from_rows(rows);
    influences.normalize(0.0);
    let inv_bind = joints.iter().map(|j| rest[j.get()].inverse()).collect();
    Ok(Bound {
        binding: SkinBinding {
            mesh: index,
            joints,
            inv_bind,
            influences,
            method: Default::default(),
        },
        repairs: heat.repairs,
        bones: bones.len(),
    })
}
