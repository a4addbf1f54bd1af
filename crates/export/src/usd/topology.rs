//! The points and faces a Mesh prim is written with. USD indexes every primvar by its own
//! interpolation, so a mesh whose vertices were split on seams (face-varying normals or
//! UVs) is written with its source's points again, merging the splits, with those
//! primvars face-varying; and with the source's polygons when the triangles are their
//! fans ([`Mesh::polygons`]). A point-indexed consumer of the source (blend shapes,
//! caches, UsdSkel's bake) then still fits the output.

use rigport_model::{Mesh, SkinBinding};

/// How one mesh is written.
pub(super) struct Topology {
    /// For each written point, the model vertex whose data it takes.
    pub(super) point_vertex: Vec<u32>,
    /// For each model vertex, its written point.
    pub(super) vertex_point: Vec<u32>,
    /// `faceVertexCounts`.
    pub(super) counts: Vec<u32>,
    /// For each face corner, in `faceVertexIndices` order, the model vertex it uses.
    pub(super) corners: Vec<u32>,
    /// Whether the points are the source's vertices (split vertices merged back).
    pub(super) merged: bool,
}

impl Topology {
    /// Whether per-vertex values `same(a, b)` agree on every vertex of each point, so a
    /// primvar can be `vertex`; else it has to be `faceVarying`.
    pub(super) fn per_point(&self, same: impl Fn(usize, usize) -> bool) -> bool {
        self.vertex_point
            .iter()
            .enumerate()
            .all(|(v, &p)| same(v, self.point_vertex[p as usize] as usize))
    }
}

/// The topology to write `mesh` (skinned by `skin`, if any) with.
///
/// Split vertices are merged back into their source vertex when every source vertex has
/// a vertex and the copies agree bit for bit on position, influences and morph deltas
/// (only normals and UVs may differ); otherwise the model's vertices are the points.
pub(super) fn topology(mesh: &Mesh, skin: Option<&SkinBinding>) -> Topology {
    let n = mesh.vertex_count();
    let identity = mesh
        .source_vertex
        .iter()
        .enumerate()
        .all(|(v, &s)| s as usize == v);
    let first = mesh.first_vertex_of_source();
    let mergeable = !identity
        && mesh.source_vertex.len() == n
        && first.iter().all(|&f| f != u32::MAX)
        && (0..n).all(|v| {
            let f = first[mesh.source_vertex[v] as usize] as usize;
            v == f || same_vertex(mesh, skin, v, f)
        });
    let (point_vertex, vertex_point) = if mergeable {
        (first, mesh.source_vertex.clone())
    } else {
        let all: Vec<u32> = (0..n as u32).collect();
        (all.clone(), all)
    };
    let (counts, corners) = polygons(mesh).unwrap_or_else(|| {
        (
            vec![3; mesh.triangles.len()],
            mesh.triangles.iter().flatten().copied().collect(),
        )
    });
    Topology {
        point_vertex,
        vertex_point,
        counts,
        corners,
        merged: mergeable,
    }
}

/// Whether vertices `a` and `b` hold the same point data (everything but normals and UVs).
fn same_vertex(mesh: &Mesh, skin: Option<&SkinBinding>, a: usize, b: usize) -> bool {
    let bits = |v: rigport_model::glam::Vec3| v.to_array().map(f32::to_bits);
    let same3 = |s: &[rigport_model::glam::Vec3]| match (s.get(a), s.get(b)) {
        (Some(x), Some(y)) => bits(*x) == bits(*y),
        _ => false,
    };
    same3(&mesh.positions)
        && skin.is_none_or(|skin| {
            let (x, y) = (skin.influences.vertex(a), skin.influences.vertex(b));
            x.len() == y.len()
                && x.iter()
                    .zip(y)
                    .all(|(p, q)| p.joint == q.joint && p.weight.to_bits() == q.weight.to_bits())
        })
        && mesh
            .morph_targets
            .iter()
            .all(|t| same3(&t.position_deltas) && t.normal_deltas.as_deref().is_none_or(&same3))
}

/// The source polygons rebuilt from their triangle fans: (`faceVertexCounts`, corner
/// vertices), counter-clockwise. `None` when the mesh has no polygons or they do not fit.
fn polygons(mesh: &Mesh) -> Option<(Vec<u32>, Vec<u32>)> {
    if mesh.polygons.is_empty() {
        return None;
    }
    let mut tris = mesh.triangles.iter();
    let mut corners = Vec::with_capacity(mesh.triangles.len() + 2 * mesh.polygons.len());
    for &size in &mesh.polygons {
        let fan = size.checked_sub(2).filter(|&k| k >= 1)?;
        let &[a, b, c] = tris.next()?;
        // Corners after `a`, counter-clockwise. A fan from `a` continues either at the end
        // (the triangles wind like the polygon) or at the front (they wind against it, as
        // a left-handed source's do once turned counter-clockwise).
        let mut ring = std::collections::VecDeque::from([b, c]);
        for _ in 1..fan {
            let &[x, y, z] = tris.next()?;
            if x != a {
                return None;
            }
            if ring.back() == Some(&y) {
                ring.push_back(z);
            } else if ring.front() == Some(&z) {
                ring.push_front(y);
            } else {
                return None;
            }
        }
        corners.push(a);
        corners.extend(ring);
    }
    if tris.next().is_some() {
        return None;
    }
    Some((mesh.polygons.clone(), corners))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rigport_model::glam::Vec3;

    fn quad_pair(triangles: Vec<[u32; 3]>) -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO; 6],
            triangles,
            source_vertex: (0..6).collect(),
            polygons: vec![4, 4],
            ..Default::default()
        }
    }

    #[test]
    fn polygons_come_back_from_fans_of_either_winding() {
        // Right-handed fans of (0 1 2 3) and (1 4 5 2).
        let m = quad_pair(vec![[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]]);
        let t = topology(&m, None);
        assert_eq!(t.counts, vec![4, 4]);
        assert_eq!(t.corners, vec![0, 1, 2, 3, 1, 4, 5, 2]);
        // A left-handed source's fans: [a, f(k+1), f(k)].
        let m = quad_pair(vec![[0, 2, 1], [0, 3, 2], [1, 5, 4], [1, 2, 5]]);
        let t = topology(&m, None);
        assert_eq!(t.corners, vec![0, 3, 2, 1, 1, 2, 5, 4]);
        // Not fans: triangles.
        let m = quad_pair(vec![[0, 1, 2], [3, 0, 2], [1, 4, 5], [1, 5, 2]]);
        assert_eq!(topology(&m, None).counts, vec![3; 4]);
    }

    #[test]
    fn splits_merge_back_unless_their_data_differs() {
        let mut m = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X],
            normals: Some(vec![Vec3::Z, Vec3::Z, Vec3::Z, Vec3::X]),
            triangles: vec![[0, 1, 2], [3, 2, 0]],
            source_vertex: vec![0, 1, 2, 1],
            ..Default::default()
        };
        let t = topology(&m, None);
        assert!(t.merged);
        assert_eq!(t.point_vertex, vec![0, 1, 2]);
        assert_eq!(t.vertex_point, vec![0, 1, 2, 1]);
        let normals = m.normals.clone().unwrap();
        assert!(!t.per_point(|a, b| normals[a] == normals[b]));
        // A copy that moved is not a split.
        m.positions[3] = Vec3::ONE;
        assert!(!topology(&m, None).merged);
    }
}
