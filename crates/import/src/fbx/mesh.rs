//! Meshes: one model [`Mesh`] per material part of each mesh node, with its skin binding
//! and blend shapes.

use std::path::Path;

use rigport_model::glam::{DMat4, Mat4, Vec2, Vec3};
use rigport_model::{
    Influence, Influences, MaterialIndex, Mesh, MeshIndex, SkinBinding, SkinningMethod, Warning,
};

use super::skeleton::{mat, Skel};
use crate::names::unique;

/// The meshes, their skins, and which blend channels drive each mesh's morph targets.
pub(super) struct Built {
    pub(super) meshes: Vec<rigport_model::Mesh>,
    pub(super) skins: Vec<SkinBinding>,
    /// Per mesh with morph targets: the blend channel span each target covers.
    pub(super) channels: Vec<(MeshIndex, Vec<super::blend::Segment>)>,
}

/// Every mesh node's meshes (see the module table in `mod.rs`); the asset's checks run
/// once it is assembled.
pub(super) fn build(
    scene: &ufbx::Scene,
    skel: &Skel,
    path: &Path,
    warnings: &mut Vec<Warning>,
) -> Built {
    let mut out = Built {
        meshes: Vec::new(),
        skins: Vec::new(),
        channels: Vec::new(),
    };
    let mut used = std::collections::HashSet::new();
    for node in scene.nodes.iter() {
        let Some(mesh) = node.mesh.as_ref() else {
            continue;
        };
        if mesh.num_triangles == 0 {
            continue;
        }
        let skin = mesh
            .skin_deformers
            .first()
            .filter(|s| s.clusters.iter().any(|c| c.bone_node.is_some()));
        // Where the points go: bind-time model space for a skinned mesh (the first cluster's
        // bind matrix times geometry-to-bone), else the nearest joint's space, else model space.
        let (to_space, attached_to) = match skin {
            Some(skin) => (cluster_geometry_to_world(skin), None),
            None => match skel.nearest_joint(node) {
                Some(j) => (
                    skel.world_rest[j.0 as usize].inverse() * mat(&node.geometry_to_world),
                    Some(j),
                ),
                None => (mat(&node.geometry_to_world), None),
            },
        };
        let to_space_f = to_space.as_mat4();
        let normal_m = to_space_f.inverse().transpose();
        let parts: Vec<(Option<MaterialIndex>, Vec<u32>)> = if mesh.material_parts.is_empty() {
            vec![(None, (0..mesh.faces.len() as u32).collect())]
        } else {
            mesh.material_parts
                .iter()
                .filter(|p| p.num_triangles > 0)
                .map(|p| {
                    let material = mesh
                        .materials
                        .get(p.index as usize)
                        .map(|m| MaterialIndex(m.element.typed_id));
                    (material, p.face_indices.to_vec())
                })
                .collect()
        };
        let several = parts.len() > 1;
        for (k, (material, faces)) in parts.iter().enumerate() {
            let base = if mesh.element.name.is_empty() {
                node.element.name.to_string()
            } else {
                mesh.element.name.to_string()
            };
            let name = if several { format!("{base}_{k}") } else { base };
            let mut m = geometry(mesh, faces, &to_space_f, &normal_m);
            m.name = unique(&name, "mesh", &mut used);
            m.node_name = node.element.name.to_string();
            m.material = *material;
            m.attached_to = attached_to;
            let index = MeshIndex(out.meshes.len() as u32);
            if let Some(skin) = skin {
                let mut binding = binding(skin, &m, index, skel);
                // As every importer: rows rescaled to sum to 1, as Blender deforms and as
                // the writers store them (ufbx keeps the file's weights).
                let (rows, max_row_sum_error) = binding.influences.normalize(1e-3);
                if rows > 0 {
                    warnings.push(Warning::WeightsRenormalized {
                        source: format!("{}: {}", crate::Location::file(path), skin.element.name),
                        rows,
                        max_row_sum_error,
                    });
                }
                out.skins.push(binding);
            }
            let channels = super::blend::targets(mesh, &mut m, &to_space_f, path, warnings);
            if !channels.is_empty() {
                out.channels.push((index, channels));
            }
            out.meshes.push(m);
        }
    }
    out
}

/// The mesh's geometry-to-world matrix at bind time, from its first cluster with a bone:
/// the bone's bind matrix (`TransformLink`) times the cluster's geometry-to-bone matrix
/// (`Transform` and the geometric transform). Not ufbx's `geometry_to_world`, which is the
/// bone's transform as loaded (the file's `Lcl` pose, not its bind pose) times
/// geometry-to-bone: the two agree only when a file's `Lcl` pose is its bind pose, and
/// Blender writes the pose of the current frame there (ufbx.h, `ufbx_skin_cluster`).
fn cluster_geometry_to_world(skin: &ufbx::SkinDeformer) -> DMat4 {
    skin.clusters
        .iter()
        .find(|c| c.bone_node.is_some())
        .map_or(DMat4::IDENTITY, |c| {
            mat(&c.bind_to_world) * mat(&c.geometry_to_bone)
        })
}

/// The triangles of `faces`, their corners made unique by (control point, normal, UV
/// indices), positions and normals through `to_space`/`normal_m`, UVs flipped to glTF's
/// top-left origin.
fn geometry(mesh: &ufbx::Mesh, faces: &[u32], to_space: &Mat4, normal_m: &Mat4) -> Mesh {
    let uv_sets: Vec<&ufbx::VertexVec2> = if mesh.uv_sets.is_empty() {
        if mesh.vertex_uv.exists {
            vec![&mesh.vertex_uv]
        } else {
            Vec::new()
        }
    } else {
        mesh.uv_sets.iter().map(|s| &s.vertex_uv).collect()
    };
    let normals = mesh.vertex_normal.exists.then_some(&mesh.vertex_normal);
    let mut out = Mesh::default();
    let mut uvs: Vec<Vec<Vec2>> = vec![Vec::new(); uv_sets.len()];
    let mut normal_values = Vec::new();
    // Corners made unique without hashing or allocating per corner (a Mixamo character
    // has about 170k): per control point, the list of vertices made from it (`head`,
    // `next`), each with its key (point, normal, UV indices) in `keys`, `stride` apiece.
    let stride = 2 + uv_sets.len();
    let mut head = vec![u32::MAX; mesh.vertex_position.values.len().max(1)];
    let mut next: Vec<u32> = Vec::with_capacity(faces.len() * 3);
    let mut keys: Vec<u32> = Vec::with_capacity(faces.len() * 3 * stride);
    let mut key = vec![0u32; stride];
    let mut corner_vertex = |corner: usize, out: &mut Mesh, uvs: &mut Vec<Vec<Vec2>>| -> u32 {
        let point = mesh
            .vertex_position
            .indices
            .get(corner)
            .copied()
            .unwrap_or(0);
        key[0] = point;
        key[1] = normals.map_or(0, |n| n.indices.get(corner).copied().unwrap_or(0));
        for (slot, s) in key[2..].iter_mut().zip(&uv_sets) {
            *slot = s.indices.get(corner).copied().unwrap_or(0);
        }
        let bucket = (point as usize).min(head.len() - 1);
        let mut at = head[bucket];
        while at != u32::MAX {
            let k = at as usize * stride;
            if keys[k..k + stride] == key[..] {
                return at;
            }
            at = next[at as usize];
        }
        let v = out.positions.len() as u32;
        next.push(head[bucket]);
        head[bucket] = v;
        keys.extend_from_slice(&key);
        let p = mesh.vertex_position.values.get(point as usize);
        out.positions.push(p.map_or(Vec3::ZERO, |p| {
            to_space.transform_point3(super::skeleton::vec3(p))
        }));
        out.source_vertex.push(point);
        if let Some(n) = normals {
            let value = n
                .values
                .get(key[1] as usize)
                .map_or(Vec3::Y, super::skeleton::vec3);
            normal_values.push(normal_m.transform_vector3(value).normalize_or(Vec3::Y));
        }
        for (set, (values, uv)) in uv_sets.iter().zip(uvs.iter_mut()).enumerate() {
            let index = key[2 + set] as usize;
            let t = values
                .values
                .get(index)
                .map_or(Vec2::ZERO, |t| Vec2::new(t.x as f32, 1.0 - t.y as f32));
            uv.push(t);
        }
        v
    };
    let mut tri = vec![0u32; mesh.max_face_triangles.max(1) * 3];
    let mut fans = true;
    for &f in faces {
        let Some(face) = mesh.faces.get(f as usize) else {
            continue;
        };
        if face.num_indices < 3 {
            continue;
        }
        let face = ufbx::Face {
            index_begin: face.index_begin,
            num_indices: face.num_indices,
        };
        let n = ufbx::triangulate_face(&mut tri, mesh, face) as usize;
        // A polygon is kept only when its triangles are its fan from its first corner.
        fans &= n + 2 == face.num_indices as usize;
        let first = face.index_begin;
        for t in tri.chunks_exact(3).take(n) {
            fans &= t.contains(&first);
            let a = corner_vertex(t[0] as usize, &mut out, &mut uvs);
            let b = corner_vertex(t[1] as usize, &mut out, &mut uvs);
            let c = corner_vertex(t[2] as usize, &mut out, &mut uvs);
            out.triangles.push([a, b, c]);
        }
        out.polygons.push(face.num_indices);
    }
    if !fans || out.polygons.iter().all(|&n| n == 3) {
        out.polygons.clear();
    }
    if normals.is_some() {
        out.normals = Some(normal_values);
    }
    let mut sets = uvs.into_iter();
    out.uvs = sets.next();
    out.extra_uvs = sets.collect();
    out
}

/// The skin binding of `m`: one palette entry per cluster with a bone, inverse bind =
/// the cluster's `bind_to_world` inverted, every influence of each control point.
fn binding(skin: &ufbx::SkinDeformer, m: &Mesh, mesh: MeshIndex, skel: &Skel) -> SkinBinding {
    let mut joints = Vec::new();
    let mut inv_bind = Vec::new();
    let mut palette_of_cluster = vec![None; skin.clusters.len()];
    for (k, cluster) in skin.clusters.iter().enumerate() {
        let Some(bone) = cluster.bone_node.as_ref() else {
            continue;
        };
        let Some(&joint) = skel.joint_of.get(&bone.element.typed_id) else {
            continue;
        };
        palette_of_cluster[k] = Some(joints.len() as u32);
        joints.push(joint);
        inv_bind.push(mat(&cluster.bind_to_world).inverse().as_mat4());
    }
    let rows = m.source_vertex.iter().map(|&point| {
        let Some(v) = skin.vertices.get(point as usize) else {
            return Vec::new();
        };
        let begin = v.weight_begin as usize;
        let end = begin + v.num_weights as usize;
        skin.weights
            .get(begin..end)
            .unwrap_or_default()
            .iter()
            .filter_map(|w| {
                let joint = (*palette_of_cluster.get(w.cluster_index as usize)?)?;
                (w.weight > 0.0).then_some(Influence {
                    joint,
                    weight: w.weight as f32,
                })
            })
            .collect::<Vec<_>>()
    });
    SkinBinding {
        mesh,
        joints,
        inv_bind,
        influences: Influences::from_rows(rows),
        method: match skin.skinning_method {
            ufbx::SkinningMethod::DualQuaternion => SkinningMethod::Dqs,
            _ => SkinningMethod::Lbs,
        },
    }
}
