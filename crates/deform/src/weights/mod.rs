//! Automatic skin weights by bone heat (Baran and Popović 2007, "Automatic Rigging and
//! Animation of 3D Characters", section 4), the attachment step of Pinocchio.
//!
//! Each bone's weight is the equilibrium of heat diffusing over the surface from the
//! bones: `(-Δ + H) w_j = H p_j`, where `Δ` is the mesh's cotangent Laplacian, `H` is
//! diagonal with `H_ii = c / d_i²` for `d_i` the distance from vertex `i` to its nearest
//! *visible* bone (the straight line from the vertex to the bone's nearest point crosses
//! no face), and `p_j(i)` is 1 when bone `j` is that bone (shared equally by bones equally
//! near). Multiplied through by the vertex areas the system is symmetric positive
//! definite: one sparse Cholesky factorization (`faer`) serves every bone's solve.
//! Weights under [`HeatOptions::prune`] are dropped and each row renormalized.
//!
//! It never fails on a mesh with faces. What it repairs is counted in [`Repairs`]:
//! - coincident vertices are welded first (`laplacian`), so seams do not cut the surface;
//! - zero-area faces and faces with repeated corners carry no heat;
//! - cotangent weights are clamped to be non-negative and finite, so non-manifold edges,
//!   needles and obtuse pairs keep the operator positive semi-definite;
//! - a vertex that sees no bone gets no heat source and takes its weights from its
//!   neighbours by diffusion, as in Pinocchio;
//! - a piece of the surface (a connected component) where no vertex sees a bone, and a
//!   vertex in no face, is weighted by plain distance: its sources are the nearest bones
//!   whether seen or not.

mod bind;
mod laplacian;
#[cfg(test)]
mod tests;
mod visibility;

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use visibility::Sight;

pub use bind::{bind, Bound};

/// A bone: the segment from its head (the joint it turns about) to its tail.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bone {
    /// The joint the bone turns about.
    pub head: Vec3,
    /// The bone's other end.
    pub tail: Vec3,
}

/// Options of [`bone_heat`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeatOptions {
    /// The heat constant `c` of `H_ii = c / d²` (Pinocchio's 1).
    pub heat: f64,
    /// Weights under this are dropped (then each row is renormalized).
    pub prune: f32,
}

impl Default for HeatOptions {
    fn default() -> Self {
        Self {
            heat: 3.0,
            prune: 0.001,
        }
    }
}

/// What [`bone_heat`] repaired or worked around, counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Repairs {
    /// Input vertices welded onto a coincident one.
    pub welded: usize,
    /// Faces with no area or repeated corners (no heat flows across them).
    pub degenerate_faces: usize,
    /// Edges shared by more than two faces.
    pub non_manifold_edges: usize,
    /// Vertices that see no bone (weighted by diffusion from their neighbours).
    pub unseen: usize,
    /// Vertices weighted by plain distance: in a piece of the surface where no vertex sees
    /// a bone, or in no face.
    pub by_distance: usize,
    /// Edges whose negative cotangent weight (an obtuse pair of angles) was clamped to 0,
    /// because the system was not positive definite with it.
    pub negative_edges: usize,
}

impl Repairs {
    /// Whether anything was repaired.
    pub fn any(&self) -> bool {
        *self != Repairs::default()
    }
}

/// Weights per input vertex: `(bone index, weight)` pairs summing to 1, heaviest first.
#[derive(Clone, Debug, PartialEq)]
pub struct HeatWeights {
    /// One row per input vertex.
    pub rows: Vec<Vec<(u32, f32)>>,
    /// What was repaired.
    pub repairs: Repairs,
}

/// Why [`bone_heat`] could not run.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum WeightsError {
    /// The mesh has no faces: there is no surface for heat to flow over.
    #[error("the mesh has no faces: automatic weights need a surface")]
    NoFaces,
    /// No bones to weight.
    #[error("the skeleton has no bones (at least two joints are needed)")]
    NoBones,
    /// A face names a vertex past the end.
    #[error("face {face} names vertex {vertex}, but the mesh has {count} vertices")]
    BadIndex {
        /// The face.
        face: usize,
        /// The vertex it names.
        vertex: u32,
        /// The vertex count.
        count: usize,
    },
    /// A position or bone end is not finite.
    #[error("{0} is not finite")]
    NonFinite(&'static str),
    /// The factorization failed (not expected: the system is positive definite by
    /// construction).
    #[error("the heat system could not be factored: {0}")]
    Solver(String),
}

/// The Cholesky factor of `diag + L` (`L` from the edge weights, negative ones clamped to
/// 0 when `clamp`).
fn factor(
    n: usize,
    diag: &[f64],
    edges: &[(u32, u32, f64)],
    clamp: bool,
) -> Result<faer::sparse::linalg::solvers::Llt<usize, f64>, WeightsError> {
    let mut d = diag.to_vec();
    let mut triplets = Vec::with_capacity(n + 2 * edges.len());
    for &(i, j, w) in edges {
        let w = if clamp { w.max(0.0) } else { w };
        if w != 0.0 {
            d[i as usize] += w;
            d[j as usize] += w;
            triplets.push(Triplet::new(i as usize, j as usize, -w));
            triplets.push(Triplet::new(j as usize, i as usize, -w));
        }
    }
    triplets.extend(d.iter().enumerate().map(|(i, &v)| Triplet::new(i, i, v)));
    let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
        .map_err(|e| WeightsError::Solver(format!("{e:?}")))?;
    matrix
        .sp_cholesky(faer::Side::Lower)
        .map_err(|e| WeightsError::Solver(format!("{e:?}")))
}

/// The nearest point of segment `a`-`b` to `p`.
fn nearest_on(a: DVec3, b: DVec3, p: DVec3) -> DVec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    a + ab * t
}

/// A vertex's heat source: the bones sharing it and their distance.
type Source = (Vec<u32>, f64);

/// Bones sharing a vertex's heat source: those this close to the nearest, relatively.
const TIE: f64 = 1e-4;

/// Counted work of [`bone_heat`], told to its caller at most about a hundred times.
struct Work<'a> {
    done: std::sync::atomic::AtomicUsize,
    total: usize,
    step: usize,
    progress: &'a (dyn Fn(usize, usize) + Sync),
}

impl<'a> Work<'a> {
    fn new(total: usize, progress: &'a (dyn Fn(usize, usize) + Sync)) -> Self {
        progress(0, total);
        Self {
            done: 0.into(),
            total,
            step: (total / 100).max(1),
            progress,
        }
    }

    /// `units` more are done: tells the caller when that crosses a step.
    fn add(&self, units: usize) {
        use std::sync::atomic::Ordering;
        let before = self.done.fetch_add(units, Ordering::Relaxed);
        let after = (before + units).min(self.total);
        if after / self.step != before / self.step || after == self.total {
            (self.progress)(after, self.total);
        }
    }
}

/// A bone is seen from the side a vertex faces when the line from the bone to the vertex
/// is within 60° of the mean of the vertex's face normals (cosine over this).
const FACING: f64 = 0.5;

/// Automatic weights of a mesh (`positions`, `triangles`) for `bones` (see the module
/// docs). Rows follow the input vertices; bones are numbered as given.
///
/// `progress(done, total)` is told how far the work is, from any thread, in units of
/// welded vertices: one per vertex checked for sight of its bones, then as many as there
/// are vertices when the factorization is done, and as many again when the solves are
/// (each of the three takes about a third of the time on a 120k-vertex mesh). `total` is
/// three times the welded vertex count; `done` reaches it at the end.
///
/// # Errors
/// No faces, no bones, a face index out of range, a non-finite position, or (not expected)
/// a failed factorization.
pub fn bone_heat(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    bones: &[Bone],
    opts: &HeatOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<HeatWeights, WeightsError> {
    if triangles.is_empty() {
        return Err(WeightsError::NoFaces);
    }
    if bones.is_empty() {
        return Err(WeightsError::NoBones);
    }
    for (face, t) in triangles.iter().enumerate() {
        if let Some(&vertex) = t.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(WeightsError::BadIndex {
                face,
                vertex,
                count: positions.len(),
            });
        }
    }
    if positions.iter().any(|p| !p.is_finite()) {
        return Err(WeightsError::NonFinite("a vertex position"));
    }
    if bones
        .iter()
        .any(|b| !(b.head.is_finite() && b.tail.is_finite()))
    {
        return Err(WeightsError::NonFinite("a bone end"));
    }
    let points: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
    let surf = laplacian::surface(&points, triangles);
    let sight = Sight::new(&surf.points, &surf.triangles);
    let segs: Vec<(DVec3, DVec3)> = bones
        .iter()
        .map(|b| (b.head.as_dvec3(), b.tail.as_dvec3()))
        .collect();
    let n = surf.points.len();
    let work = Work::new(3 * n, progress);
    // Per welded vertex: the mean of its faces' unit normals (the outside it faces).
    let mut facing = vec![DVec3::ZERO; n];
    for t in &surf.triangles {
        let [a, b, c] = t.map(|i| surf.points[i as usize]);
        let normal = (b - a).cross(c - a).normalize_or_zero();
        for &v in t {
            facing[v as usize] += normal;
        }
    }

    // Per welded vertex: its heat sources (the nearest bones, when it sees them from the
    // side it faces) and their distance, and the nearest bones regardless of sight.
    let near: Vec<(Option<Source>, Source)> = surf
        .points
        .par_iter()
        .zip(&facing)
        .map(|(&p, &facing)| {
            let mut order: Vec<(f64, u32, DVec3)> = segs
                .iter()
                .enumerate()
                .map(|(j, &(a, b))| {
                    let q = nearest_on(a, b, p);
                    (p.distance(q), j as u32, q)
                })
                .collect();
            order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let ties = |d: f64| -> Vec<u32> {
                order
                    .iter()
                    .filter(|o| o.0 <= d * (1.0 + TIE) + f64::MIN_POSITIVE)
                    .map(|o| o.1)
                    .collect()
            };
            let any = (ties(order[0].0), order[0].0);
            // The nearest bones only: a vertex whose nearest bone is hidden (behind
            // another part of the body, or behind its own surface) gets no source.
            let bones: Vec<u32> = order
                .iter()
                .filter(|o| o.0 <= order[0].0 * (1.0 + TIE) + f64::MIN_POSITIVE)
                .filter(|&&(_, _, q)| {
                    let out = (p - q).normalize_or_zero();
                    out.dot(facing.normalize_or_zero()) > FACING && !sight.blocked(p, q)
                })
                .map(|o| o.1)
                .collect();
            let seen = (!bones.is_empty()).then_some((bones, order[0].0));
            work.add(1);
            (seen, any)
        })
        .collect();

    // Which components have a heat source; which vertices are in a face.
    let components = surf
        .component
        .iter()
        .copied()
        .max()
        .map_or(0, |m| m as usize + 1);
    let mut heated = vec![false; components];
    let mut in_face = vec![false; n];
    for &(i, j, w) in &surf.edges {
        if w != 0.0 {
            in_face[i as usize] = true;
            in_face[j as usize] = true;
        }
    }
    for (v, (seen, _)) in near.iter().enumerate() {
        if seen.is_some() && in_face[v] {
            heated[surf.component[v] as usize] = true;
        }
    }
    let mut repairs = Repairs {
        welded: surf.welded,
        degenerate_faces: surf.degenerate,
        non_manifold_edges: surf.non_manifold,
        ..Repairs::default()
    };
    // The heat sources: (H_ii, bones sharing p).
    let sources: Vec<(f64, &[u32])> = near
        .iter()
        .enumerate()
        .map(|(v, (seen, any))| {
            let by_distance = !in_face[v] || !heated[surf.component[v] as usize];
            let source = if by_distance {
                repairs.by_distance += 1;
                Some((&any.0, any.1))
            } else {
                if seen.is_none() {
                    repairs.unseen += 1;
                }
                seen.as_ref().map(|(b, d)| (b, *d))
            };
            match source {
                Some((b, d)) => (opts.heat / (d * d).max(1e-300), b.as_slice()),
                None => (0.0, &[][..]),
            }
        })
        .collect();
    // Scaled by the areas: (L + A H) w = A H p. With the cotangent weights as they are
    // (as Pinocchio solves it) the matrix is positive definite on a well-shaped mesh; an
    // obtuse enough pair of angles makes an edge weight negative, and if the
    // factorization then fails, it is redone with the negative weights clamped to 0.
    let diag: Vec<f64> = sources
        .iter()
        .zip(&surf.area)
        .map(|((h, _), a)| h * a)
        .collect();
    let llt = match factor(n, &diag, &surf.edges, false) {
        Ok(llt) => llt,
        Err(_) => {
            repairs.negative_edges = surf.edges.iter().filter(|e| e.2 < 0.0).count();
            factor(n, &diag, &surf.edges, true)?
        }
    };
    work.add(n);
    let mut solved = Mat::<f64>::zeros(n, bones.len());
    for (v, ((h, share), a)) in sources.iter().zip(&surf.area).enumerate() {
        for &j in *share {
            solved[(v, j as usize)] = h * a / share.len() as f64;
        }
    }
    // Every bone at once: each solve walks the whole factor, so bones solved a few at a
    // time cost more than half as much again on a 120k-vertex mesh.
    llt.solve_in_place(solved.as_mut());
    work.add(n);

    let welded_rows: Vec<Vec<(u32, f32)>> = (0..n)
        .into_par_iter()
        .map(|v| {
            let mut row: Vec<(u32, f32)> = (0..bones.len())
                .map(|j| (j as u32, solved[(v, j)].clamp(0.0, 1.0) as f32))
                .collect();
            row.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            let keep = row.iter().take_while(|e| e.1 >= opts.prune).count().max(1);
            row.truncate(keep);
            let sum: f32 = row.iter().map(|e| e.1).sum();
            if sum > 0.0 {
                row.iter_mut().for_each(|e| e.1 /= sum);
            } else {
                // Not expected (the solution is a convex blend); the nearest bone.
                row = vec![(near[v].1 .0[0], 1.0)];
            }
            row
        })
        .collect();
    Ok(HeatWeights {
        rows: surf
            .weld
            .iter()
            .map(|&w| welded_rows[w as usize].clone())
            .collect(),
        repairs,
    })
}
