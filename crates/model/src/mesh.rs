use glam::{Vec2, Vec3};

use crate::{JointIndex, MaterialIndex};

/// A triangle mesh. One [`Mesh`] is one glTF primitive or one USD `Mesh` prim.
///
/// Vertex attributes are per output vertex. A source format that indexes positions, UVs and
/// normals separately (OBJ) splits a position into several output vertices; `source_vertex`
/// maps each output vertex back to the source's own vertex numbering (OBJ `v` line order),
/// which is the order per-vertex data such as Pinocchio weight rows refers to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Name (may be empty): the source's mesh name (glTF `mesh.name`, a USD `Mesh` prim's
    /// name, an OBJ `o`/`g` name), `<mesh>_<primitive>` when the source mesh had several
    /// primitives.
    pub name: String,
    /// Name of the scene node (glTF node, USD prim) that carried the mesh in the source;
    /// empty when the source has no such node. When it equals the name of the joint the
    /// mesh is [`attached_to`](Self::attached_to), the mesh sat on that node itself, and
    /// exporters put it back there; else they name the mesh's own node after it, so apps
    /// that look a mesh up by its node's name still find it.
    pub node_name: String,
    /// Positions: model space at bind time for skinned meshes, else the space given by
    /// `attached_to`.
    pub positions: Vec<Vec3>,
    /// Unit normals, same space as `positions`, one per vertex.
    pub normals: Option<Vec<Vec3>>,
    /// Texture coordinates, one per vertex, glTF convention (origin top-left, v down).
    pub uvs: Option<Vec<Vec2>>,
    /// Further texture coordinate sets, same convention as `uvs`, one per vertex each:
    /// `extra_uvs[k - 1]` is glTF `TEXCOORD_k` (USD: the `k`-th `texCoord2f` primitive
    /// after `st`). Empty unless `uvs` is `Some`.
    pub extra_uvs: Vec<Vec<Vec2>>,
    /// The material it is drawn with (`None`: the viewer's default).
    pub material: Option<MaterialIndex>,
    /// Triangles as counter-clockwise vertex index triples.
    pub triangles: Vec<[u32; 3]>,
    /// The source's polygons, when the triangles are their fans: polygon `k` of
    /// `polygons[k]` corners is the next `polygons[k] - 2` triangles, each sharing the
    /// polygon's first corner (in either winding). Empty for a triangle mesh or a source
    /// without polygons. A writer that keeps polygons (USD) rebuilds them from the fans and
    /// writes triangles when they do not fit.
    pub polygons: Vec<u32>,
    /// For each vertex, its index in the source's own vertex numbering.
    pub source_vertex: Vec<u32>,
    /// Morph targets (blend shapes), applied before skinning.
    pub morph_targets: Vec<MorphTarget>,
    /// Default morph weights, one per target (empty means all zero).
    pub morph_weights: Vec<f32>,
    /// For an unskinned mesh: the joint it moves rigidly with (positions are then in that
    /// joint's space); `None` means model space.
    pub attached_to: Option<JointIndex>,
    /// Extra per-vertex numbers the source names, kept for tools that use them (USD `float[]`
    /// primvars with vertex interpolation, by name without `primvars:`, e.g. the
    /// `ControlPoints` that mark a garment's pinned vertices), one value per vertex.
    /// Writers do not export them.
    pub vertex_values: Vec<(String, Vec<f32>)>,
}

/// One morph target: per-vertex displacements.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphTarget {
    /// Name (may be empty).
    pub name: String,
    /// Position displacement per vertex.
    pub position_deltas: Vec<Vec3>,
    /// Normal displacement per vertex, if any.
    pub normal_deltas: Option<Vec<Vec3>>,
}

impl Mesh {
    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of distinct source vertices (`max(source_vertex) + 1`).
    pub fn source_vertex_count(&self) -> usize {
        self.source_vertex
            .iter()
            .max()
            .map_or(0, |&m| m as usize + 1)
    }

    /// For each source vertex, the first output vertex made from it (`u32::MAX` if none).
    pub fn first_vertex_of_source(&self) -> Vec<u32> {
        let mut out = vec![u32::MAX; self.source_vertex_count()];
        for (v, &s) in self.source_vertex.iter().enumerate() {
            let slot = &mut out[s as usize];
            if *slot == u32::MAX {
                *slot = v as u32;
            }
        }
        out
    }

    /// Area-weighted vertex normals computed from the triangles.
    ///
    /// Vertices that share a source vertex share a normal, so a seam in the UVs does not
    /// become a crease in the shading. Degenerate vertices get +Y.
    pub fn compute_normals(&self) -> Vec<Vec3> {
        let n_src = self.source_vertex_count();
        let mut acc = vec![Vec3::ZERO; n_src];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| i as usize);
            let (Some(pa), Some(pb), Some(pc)) = (
                self.positions.get(a),
                self.positions.get(b),
                self.positions.get(c),
            ) else {
                continue;
            };
            // The cross product's length is twice the area: area weighting for free.
            let n = (*pb - *pa).cross(*pc - *pa);
            for v in [a, b, c] {
                acc[self.source_vertex[v] as usize] += n;
            }
        }
        self.source_vertex
            .iter()
            .map(|&s| acc[s as usize].try_normalize().unwrap_or(Vec3::Y))
            .collect()
    }

    /// Axis-aligned bounds of the positions (`None` when empty).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_are_area_weighted_and_shared_across_seams() {
        // Two triangles in the z=0 plane plus a tiny one tilted; a seam duplicates vertex 0.
        let mesh = Mesh {
            positions: vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Y,
                Vec3::ZERO,
                Vec3::new(0.0, -0.01, 0.01),
            ],
            triangles: vec![[0, 1, 2], [3, 4, 1]],
            source_vertex: vec![0, 1, 2, 0, 3],
            ..Default::default()
        };
        let n = mesh.compute_normals();
        assert_eq!(n[0], n[3], "seam copies share a normal");
        assert!((n[2] - Vec3::Z).length() < 1e-6);
        // The big triangle dominates vertex 0's normal.
        assert!(n[0].dot(Vec3::Z) > 0.99, "{:?}", n[0]);
        assert_eq!(mesh.first_vertex_of_source(), vec![0, 1, 2, 4]);
    }
}
