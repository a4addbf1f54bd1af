//! Which candidate vertex stands for each reference vertex of a mesh pair: the same index
//! when the meshes agree vertex for vertex, the source-vertex maps when both came from one
//! source through rigport (a glTF keeps split seams, a USD merges them back into its
//! points), else the nearest rest position in the comparison frame, so split seams and
//! welded vertices are both handled. Coincident candidates (a seam's copies) are all kept
//! as ties, and a frame's deviation is the nearest of them.

use std::collections::HashMap;

use glam::DVec3;

/// How a map was made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    /// Vertex `i` is vertex `i`.
    Index,
    /// Through both meshes' source-vertex numbering (`Mesh::source_vertex`).
    SourceVertex,
    /// The nearest candidate vertex at rest.
    Nearest,
}

impl MapKind {
    /// Words for a report.
    pub fn as_str(self) -> &'static str {
        match self {
            MapKind::Index => "same vertex order",
            MapKind::SourceVertex => "source-vertex map",
            MapKind::Nearest => "nearest rest position",
        }
    }
}

/// For each reference vertex, its candidate vertices (one, or a seam's coincident copies).
#[derive(Clone, Debug, PartialEq)]
pub struct VertexMap {
    /// How it was made.
    pub kind: MapKind,
    /// `candidates[offsets[v]..offsets[v + 1]]` are reference vertex `v`'s.
    pub offsets: Vec<u32>,
    /// Candidate vertex indices.
    pub candidates: Vec<u32>,
    /// The largest rest distance between a reference vertex and its nearest candidate
    /// (metres), and that reference vertex.
    pub worst: (f64, usize),
}

impl VertexMap {
    /// Reference vertex `v`'s candidates.
    pub fn of(&self, v: usize) -> &[u32] {
        match (self.offsets.get(v), self.offsets.get(v + 1)) {
            (Some(&a), Some(&b)) => self.candidates.get(a as usize..b as usize).unwrap_or(&[]),
            _ => &[],
        }
    }

    /// Reference vertices mapped.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Whether no vertex is mapped.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Builds a map from per-reference-vertex candidate lists, measuring its worst rest
    /// distance.
    fn from_lists(
        kind: MapKind,
        lists: impl Iterator<Item = Vec<u32>>,
        reference: &[DVec3],
        candidate: &[DVec3],
    ) -> Self {
        let mut offsets = vec![0u32];
        let mut candidates = Vec::new();
        let mut worst = (0.0f64, 0usize);
        for (v, list) in lists.enumerate() {
            let d = list
                .iter()
                .filter_map(|&c| candidate.get(c as usize))
                .map(|c| c.distance(reference[v]))
                .fold(f64::INFINITY, f64::min);
            if d > worst.0 {
                worst = (d, v);
            }
            candidates.extend(list);
            offsets.push(candidates.len() as u32);
        }
        Self {
            kind,
            offsets,
            candidates,
            worst,
        }
    }
}

/// The map of one mesh pair, from rest positions in the comparison frame and each mesh's
/// source-vertex numbering: by index or by source vertex when that map's worst distance is
/// within `accept` (metres), else by nearest rest position (coincident candidates within
/// `tie` metres of the nearest kept as ties).
///
/// ```
/// use rigport_compare::vertex_map::{map_vertices, MapKind};
/// use rigport_compare::glam::DVec3;
/// let reference = [DVec3::ZERO, DVec3::X, DVec3::Y];
/// // The candidate lists them in another order.
/// let candidate = [DVec3::Y, DVec3::ZERO, DVec3::X];
/// let map = map_vertices((&reference, &[0, 1, 2]), (&candidate, &[0, 1, 2]), 1e-6, 1e-9);
/// assert_eq!(map.kind, MapKind::Nearest);
/// assert_eq!((map.of(0), map.of(1), map.of(2)), (&[1][..], &[2][..], &[0][..]));
/// ```
pub fn map_vertices(
    reference: (&[DVec3], &[u32]),
    candidate: (&[DVec3], &[u32]),
    accept: f64,
    tie: f64,
) -> VertexMap {
    let (ref_pos, cand_pos) = (reference.0, candidate.0);
    if ref_pos.len() == cand_pos.len() {
        let map = VertexMap::from_lists(
            MapKind::Index,
            (0..ref_pos.len() as u32).map(|v| vec![v]),
            ref_pos,
            cand_pos,
        );
        if map.worst.0 <= accept {
            return map;
        }
    }
    if let Some(map) = by_source(reference, candidate).filter(|m| m.worst.0 <= accept) {
        return map;
    }
    nearest(ref_pos, cand_pos, tie)
}

/// The source-vertex map, when both numberings cover the same source vertices.
fn by_source(reference: (&[DVec3], &[u32]), candidate: (&[DVec3], &[u32])) -> Option<VertexMap> {
    let (ref_pos, ref_src) = reference;
    let (cand_pos, cand_src) = candidate;
    if ref_src.len() != ref_pos.len() || cand_src.len() != cand_pos.len() {
        return None;
    }
    let count = |s: &[u32]| s.iter().max().map_or(0, |&m| m as usize + 1);
    let n = count(ref_src);
    if n == 0 || n != count(cand_src) {
        return None;
    }
    let mut of_source: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (v, &s) in cand_src.iter().enumerate() {
        of_source[s as usize].push(v as u32);
    }
    if of_source.iter().any(Vec::is_empty) {
        return None;
    }
    let lists = ref_src.iter().map(|&s| of_source[s as usize].clone());
    Some(VertexMap::from_lists(
        MapKind::SourceVertex,
        lists,
        ref_pos,
        cand_pos,
    ))
}

/// Each reference vertex's nearest candidate vertex (and those within `tie` of it), found
/// in a uniform grid of about two candidates per cell.
fn nearest(reference: &[DVec3], candidate: &[DVec3], tie: f64) -> VertexMap {
    let Some(grid) = Grid::new(candidate) else {
        return VertexMap::from_lists(
            MapKind::Nearest,
            reference.iter().map(|_| Vec::new()),
            reference,
            candidate,
        );
    };
    let lists = reference.iter().map(|&p| grid.nearest(p, candidate, tie));
    VertexMap::from_lists(MapKind::Nearest, lists, reference, candidate)
}

/// Candidate vertices bucketed by cell.
struct Grid {
    min: DVec3,
    cell: f64,
    dims: [i64; 3],
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl Grid {
    fn new(points: &[DVec3]) -> Option<Self> {
        let first = *points.first()?;
        let (min, max) = points
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let size = (max - min).max(DVec3::splat(1e-12));
        let volume = size.x * size.y * size.z;
        let cell = (volume * 2.0 / points.len() as f64)
            .cbrt()
            .max(size.max_element() / 256.0)
            .max(1e-12);
        if !cell.is_finite() {
            return None;
        }
        let dims = ((size / cell).ceil().as_i64vec3() + 1).to_array();
        let mut grid = Self {
            min,
            cell,
            dims,
            cells: HashMap::new(),
        };
        for (i, &p) in points.iter().enumerate() {
            let key = grid.key(p);
            grid.cells.entry(key).or_default().push(i as u32);
        }
        Some(grid)
    }

    fn key(&self, p: DVec3) -> [i64; 3] {
        let k = ((p - self.min) / self.cell).floor();
        [k.x as i64, k.y as i64, k.z as i64]
    }

    /// The nearest point to `p` and every point within `tie` of that distance, searched in
    /// growing shells of cells (clamped to the grid) until no closer point can be left.
    fn nearest(&self, p: DVec3, points: &[DVec3], tie: f64) -> Vec<u32> {
        let c = self.key(p);
        let mut best = f64::INFINITY;
        let mut found: Vec<(f64, u32)> = Vec::new();
        // The Chebyshev distance in cells from `c` to the grid, and to its far corner.
        let gap = |k: usize| (-c[k]).max(c[k] - (self.dims[k] - 1)).max(0);
        let far = |k: usize| c[k].abs().max((self.dims[k] - 1 - c[k]).abs());
        let first = gap(0).max(gap(1)).max(gap(2));
        let last = far(0).max(far(1)).max(far(2));
        let visit = |key: [i64; 3], found: &mut Vec<(f64, u32)>, best: &mut f64| {
            for &i in self.cells.get(&key).map_or(&[][..], Vec::as_slice) {
                let d = points[i as usize].distance(p);
                if d <= *best + tie {
                    *best = best.min(d);
                    found.push((d, i));
                }
            }
        };
        for r in first..=last {
            // Every point in shell r or beyond is at least (r - 1) cells away.
            if (r - 1) as f64 * self.cell > best + tie {
                break;
            }
            let range = |k: usize| (c[k] - r).max(0)..=(c[k] + r).min(self.dims[k] - 1);
            for z in range(2) {
                for y in range(1) {
                    if (z - c[2]).abs() == r || (y - c[1]).abs() == r {
                        for x in range(0) {
                            visit([x, y, z], &mut found, &mut best);
                        }
                    } else {
                        for x in [c[0] - r, c[0] + r] {
                            if (0..self.dims[0]).contains(&x) {
                                visit([x, y, z], &mut found, &mut best);
                            }
                        }
                    }
                }
            }
        }
        let mut out: Vec<u32> = found
            .into_iter()
            .filter(|&(d, _)| d <= best + tie)
            .map(|(_, i)| i)
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seams_map_through_source_vertices_with_their_copies_as_ties() {
        // Reference: 3 source vertices, vertex 1 split in two (a UV seam).
        let reference = [DVec3::ZERO, DVec3::X, DVec3::X, DVec3::Y];
        let ref_src = [0, 1, 1, 2];
        // Candidate: the seam merged back (a USD's points).
        let candidate = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let map = map_vertices((&reference, &ref_src), (&candidate, &[0, 1, 2]), 1e-6, 1e-9);
        assert_eq!(map.kind, MapKind::SourceVertex);
        assert_eq!(map.of(2), &[1]);
        // The other way round, the copies are ties.
        let back = map_vertices((&candidate, &[0, 1, 2]), (&reference, &ref_src), 1e-6, 1e-9);
        assert_eq!(back.of(1), &[1, 2]);
    }

    #[test]
    fn nearest_finds_far_points_too() {
        let reference = [DVec3::new(5.0, 5.0, 5.0)];
        let candidate: Vec<DVec3> = (0..100)
            .map(|i| DVec3::new(f64::from(i) * 0.01, 0.0, 0.0))
            .collect();
        let map = nearest(&reference, &candidate, 0.0);
        assert_eq!(map.of(0), &[99]);
    }
}
