//! Per joint, once per frame: a skinning matrix split into a rigid part (a unit dual
//! quaternion) and the rest (scale and shear), as UsdSkel's `_ConvertToDualQuaternions`
//! does with `GfMatrix4d::Factor`.

use glam::{DMat3, DQuat, DVec3, Mat3, Mat4, Quat, Vec3, Vec4};

use crate::skinning::common::MIN_REAL_LENGTH;

/// Joint matrices whose upper 3x3 has `|det| < SINGULAR_DET` are singular (the `eps`
/// default of `GfMatrix4d::Factor`, which `_ConvertToDualQuaternions` calls).
const SINGULAR_DET: f64 = 1e-10;

/// A dual quaternion `real + ε dual`; as a rigid transform (unit real part, dual part
/// orthogonal to it) it rotates by `real`, then translates by `2 dual real*`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualQuat {
    /// Rotation part (xyzw).
    pub real: Quat,
    /// Translation part: `½ (t, 0) * real`.
    pub dual: Quat,
}

impl DualQuat {
    /// The identity transform.
    pub const IDENTITY: Self = Self {
        real: Quat::IDENTITY,
        dual: Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
    };

    /// Rotation `rotation` (unit quaternion) followed by translation `translation`.
    pub fn from_rotation_translation(rotation: Quat, translation: Vec3) -> Self {
        let t = Quat::from_xyzw(translation.x, translation.y, translation.z, 0.0);
        Self {
            real: rotation,
            dual: (t * rotation) * 0.5,
        }
    }

    /// Normalized as UsdSkel's `GfDualQuat::Normalize`: both parts divided by the real
    /// part's length, then the dual part made orthogonal to the real part. A real part
    /// shorter than `1e-10` gives the identity.
    pub fn normalized(self) -> Self {
        let real = Vec4::from(self.real);
        let len = real.length();
        // `is_nan` too: a NaN length is not a valid rotation either.
        if len < MIN_REAL_LENGTH || len.is_nan() {
            return Self::IDENTITY;
        }
        let real = real / len;
        let dual = Vec4::from(self.dual) / len;
        let dual = dual - real * real.dot(dual);
        Self {
            real: Quat::from_vec4(real),
            dual: Quat::from_vec4(dual),
        }
    }

    /// The translation `2 (dual * conj(real))` of a normalized dual quaternion.
    pub fn translation(self) -> Vec3 {
        let (r, d) = (Vec4::from(self.real), Vec4::from(self.dual));
        let (rv, dv) = (r.truncate(), d.truncate());
        2.0 * (r.w * dv - d.w * rv + rv.cross(dv))
    }

    /// Applies a normalized dual quaternion to a point: rotate, then translate.
    pub fn transform_point3(self, p: Vec3) -> Vec3 {
        self.real * p + self.translation()
    }
}

/// The parts of one joint skinning matrix that UsdSkel's DQS uses (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointDecomposition {
    /// The rigid part `T(t) * R` as a unit dual quaternion.
    pub rigid: DualQuat,
    /// The remaining scale/shear `S = Rᵀ A` (column vectors; applied before `rigid`).
    pub scale: Mat3,
}

/// Splits a skinning matrix (column vectors, affine) into rigid part and scale/shear the
/// way UsdSkel's `_ConvertToDualQuaternions` does, in double precision.
///
/// Returns `None` when the upper 3x3 is singular (`|det| < 1e-10`) or not finite; UsdSkel
/// then uses the zero dual quaternion and `S = I`.
pub fn decompose(m: &Mat4) -> Option<JointDecomposition> {
    let (rotation, translation, scale) = decompose_f64(m)?;
    let rotation = rotation.as_quat();
    Some(JointDecomposition {
        rigid: DualQuat::from_rotation_translation(rotation, translation.as_vec3()),
        scale: scale.as_mat3(),
    })
}

/// [`decompose`] in `f64`: rotation, translation, scale/shear with `A = R S`.
pub(super) fn decompose_f64(m: &Mat4) -> Option<(DQuat, DVec3, DMat3)> {
    let a = DMat3::from_cols(
        m.x_axis.truncate().as_dvec3(),
        m.y_axis.truncate().as_dvec3(),
        m.z_axis.truncate().as_dvec3(),
    );
    let det = a.determinant();
    if det.abs() < SINGULAR_DET || !det.is_finite() || !a.is_finite() {
        return None;
    }
    let mut r = polar_orthogonal(a)?;
    if det < 0.0 {
        // Factor puts the mirror into the scale (all three factors negative), leaving a
        // proper rotation: for 3x3, -Q has determinant +1 when Q has -1.
        r = -r;
    }
    let scale = r.transpose() * a;
    let rotation = DQuat::from_mat3(&r).normalize();
    let translation = m.w_axis.truncate().as_dvec3();
    translation
        .is_finite()
        .then_some((rotation, translation, scale))
}

/// The orthogonal factor `Q` of the polar decomposition `A = Q P` (`P` symmetric positive
/// definite) of an invertible matrix, by Newton's iteration `X ← ½ (γX + X⁻ᵀ/γ)` with
/// Higham's Frobenius-norm scaling `γ` (Higham 1986, "Computing the polar decomposition
/// with applications", SIAM J. Sci. Stat. Comput. 7(4)), which converges quadratically.
fn polar_orthogonal(a: DMat3) -> Option<DMat3> {
    let frobenius = |m: &DMat3| {
        (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt()
    };
    let mut x = a;
    let mut scaled = true;
    for _ in 0..100 {
        let det = x.determinant();
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv_t = x.inverse().transpose();
        let gamma = if scaled {
            (frobenius(&inv_t) / frobenius(&x)).sqrt()
        } else {
            1.0
        };
        let next = (x * gamma + inv_t * (1.0 / gamma)) * 0.5;
        let diff = frobenius(&(next - x));
        x = next;
        if diff < 1e-2 {
            // Near convergence scaling no longer helps, and plain Newton keeps the last
            // digits (Higham's recommendation).
            scaled = false;
        }
        if diff <= 4.0 * f64::EPSILON {
            break;
        }
    }
    x.is_finite().then_some(x)
}
