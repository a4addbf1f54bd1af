//! Garment setup: the particles and triangles of a garment mesh, and which of them are
//! pinned to the body.

use glam::{Mat4, Vec3};
use rigport_model::{Asset, Mesh};

use super::ClothError;

/// A garment ready to simulate: particles (model space, at rest), triangles and pins.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Garment {
    /// Particle rest positions, model space (the skeleton's).
    pub positions: Vec<Vec3>,
    /// Triangles as particle index triples.
    pub triangles: Vec<[u32; 3]>,
    /// Pinned particles (ascending, unique): they follow the body surface.
    pub pinned: Vec<u32>,
}

/// How the garment's pinned vertices are chosen. Several selections add up.
#[derive(Clone, Debug, PartialEq)]
pub enum PinSelection {
    /// Vertices whose per-vertex value of this name ([`Mesh::vertex_values`]) is non-zero
    /// (e.g. the `primvars:ControlPoints` of the USTC course files: `ControlPoints`).
    Values(String),
    /// These source vertices (OBJ `v` order, USD `points` order).
    Vertices(Vec<u32>),
    /// Vertices at or below this height (scene up axis, scene units).
    Below(f32),
    /// Vertices at or above this height.
    Above(f32),
}

/// The name of the per-vertex value marking pinned vertices in the USTC course files
/// (`float[] primvars:ControlPoints`, 1 for pinned).
pub const CONTROL_POINTS: &str = "ControlPoints";

/// The height of a model-space point along the scene's up axis, in scene units.
pub fn scene_height(asset: &Asset) -> impl Fn(Vec3) -> f32 {
    let m = asset.frame.model_to_scene.as_mat4();
    let up = match asset.frame.up_axis {
        rigport_model::UpAxis::Z => Vec3::Z,
        _ => Vec3::Y,
    };
    move |p| m.transform_point3(p).dot(up)
}

impl Garment {
    /// The garment of `mesh` (of `asset`): one particle per source vertex (vertices split at
    /// seams move together), positions in model space, pins chosen by `pins`.
    ///
    /// # Errors
    /// [`ClothError::EmptyGarment`] without triangles, [`ClothError::NonFinite`],
    /// [`ClothError::PinVertex`] for a pinned vertex the mesh does not have,
    /// [`ClothError::NoValues`] for a missing value name, [`ClothError::NoPins`] when the
    /// selection pins nothing.
    pub fn from_mesh(
        asset: &Asset,
        mesh: &Mesh,
        pins: &[PinSelection],
    ) -> Result<Self, ClothError> {
        let label = mesh.name.clone();
        let to_model = match mesh.attached_to {
            Some(j) => asset
                .skeleton
                .model_rest_matrices()
                .get(j.get())
                .copied()
                .unwrap_or(Mat4::IDENTITY),
            None => Mat4::IDENTITY,
        };
        let n = mesh.source_vertex_count();
        let first = mesh.first_vertex_of_source();
        let mut positions = Vec::with_capacity(n);
        for &v in &first {
            let p = mesh
                .positions
                .get(v as usize)
                .copied()
                .unwrap_or(Vec3::ZERO);
            positions.push(to_model.transform_point3(p));
        }
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(ClothError::NonFinite {
                what: format!("garment {label:?} positions"),
            });
        }
        let src = |v: u32| mesh.source_vertex.get(v as usize).copied();
        let triangles: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .filter_map(|t| match t.map(src) {
                [Some(a), Some(b), Some(c)] if a != b && b != c && a != c => Some([a, b, c]),
                _ => None,
            })
            .collect();
        if triangles.is_empty() {
            return Err(ClothError::EmptyGarment { garment: label });
        }
        let height = scene_height(asset);
        let mut pinned = Vec::new();
        for sel in pins {
            match sel {
                PinSelection::Values(name) => {
                    let values = mesh
                        .vertex_values
                        .iter()
                        .find(|(n, _)| n == name)
                        .map(|(_, v)| v)
                        .ok_or_else(|| ClothError::NoValues {
                            garment: label.clone(),
                            name: name.clone(),
                        })?;
                    for (v, &x) in values.iter().enumerate() {
                        if x != 0.0 {
                            if let Some(s) = src(v as u32) {
                                pinned.push(s);
                            }
                        }
                    }
                }
                PinSelection::Vertices(list) => {
                    for &s in list {
                        if s as usize >= n {
                            return Err(ClothError::PinVertex {
                                garment: label.clone(),
                                vertex: s,
                                count: n,
                            });
                        }
                        pinned.push(s);
                    }
                }
                PinSelection::Below(h) | PinSelection::Above(h) => {
                    let below = matches!(sel, PinSelection::Below(_));
                    for (s, &p) in positions.iter().enumerate() {
                        let y = height(p);
                        if (below && y <= *h) || (!below && y >= *h) {
                            pinned.push(s as u32);
                        }
                    }
                }
            }
        }
        pinned.sort_unstable();
        pinned.dedup();
        if pinned.is_empty() {
            return Err(ClothError::NoPins { garment: label });
        }
        Ok(Self {
            positions,
            triangles,
            pinned,
        })
    }
}
