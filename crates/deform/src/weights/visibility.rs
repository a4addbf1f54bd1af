//! Which bones a vertex sees: the segment from the vertex to the nearest point of the bone
//! crosses no triangle of the mesh (a bounding-volume tree of the triangles, median splits
//! on the longest axis, Möller-Trumbore segment tests).
//!
//! The segment's first and last `END` of its length are not tested: the vertex's own
//! triangles touch its start, and a bone lying on the surface touches its end.

use glam::DVec3;

/// How much of each end of a sight line is not tested.
const END: f64 = 1e-4;

/// Triangles per leaf.
const LEAF: usize = 4;

#[derive(Clone, Copy)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: `start..end` into `order`; inner: children `left` and `right`.
    start: u32,
    end: u32,
    left: u32,
    right: u32,
}

/// The tree.
pub(super) struct Sight {
    nodes: Vec<Node>,
    order: Vec<u32>,
    tris: Vec<[DVec3; 3]>,
}

impl Sight {
    /// The tree of `triangles` over `points`.
    pub(super) fn new(points: &[DVec3], triangles: &[[u32; 3]]) -> Self {
        let tris: Vec<[DVec3; 3]> = triangles
            .iter()
            .map(|t| t.map(|i| points[i as usize]))
            .collect();
        let mut sight = Sight {
            nodes: Vec::new(),
            order: (0..tris.len() as u32).collect(),
            tris,
        };
        if !sight.tris.is_empty() {
            sight.build(0, sight.order.len());
        }
        sight
    }

    fn build(&mut self, start: usize, end: usize) -> u32 {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &t in &self.order[start..end] {
            for p in self.tris[t as usize] {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        let id = self.nodes.len() as u32;
        self.nodes.push(Node {
            lo,
            hi,
            start: start as u32,
            end: end as u32,
            left: 0,
            right: 0,
        });
        if end - start <= LEAF {
            return id;
        }
        let axis = (hi - lo).max_position();
        let centre = |t: u32| {
            let [a, b, c] = self.tris[t as usize];
            (a + b + c)[axis]
        };
        let mid = (start + end) / 2;
        self.order[start..end]
            .select_nth_unstable_by(mid - start, |&a, &b| centre(a).total_cmp(&centre(b)));
        let left = self.build(start, mid);
        let right = self.build(mid, end);
        self.nodes[id as usize].left = left;
        self.nodes[id as usize].right = right;
        id
    }

    /// Whether a triangle crosses the segment from `p` to `q` (away from its ends).
    pub(super) fn blocked(&self, p: DVec3, q: DVec3) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let d = q - p;
        let inv = d.recip();
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = self.nodes[n as usize];
            if !hits_box(p, inv, node.lo, node.hi) {
                continue;
            }
            if node.end - node.start <= LEAF as u32 {
                for &t in &self.order[node.start as usize..node.end as usize] {
                    if crosses(p, d, self.tris[t as usize]) {
                        return true;
                    }
                }
            } else {
                stack.push(node.left);
                stack.push(node.right);
            }
        }
        false
    }
}

/// Whether the segment `p + s (1/inv)`, `s` in `[0, 1]`, meets the box (slabs).
fn hits_box(p: DVec3, inv: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        let (a, b) = ((lo[k] - p[k]) * inv[k], (hi[k] - p[k]) * inv[k]);
        // An axis the segment does not move along: inside the slab or not at all (0 * inf
        // is NaN; `max`/`min` skip NaN).
        let (a, b) = if a.is_nan() || b.is_nan() {
            if p[k] < lo[k] || p[k] > hi[k] {
                return false;
            }
            continue;
        } else {
            (a.min(b), a.max(b))
        };
        t0 = t0.max(a);
        t1 = t1.min(b);
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Whether the segment `p + t d`, `t` in `(END, 1 - END)`, crosses triangle `tri`
/// (Möller and Trumbore 1997).
fn crosses(p: DVec3, d: DVec3, [a, b, c]: [DVec3; 3]) -> bool {
    let (e1, e2) = (b - a, c - a);
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det.abs() < 1e-300 {
        return false;
    }
    let f = 1.0 / det;
    let s = p - a;
    let u = f * s.dot(h);
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let qv = s.cross(e1);
    let v = f * d.dot(qv);
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = f * e2.dot(qv);
    t > END && t < 1.0 - END
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wall_blocks_the_view_and_its_edge_does_not() {
        let points = [
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(-1.0, 1.0, 0.0),
        ];
        let sight = Sight::new(&points, &[[0, 1, 2], [0, 2, 3]]);
        assert!(sight.blocked(DVec3::new(0.2, 0.1, -1.0), DVec3::new(0.2, 0.1, 1.0)));
        assert!(!sight.blocked(DVec3::new(2.0, 0.0, -1.0), DVec3::new(2.0, 0.0, 1.0)));
        // Ending on the wall is not blocked by it.
        assert!(!sight.blocked(DVec3::new(0.2, 0.1, -1.0), DVec3::new(0.2, 0.1, 0.0)));
        // A wall of many triangles (inner nodes of the tree): blocked wherever it is hit.
        let mut grid = Vec::new();
        let mut tris = Vec::new();
        for r in 0..11 {
            for c in 0..11 {
                grid.push(DVec3::new(
                    f64::from(c) * 0.2 - 1.0,
                    f64::from(r) * 0.2 - 1.0,
                    0.0,
                ));
            }
        }
        for r in 0..10u32 {
            for c in 0..10u32 {
                let a = r * 11 + c;
                tris.push([a, a + 1, a + 12]);
                tris.push([a, a + 12, a + 11]);
            }
        }
        let wall = Sight::new(&grid, &tris);
        for k in 0..20 {
            let x = -0.95 + 0.1 * f64::from(k);
            assert!(
                wall.blocked(DVec3::new(x, 0.33, -1.0), DVec3::new(x, -0.41, 1.0)),
                "{x}"
            );
        }
        assert!(!wall.blocked(DVec3::new(1.5, 0.0, -1.0), DVec3::new(1.5, 0.0, 1.0)));
        // Along an axis (a zero direction component).
        assert!(!sight.blocked(DVec3::new(3.0, 0.0, 0.5), DVec3::new(3.0, 0.0, -0.5)));
    }
}
