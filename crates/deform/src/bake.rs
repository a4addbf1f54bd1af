//! Baking dual quaternion skinning into corrective morph targets for LBS viewers.
//!
//! glTF 2.0 defines only linear blend skinning, and applies morph targets *before*
//! skinning (glTF 2.0 §3.7.2.2 and §3.7.3). For a vertex with bind-space position `p_rest`
//! whose blended LBS matrix at a frame is `M = Σ wᵢ Sᵢ`, the bind-space displacement
//! `d = M⁻¹ · p_dqs − p_rest` makes the viewer's LBS of `p_rest + d` land exactly on the DQS
//! position `p_dqs` (FORMATS.md, "glTF 2.0 skins and animation"). [`CorrectiveDeltasJob`]
//! computes these displacements for a block of frames; [`compress_correctives`] replaces
//! the one-target-per-frame set by a few shared targets with per-frame weights.

pub mod asset;

use glam::{DMat3, DMat4, DVec3, Mat4, Vec3};
use rigport_model::Influences;

use rigport_eval::dqs::{DqsJob, DqsPalette};
use rigport_eval::EvalError;

/// Default for [`CorrectiveDeltasJob::min_relative_scale`].
///
/// The blended matrix's 3x3 part `A` is judged by `r = 1 / (‖A⁻¹‖_F/√3 · s)` with
/// `s = Σ |wᵢ| ‖Aᵢ‖_F/√3` (1 for rigid joints): `r` is 1 for a rotation and about the smallest
/// singular value of `A` relative to the joints' scale otherwise (the candy-wrapper twist by
/// θ gives `cos(θ/2)`). A viewer blends `A` in `f32` with absolute rounding `~6e-8 · s`
/// and applies it to `p_rest + d`, whose size grows as `1/r`; at `r = 1e-2` that costs
/// about `6e-6` of the point's distance to its joints, well inside the `1e-4` of the
/// bounding-box diagonal the bake is tested against.
pub const DEFAULT_MIN_RELATIVE_SCALE: f32 = 1e-2;

/// Per-frame counts written by [`CorrectiveDeltasJob`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameBakeStats {
    /// Vertices whose correction exceeds the threshold (non-zero in the output).
    pub corrected: u32,
    /// Vertices whose blended LBS matrix is near-singular: their correction is left 0.
    pub singular: u32,
}

/// Computes, for `F` frames, each vertex's DQS position and its bind-space corrective
/// displacement for a linear blend skinning viewer.
///
/// All buffers are caller-owned; `run()` allocates nothing. With `J` skinning matrices per
/// frame and `V` vertices, `F = frame_skin_matrices.len() / J`.
pub struct CorrectiveDeltasJob<'a> {
    /// Influences per vertex, exactly the ones the viewer uses (e.g. a glTF exporter's
    /// limited and renormalized set); joint values index a frame's palette.
    pub influences: &'a Influences,
    /// Bind-space positions, `V`.
    pub rest_positions: &'a [Vec3],
    /// Palette size `J` (> 0).
    pub joints: usize,
    /// `F x J` skinning matrices (model-from-bind), frame-major.
    pub frame_skin_matrices: &'a [Mat4],
    /// Displacements with length at most this (bind-space units) are written as 0 and not
    /// counted as corrected.
    pub threshold: f32,
    /// Relative scale below which a blended matrix counts as near-singular (see
    /// [`DEFAULT_MIN_RELATIVE_SCALE`]).
    pub min_relative_scale: f32,
    /// Output: `F x V` DQS model-space positions, frame-major.
    pub out_dqs_positions: &'a mut [Vec3],
    /// Output: `F x V` bind-space displacements, frame-major.
    pub out_deltas: &'a mut [Vec3],
    /// Output: `F` per-frame counts.
    pub out_stats: &'a mut [FrameBakeStats],
    /// Scratch with room for `J` joints and at least one frame.
    pub palette: &'a mut DqsPalette,
}

impl CorrectiveDeltasJob<'_> {
    /// Checks the buffer sizes against each other and the palette's capacity (influence
    /// indices are checked per frame by the DQS job).
    ///
    /// # Errors
    /// [`EvalError::Length`] when sizes disagree.
    pub fn validate(&self) -> Result<usize, EvalError> {
        let v = self.rest_positions.len();
        if self.joints == 0 || self.frame_skin_matrices.len() % self.joints != 0 {
            return Err(EvalError::Length {
                what: "frame skin matrices",
                expected: self.joints.max(1),
                found: self.frame_skin_matrices.len(),
            });
        }
        let frames = self.frame_skin_matrices.len() / self.joints;
        let checks = [
            ("influences", v, self.influences.vertex_count()),
            (
                "out_dqs_positions",
                frames * v,
                self.out_dqs_positions.len(),
            ),
            ("out_deltas", frames * v, self.out_deltas.len()),
            ("out_stats", frames, self.out_stats.len()),
        ];
        for (what, expected, found) in checks {
            if expected != found {
                return Err(EvalError::Length {
                    what,
                    expected,
                    found,
                });
            }
        }
        if self.palette.joint_capacity() < self.joints || self.palette.frame_capacity() < 1 {
            return Err(EvalError::Length {
                what: "DqsPalette joints",
                expected: self.joints,
                found: self.palette.joint_capacity(),
            });
        }
        Ok(frames)
    }

    /// Runs the job on the calling thread. Allocates nothing.
    ///
    /// # Errors
    /// As [`CorrectiveDeltasJob::validate`], which it calls first, and
    /// [`EvalError::Index`] for an influence outside the palette.
    pub fn run(&mut self) -> Result<(), EvalError> {
        let frames = self.validate()?;
        let v = self.rest_positions.len();
        let j = self.joints;
        for f in 0..frames {
            let mats = &self.frame_skin_matrices[f * j..(f + 1) * j];
            let dqs = &mut self.out_dqs_positions[f * v..(f + 1) * v];
            DqsJob {
                skin_matrices: mats,
                influences: self.influences,
                rest_positions: self.rest_positions,
                rest_normals: None,
                out_positions: dqs,
                out_normals: None,
                palette: self.palette,
            }
            .run()?;
            let deltas = &mut self.out_deltas[f * v..(f + 1) * v];
            let mut stats = FrameBakeStats::default();
            for (((d, p_dqs), p_rest), row) in deltas
                .iter_mut()
                .zip(dqs.iter())
                .zip(self.rest_positions)
                .zip(self.influences.rows())
            {
                *d = Vec3::ZERO;
                // Blend in f64: the inverse amplifies the blend's rounding.
                let mut m = DMat4::ZERO;
                // Σ |wᵢ| |Aᵢ|_F / √3: 1 for rigid joints with weights summing to 1.
                let mut joint_scale = 0.0f64;
                let mut any = false;
                for inf in row {
                    // Indices were checked by the DQS job above.
                    if let Some(s) = mats.get(inf.joint as usize) {
                        let s = s.as_dmat4();
                        let w = f64::from(inf.weight);
                        m += s * w;
                        joint_scale += w.abs() * frobenius(DMat3::from_mat4(s));
                        any |= inf.weight != 0.0;
                    }
                }
                if !any {
                    // Both skinnings keep such a vertex where it is (see the dqs module).
                    continue;
                }
                let a = DMat3::from_mat4(m);
                let det = a.determinant();
                let inv = a.inverse();
                // 1 / (|A⁻¹|_F/√3 · scale) estimates of σ_min(A) / scale (1 when rigid).
                let ratio = 1.0 / (frobenius(inv) * joint_scale);
                if !(det != 0.0 && ratio.is_finite() && ratio >= f64::from(self.min_relative_scale))
                {
                    stats.singular += 1;
                    continue;
                }
                let bind = inv * (p_dqs.as_dvec3() - m.w_axis.truncate());
                let delta = (bind - p_rest.as_dvec3()).as_vec3();
                if delta.is_finite() && delta.length() > self.threshold {
                    *d = delta;
                    stats.corrected += 1;
                }
            }
            if let Some(s) = self.out_stats.get_mut(f) {
                *s = stats;
            }
        }
        Ok(())
    }
}

/// `K` shared corrective targets with per-frame weights, from [`compress_correctives`].
#[derive(Clone, Debug, PartialEq)]
pub struct Correctives {
    /// `K` targets of `V` bind-space displacements each.
    pub targets: Vec<Vec<Vec3>>,
    /// `F x K` weights, frame-major: frame `f`'s displacement is approximately
    /// `Σ_k weights[f * K + k] * targets[k]`.
    pub frame_weights: Vec<f32>,
    /// The largest bind-space distance between a frame's displacement and its
    /// approximation, over every frame and vertex.
    pub max_error: f32,
}

/// Compresses `F` per-frame displacement sets (`deltas`: `F x V`, frame-major) to at most
/// `k` shared targets: the truncated singular value decomposition of the `F x 3V` matrix
/// `D` (uncentred PCA, the best rank-`k` approximation in the Frobenius norm, Eckart–Young).
///
/// The decomposition goes through the `F x F` Gram matrix `G = D Dᵀ = U Σ² Uᵀ` (cyclic
/// Jacobi eigen-decomposition in `f64`): target `k` is `Dᵀ uₖ` and frame `f`'s weight on it
/// is `U[f][k]`, so `Σ_k U[f][k] Dᵀ uₖ = (U_K U_Kᵀ D)_f`. Fewer than `k` targets come back
/// when `D` has lower rank (eigenvalues below `1e-12` of the largest are dropped).
///
/// # Errors
/// [`EvalError::Length`] if `deltas.len()` is not a multiple of `frames`, or `frames` is 0.
pub fn compress_correctives(
    deltas: &[Vec3],
    frames: usize,
    k: usize,
) -> Result<Correctives, EvalError> {
    if frames == 0 || deltas.len() % frames != 0 {
        return Err(EvalError::Length {
            what: "corrective deltas",
            expected: frames.max(1),
            found: deltas.len(),
        });
    }
    let v = deltas.len() / frames;
    let frame = |f: usize| deltas.get(f * v..(f + 1) * v).unwrap_or(&[]);
    let mut gram = vec![0.0f64; frames * frames];
    for a in 0..frames {
        for b in a..frames {
            let dot: f64 = frame(a)
                .iter()
                .zip(frame(b))
                .map(|(x, y)| x.as_dvec3().dot(y.as_dvec3()))
                .sum();
            gram[a * frames + b] = dot;
            gram[b * frames + a] = dot;
        }
    }
    let (values, vectors) = jacobi_eigen(&mut gram, frames);
    let mut order: Vec<usize> = (0..frames).collect();
    order.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
    let largest = order.first().map_or(0.0, |&i| values[i]).max(0.0);
    let kept: Vec<usize> = order
        .into_iter()
        .take(k)
        .filter(|&i| largest > 0.0 && values[i] > 1e-12 * largest)
        .collect();
    // vectors is column-major: vectors[f * frames + i] is component f of eigenvector i.
    let u = |f: usize, i: usize| vectors[f * frames + i];
    let targets: Vec<Vec<Vec3>> = kept
        .iter()
        .map(|&i| {
            let mut t = vec![DVec3::ZERO; v];
            for f in 0..frames {
                let w = u(f, i);
                for (acc, d) in t.iter_mut().zip(frame(f)) {
                    *acc += d.as_dvec3() * w;
                }
            }
            t.iter().map(|x| x.as_vec3()).collect()
        })
        .collect();
    let frame_weights: Vec<f32> = (0..frames)
        .flat_map(|f| kept.iter().map(move |&i| u(f, i) as f32))
        .collect();
    let kk = kept.len();
    let mut max_error = 0.0f32;
    for f in 0..frames {
        let w = frame_weights.get(f * kk..(f + 1) * kk).unwrap_or(&[]);
        for (vi, d) in frame(f).iter().enumerate() {
            let approx: Vec3 = targets
                .iter()
                .zip(w)
                .map(|(t, &wk)| t.get(vi).copied().unwrap_or(Vec3::ZERO) * wk)
                .sum();
            max_error = max_error.max((approx - *d).length());
        }
    }
    Ok(Correctives {
        targets,
        frame_weights,
        max_error,
    })
}

/// Frobenius norm divided by √3 (1 for a rotation).
fn frobenius(a: DMat3) -> f64 {
    ((a.x_axis.length_squared() + a.y_axis.length_squared() + a.z_axis.length_squared()) / 3.0)
        .sqrt()
}

/// Eigen-decomposition of the symmetric `n x n` matrix `a` (row-major, destroyed) by cyclic
/// Jacobi rotations (Golub & Van Loan, "Matrix Computations", §8.5): returns the
/// eigenvalues and the eigenvectors as the columns of a row-major `n x n` matrix.
fn jacobi_eigen(a: &mut [f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut vec = vec![0.0; n * n];
    for i in 0..n {
        vec[i * n + i] = 1.0;
    }
    let norm: f64 = a.iter().map(|x| x * x).sum::<f64>().sqrt();
    for _sweep in 0..64 {
        let off: f64 = (0..n)
            .flat_map(|p| (0..n).filter(move |&q| q != p).map(move |q| (p, q)))
            .map(|(p, q)| a[p * n + q] * a[p * n + q])
            .sum::<f64>()
            .sqrt();
        if off <= 1e-15 * norm || norm == 0.0 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq == 0.0 {
                    continue;
                }
                let (app, aqq) = (a[p * n + p], a[q * n + q]);
                // The rotation angle that zeroes a[p][q] (G&VL Algorithm 8.5.1).
                let tau = (aqq - app) / (2.0 * apq);
                let t = tau.signum() / (tau.abs() + (1.0 + tau * tau).sqrt());
                let t = if tau == 0.0 { 1.0 } else { t };
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = t * c;
                for r in 0..n {
                    let (arp, arq) = (a[r * n + p], a[r * n + q]);
                    a[r * n + p] = c * arp - s * arq;
                    a[r * n + q] = s * arp + c * arq;
                }
                for r in 0..n {
                    let (apr, aqr) = (a[p * n + r], a[q * n + r]);
                    a[p * n + r] = c * apr - s * aqr;
                    a[q * n + r] = s * apr + c * aqr;
                }
                for r in 0..n {
                    let (vrp, vrq) = (vec[r * n + p], vec[r * n + q]);
                    vec[r * n + p] = c * vrp - s * vrq;
                    vec[r * n + q] = s * vrp + c * vrq;
                }
            }
        }
    }
    let values = (0..n).map(|i| a[i * n + i]).collect();
    (values, vec)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3Swizzles};
    use rigport_model::Influence;

    fn two_joint_frames(angles: &[f32]) -> Vec<Mat4> {
        angles
            .iter()
            .flat_map(|&a| {
                [
                    Mat4::IDENTITY,
                    Mat4::from_translation(Vec3::X)
                        * Mat4::from_quat(Quat::from_rotation_x(a))
                        * Mat4::from_translation(-Vec3::X),
                ]
            })
            .collect()
    }

    fn ring() -> (Vec<Vec3>, Influences) {
        let rest: Vec<Vec3> = (0..8)
            .map(|i| {
                let a = i as f32 * std::f32::consts::TAU / 8.0;
                Vec3::new(1.0, 0.25 * a.cos(), 0.25 * a.sin())
            })
            .collect();
        let infl = Influences::from_rows(rest.iter().map(|_| {
            [
                Influence {
                    joint: 0,
                    weight: 0.5,
                },
                Influence {
                    joint: 1,
                    weight: 0.5,
                },
            ]
        }));
        (rest, infl)
    }

    #[test]
    fn lbs_of_corrected_rest_lands_on_dqs_and_flat_blends_fall_back() {
        let (rest, infl) = ring();
        let angles = [0.0, 1.0, 2.5, std::f32::consts::PI];
        let mats = two_joint_frames(&angles);
        let (f, v) = (angles.len(), rest.len());
        let mut dqs = vec![Vec3::ZERO; f * v];
        let mut deltas = vec![Vec3::ZERO; f * v];
        let mut stats = vec![FrameBakeStats::default(); f];
        CorrectiveDeltasJob {
            influences: &infl,
            rest_positions: &rest,
            joints: 2,
            frame_skin_matrices: &mats,
            threshold: 1e-6,
            min_relative_scale: DEFAULT_MIN_RELATIVE_SCALE,
            out_dqs_positions: &mut dqs,
            out_deltas: &mut deltas,
            out_stats: &mut stats,
            palette: &mut DqsPalette::new(2, 1),
        }
        .run()
        .unwrap();
        assert_eq!(
            stats[0],
            FrameBakeStats::default(),
            "rest needs no correction"
        );
        assert_eq!(stats[1].corrected, 8);
        // A 180° twist blends the two joints into a flat matrix: every vertex falls back.
        assert_eq!(stats[3].singular, 8);
        for fi in 0..3 {
            for vi in 0..v {
                let m = (mats[2 * fi] + mats[2 * fi + 1]) * 0.5;
                let viewer = m.transform_point3(rest[vi] + deltas[fi * v + vi]);
                let err = (viewer - dqs[fi * v + vi]).length();
                assert!(err < 1e-5, "frame {fi} vertex {vi}: {err}");
                // DQS keeps the ring's radius.
                let r = dqs[fi * v + vi].yz().length();
                assert!((r - 0.25).abs() < 1e-5, "{r}");
            }
        }
    }

    #[test]
    fn rejects_mismatched_sizes() {
        let (rest, infl) = ring();
        let mats = two_joint_frames(&[0.0, 1.0]);
        let mut dqs = vec![Vec3::ZERO; 8];
        let mut deltas = vec![Vec3::ZERO; 16];
        let mut stats = vec![FrameBakeStats::default(); 2];
        let err = CorrectiveDeltasJob {
            influences: &infl,
            rest_positions: &rest,
            joints: 2,
            frame_skin_matrices: &mats,
            threshold: 0.0,
            min_relative_scale: DEFAULT_MIN_RELATIVE_SCALE,
            out_dqs_positions: &mut dqs,
            out_deltas: &mut deltas,
            out_stats: &mut stats,
            palette: &mut DqsPalette::new(2, 1),
        }
        .run();
        assert_eq!(
            err,
            Err(EvalError::Length {
                what: "out_dqs_positions",
                expected: 16,
                found: 8
            })
        );
    }

    #[test]
    fn compression_is_exact_at_full_rank_and_bounded_below_it() {
        // Frames 2 and 3 are combinations of frames 0 and 1: rank 2.
        let a: Vec<Vec3> = (0..5).map(|i| Vec3::new(i as f32, 1.0, -0.5)).collect();
        let b: Vec<Vec3> = (0..5)
            .map(|i| Vec3::new(0.0, (i * i) as f32, 2.0))
            .collect();
        let mut deltas = Vec::new();
        for (wa, wb) in [(1.0, 0.0), (0.0, 1.0), (0.5, 0.5), (2.0, -1.0)] {
            deltas.extend(a.iter().zip(&b).map(|(x, y)| *x * wa + *y * wb));
        }
        let full = compress_correctives(&deltas, 4, 4).unwrap();
        assert_eq!(full.targets.len(), 2, "rank 2");
        assert!(full.max_error < 1e-4, "{}", full.max_error);
        let one = compress_correctives(&deltas, 4, 1).unwrap();
        assert_eq!(one.targets.len(), 1);
        assert_eq!(one.frame_weights.len(), 4);
        assert!(one.max_error > 1e-2, "rank 1 cannot hold rank 2 data");
        assert!(compress_correctives(&deltas, 3, 1).is_err());
    }

    #[test]
    fn jacobi_diagonalizes() {
        let mut a = vec![4.0, 1.0, 2.0, 1.0, 3.0, 0.5, 2.0, 0.5, 1.0];
        let orig = a.clone();
        let (vals, vecs) = jacobi_eigen(&mut a, 3);
        for i in 0..3 {
            for r in 0..3 {
                let av: f64 = (0..3).map(|c| orig[r * 3 + c] * vecs[c * 3 + i]).sum();
                assert!((av - vals[i] * vecs[r * 3 + i]).abs() < 1e-12);
            }
        }
    }
}
