//! Joint limits ([`JointLimit`]: a cone or Euler bounds on a joint's rotation relative to
//! its rest rotation) and the rotation helpers they use.

use glam::{Quat, Vec3};
use rigport_model::conventions::EulerOrder;

/// A bound on a joint's rotation relative to its rest rotation: with `delta =
/// rest_rotation⁻¹ · local_rotation`, the bound applies to `delta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointLimit {
    /// `delta`'s rotation angle is at most `max_rad` (`0 ..= π`); a longer rotation is cut
    /// to that angle about the same axis.
    Angle {
        /// The largest angle, radians.
        max_rad: f32,
    },
    /// `delta`'s Euler angles in `order` (see [`EulerOrder`]; `[x, y, z]` radians whatever the
    /// order) stay within `min_rad ..= max_rad` per axis, each clamped after decomposition.
    Euler {
        /// The axis order the angles are read in.
        order: EulerOrder,
        /// Lower bounds `[x, y, z]`, radians.
        min_rad: Vec3,
        /// Upper bounds `[x, y, z]`, radians.
        max_rad: Vec3,
    },
    /// As [`JointLimit::Euler`], with the angles those of `frame⁻¹ · delta · frame`: axes of
    /// another frame than the rest frame (an ASF bone's `axis` frame; see
    /// [`rigport_model::RotationLimit`]).
    EulerInFrame {
        /// The frame the angles are read in, relative to the rest frame (unit).
        frame: Quat,
        /// The axis order the angles are read in.
        order: EulerOrder,
        /// Lower bounds `[x, y, z]`, radians.
        min_rad: Vec3,
        /// Upper bounds `[x, y, z]`, radians.
        max_rad: Vec3,
    },
}

impl From<&rigport_model::RotationLimit> for JointLimit {
    fn from(l: &rigport_model::RotationLimit) -> Self {
        if l.frame == Quat::IDENTITY {
            JointLimit::Euler {
                order: l.order,
                min_rad: l.min_rad,
                max_rad: l.max_rad,
            }
        } else {
            JointLimit::EulerInFrame {
                frame: l.frame,
                order: l.order,
                min_rad: l.min_rad,
                max_rad: l.max_rad,
            }
        }
    }
}

impl JointLimit {
    /// Projects `delta` (the rotation relative to rest) into the limit: the angle cut for
    /// [`JointLimit::Angle`], each Euler angle clamped after decomposition for the Euler
    /// variants (a clamp, not the nearest rotation within the limit).
    pub fn project(&self, delta: Quat) -> Quat {
        match *self {
            JointLimit::Angle { max_rad } => {
                let (axis, angle) = axis_angle(delta);
                if angle > max_rad && axis.is_finite() {
                    Quat::from_axis_angle(axis, max_rad)
                } else {
                    delta
                }
            }
            JointLimit::Euler {
                order,
                min_rad,
                max_rad,
            } => {
                let angles = euler_angles(order, delta);
                let clamped = Vec3::from(angles).clamp(min_rad, max_rad);
                order.to_quat(clamped.to_array())
            }
            JointLimit::EulerInFrame {
                frame,
                order,
                min_rad,
                max_rad,
            } => {
                let inner = JointLimit::Euler {
                    order,
                    min_rad,
                    max_rad,
                };
                (frame * inner.project(frame.conjugate() * delta * frame) * frame.conjugate())
                    .normalize()
            }
        }
    }

    /// How far `delta` (the rotation relative to rest) is outside the limit, radians: the
    /// largest Euler angle excess (Euler variants) or angle excess ([`JointLimit::Angle`]).
    pub fn excess_rad(&self, delta: Quat) -> f32 {
        match *self {
            JointLimit::Angle { max_rad } => (axis_angle(delta).1 - max_rad).max(0.0),
            JointLimit::Euler {
                order,
                min_rad,
                max_rad,
            } => {
                let a = Vec3::from(euler_angles(order, delta));
                (min_rad - a).max(a - max_rad).max_element().max(0.0)
            }
            JointLimit::EulerInFrame {
                frame,
                order,
                min_rad,
                max_rad,
            } => JointLimit::Euler {
                order,
                min_rad,
                max_rad,
            }
            .excess_rad(frame.conjugate() * delta * frame),
        }
    }
}

/// The Euler angles `[x, y, z]` (radians) of `q` in `order`, the inverse of
/// [`EulerOrder::to_quat`].
pub fn euler_angles(order: EulerOrder, q: Quat) -> [f32; 3] {
    use glam::EulerRot;
    // The same table as `EulerOrder::to_quat`: glam names the outermost rotation first.
    match order {
        EulerOrder::Xyz => {
            let (z, y, x) = q.to_euler(EulerRot::ZYX);
            [x, y, z]
        }
        EulerOrder::Yzx => {
            let (x, z, y) = q.to_euler(EulerRot::XZY);
            [x, y, z]
        }
        EulerOrder::Zxy => {
            let (y, x, z) = q.to_euler(EulerRot::YXZ);
            [x, y, z]
        }
        EulerOrder::Xzy => {
            let (y, z, x) = q.to_euler(EulerRot::YZX);
            [x, y, z]
        }
        EulerOrder::Yxz => {
            let (z, x, y) = q.to_euler(EulerRot::ZXY);
            [x, y, z]
        }
        EulerOrder::Zyx => {
            let (x, y, z) = q.to_euler(EulerRot::XYZ);
            [x, y, z]
        }
    }
}

/// A unit quaternion's axis and angle (`0..=π`), accurate for small angles: `2·atan2(|v|, |w|)`
/// keeps the angle that glam's `acos(w)` loses below about `5e-4` rad in `f32`. The axis is
/// zero for the identity.
pub(crate) fn axis_angle(q: Quat) -> (Vec3, f32) {
    let q = if q.w < 0.0 { -q } else { q };
    let v = Vec3::new(q.x, q.y, q.z);
    let len = v.length();
    if len.is_nan() || len <= 0.0 || len.is_infinite() {
        return (Vec3::ZERO, 0.0);
    }
    (v / len, 2.0 * len.atan2(q.w))
}
