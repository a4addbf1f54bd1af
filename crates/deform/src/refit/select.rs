//! One vertex's refit: which K of its influences to keep, and their weights.
//!
//! The weights on a given support come from the simplex-constrained least squares of the
//! module docs. The support is chosen by that fitted error: every K-subset of the
//! candidates when there are at most [`EXHAUSTIVE_MAX`] of them (C(10, 4) = 210 small
//! problems), otherwise a swap search (exchange one kept influence for one dropped one
//! while the error falls) from two starts, the truncation's support and the K largest
//! weights of the unconstrained-support fit. Backward elimination alone (dropping the
//! smallest fitted weight until K remain) was measured to keep the truncation's row on the
//! worst vertices of human_model1, where another support lowers the held-out maximum by
//! half (BENCHMARKS.md).
//!
//! The result is kept only when its largest deviation over the fit poses is no larger than
//! the truncation's, and its squared error too: per vertex, the refit is never worse than
//! truncation on the poses it was fitted to, by either measure.

use glam::{DMat4, DVec3};
use rigport_model::Influence;

use super::row::{simplex_qp, truncate_row, MAX_CANDIDATES};

/// Vertices with at most this many influences try every K-subset of them.
pub const EXHAUSTIVE_MAX: usize = 10;
/// Most improving passes of the swap search (each pass tries every single exchange).
const SWAP_PASSES: usize = 16;
/// Reweighting rounds of the minimax refinement.
const MINIMAX_ROUNDS: usize = 16;

/// The per-vertex least-squares problem over the candidates: `cᵀ H c - 2 fᵀ c`.
struct Problem {
    /// `H + ε I`, n x n row major.
    h: Vec<f64>,
    /// `ε t`.
    f: Vec<f64>,
    n: usize,
}

impl Problem {
    fn objective(&self, c: &[f64]) -> f64 {
        let n = self.n;
        let mut e = 0.0;
        for i in 0..n {
            if c[i] == 0.0 {
                continue;
            }
            let hc: f64 = (0..n).map(|j| self.h[i * n + j] * c[j]).sum();
            e += c[i] * (hc - 2.0 * self.f[i]);
        }
        e
    }

    /// The best weights with support inside `support`.
    fn solve(&self, support: &[usize]) -> (f64, Vec<f64>) {
        let n = self.n;
        let mut allowed = vec![false; n];
        let mut start = vec![0.0; n];
        for &i in support {
            allowed[i] = true;
            start[i] = 1.0 / support.len() as f64;
        }
        let c = simplex_qp(&self.h, &self.f, &allowed, &start, n);
        (self.objective(&c), c)
    }
}

/// Refits one row; returns it and whether it differs from the truncation.
pub(super) fn refit_row(
    x: DVec3,
    row: &[Influence],
    poses: &[DMat4],
    palette_len: usize,
    k: usize,
) -> (Vec<Influence>, bool) {
    let truncated = truncate_row(row, k);
    let mut cand: Vec<Influence> = row.iter().copied().filter(|i| i.weight > 0.0).collect();
    if cand.len() <= k {
        return (truncated, false);
    }
    // The truncation's order: its support is the first k candidates.
    cand.sort_by(|a, b| b.weight.total_cmp(&a.weight).then(a.joint.cmp(&b.joint)));
    cand.truncate(MAX_CANDIDATES);
    let n = cand.len();
    let total: f64 = cand.iter().map(|i| f64::from(i.weight)).sum();
    let w: Vec<f64> = cand.iter().map(|i| f64::from(i.weight) / total).collect();
    // D_p's columns a_pi - y_p, pose after pose, and H = Σ_p D_pᵀ D_p.
    let pose_count = poses.len() / palette_len;
    let mut d = vec![DVec3::ZERO; pose_count * n];
    let mut h = vec![0.0f64; n * n];
    for (pose, dp) in poses.chunks_exact(palette_len).zip(d.chunks_exact_mut(n)) {
        let mut y = DVec3::ZERO;
        for (i, inf) in cand.iter().enumerate() {
            dp[i] = pose[inf.joint as usize].transform_point3(x);
            y += w[i] * dp[i];
        }
        for di in dp.iter_mut() {
            *di -= y;
        }
        for i in 0..n {
            for j in i..n {
                h[i * n + j] += dp[i].dot(dp[j]);
            }
        }
    }
    for i in 0..n {
        for j in 0..i {
            h[i * n + j] = h[j * n + i];
        }
    }
    let trace: f64 = (0..n).map(|i| h[i * n + i]).sum();
    if !trace.is_finite() || trace <= 0.0 {
        return (truncated, false); // no pose separates the influences
    }
    // The truncation as a point of the simplex over the candidates.
    let mut t = vec![0.0; n];
    for ti in &truncated {
        if let Some(i) = cand.iter().position(|c| c.joint == ti.joint) {
            t[i] = f64::from(ti.weight);
        }
    }
    let eps = 1e-9 * trace / n as f64;
    for i in 0..n {
        h[i * n + i] += eps;
    }
    let problem = Problem {
        f: t.iter().map(|ti| eps * ti).collect(),
        h,
        n,
    };
    let (_, c) = if n <= EXHAUSTIVE_MAX {
        exhaustive(&problem, k)
    } else {
        swap_search(&problem, k, &t)
    };
    let max_dev = |c: &[f64]| -> f64 {
        d.chunks_exact(n)
            .map(|dp| {
                dp.iter()
                    .zip(c)
                    .map(|(di, ci)| *di * *ci)
                    .sum::<DVec3>()
                    .length_squared()
            })
            .fold(0.0, f64::max)
    };
    // Lean toward the largest deviation: a minimax refinement of the chosen support and of
    // the truncation's; the candidate with the smallest largest deviation on the fit poses
    // wins, among those whose squared error is no larger than the truncation's.
    let t_obj = problem.objective(&t);
    let t_support: Vec<usize> = (0..k).collect();
    let c_support: Vec<usize> = (0..n).filter(|&i| c[i] > 0.0).collect();
    let mut best: Option<(f64, Vec<f64>)> = None;
    for trial in [
        Some(c.clone()),
        Some(minimax(&d, n, &c_support, &c)),
        Some(minimax(&d, n, &t_support, &t)),
    ]
    .into_iter()
    .flatten()
    {
        if problem.objective(&trial) > t_obj {
            continue;
        }
        let m = max_dev(&trial);
        if best.as_ref().is_none_or(|b| m < b.0) {
            best = Some((m, trial));
        }
    }
    let Some((best_max, c)) = best else {
        return (truncated, false);
    };
    if best_max >= max_dev(&t) {
        return (truncated, false);
    }
    let mut out: Vec<Influence> = (0..n)
        .filter(|&i| c[i] > 0.0)
        .map(|i| Influence {
            joint: cand[i].joint,
            weight: c[i] as f32,
        })
        .collect();
    out.sort_by(|a, b| b.weight.total_cmp(&a.weight).then(a.joint.cmp(&b.joint)));
    let changed = out != truncated;
    (out, changed)
}

/// Lawson's algorithm (Lawson 1961; Rice & Usow 1968): weighted least squares on a fixed
/// support, each pose's weight multiplied by its deviation and renormalized, which moves
/// the fit toward the smallest largest deviation over the poses. Returns the iterate with
/// the smallest largest deviation (starting with `start`).
fn minimax(d: &[DVec3], n: usize, support: &[usize], start: &[f64]) -> Vec<f64> {
    let pose_count = d.len() / n.max(1);
    let mut allowed = vec![false; n];
    for &i in support {
        allowed[i] = true;
    }
    let deviations = |c: &[f64]| -> Vec<f64> {
        d.chunks_exact(n)
            .map(|dp| {
                support
                    .iter()
                    .map(|&i| dp[i] * c[i])
                    .sum::<DVec3>()
                    .length()
            })
            .collect()
    };
    let mut best_c = start.to_vec();
    let mut e = deviations(&best_c);
    let mut best_max = e.iter().copied().fold(0.0, f64::max);
    let mut r = vec![1.0 / pose_count.max(1) as f64; pose_count];
    let mut h = vec![0.0; n * n];
    let zero = vec![0.0; n];
    for _ in 0..MINIMAX_ROUNDS {
        let s: f64 = r.iter().zip(&e).map(|(r, e)| r * e).sum();
        if s.is_nan() || s <= 0.0 {
            break;
        }
        for (rp, ep) in r.iter_mut().zip(&e) {
            *rp *= ep / s;
        }
        h.iter_mut().for_each(|x| *x = 0.0);
        for (dp, rp) in d.chunks_exact(n).zip(&r) {
            for &i in support {
                for &j in support {
                    h[i * n + j] += rp * dp[i].dot(dp[j]);
                }
            }
        }
        let trace: f64 = support.iter().map(|&i| h[i * n + i]).sum();
        if !trace.is_finite() || trace <= 0.0 {
            break;
        }
        for &i in support {
            h[i * n + i] += 1e-12 * trace;
        }
        let c = simplex_qp(&h, &zero, &allowed, &best_c, n);
        e = deviations(&c);
        let m = e.iter().copied().fold(0.0, f64::max);
        if m < best_max {
            best_max = m;
            best_c = c;
        }
    }
    best_c
}

/// The best of every `k`-subset of the candidates.
fn exhaustive(problem: &Problem, k: usize) -> (f64, Vec<f64>) {
    let n = problem.n;
    let mut idx: Vec<usize> = (0..k).collect();
    let mut best = problem.solve(&idx);
    // Next combination in lexicographic order.
    while let Some(pos) = (0..k).rev().find(|&p| idx[p] < n - k + p) {
        idx[pos] += 1;
        for q in pos + 1..k {
            idx[q] = idx[q - 1] + 1;
        }
        let s = problem.solve(&idx);
        if s.0 < best.0 {
            best = s;
        }
    }
    best
}

/// Swap search from the truncation's support and from the largest weights of the fit over
/// all candidates; the better end point.
fn swap_search(problem: &Problem, k: usize, t: &[f64]) -> (f64, Vec<f64>) {
    let n = problem.n;
    let all = simplex_qp(&problem.h, &problem.f, &vec![true; n], t, n);
    let mut by_fit: Vec<usize> = (0..n).collect();
    by_fit.sort_by(|&a, &b| all[b].total_cmp(&all[a]).then(a.cmp(&b)));
    by_fit.truncate(k);
    by_fit.sort_unstable();
    let starts = [(0..k).collect::<Vec<usize>>(), by_fit];
    let mut best: Option<(f64, Vec<f64>)> = None;
    for (s, start) in starts.iter().enumerate() {
        if s == 1 && starts[0] == starts[1] {
            break;
        }
        let mut support = start.clone();
        let mut current = problem.solve(&support);
        for _ in 0..SWAP_PASSES {
            let mut improved = false;
            for slot in 0..k {
                for out in 0..n {
                    if support.contains(&out) {
                        continue;
                    }
                    let kept = support[slot];
                    support[slot] = out;
                    let trial = problem.solve(&support);
                    if trial.0 < current.0 * (1.0 - 1e-12) {
                        current = trial;
                        improved = true;
                    } else {
                        support[slot] = kept;
                    }
                }
            }
            if !improved {
                break;
            }
        }
        if best.as_ref().is_none_or(|b| current.0 < b.0) {
            best = Some(current);
        }
    }
    best.unwrap_or_else(|| problem.solve(&(0..k).collect::<Vec<_>>()))
}
