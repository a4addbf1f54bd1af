//! The asset moved into glTF's frame (+Y up, metres) by transforming its data.
//!
//! The correction `C` = [`SceneFrame::model_to_gltf`] (source up axis to +Y, the source's
//! unit to metres when it states one, and the placement above the skeleton) is split into
//! a uniform scale `s` and a rigid part `G` (`C = G · s`), and applied to the data, so the
//! document keeps its layout (no extra node; a skinned mesh's node stays at the scene root
//! without transform, as glTF's skinning rule wants):
//! - every joint's rest translation and translation keys (values and tangents) × `s`;
//! - root joints (no parent) are then placed by `G`: rest `T·R` and their translation /
//!   rotation keys pre-multiplied by `G` (tangents by its linear part);
//! - inverse bind matrices `IB' = s·IB·s⁻¹ · G⁻¹`;
//! - skinned and free meshes: points `C·p`, normals and morph normal deltas rotated by `G`,
//!   morph position deltas by `s·G`; meshes attached to a joint stay in its space: points
//!   and deltas × `s`.
//!
//! Skinned points then come out as `C` times the source's, and joint world matrices as
//! `C · M · s⁻¹` (a joint's scale stays the source's). A correction that is not a
//! similarity (non-uniform scale or shear above the skeleton) cannot be applied to TRS
//! joints exactly: its nearest similarity is applied, and a warning says so.

use glam::{DMat3, DMat4, DQuat, DVec3, Vec3};
use rigport_model::{
    Asset, AssetError, Interpolation, Joint, SceneFrame, Skeleton, TrackTarget, Warning,
};

use crate::{ExportError, Problem};

/// Largest relative difference between the correction's axis lengths (or its deviation
/// from orthogonality) for it to count as a similarity.
const SIMILARITY_TOLERANCE: f64 = 1e-6;

/// A similarity transform: `p ↦ rotation · (scale · p) + translation`.
#[derive(Clone, Copy, Debug)]
struct Similarity {
    scale: f64,
    rotation: DQuat,
    translation: DVec3,
}

impl Similarity {
    fn rigid(&self) -> DMat4 {
        DMat4::from_rotation_translation(self.rotation, self.translation)
    }
}

/// Splits `m` into a similarity; `exact` is false when `m` has non-uniform scale or shear
/// (the result is then the nearest similarity: the mean axis length and the rotation of
/// the orthonormalized axes).
fn similarity(m: &DMat4) -> (Similarity, bool) {
    let lin = DMat3::from_mat4(*m);
    let det = lin.determinant();
    let scale = det.abs().cbrt();
    let lengths = [
        lin.x_axis.length(),
        lin.y_axis.length(),
        lin.z_axis.length(),
    ];
    let rot = if scale > 0.0 {
        lin * (1.0 / scale)
    } else {
        DMat3::IDENTITY
    };
    let ortho = (rot.transpose() * rot).abs_diff_eq(DMat3::IDENTITY, SIMILARITY_TOLERANCE);
    let uniform = lengths
        .iter()
        .all(|l| (l - scale).abs() <= SIMILARITY_TOLERANCE * scale.max(1e-30));
    let exact = ortho && uniform && det > 0.0;
    let rotation = DQuat::from_mat3(&rot).normalize();
    (
        Similarity {
            scale,
            rotation,
            translation: m.w_axis.truncate(),
        },
        exact,
    )
}

/// The uniform scale [`to_gltf_frame`] applies to the asset's lengths (1 when it applies
/// none): a length in the source's unit times this is metres in the file.
pub(crate) fn length_scale(asset: &Asset) -> f64 {
    let c = asset.frame.model_to_gltf(asset.meters_per_unit);
    if c == DMat4::IDENTITY {
        return 1.0;
    }
    similarity(&c).0.scale
}

/// The asset in glTF's frame, or `None` when the correction is the identity (a Y-up,
/// metre or unit-less source placed at the origin): the common case keeps its bytes.
///
/// # Errors
/// [`ExportError::Invalid`] when the corrected skeleton is not finite.
pub(crate) fn to_gltf_frame(
    asset: &Asset,
    warnings: &mut Vec<Warning>,
) -> Result<Option<Asset>, ExportError> {
    let c = asset.frame.model_to_gltf(asset.meters_per_unit);
    if c == DMat4::IDENTITY {
        return Ok(None);
    }
    let (sim, exact) = similarity(&c);
    if !exact {
        warnings.push(Warning::Repaired {
            location: "asset".into(),
            message: "the transform above the skeleton has non-uniform scale or shear, which \
                      glTF joints (TRS) cannot carry: its nearest similarity was applied"
                .into(),
        });
    }
    let s = sim.scale;
    let g = sim.rigid();
    let gq = sim.rotation;
    let g_inv = g.inverse();
    let c = g * DMat4::from_scale(DVec3::splat(s));

    let mut out = asset.clone();
    out.frame = SceneFrame::default();
    if out.meters_per_unit.is_some() {
        out.meters_per_unit = Some(1.0);
    }

    // Joints.
    let joints: Vec<Joint> = asset
        .skeleton
        .joints()
        .iter()
        .map(|j| {
            let mut j = j.clone();
            let t = j.rest_local.translation.as_dvec3() * s;
            let r = j.rest_local.rotation.as_dquat();
            let (t, r) = if j.parent.is_none() {
                (gq * t + sim.translation, (gq * r).normalize())
            } else {
                (t, r)
            };
            j.rest_local.translation = t.as_vec3();
            j.rest_local.rotation = r.as_quat();
            j
        })
        .collect();
    out.skeleton = Skeleton::new(joints).map_err(|problems| ExportError::Invalid {
        problems: problems
            .into_iter()
            .map(|p| {
                Problem::Asset(AssetError::NonFinite {
                    what: format!("skeleton in glTF's frame: {p}"),
                })
            })
            .collect(),
    })?;
    let is_root = |j: usize| {
        asset
            .skeleton
            .joints()
            .get(j)
            .is_some_and(|j| j.parent.is_none())
    };

    // Tracks.
    for clip in &mut out.clips {
        for track in &mut clip.tracks {
            let cubic = track.interpolation == Interpolation::CubicSpline;
            // Which value slots are tangents (cubic: [in, value, out] per key).
            let is_value = |k: usize| !cubic || k % 3 == 1;
            match track.target {
                TrackTarget::Translation(j) => {
                    let root = is_root(j.get());
                    for (k, v) in track.values.chunks_exact_mut(3).enumerate() {
                        let mut p = DVec3::new(v[0].into(), v[1].into(), v[2].into()) * s;
                        if root {
                            p = gq * p;
                            if is_value(k) {
                                p += sim.translation;
                            }
                        }
                        v.copy_from_slice(&p.as_vec3().to_array());
                    }
                }
                TrackTarget::Rotation(j) if is_root(j.get()) => {
                    for v in track.values.chunks_exact_mut(4) {
                        let q =
                            DQuat::from_xyzw(v[0].into(), v[1].into(), v[2].into(), v[3].into());
                        let q = gq * q;
                        v.copy_from_slice(&q.as_quat().to_array());
                    }
                }
                _ => {}
            }
        }
    }

    // Inverse binds: s·IB·s⁻¹ · G⁻¹.
    for skin in &mut out.skins {
        for ib in &mut skin.inv_bind {
            let mut m = ib.as_dmat4();
            m.w_axis.x *= s;
            m.w_axis.y *= s;
            m.w_axis.z *= s;
            *ib = (m * g_inv).as_mat4();
        }
    }

    // Meshes.
    let skinned: Vec<bool> = (0..asset.meshes.len())
        .map(|mi| asset.skins.iter().any(|sk| sk.mesh.get() == mi))
        .collect();
    let rot = |v: &mut Vec3| *v = (gq * v.as_dvec3()).as_vec3();
    for (mi, mesh) in out.meshes.iter_mut().enumerate() {
        let free = skinned.get(mi).copied().unwrap_or(false) || mesh.attached_to.is_none();
        if free {
            for p in &mut mesh.positions {
                *p = c.transform_point3(p.as_dvec3()).as_vec3();
            }
            if let Some(normals) = &mut mesh.normals {
                normals.iter_mut().for_each(rot);
            }
            for target in &mut mesh.morph_targets {
                for d in &mut target.position_deltas {
                    *d = (gq * (d.as_dvec3() * s)).as_vec3();
                }
                if let Some(nd) = &mut target.normal_deltas {
                    nd.iter_mut().for_each(rot);
                }
            }
        } else {
            for p in &mut mesh.positions {
                *p = (p.as_dvec3() * s).as_vec3();
            }
            for target in &mut mesh.morph_targets {
                for d in &mut target.position_deltas {
                    *d = (d.as_dvec3() * s).as_vec3();
                }
            }
        }
    }
    Ok(Some(out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn similarity_splits_blender_like_corrections() {
        let m = DMat4::from_scale_rotation_translation(
            DVec3::splat(0.01),
            DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2),
            DVec3::new(1.0, 2.0, 3.0),
        );
        let (sim, exact) = similarity(&m);
        assert!(exact);
        assert!((sim.scale - 0.01).abs() < 1e-15);
        let back = sim.rigid() * DMat4::from_scale(DVec3::splat(sim.scale));
        assert!(back.abs_diff_eq(m, 1e-12));
        let sheared = DMat4::from_scale(DVec3::new(1.0, 2.0, 1.0));
        assert!(!similarity(&sheared).1);
    }

    #[test]
    fn identity_frame_is_untouched() {
        let asset = Asset {
            meters_per_unit: Some(1.0),
            ..Default::default()
        };
        let mut w = Vec::new();
        assert!(to_gltf_frame(&asset, &mut w).ok().flatten().is_none());
    }
}
