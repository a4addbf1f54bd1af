//! The Skeleton prims: joint path tokens, rest and bind matrices, and which Skeleton prim
//! (and geomBindTransform) each skin is bound to.

use glam::{DMat4, DQuat};
use rigport_model::{Asset, SkinBinding, Transform, Warning};

use super::names::{Namespace, Renames};
use super::sampler::dot;
use crate::labels::mesh_label;

/// Name of the Skeleton prim (extra bind poses get `Skeleton_1`, ...).
pub(super) const SKELETON: &str = "Skeleton";

/// Largest element difference (translations: relative to the matrices' scale) at which two
/// bind matrices count as equal. Inverse bind matrices are `f32` (about 6e-8 relative
/// precision); 1e-6 is a few ulps of slack and far below the 1e-5 acceptance tolerance.
const BIND_TOLERANCE: f64 = 1e-6;

/// The UsdSkel joint path token of every joint, and the renames made.
pub(super) fn joint_tokens(asset: &Asset) -> (Vec<String>, Renames) {
    let joints = asset.skeleton.joints();
    let mut child_ns: Vec<Namespace> = (0..joints.len()).map(|_| Namespace::default()).collect();
    let mut root_ns = Namespace::default();
    let mut renames = Renames::default();
    let mut tokens: Vec<String> = Vec::with_capacity(joints.len());
    for joint in joints {
        let parent = joint.parent.map(|p| p.get());
        let ns = match parent.and_then(|p| child_ns.get_mut(p)) {
            Some(ns) => ns,
            None => &mut root_ns,
        };
        let (name, renamed) = ns.claim(&joint.name, "joint");
        if renamed {
            renames.push(&joint.name, &name);
        }
        // Parents come first, so the parent's token exists.
        let token = match parent.and_then(|p| tokens.get(p)) {
            Some(parent_token) => format!("{parent_token}/{name}"),
            None => name,
        };
        tokens.push(token);
    }
    (tokens, renames)
}

/// `T · R · S` in `f64`, the rotation normalized.
pub(super) fn transform_d(t: &Transform) -> DMat4 {
    let q = t.rotation.to_array().map(f64::from);
    let len = dot(q, q).sqrt();
    let q = if len > 0.0 {
        q.map(|c| c / len)
    } else {
        [0.0, 0.0, 0.0, 1.0]
    };
    DMat4::from_scale_rotation_translation(
        t.scale.as_dvec3(),
        DQuat::from_xyzw(q[0], q[1], q[2], q[3]),
        t.translation.as_dvec3(),
    )
}

/// Whether two matrices agree within [`BIND_TOLERANCE`] (translations relative to their
/// magnitude, at least 1).
fn near(a: &DMat4, b: &DMat4) -> bool {
    let scale = a
        .w_axis
        .truncate()
        .abs()
        .max(b.w_axis.truncate().abs())
        .max_element()
        .max(1.0);
    let (a, b) = (a.to_cols_array_2d(), b.to_cols_array_2d());
    a.iter().zip(&b).enumerate().all(|(c, (ca, cb))| {
        ca.iter().zip(cb).enumerate().all(|(r, (x, y))| {
            let tol = if c == 3 && r < 3 {
                BIND_TOLERANCE * scale
            } else {
                BIND_TOLERANCE
            };
            (x - y).abs() <= tol
        })
    })
}

/// The bind matrices of each Skeleton prim, and for each skin its Skeleton prim and
/// geomBindTransform.
///
/// Skeleton 0's bind matrix of a joint is the inverse of the first skin's inverse bind
/// matrix that names it, else the joint's rest model matrix. A skin whose inverse bind
/// matrices disagree is placed with a common geomBindTransform `G` when one exists (UsdSkel
/// skins `jointWorld · bind⁻¹ · G · p`, rigport `jointWorld · invBind · p`, so
/// `G = bind · invBind` must be the same for all its joints), else on a Skeleton prim of its
/// own with the same joints and animation.
pub(super) fn bind_poses(
    asset: &Asset,
    rest_model: &[DMat4],
    warnings: &mut Vec<Warning>,
) -> (Vec<Vec<DMat4>>, Vec<(usize, DMat4)>) {
    let mut first: Vec<Option<DMat4>> = vec![None; rest_model.len()];
    for skin in &asset.skins {
        for (j, ib) in skin.joints.iter().zip(&skin.inv_bind) {
            if let Some(slot @ None) = first.get_mut(j.get()) {
                *slot = Some(ib.as_dmat4().inverse());
            }
        }
    }
    let bind0: Vec<DMat4> = first
        .into_iter()
        .zip(rest_model)
        .map(|(b, rest)| b.unwrap_or(*rest))
        .collect();
    let mut binds = vec![bind0];
    let mut places = Vec::with_capacity(asset.skins.len());
    for (si, skin) in asset.skins.iter().enumerate() {
        let place = place_skin(&mut binds, skin);
        if place.0 > 0 && place.0 == binds.len() - 1 {
            let mesh = asset.meshes.get(skin.mesh.get());
            warnings.push(Warning::Note {
                location: format!(
                    "skin {si} (mesh {:?})",
                    mesh.map(|m| mesh_label(skin.mesh.get(), m))
                        .unwrap_or_default()
                ),
                message: format!(
                    "its bind pose differs from that of earlier skins; written as Skeleton prim \
                     {SKELETON}_{} with the same joints and animation",
                    place.0
                ),
            });
        }
        places.push(place);
    }
    (binds, places)
}

/// Finds or makes the Skeleton prim for `skin` (see [`bind_poses`]).
fn place_skin(binds: &mut Vec<Vec<DMat4>>, skin: &SkinBinding) -> (usize, DMat4) {
    let inv: Vec<(usize, DMat4)> = skin
        .joints
        .iter()
        .zip(&skin.inv_bind)
        .map(|(j, ib)| (j.get(), ib.as_dmat4()))
        .collect();
    let g_of = |bind: &[DMat4]| -> Vec<DMat4> {
        inv.iter()
            .filter_map(|(j, ib)| bind.get(*j).map(|b| *b * *ib))
            .collect()
    };
    for (k, bind) in binds.iter().enumerate() {
        let g = g_of(bind);
        if g.iter().all(|m| near(m, &DMat4::IDENTITY)) {
            return (k, DMat4::IDENTITY);
        }
        if k == 0 {
            if let Some(g0) = g.first() {
                if g.iter().all(|m| near(m, g0)) {
                    return (0, *g0);
                }
            }
        }
    }
    let mut own = binds.first().cloned().unwrap_or_default();
    for (j, ib) in &inv {
        if let Some(slot) = own.get_mut(*j) {
            *slot = ib.inverse();
        }
    }
    binds.push(own);
    (binds.len() - 1, DMat4::IDENTITY)
}
