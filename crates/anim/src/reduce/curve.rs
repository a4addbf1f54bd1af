//! Reading a track at any time with a moving cursor, for the reducer's error checks: key
//! search, lerp, slerp (with a cached angle), and the cubic Hermite basis.

use glam::{Quat, Vec3, Vec4};
use rigport_model::{Interpolation, Track};

/// Where `t` falls in a track's keys.
pub(super) enum Position {
    /// Exactly on key `k`, or held before the first / after the last key.
    Key(usize),
    /// Between key `k` and `k + 1`, at fraction `u` in (0, 1).
    Between(usize, f32),
}

/// Finds `t`, moving `cursor` forward for increasing times (binary search otherwise).
pub(super) fn locate(times: &[f32], t: f32, cursor: &mut usize) -> Position {
    if times.get(*cursor).is_none_or(|&c| c > t) {
        *cursor = times.partition_point(|&x| x <= t).saturating_sub(1);
    }
    while times.get(*cursor + 1).is_some_and(|&next| next <= t) {
        *cursor += 1;
    }
    let k = *cursor;
    match (times.get(k), times.get(k + 1)) {
        (Some(&t0), Some(&t1)) if t0 < t => Position::Between(k, (t - t0) / (t1 - t0)),
        _ => Position::Key(k),
    }
}

/// `a + (b - a) u`: exact for equal endpoints (glam's `lerp` is not).
pub(super) fn lerp3(a: Vec3, b: Vec3, u: f32) -> Vec3 {
    a + (b - a) * u
}

/// Shortest-path spherical interpolation of unit quaternions; exact for equal endpoints.
pub(super) fn slerp(a: Quat, b: Quat, u: f32) -> Quat {
    Slerp::new(a, b).at(u)
}

/// One slerp segment with its angle computed once (the simplifier evaluates many points).
pub(super) struct Slerp {
    a: Vec4,
    b: Vec4,
    /// Angle between the 4-vectors `a` and `b` (half the rotation angle), radians.
    omega: f32,
    sin_omega: f32,
    equal: bool,
}

impl Slerp {
    pub(super) fn new(a: Quat, b: Quat) -> Self {
        let a4 = Vec4::from(a);
        let mut b4 = Vec4::from(b);
        if a4.dot(b4) < 0.0 {
            b4 = -b4;
        }
        // The angle from atan2 of chord lengths: accurate at every angle, where acos(dot)
        // loses half the digits near 0.
        let omega = 2.0 * (a4 - b4).length().atan2((a4 + b4).length());
        Self {
            a: a4,
            b: b4,
            omega,
            sin_omega: omega.sin(),
            equal: a == b,
        }
    }

    pub(super) fn at(&self, u: f32) -> Quat {
        if self.equal {
            return Quat::from_vec4(self.a);
        }
        let v = if self.omega < 1e-3 {
            // Normalized lerp deviates from slerp by O(omega^3) < 1e-9 here.
            self.a + (self.b - self.a) * u
        } else {
            self.a * (((1.0 - u) * self.omega).sin() / self.sin_omega)
                + self.b * ((u * self.omega).sin() / self.sin_omega)
        };
        Quat::from_vec4(v.normalize())
    }
}

/// Three floats at `at` (zero when out of range, which validation rules out).
pub(super) fn vec3_at(values: &[f32], at: usize) -> Vec3 {
    values.get(at..at + 3).map_or(Vec3::ZERO, Vec3::from_slice)
}

/// The angle between two unit rotations, through their chord `|a - b| = 2 sin(θ/4)` (the
/// nearer of `b` and `-b`): precise to f32 rounding at small angles, where `Quat::angle_between`
/// (an `acos` of the dot product) cannot tell angles under about 1e-3 rad apart, the
/// precision a rotation's bits are chosen at.
pub(super) fn rotation_angle(a: Quat, b: Quat) -> f32 {
    let (a, b) = (Vec4::from(a), Vec4::from(b));
    let chord = (a - b).length().min((a + b).length());
    4.0 * (0.5 * chord).min(1.0).asin()
}

/// The normalized quaternion at `at` of `values` (NaN for a zero quaternion).
pub(super) fn quat_at(values: &[f32], at: usize) -> Quat {
    let v = values.get(at..at + 4).map_or(Vec4::ZERO, Vec4::from_slice);
    Quat::from_vec4(v / v.length())
}

/// A translation or scale track at time `t`.
pub(super) fn sample_vec3(track: &Track, t: f32, cursor: &mut usize) -> Vec3 {
    let v = &track.values;
    let cubic = track.interpolation == Interpolation::CubicSpline;
    let stride = if cubic { 9 } else { 3 };
    let value = |k: usize| vec3_at(v, k * stride + if cubic { 3 } else { 0 });
    match locate(&track.times, t, cursor) {
        Position::Key(k) => value(k),
        Position::Between(k, u) => match track.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear => lerp3(value(k), value(k + 1), u),
            Interpolation::CubicSpline => {
                let dt = track.times[k + 1] - track.times[k];
                let out_tangent = vec3_at(v, k * 9 + 6);
                let in_tangent = vec3_at(v, (k + 1) * 9);
                let [h00, h10, h01, h11] = hermite(u);
                value(k) * h00
                    + out_tangent * (dt * h10)
                    + value(k + 1) * h01
                    + in_tangent * (dt * h11)
            }
        },
    }
}

/// A rotation track at time `t`, normalized.
pub(super) fn sample_quat(track: &Track, t: f32, cursor: &mut usize) -> Quat {
    let v = &track.values;
    let cubic = track.interpolation == Interpolation::CubicSpline;
    let stride = if cubic { 12 } else { 4 };
    let value = |k: usize| quat_at(v, k * stride + if cubic { 4 } else { 0 });
    match locate(&track.times, t, cursor) {
        Position::Key(k) => value(k),
        Position::Between(k, u) => match track.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear => slerp(value(k), value(k + 1), u),
            Interpolation::CubicSpline => {
                // glTF 2.0 Appendix C: Hermite on the raw components, then normalize.
                let raw = |at: usize| v.get(at..at + 4).map_or(Vec4::ZERO, Vec4::from_slice);
                let dt = track.times[k + 1] - track.times[k];
                let [h00, h10, h01, h11] = hermite(u);
                let q = raw(k * 12 + 4) * h00
                    + raw(k * 12 + 8) * (dt * h10)
                    + raw((k + 1) * 12 + 4) * h01
                    + raw((k + 1) * 12) * (dt * h11);
                Quat::from_vec4(q.normalize())
            }
        },
    }
}

/// Cubic Hermite basis at `u` (glTF 2.0 Appendix C): value k, out-tangent k, value k+1,
/// in-tangent k+1.
pub(super) fn hermite(u: f32) -> [f32; 4] {
    let u2 = u * u;
    let u3 = u2 * u;
    [
        2.0 * u3 - 3.0 * u2 + 1.0,
        u3 - 2.0 * u2 + u,
        -2.0 * u3 + 3.0 * u2,
        u3 - u2,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Small angles come out to their own precision (an `acos` of the dot product reads
    /// every angle under about 7e-4 rad as 0 or 7e-4), either sign of either quaternion.
    #[test]
    fn rotation_angle_resolves_small_angles() {
        let a = Quat::from_euler(glam::EulerRot::XYZ, 0.4, -1.1, 2.0);
        let axis = Vec3::new(0.3, -0.5, 0.8).normalize();
        for angle in [1e-6f32, 1e-5, 1e-4, 3e-4, 1e-3, 0.1, 1.0, 3.0] {
            let b = a * Quat::from_axis_angle(axis, angle);
            for b in [b, -b] {
                let got = rotation_angle(a, b);
                assert!((got - angle).abs() <= 1e-3 * angle + 2e-7, "{angle}: {got}");
            }
        }
        assert_eq!(rotation_angle(a, a), 0.0);
    }
}
