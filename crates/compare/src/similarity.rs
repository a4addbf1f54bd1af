//! The similarity transform (uniform scale, rotation, translation) that best carries one
//! point set onto another, by Horn's closed form with unit quaternions (B. K. P. Horn,
//! "Closed-form solution of absolute orientation using unit quaternions", JOSA A 4(4),
//! 1987: the rotation is the eigenvector of the largest eigenvalue of a symmetric 4x4
//! matrix built from the cross-covariance; the scale is his symmetric one, the ratio of
//! the sets' spreads, so fitting A to B gives the inverse of fitting B to A), and its
//! wording in a report: a unit difference, an axis turn, a placement.

use glam::{DMat3, DMat4, DQuat, DVec3};
use rigport_model::UpAxis;

/// `x -> scale * rotation * x + translation`: what carries the reference onto the
/// candidate. Lengths in the comparison frame's metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity {
    /// Uniform scale (1: same size).
    pub scale: f64,
    /// Rotation (unit quaternion, xyzw).
    pub rotation: DQuat,
    /// Translation, after scaling and rotating.
    pub translation: DVec3,
}

impl Similarity {
    /// The identity.
    pub const IDENTITY: Self = Self {
        scale: 1.0,
        rotation: DQuat::IDENTITY,
        translation: DVec3::ZERO,
    };

    /// As a column-vector matrix.
    pub fn matrix(&self) -> DMat4 {
        DMat4::from_scale_rotation_translation(
            DVec3::splat(self.scale),
            self.rotation,
            self.translation,
        )
    }

    /// The inverse transform (candidate -> reference).
    pub fn inverse(&self) -> DMat4 {
        self.matrix().inverse()
    }

    /// The rotation angle, radians in `[0, pi]`.
    pub fn angle(&self) -> f64 {
        let w = self.rotation.w.abs().min(1.0);
        2.0 * w.acos()
    }

    /// Whether scale, rotation and translation are each negligible: scale within
    /// `1e-6` of 1, rotation under `1e-6` rad, translation under `distance`.
    pub fn is_identity(&self, distance: f64) -> bool {
        (self.scale - 1.0).abs() <= 1e-6
            && self.angle() <= 1e-6
            && self.translation.length() <= distance
    }

    /// The transform in words, each part only when it is not negligible (`distance` as in
    /// [`Similarity::is_identity`]): "scaled by 100 (a unit difference: m -> cm)", "turned
    /// Y-up -> Z-up (an axis difference)" or "rotated 12.5 deg about (0, 1, 0)", "moved by
    /// (0.1, 0, 0) m".
    ///
    /// ```
    /// use rigport_compare::similarity::Similarity;
    /// use rigport_compare::glam::{DQuat, DVec3};
    /// let s = Similarity { scale: 100.0, ..Similarity::IDENTITY };
    /// assert_eq!(s.describe(1e-6), ["scaled by 100 (a unit difference: m -> cm)"]);
    /// let turned = Similarity { rotation: DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2), ..Similarity::IDENTITY };
    /// assert_eq!(turned.describe(1e-6), ["turned Y-up -> Z-up (an axis difference)"]);
    /// ```
    pub fn describe(&self, distance: f64) -> Vec<String> {
        let mut parts = Vec::new();
        if (self.scale - 1.0).abs() > 1e-6 {
            parts.push(match unit_ratio(self.scale) {
                Some((ratio, units)) => {
                    format!("scaled by {ratio} (a unit difference: {units})")
                }
                None => format!("scaled by {:.6}", self.scale),
            });
        }
        if self.angle() > 1e-6 {
            parts.push(match axis_turn(self.rotation) {
                Some((from, to)) => format!(
                    "turned {}-up -> {}-up (an axis difference)",
                    from.as_str(),
                    to.as_str()
                ),
                None => {
                    let (axis, angle) = self.rotation.to_axis_angle();
                    format!(
                        "rotated {:.3} deg about ({:.4}, {:.4}, {:.4})",
                        angle.to_degrees(),
                        axis.x,
                        axis.y,
                        axis.z
                    )
                }
            });
        }
        if self.translation.length() > distance {
            let t = self.translation;
            parts.push(format!("moved by ({:.6}, {:.6}, {:.6}) m", t.x, t.y, t.z));
        }
        parts
    }
}

/// Length ratios between the units files use, and their words: `(candidate units per
/// reference unit, "reference -> candidate")`.
const UNIT_RATIOS: [(f64, &str); 12] = [
    (100.0, "m -> cm"),
    (0.01, "cm -> m"),
    (1000.0, "m -> mm"),
    (0.001, "mm -> m"),
    (10.0, "cm -> mm"),
    (0.1, "mm -> cm"),
    (1.0 / 0.0254, "m -> in"),
    (0.0254, "in -> m"),
    (2.54, "in -> cm"),
    (1.0 / 2.54, "cm -> in"),
    (1.0 / 0.3048, "m -> ft"),
    (0.3048, "ft -> m"),
];

/// The unit ratio `scale` is, within `1e-4` relative (float32 data scaled and read back).
fn unit_ratio(scale: f64) -> Option<(f64, &'static str)> {
    UNIT_RATIOS
        .iter()
        .find(|(r, _)| ((scale - r) / r).abs() <= 1e-4)
        .map(|&(r, units)| ((r * 1e6).round() / 1e6, units))
}

/// The up-axis conversion `rotation` is (within `1e-4` rad): `(from, to)` as
/// [`UpAxis::conversion_to`] defines it.
fn axis_turn(rotation: DQuat) -> Option<(UpAxis, UpAxis)> {
    [(UpAxis::Y, UpAxis::Z), (UpAxis::Z, UpAxis::Y)]
        .into_iter()
        .find(|(from, to)| {
            let turn = DQuat::from_mat3(&DMat3::from_mat4(from.conversion_to(*to)));
            turn.angle_between(rotation) <= 1e-4
        })
}

/// The similarity carrying `reference[i]` onto `candidate[i]` in the least-squares sense,
/// and the largest distance left between a carried reference point and its candidate.
/// `None` for fewer than 3 pairs, sets of different lengths, or points too close to a
/// line for a rotation to be determined.
///
/// ```
/// use rigport_compare::similarity::fit;
/// use rigport_compare::glam::{DQuat, DVec3};
/// let a = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.0, 1.0, 2.0)];
/// let turn = DQuat::from_rotation_y(0.3);
/// let b: Vec<DVec3> = a.iter().map(|&p| turn * (p * 0.01) + DVec3::Z).collect();
/// let (s, residual) = fit(&a, &b).expect("well spread");
/// assert!((s.scale - 0.01).abs() < 1e-12 && s.rotation.angle_between(turn) < 1e-6);
/// assert!(residual < 1e-12);
/// ```
pub fn fit(reference: &[DVec3], candidate: &[DVec3]) -> Option<(Similarity, f64)> {
    let n = reference.len();
    if n < 3 || candidate.len() != n {
        return None;
    }
    let centroid = |s: &[DVec3]| s.iter().copied().sum::<DVec3>() / n as f64;
    let (ca, cb) = (centroid(reference), centroid(candidate));
    let mut m = [[0.0f64; 3]; 3];
    let (mut spread_a, mut spread_b) = (0.0, 0.0);
    for (a, b) in reference.iter().zip(candidate) {
        let (a, b) = ((*a - ca).to_array(), (*b - cb).to_array());
        for (i, row) in m.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v += a[i] * b[j];
            }
        }
        spread_a += a.iter().map(|x| x * x).sum::<f64>();
        spread_b += b.iter().map(|x| x * x).sum::<f64>();
    }
    if !(spread_a > 0.0 && spread_b > 0.0 && spread_a.is_finite() && spread_b.is_finite()) {
        return None;
    }
    let [[sxx, sxy, sxz], [syx, syy, syz], [szx, szy, szz]] = m;
    let horn = [
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ];
    let (values, vectors) = jacobi_eigen(horn);
    let mut order = [0usize, 1, 2, 3];
    order.sort_by(|&i, &j| values[j].total_cmp(&values[i]));
    // Points on a line leave the turn about it free: two top eigenvalues equal.
    let scale_of_values = values.iter().map(|v| v.abs()).fold(0.0, f64::max);
    if values[order[0]] - values[order[1]] <= 1e-9 * scale_of_values {
        return None;
    }
    let q = vectors[order[0]];
    let rotation = DQuat::from_xyzw(q[1], q[2], q[3], q[0]).normalize();
    let scale = (spread_b / spread_a).sqrt();
    let translation = cb - scale * (rotation * ca);
    let s = Similarity {
        scale,
        rotation,
        translation,
    };
    let carried = s.matrix();
    let residual = reference
        .iter()
        .zip(candidate)
        .map(|(a, b)| carried.transform_point3(*a).distance(*b))
        .fold(0.0, f64::max);
    Some((s, residual))
}

/// Eigenvalues and eigenvectors (`vectors[k]` for `values[k]`) of a symmetric 4x4 matrix by
/// cyclic Jacobi rotations (Golub and Van Loan, "Matrix Computations", 8.5).
fn jacobi_eigen(mut a: [[f64; 4]; 4]) -> ([f64; 4], [[f64; 4]; 4]) {
    let mut v = [[0.0f64; 4]; 4];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _sweep in 0..64 {
        let off: f64 = (0..4)
            .flat_map(|i| (0..4).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        if off <= 1e-30 {
            break;
        }
        for p in 0..3 {
            for q in p + 1..4 {
                if a[p][q].abs() <= f64::MIN_POSITIVE {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in &mut a {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (row_p, row_q) = (a[p], a[q]);
                for (k, (apk, aqk)) in row_p.into_iter().zip(row_q).enumerate() {
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in &mut v {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    let values = [a[0][0], a[1][1], a[2][2], a[3][3]];
    let mut vectors = [[0.0f64; 4]; 4];
    for (k, vector) in vectors.iter_mut().enumerate() {
        for (i, x) in vector.iter_mut().enumerate() {
            *x = v[i][k];
        }
    }
    (values, vectors)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_recovers_the_z_up_turn_and_its_inverse() {
        let a = [
            DVec3::ZERO,
            DVec3::new(0.0, 1.7, 0.0),
            DVec3::new(0.3, 1.4, 0.1),
            DVec3::new(-0.3, 1.4, -0.1),
        ];
        let turn = UpAxis::Y.conversion_to(UpAxis::Z);
        let b: Vec<DVec3> = a.iter().map(|&p| turn.transform_point3(p)).collect();
        let (s, residual) = fit(&a, &b).expect("spread");
        assert!(residual < 1e-12);
        assert_eq!(axis_turn(s.rotation), Some((UpAxis::Y, UpAxis::Z)));
        let (back, _) = fit(&b, &a).expect("spread");
        assert_eq!(axis_turn(back.rotation), Some((UpAxis::Z, UpAxis::Y)));
    }

    #[test]
    fn collinear_points_fix_no_rotation() {
        let a = [DVec3::ZERO, DVec3::Y, DVec3::Y * 2.0];
        assert!(fit(&a, &a).is_none());
    }

    #[test]
    fn identity_is_quiet() {
        let a = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let (s, _) = fit(&a, &a).expect("spread");
        assert!(s.is_identity(1e-9), "{s:?}");
        assert!(s.describe(1e-9).is_empty());
    }
}
