//! The mesh as bone heat sees it: coincident vertices welded, the cotangent Laplacian's
//! edge weights, each vertex's area, and the connected components.
//!
//! - Welding: vertices at the same position (to 1e-7 of the mesh's diagonal) are one, so
//!   UV seams and split normals do not cut the surface the heat flows over.
//! - Edge weights: `(cot α + cot β) / 2` over the triangles sharing the edge (Pinkall and
//!   Polthier 1993; Meyer et al. 2003), within `±MAX_WEIGHT` (a needle's cotangent), zero-
//!   area faces left out. A negative weight (an obtuse pair of angles) is kept, as
//!   Pinocchio keeps it; the caller clamps negatives to 0 when the system is then not
//!   positive definite (the clamped Laplacian is positive semi-definite on any mesh,
//!   manifold or not).
//! - Areas: a third of each incident triangle's area (barycentric cells), at least
//!   `MIN_AREA` of the diagonal squared.

use std::collections::HashMap;

use glam::DVec3;

/// The largest edge weight (a needle triangle's cotangent; keeps the matrix well
/// conditioned).
const MAX_WEIGHT: f64 = 1e4;

/// The smallest vertex area, as a fraction of the squared diagonal.
const MIN_AREA: f64 = 1e-12;

/// The welded mesh and its operator.
pub(super) struct Surface {
    /// Per input vertex: its welded vertex.
    pub(super) weld: Vec<u32>,
    /// Welded positions.
    pub(super) points: Vec<DVec3>,
    /// Welded triangles with three distinct corners.
    pub(super) triangles: Vec<[u32; 3]>,
    /// Edges `(i, j)`, `i < j`, and their weights.
    pub(super) edges: Vec<(u32, u32, f64)>,
    /// Per welded vertex: its area.
    pub(super) area: Vec<f64>,
    /// Per welded vertex: its connected component.
    pub(super) component: Vec<u32>,
    /// How many input vertices were welded onto another.
    pub(super) welded: usize,
    /// How many triangles had no area (or repeated corners after welding).
    pub(super) degenerate: usize,
    /// How many edges are shared by more than two triangles.
    pub(super) non_manifold: usize,
}

/// Builds the [`Surface`] of `positions` and `triangles` (indices checked by the caller).
pub(super) fn surface(positions: &[DVec3], triangles: &[[u32; 3]]) -> Surface {
    let (lo, hi) = positions.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let diagonal = (hi - lo).length().max(f64::MIN_POSITIVE);
    let cell = 1e-7 * diagonal;
    let mut index: HashMap<[i64; 3], u32> = HashMap::new();
    let mut weld = Vec::with_capacity(positions.len());
    let mut points = Vec::new();
    for p in positions {
        let key = ((*p - lo) / cell).round().as_i64vec3().to_array();
        let w = *index.entry(key).or_insert_with(|| {
            points.push(*p);
            points.len() as u32 - 1
        });
        weld.push(w);
    }
    let welded = positions.len() - points.len();
    let mut degenerate = 0;
    let mut tris = Vec::with_capacity(triangles.len());
    let mut weights: HashMap<(u32, u32), (f64, u32)> = HashMap::new();
    let mut area = vec![0.0f64; points.len()];
    for t in triangles {
        let t = t.map(|i| weld[i as usize]);
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            degenerate += 1;
            continue;
        }
        let [a, b, c] = t.map(|i| points[i as usize]);
        let twice = (b - a).cross(c - a).length();
        for k in 0..3 {
            let (i, j) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            let e = weights.entry((i.min(j), i.max(j))).or_insert((0.0, 0));
            e.1 += 1;
        }
        if twice <= 1e-12 * diagonal * diagonal {
            degenerate += 1;
            continue;
        }
        tris.push(t);
        for v in t {
            area[v as usize] += twice / 6.0;
        }
        // The angle at corner k faces the edge between the other two.
        for k in 0..3 {
            let o = [a, b, c][k];
            let (p, q) = ([a, b, c][(k + 1) % 3], [a, b, c][(k + 2) % 3]);
            let cot = (p - o).dot(q - o) / twice;
            let (i, j) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            weights.get_mut(&(i.min(j), i.max(j))).expect("edge").0 += cot / 2.0;
        }
    }
    let non_manifold = weights.values().filter(|(_, n)| *n > 2).count();
    let mut edges: Vec<(u32, u32, f64)> = weights
        .into_iter()
        .map(|((i, j), (w, _))| (i, j, w.clamp(-MAX_WEIGHT, MAX_WEIGHT)))
        .collect();
    edges.sort_unstable_by_key(|e| (e.0, e.1));
    let floor = MIN_AREA * diagonal * diagonal;
    for a in &mut area {
        *a = a.max(floor);
    }
    let component = components(points.len(), &edges);
    Surface {
        weld,
        points,
        triangles: tris,
        edges,
        area,
        component,
        welded,
        degenerate,
        non_manifold,
    }
}

/// Connected components over the edges of non-zero weight (union-find), numbered from 0
/// by first vertex: heat crosses no other edge.
fn components(n: usize, edges: &[(u32, u32, f64)]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for &(i, j, _) in edges.iter().filter(|e| e.2 != 0.0) {
        let (a, b) = (find(&mut parent, i), find(&mut parent, j));
        if a != b {
            parent[a.max(b) as usize] = a.min(b);
        }
    }
    let mut label = vec![u32::MAX; n];
    let mut next = 0;
    (0..n as u32)
        .map(|v| {
            let r = find(&mut parent, v) as usize;
            if label[r] == u32::MAX {
                label[r] = next;
                next += 1;
            }
            label[r]
        })
        .collect()
}
