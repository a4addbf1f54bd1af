//! The skinned body surface as a collider: a bounding-volume hierarchy (an AABB tree) over
//! the body's triangles, and the signed distance of a point to the posed surface.
//!
//! The tree's topology is built once, at bind, by median splits along the longest axis of
//! the triangles' centroids (at most [`LEAF`] triangles per leaf); every frame only its
//! boxes are refitted, around each triangle at the frame's start *and* end, so one tree
//! holds the surface at every substep of the frame (a lerped vertex lies in the box of its
//! two ends). A query walks the tree depth first, nearer child first, pruning boxes farther
//! than the best hit so far (Ericson, *Real-Time Collision Detection*, 6.4 and 9.5).
//!
//! Hand-written rather than a crate: `bvh` and `parry3d` build over their own shape types
//! and rebuild or refit from `&mut` shapes, while the collider here is a pair of skinned
//! frames lerped per substep without copying; the workspace's dependency rules keep
//! `deform` on glam, rayon and thiserror. The tree is a few hundred lines, and a test
//! checks it against brute force.
//!
//! Inside and outside: the sign of `(p - q)·n` at the closest point `q`, with `n` the
//! triangle's normal when `q` is inside the triangle and the vertex normals (area-weighted)
//! interpolated there when `q` is on an edge or a corner. Bærentzen and Aanæs 2005 prove
//! the sign exact with angle-weighted pseudonormals; area weights differ from them only
//! where neighbouring triangles differ much in size, which smooth skin meshes rarely do.
//! Normals face out: the winding is flipped when the bind surface encloses a negative
//! volume.

use glam::Vec3;

use super::attach::closest_on_triangle;

/// Triangles per leaf at most.
const LEAF: usize = 4;

/// A tree node: a box and either two children (`left`, `right`) or a range of
/// [`Surface::order`] (`start..end`, `left == NONE`).
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    start: u32,
    end: u32,
    left: u32,
    right: u32,
}

const NONE: u32 = u32::MAX;

/// The body surface: triangles and the tree over them (boxes as of the last
/// [`Surface::refit`]).
#[derive(Clone, Debug)]
pub(crate) struct Surface {
    triangles: Vec<[u32; 3]>,
    /// Triangle indices in leaf order.
    order: Vec<u32>,
    /// Preorder: a parent before its children, so a reverse pass refits bottom up.
    nodes: Vec<Node>,
    /// 1 when the triangles wind counter-clockwise seen from outside, -1 otherwise.
    outward: f32,
    /// Whether the surface encloses a volume (every edge, between vertices welded by
    /// position, has two triangles): only then has it an inside.
    closed: bool,
}

/// The posed surface at one instant: vertex positions and normals lerped between a frame's
/// start (`a = 0`) and end (`a = 1`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Posed<'a> {
    pub(crate) from: &'a [Vec3],
    pub(crate) to: &'a [Vec3],
    pub(crate) from_normals: &'a [Vec3],
    pub(crate) to_normals: &'a [Vec3],
    pub(crate) a: f32,
}

impl Posed<'_> {
    /// The body at one frame.
    pub(crate) fn at<'a>(positions: &'a [Vec3], normals: &'a [Vec3]) -> Posed<'a> {
        Posed {
            from: positions,
            to: positions,
            from_normals: normals,
            to_normals: normals,
            a: 1.0,
        }
    }

    fn vertex(&self, v: u32) -> Vec3 {
        let v = v as usize;
        let (p, q) = (self.from.get(v), self.to.get(v));
        match (p, q) {
            (_, Some(q)) if self.a >= 1.0 => *q,
            (Some(p), Some(q)) => p.lerp(*q, self.a),
            _ => Vec3::ZERO,
        }
    }

    fn normal(&self, v: u32) -> Vec3 {
        let v = v as usize;
        match (self.from_normals.get(v), self.to_normals.get(v)) {
            (_, Some(q)) if self.a >= 1.0 => *q,
            (Some(p), Some(q)) => p.lerp(*q, self.a),
            _ => Vec3::ZERO,
        }
    }
}

/// The point of the surface nearest to a query point, and which side the query is on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Nearest {
    /// The nearest surface point.
    pub(crate) point: Vec3,
    /// Signed distance: positive outside, negative inside.
    pub(crate) signed: f32,
    /// The unit direction out of the body at the query: from `point` towards the query
    /// outside, away from it inside, the surface normal when the query is on the surface.
    pub(crate) out: Vec3,
}

impl Surface {
    /// The tree over `triangles` of a surface at `bind`, its boxes fitted to `bind`.
    pub(crate) fn new(bind: &[Vec3], triangles: &[[u32; 3]]) -> Self {
        let vertex = |v: u32| bind.get(v as usize).copied().unwrap_or(Vec3::ZERO);
        let centroids: Vec<Vec3> = triangles
            .iter()
            .map(|t| (vertex(t[0]) + vertex(t[1]) + vertex(t[2])) / 3.0)
            .collect();
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * triangles.len() / LEAF + 1);
        build(&mut nodes, &mut order, &centroids, 0, triangles.len());
        // Twice the signed volume times 3 (the sign is all that matters).
        let volume: f64 = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| vertex(v).as_dvec3());
                a.dot(b.cross(c))
            })
            .sum();
        let mut s = Self {
            triangles: triangles.to_vec(),
            order,
            nodes,
            outward: if volume < 0.0 { -1.0 } else { 1.0 },
            closed: is_closed(bind, triangles),
        };
        s.refit(bind, bind);
        s
    }

    /// This surface, a part of `whole` (some of its triangles), with the whole's inside:
    /// a part cut out of a closed body has edges with one triangle, yet a point deep in a
    /// hand is inside the body.
    pub(crate) fn inside_as(mut self, whole: &Surface) -> Self {
        self.outward = whole.outward;
        self.closed = whole.closed;
        self
    }

    /// Fits every box around the triangles at `from` and at `to` (same vertex count).
    pub(crate) fn refit(&mut self, from: &[Vec3], to: &[Vec3]) {
        let vertex = |p: &[Vec3], v: u32| p.get(v as usize).copied().unwrap_or(Vec3::ZERO);
        for k in (0..self.nodes.len()).rev() {
            let n = self.nodes[k];
            let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            if n.left == NONE {
                for &t in &self.order[n.start as usize..n.end as usize] {
                    for &v in &self.triangles[t as usize] {
                        for p in [vertex(from, v), vertex(to, v)] {
                            lo = lo.min(p);
                            hi = hi.max(p);
                        }
                    }
                }
            } else {
                let (l, r) = (self.nodes[n.left as usize], self.nodes[n.right as usize]);
                lo = l.lo.min(r.lo);
                hi = l.hi.max(r.hi);
            }
            self.nodes[k].lo = lo;
            self.nodes[k].hi = hi;
        }
    }

    /// Outward unit vertex normals of the surface at `positions` (area-weighted; zero at a
    /// vertex no triangle with an area uses), into `out` (resized).
    pub(crate) fn normals(&self, positions: &[Vec3], out: &mut Vec<Vec3>) {
        out.clear();
        out.resize(positions.len(), Vec3::ZERO);
        for t in &self.triangles {
            let [Some(&a), Some(&b), Some(&c)] = t.map(|v| positions.get(v as usize)) else {
                continue;
            };
            let n = (b - a).cross(c - a) * self.outward;
            for &v in t {
                out[v as usize] += n;
            }
        }
        for n in out.iter_mut() {
            *n = n.normalize_or_zero();
        }
    }

    /// Triangle `t` as the best hit when closer than `best_d2`.
    fn closer(
        &self,
        posed: &Posed<'_>,
        p: Vec3,
        t: u32,
        best: &mut Option<(u32, [f32; 3], Vec3)>,
        best_d2: &mut f32,
    ) {
        let [a, b, c] = self.triangles[t as usize].map(|v| posed.vertex(v));
        let w = closest_on_triangle(p, a, b, c);
        let q = a * w[0] + b * w[1] + c * w[2];
        let d2 = (p - q).length_squared();
        // Ties go to the first triangle met (a fixed order: the same result every run).
        if d2 < *best_d2 || (best.is_none() && d2 <= *best_d2) {
            *best_d2 = d2;
            *best = Some((t, w, q));
        }
    }

    /// The nearest point of the surface `posed` to `p` no farther than `max` (the boxes
    /// must hold `posed`: [`Surface::refit`] to its frame). `None` without one.
    pub(crate) fn nearest(&self, posed: &Posed<'_>, p: Vec3, max: f32) -> Option<Nearest> {
        self.nearest_with(posed, p, max, self.closed)
    }

    /// [`Surface::nearest`] with an inside as if the surface were closed: for a part of a
    /// closed body (its own cut edges make it open), where a point past the part's skin is
    /// inside the body.
    pub(crate) fn nearest_closed(&self, posed: &Posed<'_>, p: Vec3, max: f32) -> Option<Nearest> {
        self.nearest_with(posed, p, max, true)
    }

    fn nearest_with(&self, posed: &Posed<'_>, p: Vec3, max: f32, closed: bool) -> Option<Nearest> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best: Option<(u32, [f32; 3], Vec3)> = None;
        let mut best_d2 = max * max;
        // Median splits keep the depth under log2(triangles) + 2: 64 is never reached.
        let mut stack = [0u32; 64];
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            if box_distance2(n.lo, n.hi, p) > best_d2 {
                continue;
            }
            if n.left == NONE {
                for &t in &self.order[n.start as usize..n.end as usize] {
                    self.closer(posed, p, t, &mut best, &mut best_d2);
                }
            } else if top + 2 <= stack.len() {
                let (l, r) = (self.nodes[n.left as usize], self.nodes[n.right as usize]);
                // Push the farther child first so the nearer one is searched first.
                let (dl, dr) = (box_distance2(l.lo, l.hi, p), box_distance2(r.lo, r.hi, p));
                let (near, far) = if dl <= dr {
                    (n.left, n.right)
                } else {
                    (n.right, n.left)
                };
                stack[top] = far;
                stack[top + 1] = near;
                top += 2;
            }
        }
        self.finish(posed, p, best, closed)
    }

    /// The signed hit of the best triangle found.
    fn finish(
        &self,
        posed: &Posed<'_>,
        p: Vec3,
        best: Option<(u32, [f32; 3], Vec3)>,
        closed: bool,
    ) -> Option<Nearest> {
        let (t, w, q) = best?;
        let tri = self.triangles[t as usize];
        let [a, b, c] = tri.map(|v| posed.vertex(v));
        let face = (b - a).cross(c - a) * self.outward;
        // Inside the triangle the face normal decides; on an edge or a corner the vertex
        // normals there.
        let interior = w.iter().all(|&x| x > 1e-4);
        let smooth = tri
            .iter()
            .zip(w)
            .fold(Vec3::ZERO, |s, (&v, x)| s + posed.normal(v) * x);
        let n = if interior { face } else { smooth }
            .try_normalize()
            .or_else(|| face.try_normalize())
            .unwrap_or(Vec3::ZERO);
        let d = p - q;
        let len = d.length();
        // An open surface (a sheet) has no inside: a point is off it on either side.
        let inside = closed && d.dot(n) < 0.0;
        let out = if len > 1e-7 * (1.0 + q.abs().max_element()) {
            if inside {
                -d / len
            } else {
                d / len
            }
        } else {
            n
        };
        Some(Nearest {
            point: q,
            signed: if inside { -len } else { len },
            out,
        })
    }
}

/// Whether every edge of `triangles` (vertices welded by exact position) has exactly two
/// triangles.
fn is_closed(positions: &[Vec3], triangles: &[[u32; 3]]) -> bool {
    use std::collections::BTreeMap;
    let mut weld: BTreeMap<[u32; 3], u32> = BTreeMap::new();
    let id: Vec<u32> = positions
        .iter()
        .map(|p| {
            let next = weld.len() as u32;
            *weld.entry(p.to_array().map(f32::to_bits)).or_insert(next)
        })
        .collect();
    let mut edges: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    for t in triangles {
        let v = t.map(|i| id.get(i as usize).copied().unwrap_or(u32::MAX));
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            if a != b {
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
    }
    !edges.is_empty() && edges.values().all(|&c| c == 2)
}

/// Squared distance from `p` to the box `lo..hi` (0 inside).
fn box_distance2(lo: Vec3, hi: Vec3, p: Vec3) -> f32 {
    let d = (lo - p).max(p - hi).max(Vec3::ZERO);
    d.length_squared()
}

/// Builds the subtree over `order[start..end]` (preorder), returning its node index.
fn build(
    nodes: &mut Vec<Node>,
    order: &mut [u32],
    centroids: &[Vec3],
    start: usize,
    end: usize,
) -> u32 {
    let index = nodes.len() as u32;
    nodes.push(Node {
        lo: Vec3::ZERO,
        hi: Vec3::ZERO,
        start: start as u32,
        end: end as u32,
        left: NONE,
        right: NONE,
    });
    if end - start <= LEAF {
        return index;
    }
    let slice = &mut order[start..end];
    let (lo, hi) = slice.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &t| {
            let c = centroids[t as usize];
            (lo.min(c), hi.max(c))
        },
    );
    let extent = hi - lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = slice.len() / 2;
    // Ties broken by index: the same tree on every run.
    slice.select_nth_unstable_by(mid, |&a, &b| {
        centroids[a as usize][axis]
            .total_cmp(&centroids[b as usize][axis])
            .then(a.cmp(&b))
    });
    let left = build(nodes, order, centroids, start, start + mid);
    let right = build(nodes, order, centroids, start + mid, end);
    nodes[index as usize].left = left;
    nodes[index as usize].right = right;
    index
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A closed box `0..1` cubed as 12 triangles wound counter-clockwise from outside, or
    /// clockwise when `flip`.
    /// The unit cube's corners and triangles (wound outward, or inward with `flip`).
    pub(crate) fn cube(flip: bool) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p: Vec<Vec3> = (0..8)
            .map(|k| Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, ((k >> 2) & 1) as f32))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let mut t = Vec::new();
        for [a, b, c, d] in quads {
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
        if flip {
            for tri in &mut t {
                tri.swap(1, 2);
            }
        }
        (p, t)
    }

    #[test]
    fn signed_distance_of_a_cube_either_winding() {
        for flip in [false, true] {
            let (p, t) = cube(flip);
            let s = Surface::new(&p, &t);
            let mut n = Vec::new();
            s.normals(&p, &mut n);
            let posed = Posed::at(&p, &n);
            let inside = s.nearest(&posed, Vec3::new(0.5, 0.5, 0.9), 10.0).unwrap();
            assert!((inside.signed + 0.1).abs() < 1e-6, "{inside:?}");
            assert!((inside.out - Vec3::Z).length() < 1e-6, "{inside:?}");
            let outside = s.nearest(&posed, Vec3::new(1.5, 1.5, 0.5), 10.0).unwrap();
            assert!((outside.signed - 0.5f32.sqrt()).abs() < 1e-6, "{outside:?}");
            // Out of reach.
            assert!(s.nearest(&posed, Vec3::new(3.0, 0.5, 0.5), 1.0).is_none());
            // Without its top, the box has no inside.
            let open = Surface::new(&p, &t[..10]);
            let hit = open
                .nearest(&posed, Vec3::new(0.5, 0.5, 0.9), 10.0)
                .unwrap();
            assert!(hit.signed > 0.0, "{hit:?}");
            // As a part of the closed box, it has the box's inside, near its own faces.
            let part = Surface::new(&p, &t[..10]).inside_as(&s);
            let hit = part
                .nearest(&posed, Vec3::new(0.5, 0.5, 0.1), 10.0)
                .unwrap();
            assert!((hit.signed + 0.1).abs() < 1e-6, "{hit:?}");
            let hit = open
                .nearest_closed(&posed, Vec3::new(0.5, 0.5, 0.1), 10.0)
                .unwrap();
            assert!((hit.signed + 0.1).abs() < 1e-6, "{hit:?}");
        }
    }

    #[test]
    fn tree_matches_brute_force_on_a_moving_grid() {
        // A wavy 20 x 20 height field, lerped half way to a shifted copy.
        let mut p = Vec::new();
        let mut q = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                let (x, z) = (i as f32 * 0.1, j as f32 * 0.1);
                p.push(Vec3::new(x, (3.0 * x).sin() * 0.2, z));
                q.push(Vec3::new(x, (3.0 * z).cos() * 0.2 + 0.1, z));
            }
        }
        let mut t = Vec::new();
        for i in 0..19u32 {
            for j in 0..19u32 {
                let a = i * 20 + j;
                t.push([a, a + 1, a + 20]);
                t.push([a + 1, a + 21, a + 20]);
            }
        }
        let mut s = Surface::new(&p, &t);
        s.refit(&p, &q);
        let (mut np, mut nq) = (Vec::new(), Vec::new());
        s.normals(&p, &mut np);
        s.normals(&q, &mut nq);
        let posed = Posed {
            from: &p,
            to: &q,
            from_normals: &np,
            to_normals: &nq,
            a: 0.5,
        };
        let mid: Vec<Vec3> = p.iter().zip(&q).map(|(a, b)| a.lerp(*b, 0.5)).collect();
        for k in 0..200 {
            let x = Vec3::new(
                (k * 37 % 100) as f32 * 0.021 - 0.05,
                (k * 53 % 100) as f32 * 0.008 - 0.4,
                (k * 71 % 100) as f32 * 0.02,
            );
            let brute = t
                .iter()
                .map(|tri| {
                    let [a, b, c] = tri.map(|v| mid[v as usize]);
                    let w = closest_on_triangle(x, a, b, c);
                    (a * w[0] + b * w[1] + c * w[2] - x).length()
                })
                .fold(f32::INFINITY, f32::min);
            let hit = s.nearest(&posed, x, f32::INFINITY).unwrap();
            assert!(
                (hit.signed.abs() - brute).abs() < 1e-5,
                "{x}: {hit:?} vs {brute}"
            );
        }
    }
}
