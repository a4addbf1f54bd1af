//! Mesh primitives: geometry, triangle lists from strips and fans, morph targets and their
//! default weights.

use ::gltf::mesh::Mode;
use ::gltf::Semantic;
use rigport_model::glam::Vec3;
use rigport_model::{Mesh, MorphTarget};

use crate::ImportError;

use super::importer::Importer;

impl<'a> Importer<'a> {
    /// One primitive's geometry and morph targets; `None` for points and lines.
    pub(super) fn primitive(
        &mut self,
        mesh: &::gltf::Mesh<'a>,
        prim: &::gltf::Primitive<'a>,
        base: &str,
        name: String,
    ) -> Result<Option<Mesh>, ImportError> {
        let mode = prim.mode();
        if matches!(
            mode,
            Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip
        ) {
            self.note(
                &format!("{base}/mode"),
                format!("{mode:?} primitive skipped: rigport imports triangles only"),
            );
            return Ok(None);
        }
        let pos_at = format!("{base}/attributes/POSITION");
        let Some(pos_acc) = prim.get(&Semantic::Positions) else {
            return Err(self.err(pos_at, "primitive has no POSITION"));
        };
        let positions = self.read_vec3(&pos_acc, &pos_at)?;
        let n = positions.len();
        if u32::try_from(n).is_err() {
            return Err(self.err(pos_at, format!("{n} vertices is too many")));
        }
        let count_check = |this: &Self, at: &str, found: usize| {
            if found == n {
                Ok(())
            } else {
                Err(this.err(at, format!("has {found} elements for {n} vertices")))
            }
        };

        let normals = match prim.get(&Semantic::Normals) {
            Some(acc) => {
                let at = format!("{base}/attributes/NORMAL");
                let normals = self.read_vec3(&acc, &at)?;
                count_check(self, &at, normals.len())?;
                Some(normals)
            }
            None => None,
        };
        let uvs = match prim.get(&Semantic::TexCoords(0)) {
            Some(acc) => {
                let at = format!("{base}/attributes/TEXCOORD_0");
                let uvs = self.read_tex_coords(&acc, &at)?;
                count_check(self, &at, uvs.len())?;
                Some(uvs)
            }
            None => None,
        };
        let mut extra_uvs = Vec::new();
        if uvs.is_some() {
            for set in 1.. {
                let Some(acc) = prim.get(&Semantic::TexCoords(set)) else {
                    break;
                };
                let at = format!("{base}/attributes/TEXCOORD_{set}");
                let more = self.read_tex_coords(&acc, &at)?;
                count_check(self, &at, more.len())?;
                extra_uvs.push(more);
            }
        }
        let uv_sets = if uvs.is_some() {
            1 + extra_uvs.len() as u32
        } else {
            0
        };
        let ignored: Vec<String> = prim
            .attributes()
            .filter_map(|(semantic, _)| match semantic {
                Semantic::Positions
                | Semantic::Normals
                | Semantic::Joints(_)
                | Semantic::Weights(_) => None,
                Semantic::TexCoords(k) if k < uv_sets => None,
                other => Some(other.to_string()),
            })
            .collect();
        if !ignored.is_empty() {
            self.note(
                &format!("{base}/attributes"),
                format!("attributes not imported: {}", ignored.join(", ")),
            );
        }

        let indices = match prim.indices() {
            Some(acc) => {
                let at = format!("{base}/indices");
                let indices = self.read_indices(&acc, &at)?;
                if let Some(k) = indices.iter().position(|&i| i as usize >= n) {
                    return Err(self.err(
                        at,
                        format!("index {k} is {}, but there are {n} vertices", indices[k]),
                    ));
                }
                indices
            }
            None => (0..n as u32).collect(),
        };
        let triangles = match mode {
            Mode::TriangleStrip => strip_triangles(&indices),
            Mode::TriangleFan => fan_triangles(&indices),
            _ => {
                let rest = indices.len() % 3;
                if rest != 0 {
                    self.repaired(
                        base,
                        format!(
                            "{} indices is not a multiple of 3; last {rest} ignored",
                            indices.len()
                        ),
                    );
                }
                indices
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect()
            }
        };

        let names = target_names(mesh);
        let mut morph_targets = Vec::new();
        for (t, target) in prim.morph_targets().enumerate() {
            let position_deltas = match target.positions() {
                Some(acc) => {
                    let at = format!("{base}/targets/{t}/POSITION");
                    let d = self.read_vec3(&acc, &at)?;
                    count_check(self, &at, d.len())?;
                    d
                }
                None => vec![Vec3::ZERO; n],
            };
            let normal_deltas = match target.normals() {
                Some(acc) => {
                    let at = format!("{base}/targets/{t}/NORMAL");
                    let d = self.read_vec3(&acc, &at)?;
                    count_check(self, &at, d.len())?;
                    Some(d)
                }
                None => None,
            };
            morph_targets.push(MorphTarget {
                name: names.get(t).cloned().unwrap_or_default(),
                position_deltas,
                normal_deltas,
            });
        }
        if !names.is_empty() && names.len() != morph_targets.len() {
            self.note(
                &format!("/meshes/{}/extras/targetNames", mesh.index()),
                format!(
                    "{} target names for {} morph targets",
                    names.len(),
                    morph_targets.len()
                ),
            );
        }

        Ok(Some(Mesh {
            name,
            positions,
            normals,
            uvs,
            triangles,
            source_vertex: (0..n as u32).collect(),
            morph_targets,
            morph_weights: Vec::new(),
            attached_to: None,
            extra_uvs,
            material: prim
                .material()
                .index()
                .map(|m| rigport_model::MaterialIndex(m as u32)),
            node_name: String::new(),
            polygons: Vec::new(),
            vertex_values: Vec::new(),
        }))
    }

    /// Default morph weights (node `weights` override mesh `weights`, glTF 2.0 §3.7.2.2).
    pub(super) fn default_weights(
        &mut self,
        weights: Option<&[f32]>,
        targets: usize,
        at: &str,
    ) -> Result<Vec<f32>, ImportError> {
        let Some(weights) = weights else {
            return Ok(Vec::new());
        };
        if let Some(k) = weights.iter().position(|w| !w.is_finite()) {
            return Err(self.err(format!("{at}/{k}"), "weight is not finite"));
        }
        if weights.len() == targets {
            return Ok(weights.to_vec());
        }
        self.repaired(
            at,
            format!(
                "{} default weights for {targets} morph targets; {}",
                weights.len(),
                if weights.len() > targets {
                    "extra weights dropped"
                } else {
                    "missing weights set to 0"
                }
            ),
        );
        let mut out = weights.to_vec();
        out.resize(targets, 0.0);
        Ok(out)
    }
}

/// Triangles of a strip: `{v_i, v_(i+1+i%2), v_(i+2-i%2)}` (glTF 2.0 §3.7.2.1), degenerate
/// ones (restart tricks) dropped.
pub(super) fn strip_triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    indices
        .windows(3)
        .enumerate()
        .map(|(i, w)| {
            if i % 2 == 0 {
                [w[0], w[1], w[2]]
            } else {
                [w[0], w[2], w[1]]
            }
        })
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect()
}

/// Triangles of a fan: `{v_(i+1), v_(i+2), v_0}` (glTF 2.0 §3.7.2.1), degenerate ones
/// dropped.
pub(super) fn fan_triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    let Some((&first, rest)) = indices.split_first() else {
        return Vec::new();
    };
    rest.windows(2)
        .map(|w| [w[0], w[1], first])
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect()
}

/// `mesh.extras.targetNames` (the de-facto convention for morph target names).
fn target_names(mesh: &::gltf::Mesh<'_>) -> Vec<String> {
    let Some(raw) = mesh.extras().as_ref() else {
        return Vec::new();
    };
    let Ok(value) = ::gltf::json::deserialize::from_str::<::gltf::json::Value>(raw.get()) else {
        return Vec::new();
    };
    value
        .get("targetNames")
        .and_then(|v| v.as_array())
        .map(|names| {
            names
                .iter()
                .map(|n| n.as_str().unwrap_or_default().to_string())
                .collect()
        })
        .unwrap_or_default()
}
