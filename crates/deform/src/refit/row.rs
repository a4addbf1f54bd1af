//! Per-row arithmetic of the refit: truncation to the largest weights, and the small
//! quadratic program over the simplex (w >= 0, sum w = 1) that the refit solves per vertex.

use rigport_model::Influence;

/// Largest number of influences per vertex the refit solves for (Pinocchio rigs carry up to
/// 21 bones, CSCI 520 rigs up to 18 weights per vertex); rows with more are first cut to
/// the largest ones.
pub const MAX_CANDIDATES: usize = 24;

/// The largest `k` weights of a row (ties: lower joint first), renormalized in `f64`.
pub fn truncate_row(row: &[Influence], k: usize) -> Vec<Influence> {
    let mut sorted: Vec<Influence> = row.iter().copied().filter(|i| i.weight > 0.0).collect();
    sorted.sort_by(|a, b| b.weight.total_cmp(&a.weight).then(a.joint.cmp(&b.joint)));
    sorted.truncate(k);
    let sum: f64 = sorted.iter().map(|i| f64::from(i.weight)).sum();
    if sum > 0.0 {
        for i in &mut sorted {
            i.weight = (f64::from(i.weight) / sum) as f32;
        }
    }
    sorted
}

/// Minimises `cᵀ H c - 2 fᵀ c` over `{c >= 0, Σ c = 1, c_i = 0 where !allowed[i]}` from the
/// feasible point `start`, by a primal active-set method (Nocedal & Wright, "Numerical
/// Optimization", 2nd ed., algorithm 16.3). `H` is symmetric positive definite (n x n, row
/// major).
pub(super) fn simplex_qp(
    h: &[f64],
    f: &[f64],
    allowed: &[bool],
    start: &[f64],
    n: usize,
) -> Vec<f64> {
    const TOL: f64 = 1e-14;
    let mut c: Vec<f64> = (0..n)
        .map(|i| if allowed[i] { start[i].max(0.0) } else { 0.0 })
        .collect();
    let sum: f64 = c.iter().sum();
    if sum > 0.0 {
        c.iter_mut().for_each(|ci| *ci /= sum);
    } else if let Some(i) = (0..n).find(|&i| allowed[i]) {
        c[i] = 1.0;
    }
    let mut free: Vec<bool> = (0..n).map(|i| c[i] > 0.0).collect();
    let mut system = Vec::with_capacity((n + 1) * (n + 2));
    for _ in 0..(4 * n + 20) {
        let idx: Vec<usize> = (0..n).filter(|&i| free[i]).collect();
        let Some(star) = solve_equality(h, f, &idx, n, &mut system) else {
            break;
        };
        let mut full = vec![0.0; n];
        for (slot, &i) in idx.iter().enumerate() {
            full[i] = star.0[slot];
        }
        if idx.iter().all(|&i| full[i] >= 0.0) {
            c = full;
            // Multipliers of the variables held at zero: ν_i = 2((H c)_i - f_i + m).
            let m = star.1;
            let mut worst = None;
            let mut worst_nu = -TOL;
            for i in 0..n {
                if free[i] || !allowed[i] {
                    continue;
                }
                let hc: f64 = (0..n).map(|j| h[i * n + j] * c[j]).sum();
                let nu = hc - f[i] + m;
                if nu < worst_nu {
                    worst_nu = nu;
                    worst = Some(i);
                }
            }
            match worst {
                Some(i) => free[i] = true,
                None => break,
            }
        } else {
            // Step toward the equality solution until a weight reaches zero.
            let mut alpha = 1.0f64;
            let mut blocking = None;
            for &i in &idx {
                if full[i] < 0.0 && c[i] > full[i] {
                    let a = c[i] / (c[i] - full[i]);
                    if a < alpha {
                        alpha = a;
                        blocking = Some(i);
                    }
                }
            }
            for i in 0..n {
                c[i] += alpha * (full[i] - c[i]);
                if c[i] < 0.0 {
                    c[i] = 0.0;
                }
            }
            if let Some(b) = blocking {
                c[b] = 0.0;
                free[b] = false;
            }
            for i in 0..n {
                if free[i] && c[i] <= 0.0 {
                    free[i] = false;
                    c[i] = 0.0;
                }
            }
        }
    }
    let sum: f64 = c.iter().sum();
    if sum > 0.0 {
        c.iter_mut().for_each(|ci| *ci /= sum);
    }
    c
}

/// Solves `[H_FF 1; 1ᵀ 0] [c; m] = [f_F; 1]` for the free set `idx`; `None` if singular.
fn solve_equality(
    h: &[f64],
    f: &[f64],
    idx: &[usize],
    n: usize,
    a: &mut Vec<f64>,
) -> Option<(Vec<f64>, f64)> {
    let m = idx.len();
    if m == 0 {
        return None;
    }
    let size = m + 1;
    let cols = size + 1;
    a.clear();
    a.resize(size * cols, 0.0);
    for (r, &i) in idx.iter().enumerate() {
        for (s, &j) in idx.iter().enumerate() {
            a[r * cols + s] = h[i * n + j];
        }
        a[r * cols + m] = 1.0;
        a[r * cols + size] = f[i];
    }
    for s in 0..m {
        a[m * cols + s] = 1.0;
    }
    a[m * cols + size] = 1.0;
    // Gaussian elimination with partial pivoting.
    for col in 0..size {
        let pivot = (col..size)
            .max_by(|&x, &y| a[x * cols + col].abs().total_cmp(&a[y * cols + col].abs()))?;
        if a[pivot * cols + col].abs() < 1e-300 {
            return None;
        }
        if pivot != col {
            for k in 0..cols {
                a.swap(pivot * cols + k, col * cols + k);
            }
        }
        let p = a[col * cols + col];
        for row in (col + 1)..size {
            let factor = a[row * cols + col] / p;
            if factor != 0.0 {
                for k in col..cols {
                    a[row * cols + k] -= factor * a[col * cols + k];
                }
            }
        }
    }
    let mut x = vec![0.0; size];
    for row in (0..size).rev() {
        let mut s = a[row * cols + size];
        for k in (row + 1)..size {
            s -= a[row * cols + k] * x[k];
        }
        x[row] = s / a[row * cols + row];
    }
    if x.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mult = x[m];
    x.truncate(m);
    Some((x, mult))
}
