//! What makes an asset unexportable, for both writers: [`Asset::validate`]'s problems and
//! the exporters' own checks, with each format's limits given as data ([`GLTF`], [`USD`]).

use std::collections::BTreeMap;

use rigport_model::{Asset, AssetError, Interpolation, TrackTarget};

use crate::Problem;

/// Quaternions shorter than this are degenerate (cannot be normalized meaningfully).
const MIN_QUAT_LENGTH: f64 = 1e-6;

/// What a format cannot hold, beyond the checks every writer makes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    /// A mesh needs vertices and triangles (glTF: a primitive with no triangles is
    /// invalid; a USD Mesh may be empty).
    pub(crate) triangles_needed: bool,
    /// The most joints a skin's palette may hold (glTF: `UNSIGNED_SHORT` joint indices;
    /// UsdSkel's are `int`).
    pub(crate) max_palette: Option<usize>,
}

/// glTF 2.0's limits.
pub(crate) const GLTF: Limits = Limits {
    triangles_needed: true,
    max_palette: Some(1 << 16),
};

/// USD's limits: none beyond the shared checks.
pub(crate) const USD: Limits = Limits {
    triangles_needed: false,
    max_palette: None,
};

/// Whether a quaternion is too short (or not finite) to normalize meaningfully.
fn degenerate(q: [f32; 4]) -> bool {
    let length = q
        .iter()
        .map(|&c| f64::from(c) * f64::from(c))
        .sum::<f64>()
        .sqrt();
    !length.is_finite() || length < MIN_QUAT_LENGTH
}

/// Everything that makes an asset unexportable: [`Asset::validate`]'s problems, then the
/// exporter's own checks (written to be safe on an asset that failed validation).
pub(crate) fn check(asset: &Asset, limits: &Limits) -> Vec<Problem> {
    let mut problems: Vec<Problem> = match asset.validate() {
        Ok(()) => Vec::new(),
        Err(errs) => errs.into_iter().map(Problem::Asset).collect(),
    };
    for (mi, mesh) in asset.meshes.iter().enumerate() {
        let n = mesh.vertex_count();
        if limits.triangles_needed && (n == 0 || mesh.triangles.is_empty()) {
            problems.push(Problem::EmptyMesh {
                mesh: mi,
                vertices: n,
                triangles: mesh.triangles.len(),
            });
        }
        let non_finite = |what: String| Problem::Asset(AssetError::NonFinite { what });
        if mesh
            .normals
            .as_ref()
            .is_some_and(|v| v.iter().any(|x| !x.is_finite()))
        {
            problems.push(non_finite(format!("mesh {mi} normals")));
        }
        if mesh
            .uvs
            .iter()
            .chain(&mesh.extra_uvs)
            .any(|v| v.iter().any(|x| !x.is_finite()))
        {
            problems.push(non_finite(format!("mesh {mi} uvs")));
        }
        for (ti, target) in mesh.morph_targets.iter().enumerate() {
            if let Some(d) = &target.normal_deltas {
                if d.len() != n {
                    problems.push(Problem::Asset(AssetError::AttributeLength {
                        mesh: mi,
                        attribute: "morph target normals",
                        found: d.len(),
                        expected: n,
                    }));
                }
                if d.iter().any(|x| !x.is_finite()) {
                    problems.push(non_finite(format!("mesh {mi} morph target {ti} normals")));
                }
            }
        }
        if !mesh.morph_weights.is_empty() && mesh.morph_weights.len() != mesh.morph_targets.len() {
            problems.push(Problem::MorphWeightCount {
                mesh: mi,
                found: mesh.morph_weights.len(),
                expected: mesh.morph_targets.len(),
            });
        }
        if mesh.morph_weights.iter().any(|w| !w.is_finite()) {
            problems.push(non_finite(format!("mesh {mi} default morph weights")));
        }
    }

    let mut skin_of_mesh: BTreeMap<usize, usize> = BTreeMap::new();
    for (si, skin) in asset.skins.iter().enumerate() {
        if let Some(&first) = skin_of_mesh.get(&skin.mesh.get()) {
            problems.push(Problem::SharedSkinMesh {
                mesh: skin.mesh.get(),
                first_skin: first,
                second_skin: si,
            });
        } else {
            skin_of_mesh.insert(skin.mesh.get(), si);
        }
        if skin.joints.is_empty() {
            problems.push(Problem::EmptyPalette { skin: si });
        }
        if limits
            .max_palette
            .is_some_and(|max| skin.joints.len() > max)
        {
            problems.push(Problem::PaletteTooLarge {
                skin: si,
                joints: skin.joints.len(),
            });
        }
        let mut sorted = skin.joints.clone();
        sorted.sort_unstable();
        for w in sorted.windows(2) {
            if w[0] == w[1] {
                problems.push(Problem::DuplicatePaletteJoint {
                    skin: si,
                    joint: w[0],
                });
            }
        }
    }

    for (index, joint) in asset.skeleton.joints().iter().enumerate() {
        if degenerate(joint.rest_local.rotation.to_array()) {
            problems.push(Problem::DegenerateRestRotation {
                joint: index,
                name: joint.name.clone(),
            });
        }
    }

    for clip in &asset.clips {
        for (ti, track) in clip.tracks.iter().enumerate() {
            if !matches!(track.target, TrackTarget::Rotation(_)) {
                continue;
            }
            let (stride, offset) = match track.interpolation {
                Interpolation::CubicSpline => (12, 4),
                _ => (4, 0),
            };
            for key in 0..track.times.len() {
                let start = key * stride + offset;
                let Some(&[x, y, z, w]) = track.values.get(start..start + 4) else {
                    break; // a value-count problem, already reported by validate()
                };
                if degenerate([x, y, z, w]) {
                    problems.push(Problem::DegenerateRotationKey {
                        clip: clip.name.clone(),
                        track: ti,
                        key,
                    });
                }
            }
        }
    }
    problems
}
