//! Small dense linear algebra for the IK solvers, in `f64`, on caller-owned row-major
//! buffers: a guarded Cholesky solve, a one-sided Jacobi SVD step and Horn's best-fit
//! rotation. Nothing here allocates.

use glam::{DQuat, Quat, Vec3};

/// Solves `a x = b` for a symmetric positive (semi-)definite `k x k` matrix `a` (row-major,
/// only the lower triangle is read; overwritten by its Cholesky factor), `b` overwritten by
/// `x`.
///
/// A pivot below `1e-12` of the largest diagonal entry (a singular or nearly singular
/// system, e.g. `lambda = 0` at a singular pose) is replaced by that floor, which damps the
/// direction instead of dividing by zero: the result is always finite for finite input.
pub(crate) fn cholesky_solve(a: &mut [f64], k: usize, b: &mut [f64]) {
    let max_diag = (0..k).fold(0.0_f64, |m, i| m.max(a[i * k + i].abs()));
    let floor = (max_diag * 1e-12).max(f64::MIN_POSITIVE);
    for j in 0..k {
        let (done, rest) = a.split_at_mut(j * k + k);
        let row_j = &mut done[j * k..j * k + k];
        let d = (row_j[j] - dot(&row_j[..j], &row_j[..j])).max(floor).sqrt();
        row_j[j] = d;
        let inv_d = 1.0 / d;
        let row_j = &row_j[..j];
        for row_i in rest.chunks_exact_mut(k) {
            row_i[j] = (row_i[j] - dot(&row_i[..j], row_j)) * inv_d;
        }
    }
    // L y = b, then L^T x = y.
    for i in 0..k {
        let row = &a[i * k..i * k + k];
        b[i] = (b[i] - dot(&row[..i], &b[..i])) / row[i];
    }
    for i in (0..k).rev() {
        let mut s = b[i];
        for p in i + 1..k {
            s -= a[p * k + i] * b[p];
        }
        b[i] = s / a[i * k + i];
    }
}

/// `x · y` over the shorter length, with four partial sums (shorter dependency chains).
#[inline]
pub(crate) fn dot(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().min(y.len());
    let (x, y) = (&x[..n], &y[..n]);
    let mut acc = [0.0_f64; 4];
    let (xc, yc) = (x.chunks_exact(4), y.chunks_exact(4));
    let (xr, yr) = (xc.remainder(), yc.remainder());
    for (a, b) in xc.zip(yc) {
        acc[0] += a[0] * b[0];
        acc[1] += a[1] * b[1];
        acc[2] += a[2] * b[2];
        acc[3] += a[3] * b[3];
    }
    let tail: f64 = xr.iter().zip(yr).map(|(a, b)| a * b).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// Most sweeps of [`pinv_solve`]'s Jacobi iteration; it converges quadratically, in 5 to 10
/// sweeps for the matrices IK builds (Demmel & Veselić 1992).
const MAX_SVD_SWEEPS: usize = 40;

/// `out = J⁺ e` with the pseudo-inverse from an SVD of the `m x n` row-major `jac`
/// (overwritten), singular values below `cutoff_rel · σ_max` treated as zero.
///
/// One-sided Jacobi (Hestenes 1958): plane rotations `G` applied to the rows of `J` until
/// they are mutually orthogonal, so `G J = B` with rows `b_i = σ_i v_iᵀ` and `J = Gᵀ B`.
/// Then `J⁺ e = Σ_i b_i (g_i · e) / σ_i²` over the kept `σ_i`. Unlike an eigen-decomposition
/// of `J Jᵀ` this never squares the condition number. `work` holds `m · m + m` values (`G`,
/// then the `σ_i²`), `out` `n`.
pub(crate) fn pinv_solve(
    jac: &mut [f64],
    (m, n): (usize, usize),
    e: &[f64],
    cutoff_rel: f64,
    work: &mut [f64],
    out: &mut [f64],
) {
    let (g, sigma2) = work.split_at_mut(m * m);
    g[..m * m].fill(0.0);
    for i in 0..m {
        g[i * m + i] = 1.0;
    }
    for _ in 0..MAX_SVD_SWEEPS {
        let mut rotated = false;
        for i in 0..m {
            for k in i + 1..m {
                let (mut alpha, mut beta, mut gamma) = (0.0, 0.0, 0.0);
                for c in 0..n {
                    let (x, y) = (jac[i * n + c], jac[k * n + c]);
                    alpha += x * x;
                    beta += y * y;
                    gamma += x * y;
                }
                // Rows already orthogonal to working precision: no rotation.
                if gamma.abs() <= 1e-15 * (alpha * beta).sqrt() || gamma == 0.0 {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                let cs = 1.0 / (1.0 + t * t).sqrt();
                let sn = cs * t;
                for c in 0..n {
                    let (x, y) = (jac[i * n + c], jac[k * n + c]);
                    jac[i * n + c] = cs * x - sn * y;
                    jac[k * n + c] = sn * x + cs * y;
                }
                for c in 0..m {
                    let (x, y) = (g[i * m + c], g[k * m + c]);
                    g[i * m + c] = cs * x - sn * y;
                    g[k * m + c] = sn * x + cs * y;
                }
            }
        }
        if !rotated {
            break;
        }
    }
    let mut max_s2 = 0.0_f64;
    for (i, s2) in sigma2.iter_mut().enumerate().take(m) {
        *s2 = jac[i * n..(i + 1) * n].iter().map(|v| v * v).sum();
        max_s2 = max_s2.max(*s2);
    }
    let cut2 = (cutoff_rel * cutoff_rel * max_s2).max(f64::MIN_POSITIVE);
    out[..n].fill(0.0);
    for i in 0..m {
        if sigma2[i] < cut2 || sigma2[i] <= 0.0 {
            continue;
        }
        let ge: f64 = (0..m).map(|c| g[i * m + c] * e[c]).sum();
        let f = ge / sigma2[i];
        for c in 0..n {
            out[c] += jac[i * n + c] * f;
        }
    }
}

/// The rotation `R` minimising `Σ w |R a - b|²` over weighted vector pairs (Horn 1987,
/// "Closed-form solution of absolute orientation using unit quaternions", JOSA A 4(4):
/// the unit quaternion is the eigenvector of the largest eigenvalue of the 4x4 matrix `N`
/// built from `H = Σ w a bᵀ`). With one usable pair it is the shortest arc from `a` to `b`
/// (no twist about `b`, which Horn leaves undetermined). Identity when no pair is usable.
pub(crate) fn best_rotation(pairs: impl Iterator<Item = (Vec3, Vec3, f32)>) -> Quat {
    let mut h = [[0.0_f64; 3]; 3];
    let mut used = 0;
    let mut single = (Vec3::ZERO, Vec3::ZERO);
    for (a, b, w) in pairs {
        let usable = w > 0.0
            && a.length_squared() > f32::MIN_POSITIVE
            && b.length_squared() > f32::MIN_POSITIVE;
        if !usable {
            continue;
        }
        used += 1;
        single = (a, b);
        let (a, b, w) = (a.as_dvec3(), b.as_dvec3(), f64::from(w));
        let (a, b) = (a.to_array(), b.to_array());
        for (r, row) in h.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v += w * a[r] * b[c];
            }
        }
    }
    match used {
        0 => Quat::IDENTITY,
        1 => shortest_arc(single.0.normalize(), single.1.normalize()),
        _ => {
            let [[sxx, sxy, sxz], [syx, syy, syz], [szx, szy, szz]] = h;
            let mut n = [
                [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
                [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
                [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
                [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
            ];
            let [w, x, y, z] = max_eigenvector4(&mut n);
            let q = DQuat::from_xyzw(x, y, z, w);
            let len = q.length();
            if len.is_nan() || len <= 0.0 || len.is_infinite() {
                return Quat::IDENTITY;
            }
            let q = q / len;
            let q = if q.w < 0.0 { -q } else { q };
            q.as_quat().normalize()
        }
    }
}

/// The shortest rotation taking unit `a` to unit `b`: `normalize(1 + a·b, a × b)`, which
/// keeps small angles that glam's `from_rotation_arc` rounds to the identity (below about
/// 1.4e-3 rad); glam's handles the nearly opposite case.
pub(crate) fn shortest_arc(a: Vec3, b: Vec3) -> Quat {
    let w = 1.0 + a.dot(b);
    if w < 1e-4 {
        return Quat::from_rotation_arc(a, b);
    }
    let v = a.cross(b);
    Quat::from_xyzw(v.x, v.y, v.z, w).normalize()
}

/// The unit eigenvector of the largest eigenvalue of a symmetric 4x4 matrix, by cyclic
/// Jacobi rotations (`n` is destroyed).
fn max_eigenvector4(n: &mut [[f64; 4]; 4]) -> [f64; 4] {
    let mut v = [[0.0_f64; 4]; 4];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _ in 0..50 {
        let off: f64 = (0..4)
            .flat_map(|p| (p + 1..4).map(move |q| (p, q)))
            .map(|(p, q)| n[p][q] * n[p][q])
            .sum();
        let scale: f64 = (0..4).map(|p| n[p][p] * n[p][p]).sum::<f64>() + off;
        if off <= 1e-30 * scale || off == 0.0 {
            break;
        }
        for p in 0..4 {
            for q in p + 1..4 {
                if n[p][q] == 0.0 {
                    continue;
                }
                let theta = (n[q][q] - n[p][p]) / (2.0 * n[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in n.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (rp, rq) = (n[p], n[q]);
                n[p] = std::array::from_fn(|k| c * rp[k] - s * rq[k]);
                n[q] = std::array::from_fn(|k| s * rp[k] + c * rq[k]);
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    let best = (0..4).fold(0, |b, i| if n[i][i] > n[b][b] { i } else { b });
    [v[0][best], v[1][best], v[2][best], v[3][best]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_spd_and_stays_finite_when_singular() {
        // A = M Mᵀ + I for a fixed M.
        let m = [1.0, 2.0, 0.5, -1.0, 0.0, 3.0, 2.0, 1.0, 1.0];
        let mut a = [0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                a[i * 3 + j] = (0..3).map(|k| m[i * 3 + k] * m[j * 3 + k]).sum::<f64>()
                    + if i == j { 1.0 } else { 0.0 };
            }
        }
        let x = [0.3, -2.0, 1.5];
        let mut b = [0.0; 3];
        for i in 0..3 {
            b[i] = (0..3).map(|j| a[i * 3 + j] * x[j]).sum();
        }
        let mut f = a;
        cholesky_solve(&mut f, 3, &mut b);
        for i in 0..3 {
            assert!((b[i] - x[i]).abs() < 1e-12, "{b:?} vs {x:?}");
        }
        // Rank 1: still finite.
        let mut s = [1.0, 1.0, 1.0, 1.0];
        let mut rhs = [1.0, 2.0];
        cholesky_solve(&mut s, 2, &mut rhs);
        assert!(rhs.iter().all(|v| v.is_finite()), "{rhs:?}");
    }

    #[test]
    fn pinv_matches_the_normal_equations_and_drops_small_singular_values() {
        // Full row rank 2x3: J⁺ e = Jᵀ (J Jᵀ)⁻¹ e.
        let j = [1.0, 2.0, 0.0, 0.0, 1.0, -1.0];
        let e = [0.5, -1.0];
        let mut jj = [0.0; 4];
        for r in 0..2 {
            for c in 0..2 {
                jj[r * 2 + c] = (0..3).map(|k| j[r * 3 + k] * j[c * 3 + k]).sum();
            }
        }
        let mut y = e;
        cholesky_solve(&mut jj, 2, &mut y);
        let expect: Vec<f64> = (0..3).map(|c| j[c] * y[0] + j[3 + c] * y[1]).collect();
        let (mut jw, mut work, mut out) = (j, [0.0; 6], [0.0; 3]);
        pinv_solve(&mut jw, (2, 3), &e, 1e-6, &mut work, &mut out);
        for c in 0..3 {
            assert!((out[c] - expect[c]).abs() < 1e-12, "{out:?} vs {expect:?}");
        }
        // Two identical rows (rank 1) and an inconsistent e: the minimum-norm least-squares
        // answer, J⁺ e = v (mean of e) / |v|² with v the common row.
        let (mut jw, e) = ([1.0, 1.0, 1.0, 1.0], [1.0, 3.0]);
        let mut out = [0.0; 2];
        pinv_solve(&mut jw, (2, 2), &e, 1e-6, &mut work, &mut out);
        assert!(
            (out[0] - 1.0).abs() < 1e-12 && (out[1] - 1.0).abs() < 1e-12,
            "{out:?}"
        );
    }

    #[test]
    fn horn_recovers_a_rotation_and_one_pair_is_the_shortest_arc() {
        let r = Quat::from_euler(glam::EulerRot::ZYX, 0.7, -0.4, 1.9);
        let a = [Vec3::X, Vec3::new(0.0, 2.0, 0.5), Vec3::new(-1.0, 0.3, 0.2)];
        let q = best_rotation(a.iter().map(|&a| (a, r * a, 1.0)));
        assert!(
            q.abs_diff_eq(r, 1e-5) || q.abs_diff_eq(-r, 1e-5),
            "{q} vs {r}"
        );
        let q = best_rotation([(Vec3::X, Vec3::Y * 3.0, 1.0)].into_iter());
        assert!(q.abs_diff_eq(Quat::from_rotation_z(std::f32::consts::FRAC_PI_2), 1e-6));
        // Small angles survive (glam's from_rotation_arc returns the identity below 1.4e-3).
        let tiny = Quat::from_rotation_y(1e-4);
        let q = best_rotation([(Vec3::X, tiny * Vec3::X, 1.0)].into_iter());
        assert!((crate::axis_angle(q).1 - 1e-4).abs() < 1e-6, "{q}");
        let q = best_rotation([(Vec3::X, -Vec3::X, 1.0)].into_iter());
        assert!((q * Vec3::X).abs_diff_eq(-Vec3::X, 1e-5), "{q}");
        assert_eq!(best_rotation(std::iter::empty()), Quat::IDENTITY);
    }
}
