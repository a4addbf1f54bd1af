//! Influence refit: fewer influences per vertex that keep the deformation.
//!
//! glTF viewers skin with 4 influences per vertex (three.js, model-viewer, Filament, Bevy
//! and Unity read only `JOINTS_0`/`WEIGHTS_0`), and Pinocchio or CSCI 520 rigs carry up to
//! 18. Keeping the largest K weights and renormalizing (what Blender, gltfpack,
//! glTF-Transform and Assimp do) changes the deformation wherever the dropped weights
//! mattered. [`RefitJob`] instead chooses, per vertex, at most K of its original influences
//! and weights `w >= 0`, `sum w = 1`, that minimise the squared distance between the
//! K-influence linear blend and the full-weight linear blend over a set of poses
//! (Kavan et al. 2010, "Fast and Efficient Skinning of Animated Meshes", and Le & Deng
//! 2012, "Smooth Skinning Decomposition with Rigid Bones", solve the same per-vertex
//! constrained least squares when they fit weights to poses).
//!
//! # The problem per vertex
//! With `a_pi = M_p[j_i] · x` (the vertex moved by influence `i`'s skinning matrix in pose
//! `p`) and `y_p = Σ w_i a_pi` (the full-weight result), any weights summing to 1 give the
//! error `Σ_p |Σ_i c_i (a_pi - y_p)|² = cᵀ H c` with `H = Σ_p D_pᵀ D_p`, `D_p` the 3 x n
//! matrix of columns `a_pi - y_p`. The bind pose (every skinning matrix the identity) has
//! `a_pi = x` for every `i`, so **any** convex weights reproduce the bind shape exactly.
//!
//! rigport minimises `cᵀ H c + ε |c - t|²` over the simplex `{c >= 0, Σ c = 1}` restricted
//! to a support of K candidates, by a primal active-set method (KKT systems of at most
//! K + 1 unknowns, `f64`), where `t` is the truncated-and-renormalized row and
//! `ε = 1e-9 · trace(H) / n` a tiny ridge that makes `H` definite and breaks ties toward
//! the truncation (joints that never move apart in the pose set). The support is chosen by
//! that error: every K-subset when the vertex has at most 10 influences, otherwise a swap
//! search; then a minimax refinement (Lawson's reweighting) of that support and of the
//! truncation's leans toward the largest deviation, which is what a viewer shows worst
//! (see `select.rs`). Finally the refit row is kept only if, over the fit poses, its largest
//! deviation is smaller than the truncation's and its squared error no larger: the refit is
//! never worse than truncation on the poses it was fitted to.
//!
//! Why the worst case does not always halve: in a pose that turns only joints none of
//! whose descendants is kept, every kept influence moves alike and the error is the
//! dropped weight times that motion, whatever the weights. Vertices of the CSCI 520 rigs
//! carry 5 to 7 influences of similar size spread over separate chains, where this floor
//! is close to the truncation's error (BENCHMARKS.md has the figures).
//!
//! # Pose sets
//! [`RefitJob`] takes skinning matrices per pose from the caller: a clip's frames when the
//! asset has clips, otherwise [`range_of_motion`] (documented there). Held-out poses (a
//! different seed) measure how well a refit generalizes.

pub mod asset;
mod row;
mod select;

pub use row::{truncate_row, MAX_CANDIDATES};
use select::refit_row;

use std::num::NonZeroUsize;

use glam::{DMat4, DVec3, Mat4, Quat, Vec3};
use rayon::prelude::*;
use rigport_model::{Influence, Influences, Skeleton, Transform};

use rigport_eval::{EvalError, Pose};

/// How far a set of weights deforms away from the full-weight linear blend over a pose set.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Deviation {
    /// Largest distance of any vertex in any pose, in the mesh's length unit.
    pub max: f64,
    /// Root mean square over all vertices and poses.
    pub rms: f64,
}

/// Fits at most `max_influences` influences per vertex to the full-weight deformation over
/// a set of poses. Parallel over vertices (rayon; the caller's pool).
pub struct RefitJob<'a> {
    /// Bind-space positions, one per vertex (what the skinning matrices apply to).
    pub positions: &'a [Vec3],
    /// The full influences, one row per vertex, indexing the palette.
    pub influences: &'a Influences,
    /// Skinning matrices (`model · inv_bind`) of every pose, `palette_len` per pose, pose
    /// after pose.
    pub pose_matrices: &'a [Mat4],
    /// Palette length (matrices per pose).
    pub palette_len: usize,
    /// K: the most influences a vertex may keep.
    pub max_influences: NonZeroUsize,
}

/// What [`RefitJob::run`] returns.
#[derive(Clone, Debug, PartialEq)]
pub struct Refit {
    /// At most K influences per vertex, non-negative, summing to 1 (in `f64`, then rounded
    /// to `f32`), sorted by decreasing weight.
    pub influences: Influences,
    /// Vertices whose refit row differs from the truncated one.
    pub changed: usize,
}

impl RefitJob<'_> {
    /// Checks sizes and indices.
    ///
    /// # Errors
    /// [`EvalError::Length`] when the positions and influences disagree or the matrices do
    /// not fill whole poses; [`EvalError::Index`] for an influence outside the palette;
    pub fn validate(&self) -> Result<(), EvalError> {
        if self.influences.vertex_count() != self.positions.len() {
            return Err(EvalError::Length {
                what: "refit influences",
                expected: self.positions.len(),
                found: self.influences.vertex_count(),
            });
        }
        if self.palette_len == 0 || self.pose_matrices.len() % self.palette_len != 0 {
            return Err(EvalError::Length {
                what: "refit pose matrices (whole poses)",
                expected: self.palette_len,
                found: self.pose_matrices.len(),
            });
        }
        if let Some(i) = self
            .influences
            .entries()
            .iter()
            .find(|i| i.joint as usize >= self.palette_len)
        {
            return Err(EvalError::Index {
                what: "refit influence joint",
                index: i.joint as usize,
            });
        }
        Ok(())
    }

    /// Runs the refit.
    ///
    /// # Errors
    /// As [`RefitJob::validate`].
    pub fn run(&self) -> Result<Refit, EvalError> {
        self.validate()?;
        let poses: Vec<DMat4> = self.pose_matrices.iter().map(|m| m.as_dmat4()).collect();
        let k = self.max_influences.get();
        let rows: Vec<(Vec<Influence>, bool)> = (0..self.positions.len())
            .into_par_iter()
            .with_min_len(64)
            .map(|v| {
                refit_row(
                    self.positions[v].as_dvec3(),
                    self.influences.vertex(v),
                    &poses,
                    self.palette_len,
                    k,
                )
            })
            .collect();
        let changed = rows.iter().filter(|(_, c)| *c).count();
        Ok(Refit {
            influences: Influences::from_rows(rows.into_iter().map(|(r, _)| r)),
            changed,
        })
    }
}

/// The deviation of `influences` from `full` over the poses: per vertex and pose, the
/// distance between the two linear blends.
///
/// # Errors
/// As [`RefitJob::validate`] (for both influence sets).
pub fn deviation(
    positions: &[Vec3],
    full: &Influences,
    influences: &Influences,
    pose_matrices: &[Mat4],
    palette_len: usize,
) -> Result<Deviation, EvalError> {
    for inf in [full, influences] {
        RefitJob {
            positions,
            influences: inf,
            pose_matrices,
            palette_len,
            max_influences: NonZeroUsize::MIN,
        }
        .validate()?;
    }
    let poses: Vec<DMat4> = pose_matrices.iter().map(|m| m.as_dmat4()).collect();
    let blend = |x: DVec3, row: &[Influence], pose: &[DMat4]| -> DVec3 {
        row.iter()
            .map(|i| f64::from(i.weight) * pose[i.joint as usize].transform_point3(x))
            .sum()
    };
    let (max, sum_sq, count) = (0..positions.len())
        .into_par_iter()
        .with_min_len(64)
        .map(|v| {
            let x = positions[v].as_dvec3();
            let (a, b) = (full.vertex(v), influences.vertex(v));
            let mut max = 0.0f64;
            let mut sum_sq = 0.0;
            for pose in poses.chunks_exact(palette_len) {
                let e = blend(x, a, pose).distance(blend(x, b, pose));
                max = max.max(e);
                sum_sq += e * e;
            }
            (max, sum_sq, poses.len() / palette_len)
        })
        .reduce(
            || (0.0, 0.0, 0),
            |a, b| (a.0.max(b.0), a.1 + b.1, a.2 + b.2),
        );
    Ok(Deviation {
        max,
        rms: if count > 0 {
            (sum_sq / count as f64).sqrt()
        } else {
            0.0
        },
    })
}

/// A seeded range-of-motion pose set for a skeleton, for rigs without clips.
///
/// For every joint that has a parent: rotations of that joint alone, in its rest frame,
/// by ±45° and ±90° about each of its three rest axes (12 poses per joint); then `random`
/// poses in which `bent` joints (chosen at random among those with a parent) each turn by
/// a random rotation of up to 90° about a random axis (uniform axis, angle uniform in
/// [0, 90°]), the way an animator bends an elbow and a shoulder together. `seed` makes the
/// random part repeatable: tests fit with one seed and measure with another.
pub fn range_of_motion(skeleton: &Skeleton, random: usize, bent: usize, seed: u64) -> Vec<Pose> {
    let rest = Pose::rest(skeleton);
    let mut poses = Vec::new();
    let angles = [45f32, -45.0, 90.0, -90.0];
    for (j, joint) in skeleton.joints().iter().enumerate() {
        if joint.parent.is_none() {
            continue;
        }
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            for angle in angles {
                let mut pose = rest.clone();
                rotate(
                    &mut pose.local[j],
                    Quat::from_axis_angle(axis, angle.to_radians()),
                );
                poses.push(pose);
            }
        }
    }
    let movable: Vec<usize> = (0..skeleton.len())
        .filter(|&j| skeleton.joints()[j].parent.is_some())
        .collect();
    let mut rng = SplitMix64(seed);
    for _ in 0..random {
        let mut pose = rest.clone();
        if movable.is_empty() {
            poses.push(pose);
            continue;
        }
        for _ in 0..bent {
            let j = movable[(rng.next() % movable.len() as u64) as usize];
            let axis = loop {
                let v = Vec3::new(
                    rng.unit() * 2.0 - 1.0,
                    rng.unit() * 2.0 - 1.0,
                    rng.unit() * 2.0 - 1.0,
                );
                let len = v.length();
                if len > 1e-3 && len <= 1.0 {
                    break v / len;
                }
            };
            let angle = rng.unit() * 90f32.to_radians();
            rotate(&mut pose.local[j], Quat::from_axis_angle(axis, angle));
        }
        poses.push(pose);
    }
    poses
}

fn rotate(local: &mut Transform, delta: Quat) {
    local.rotation = (local.rotation * delta).normalize();
}

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny, well-mixed generator; enough for
/// repeatable pose sets without a dependency.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::row::simplex_qp;
    use super::*;

    fn inf(joint: u32, weight: f32) -> Influence {
        Influence { joint, weight }
    }

    /// A chain of `n` joints along +X (one unit apart); a vertex influenced by all of them.
    fn chain_poses(n: usize, poses: usize, seed: u64) -> Vec<Mat4> {
        let mut rng = SplitMix64(seed);
        let mut out = Vec::new();
        for _ in 0..poses {
            let mut world = Mat4::IDENTITY;
            for j in 0..n {
                let bind = Mat4::from_translation(Vec3::new(j as f32, 0.0, 0.0));
                let local = if j == 0 {
                    Mat4::IDENTITY
                } else {
                    let axis = Vec3::new(rng.unit(), rng.unit(), rng.unit()).normalize_or(Vec3::Z);
                    Mat4::from_translation(Vec3::X)
                        * Mat4::from_quat(Quat::from_axis_angle(axis, rng.unit()))
                };
                world *= local;
                out.push(world * bind.inverse());
            }
        }
        out
    }

    #[test]
    fn rows_with_k_or_fewer_influences_are_the_truncation() {
        let infl = Influences::from_rows([vec![inf(0, 0.25), inf(1, 0.75)]]);
        let r = RefitJob {
            positions: &[Vec3::new(0.5, 0.1, 0.0)],
            influences: &infl,
            pose_matrices: &chain_poses(2, 8, 1),
            palette_len: 2,
            max_influences: NonZeroUsize::new(4).expect("4 > 0"),
        }
        .run()
        .expect("valid");
        assert_eq!(r.influences.vertex(0), &[inf(1, 0.75), inf(0, 0.25)]);
        assert_eq!(r.changed, 0);
    }

    #[test]
    fn refit_sums_to_one_keeps_k_and_beats_truncation_on_the_fit_set() {
        let n = 8;
        let mats = chain_poses(n, 40, 7);
        let positions: Vec<Vec3> = (0..50)
            .map(|i| Vec3::new(i as f32 * 0.14, 0.2 * ((i % 5) as f32 - 2.0), 0.1))
            .collect();
        let rows: Vec<Vec<Influence>> = positions
            .iter()
            .map(|p| {
                let raw: Vec<f32> = (0..n)
                    .map(|j| (-((p.x - j as f32).powi(2)) / 2.0).exp())
                    .collect();
                let s: f32 = raw.iter().sum();
                raw.iter()
                    .enumerate()
                    .map(|(j, w)| inf(j as u32, w / s))
                    .collect()
            })
            .collect();
        let full = Influences::from_rows(rows.clone());
        let job = RefitJob {
            positions: &positions,
            influences: &full,
            pose_matrices: &mats,
            palette_len: n,
            max_influences: NonZeroUsize::new(2).expect("2 > 0"),
        };
        let refit = job.run().expect("valid");
        let truncated = Influences::from_rows(rows.iter().map(|r| truncate_row(r, 2)));
        for row in refit.influences.rows() {
            assert!(row.len() <= 2 && !row.is_empty());
            let s: f64 = row.iter().map(|i| f64::from(i.weight)).sum();
            assert!((s - 1.0).abs() < 1e-6, "sum {s}");
            assert!(row.iter().all(|i| i.weight >= 0.0));
        }
        let d_trunc = deviation(&positions, &full, &truncated, &mats, n).expect("valid");
        let d_refit = deviation(&positions, &full, &refit.influences, &mats, n).expect("valid");
        assert!(refit.changed > 0);
        assert!(
            d_refit.rms < 0.8 * d_trunc.rms,
            "{d_refit:?} vs {d_trunc:?}"
        );
        // Bind pose: all identity -> every convex row reproduces the point.
        let bind = vec![Mat4::IDENTITY; n];
        let d_bind = deviation(&positions, &full, &refit.influences, &bind, n).expect("valid");
        assert!(d_bind.max < 1e-6, "{d_bind:?}");
    }

    #[test]
    fn per_vertex_the_refit_is_never_worse_than_truncation_on_the_fit_poses() {
        // 6 and 12 influences: the exhaustive and the swap-search paths.
        for n in [6usize, 12] {
            let mats = chain_poses(n, 30, 11 + n as u64);
            let positions: Vec<Vec3> = (0..40)
                .map(|i| Vec3::new(i as f32 * 0.3 % n as f32, 0.1 * (i % 3) as f32, 0.05))
                .collect();
            let rows: Vec<Vec<Influence>> = positions
                .iter()
                .map(|p| {
                    let raw: Vec<f32> = (0..n)
                        .map(|j| 1.0 / (1.0 + (p.x - j as f32).abs()))
                        .collect();
                    let sum: f32 = raw.iter().sum();
                    (0..n).map(|j| inf(j as u32, raw[j] / sum)).collect()
                })
                .collect();
            let full = Influences::from_rows(rows.clone());
            let refit = RefitJob {
                positions: &positions,
                influences: &full,
                pose_matrices: &mats,
                palette_len: n,
                max_influences: NonZeroUsize::new(3).expect("3 > 0"),
            }
            .run()
            .expect("valid");
            for (v, p) in positions.iter().enumerate() {
                let one = |r: &[Influence]| Influences::from_rows([r.to_vec()]);
                let t = truncate_row(&rows[v], 3);
                let d_t = deviation(&[*p], &one(&rows[v]), &one(&t), &mats, n).expect("valid");
                let d_r = deviation(
                    &[*p],
                    &one(&rows[v]),
                    &one(refit.influences.vertex(v)),
                    &mats,
                    n,
                )
                .expect("valid");
                assert!(refit.influences.vertex(v).len() <= 3);
                assert!(
                    d_r.max <= d_t.max * (1.0 + 1e-5) + 1e-9,
                    "n {n} vertex {v}: {d_r:?} vs {d_t:?}"
                );
            }
            assert!(refit.changed > 0, "n {n}");
        }
    }

    #[test]
    fn simplex_qp_matches_brute_force_on_two_variables() {
        // min (c0 - 0.8)² + (c1 - 0.8)²·4 on the simplex: c1 = 1 - c0.
        let h = [1.0, 0.0, 0.0, 4.0];
        let f = [0.8, 3.2];
        let c = simplex_qp(&h, &f, &[true, true], &[0.5, 0.5], 2);
        // d/dc0 of (c0-.8)² + 4(.2-c0)² = 0 -> c0 = (0.8 + 0.8) / 5 = 0.32
        assert!(
            (c[0] - 0.32).abs() < 1e-12 && (c[1] - 0.68).abs() < 1e-12,
            "{c:?}"
        );
        // A bound: the unconstrained optimum is outside the simplex.
        let c = simplex_qp(
            &[1.0, 0.0, 0.0, 1.0],
            &[2.0, -1.0],
            &[true, true],
            &[0.5, 0.5],
            2,
        );
        assert_eq!(c, vec![1.0, 0.0]);
    }

    #[test]
    fn validate_names_the_problem() {
        let infl = Influences::from_rows([vec![inf(3, 1.0)]]);
        let job = RefitJob {
            positions: &[Vec3::ZERO],
            influences: &infl,
            pose_matrices: &[Mat4::IDENTITY; 2],
            palette_len: 2,
            max_influences: NonZeroUsize::new(4).expect("4 > 0"),
        };
        assert!(matches!(
            job.validate(),
            Err(EvalError::Index { index: 3, .. })
        ));
    }

    #[test]
    fn range_of_motion_is_seeded() {
        let skeleton = Skeleton::new(vec![
            rigport_model::Joint {
                name: "a".into(),
                parent: None,
                rest_local: Transform::IDENTITY,
            },
            rigport_model::Joint {
                name: "b".into(),
                parent: Some(rigport_model::JointIndex(0)),
                rest_local: Transform::IDENTITY,
            },
        ])
        .expect("valid");
        let a = range_of_motion(&skeleton, 5, 2, 1);
        assert_eq!(a.len(), 12 + 5);
        assert_eq!(a, range_of_motion(&skeleton, 5, 2, 1));
        assert_ne!(a, range_of_motion(&skeleton, 5, 2, 2));
    }
}
