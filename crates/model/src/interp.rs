//! Keyframe interpolation, defined once: where a time falls among a track's keys and the
//! value there, per glTF 2.0 (§3.11 "Animations", Appendix C "Interpolation"), the model's
//! own semantics. The evaluator samples in `f32` ([`Keys`] over a [`Track`]'s own
//! arrays), the USD writer in `f64`; both run this code.
//!
//! - Before the first key the first value holds, after the last key the last.
//! - STEP holds each key's value until the next key.
//! - LINEAR lerps components (`a + (b − a)·u`) and slerps rotations along the shortest arc.
//! - CUBICSPLINE is the cubic Hermite spline with tangents scaled by the key interval;
//!   rotations are normalized afterwards.
//! - Rotations come out unit length ([`unit()`]).
//!
//! The arithmetic is written out in one order for both precisions, the order glam's SSE2
//! quaternions use on x86-64 (a dot product is `(x·x' + z·z') + (y·y' + w·w')`), so the
//! evaluator's results are bit for bit those of its former glam code.
//!
//! ```
//! use rigport_model::interp::Keys;
//! use rigport_model::Interpolation;
//!
//! let keys = Keys { interpolation: Interpolation::Linear, times: &[0.0f64, 2.0], values: &[1.0, 3.0], components: 1 };
//! let mut out = [0.0];
//! keys.sample(1.0, &mut out);
//! assert_eq!(out, [2.0]);
//! keys.sample(-5.0, &mut out);
//! assert_eq!(out, [1.0]);
//! ```

use std::ops::{Add, Div, Mul, Neg, Sub};

use crate::{Interpolation, Track};

/// The floating-point types keys are sampled in: `f32` and `f64`.
pub trait Real:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// 2.
    const TWO: Self;
    /// 3.
    const THREE: Self;
    /// Below this `sin θ`, [`slerp`] lerps (the quaternions are within float noise).
    const SLERP_LERP_BELOW: Self;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Sine.
    fn sin(self) -> Self;
    /// Four-quadrant arc tangent of `self / x`.
    fn atan2(self, x: Self) -> Self;
    /// Neither infinite nor NaN.
    fn is_finite(self) -> bool;
    /// From a key time or value.
    fn from_f32(v: f32) -> Self;
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const TWO: Self = 2.0;
    const THREE: Self = 3.0;
    const SLERP_LERP_BELOW: Self = 1e-6;
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    fn sin(self) -> Self {
        f32::sin(self)
    }
    fn atan2(self, x: Self) -> Self {
        f32::atan2(self, x)
    }
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    fn from_f32(v: f32) -> Self {
        v
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const TWO: Self = 2.0;
    const THREE: Self = 3.0;
    const SLERP_LERP_BELOW: Self = 1e-6;
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn sin(self) -> Self {
        f64::sin(self)
    }
    fn atan2(self, x: Self) -> Self {
        f64::atan2(self, x)
    }
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
    fn from_f32(v: f32) -> Self {
        f64::from(v)
    }
}

/// Where a time falls among a track's keys.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Span<T> {
    /// Exactly the value of key `k` (before the first key, after the last, or a STEP hold
    /// decided later).
    Key(usize),
    /// Between keys `k` and `k + 1`: `u` in `[0, 1]` is the normalized position, `dt` the
    /// interval in seconds (the tangent scale of glTF's cubic spline).
    Between {
        /// The key before.
        k: usize,
        /// The normalized position.
        u: T,
        /// The key interval.
        dt: T,
    },
}

/// Finds the key interval holding `time` by binary search (`times` increasing).
pub fn locate<T: Real>(times: &[T], time: T) -> Span<T> {
    let after = times.partition_point(|&t| t <= time);
    if after == 0 {
        return Span::Key(0);
    }
    let k = after - 1;
    match (times.get(k), times.get(after)) {
        (Some(&t0), Some(&t1)) if t1 > t0 => {
            let u = (time - t0) / (t1 - t0);
            // Clamped to [0, 1] (NaN stays NaN, as `f32::clamp`).
            let u = if u < T::ZERO {
                T::ZERO
            } else if u > T::ONE {
                T::ONE
            } else {
                u
            };
            Span::Between { k, u, dt: t1 - t0 }
        }
        _ => Span::Key(k),
    }
}

/// The cubic Hermite spline of glTF 2.0 Appendix C, with tangents already scaled by the
/// key interval: `p(u) = (2u³-3u²+1)·v0 + (u³-2u²+u)·m0 + (-2u³+3u²)·v1 + (u³-u²)·m1`.
pub fn hermite<T: Real>(v0: T, m0: T, v1: T, m1: T, u: T) -> T {
    let u2 = u * u;
    let u3 = u2 * u;
    (T::TWO * u3 - T::THREE * u2 + T::ONE) * v0
        + (u3 - T::TWO * u2 + u) * m0
        + (-T::TWO * u3 + T::THREE * u2) * v1
        + (u3 - u2) * m1
}

/// Dot product of two quaternions (xyzw), summed as `(x·x' + z·z') + (y·y' + w·w')`.
pub fn dot<T: Real>(a: [T; 4], b: [T; 4]) -> T {
    (a[0] * b[0] + a[2] * b[2]) + (a[1] * b[1] + a[3] * b[3])
}

/// `q / |q|` (as `q · (1/|q|)`), or the identity for a zero or non-finite `q` (which valid
/// keys never give, but a cubic spline's interpolated value could in principle pass
/// through zero).
pub fn unit<T: Real>(q: [T; 4]) -> [T; 4] {
    let length = dot(q, q).sqrt();
    if length > T::ZERO && length.is_finite() {
        let inv = T::ONE / length;
        q.map(|c| c * inv)
    } else {
        [T::ZERO, T::ZERO, T::ZERO, T::ONE]
    }
}

/// Shortest-path spherical linear interpolation between unit quaternions, normalized
/// (glTF 2.0 Appendix C, "Spherical Linear Interpolation").
///
/// The angle comes from Kahan's `2·atan2(|a−b|, |a+b|)`, which stays accurate for nearly
/// equal quaternions where `acos(dot)` loses digits; below [`Real::SLERP_LERP_BELOW`] the
/// quaternions are lerped (exact to O(θ³)).
pub fn slerp<T: Real>(a: [T; 4], b: [T; 4], u: T) -> [T; 4] {
    let b = if dot(a, b) < T::ZERO {
        b.map(|c| -c)
    } else {
        b
    };
    let diff: [T; 4] = std::array::from_fn(|k| a[k] - b[k]);
    let sum: [T; 4] = std::array::from_fn(|k| a[k] + b[k]);
    let theta = T::TWO * dot(diff, diff).sqrt().atan2(dot(sum, sum).sqrt());
    let sin_theta = theta.sin();
    if sin_theta < T::SLERP_LERP_BELOW {
        return unit(std::array::from_fn(|k| a[k] + (b[k] - a[k]) * u));
    }
    let wa = ((T::ONE - u) * theta).sin() / sin_theta;
    let wb = (u * theta).sin() / sin_theta;
    unit(std::array::from_fn(|k| a[k] * wa + b[k] * wb))
}

/// The in-tangent slot of a cubic-spline key (glTF: `[in_tangent, value, out_tangent]`).
pub const IN_TANGENT: usize = 0;
/// The value slot of a key (the middle one of a cubic-spline key).
pub const VALUE: usize = 1;
/// The out-tangent slot of a cubic-spline key.
pub const OUT_TANGENT: usize = 2;

/// A track's keys in one precision: flat values in the track's layout (`[in, value, out]`
/// per key for cubic splines), `components` floats per value.
#[derive(Clone, Copy, Debug)]
pub struct Keys<'a, T> {
    /// How values between keys are found.
    pub interpolation: Interpolation,
    /// Key times in seconds, strictly increasing.
    pub times: &'a [T],
    /// The values.
    pub values: &'a [T],
    /// Floats per value.
    pub components: usize,
}

impl<'a> Keys<'a, f32> {
    /// A track's own keys.
    pub fn of(track: &'a Track) -> Self {
        Self {
            interpolation: track.interpolation,
            times: &track.times,
            values: &track.values,
            components: track.components(),
        }
    }
}

impl Keys<'_, f32> {
    /// A rotation track (xyzw keys) at `time` as a viewer composes it: the keys as stored,
    /// not normalized. 16-bit normalized keys (and meshopt's quaternion filter) are up to
    /// about 3e-5 off unit length, and three.js builds the joint's matrix from them as
    /// they are, scaled by the squared length, except where its slerp normalizes. Before
    /// the first key, from the last, and for STEP: the stored key; LINEAR elsewhere, on a
    /// key too: three.js's `Quaternion.slerpFlat` of the stored keys ([`slerp_flat`]), from
    /// a key to the next; CUBICSPLINE: normalized, as three.js's glTF loader normalizes its
    /// cubic rotations.
    ///
    /// ```
    /// use rigport_model::interp::Keys;
    /// use rigport_model::Interpolation;
    /// // Keys 90 degrees apart, the first 2e-5 too long: three.js slerps them as stored.
    /// let (a, b) = ([0.0f32, 0.0, 0.0, 1.00002], [0.0, 0.70711, 0.0, 0.70711]);
    /// let values = [a, b].concat();
    /// let keys = Keys { interpolation: Interpolation::Linear, times: &[0.0, 1.0], values: &values, components: 4 };
    /// assert_eq!(keys.sample_rotation_as_stored(0.0), a);
    /// let mid = keys.sample_rotation_as_stored(0.5);
    /// let length = mid.iter().map(|c| c * c).sum::<f32>().sqrt();
    /// assert!((length - 1.0).abs() > 1e-6, "{length}");
    /// // Keys close together: it lerps and normalizes, on the first key too.
    /// let near = [a, [0.0, 0.01, 0.0, 0.99995]].concat();
    /// let keys = Keys { values: &near, ..keys };
    /// let first = keys.sample_rotation_as_stored(0.0);
    /// assert!((first.iter().map(|c| c * c).sum::<f32>().sqrt() - 1.0).abs() < 1e-6);
    /// ```
    pub fn sample_rotation_as_stored(&self, time: f32) -> [f32; 4] {
        let wide = |q: [f32; 4]| q.map(f64::from);
        let last = self.times.len().saturating_sub(1);
        match (locate(self.times, time), self.interpolation) {
            // three.js's interpolant holds the stored key before the first and from the last.
            (Span::Key(k), _) if k == last || time < self.times[0] => self.quat_key(k, VALUE),
            // On a key it interpolates from that key to the next at 0.
            (Span::Key(k), Interpolation::Linear) => {
                let (a, b) = (self.quat_key(k, VALUE), self.quat_key(k + 1, VALUE));
                slerp_flat(wide(a), wide(b), 0.0).map(|c| c as f32)
            }
            (Span::Key(k), _) | (Span::Between { k, .. }, Interpolation::Step) => {
                self.quat_key(k, VALUE)
            }
            (Span::Between { k, u, .. }, Interpolation::Linear) => {
                let (a, b) = (self.quat_key(k, VALUE), self.quat_key(k + 1, VALUE));
                slerp_flat(wide(a), wide(b), f64::from(u)).map(|c| c as f32)
            }
            (span @ Span::Between { .. }, Interpolation::CubicSpline) => {
                unit(std::array::from_fn(|i| self.sample_component(span, i)))
            }
        }
    }
}

/// three.js's `Quaternion.slerpFlat` (r187), which its animation mixer applies to stored
/// keys, step for step, for [`Keys::sample_rotation_as_stored`]: `a` when the keys are
/// equal; else the shorter way, a slerp on `acos` of the (not necessarily unit) keys' dot
/// product, unnormalized, when that is under 0.9995, and a lerp, normalized, above it (so
/// at `t = 0` too).
pub fn slerp_flat(a: [f64; 4], b: [f64; 4], t: f64) -> [f64; 4] {
    if a == b {
        return a;
    }
    let mut dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    let b = if dot < 0.0 {
        dot = -dot;
        b.map(|c| -c)
    } else {
        b
    };
    let s = 1.0 - t;
    if dot < 0.9995 {
        let theta = dot.acos();
        let sin = theta.sin();
        let (ws, wt) = ((s * theta).sin() / sin, (t * theta).sin() / sin);
        std::array::from_fn(|i| a[i] * ws + b[i] * wt)
    } else {
        let out: [f64; 4] = std::array::from_fn(|i| a[i] * s + b[i] * t);
        let f = 1.0 / out.iter().map(|c| c * c).sum::<f64>().sqrt();
        out.map(|c| c * f)
    }
}

impl<T: Real> Keys<'_, T> {
    /// Component `c` of element `element` (a cubic-spline slot; ignored otherwise) of key
    /// `k`, 0 if out of range (only for unchecked tracks).
    pub fn component(&self, k: usize, element: usize, c: usize) -> T {
        let slot = match self.interpolation {
            Interpolation::CubicSpline => 3 * k + element,
            _ => k,
        };
        (self.values)
            .get(slot * self.components + c)
            .copied()
            .unwrap_or(T::ZERO)
    }

    /// Component `c` at `span`.
    pub fn sample_component(&self, span: Span<T>, c: usize) -> T {
        let at = |k, element| self.component(k, element, c);
        match span {
            Span::Key(k) => at(k, VALUE),
            Span::Between { k, u, dt } => match self.interpolation {
                Interpolation::Step => at(k, VALUE),
                Interpolation::Linear => {
                    let (a, b) = (at(k, VALUE), at(k + 1, VALUE));
                    a + (b - a) * u
                }
                Interpolation::CubicSpline => hermite(
                    at(k, VALUE),
                    dt * at(k, OUT_TANGENT),
                    at(k + 1, VALUE),
                    dt * at(k + 1, IN_TANGENT),
                    u,
                ),
            },
        }
    }

    /// Writes the components at `time` into `out` (one per component; a shorter `out` gets
    /// a prefix). Nothing is normalized.
    pub fn sample(&self, time: T, out: &mut [T]) {
        let span = locate(self.times, time);
        for (c, o) in out.iter_mut().enumerate().take(self.components) {
            *o = self.sample_component(span, c);
        }
    }

    /// Element `element` of rotation key `k` as a (not necessarily unit) quaternion.
    pub fn quat_key(&self, k: usize, element: usize) -> [T; 4] {
        std::array::from_fn(|i| self.component(k, element, i))
    }

    /// A rotation track (xyzw keys) at `time`, unit length.
    pub fn sample_rotation(&self, time: T) -> [T; 4] {
        match (locate(self.times, time), self.interpolation) {
            (Span::Key(k), _) | (Span::Between { k, .. }, Interpolation::Step) => {
                unit(self.quat_key(k, VALUE))
            }
            (Span::Between { k, u, .. }, Interpolation::Linear) => slerp(
                unit(self.quat_key(k, VALUE)),
                unit(self.quat_key(k + 1, VALUE)),
                u,
            ),
            (span @ Span::Between { .. }, Interpolation::CubicSpline) => {
                unit(std::array::from_fn(|i| self.sample_component(span, i)))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    /// The evaluator's former glam code, kept as the reference the f32 path must match bit
    /// for bit.
    fn glam_unit(q: Quat) -> Quat {
        let length = q.length();
        if length > 0.0 && length.is_finite() {
            q * (1.0 / length)
        } else {
            Quat::IDENTITY
        }
    }

    fn glam_slerp(a: Quat, b: Quat, u: f32) -> Quat {
        let b = if a.dot(b) < 0.0 { -b } else { b };
        let theta = 2.0 * (a - b).length().atan2((a + b).length());
        let sin_theta = theta.sin();
        if sin_theta < 1e-6 {
            return glam_unit(a + (b - a) * u);
        }
        let wa = ((1.0 - u) * theta).sin() / sin_theta;
        let wb = (u * theta).sin() / sin_theta;
        glam_unit(a * wa + b * wb)
    }

    #[test]
    fn f32_unit_and_slerp_are_glams_bit_for_bit() {
        // A small deterministic generator (no dependency): xorshift.
        let mut state = 0x9E37_79B9_7F4A_7C15_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        for _ in 0..20_000 {
            let a = Quat::from_xyzw(next(), next(), next(), next());
            let b = Quat::from_xyzw(next(), next(), next(), next());
            let near = Quat::from_xyzw(a.x + next() * 1e-7, a.y, a.z, a.w);
            let u = next().abs();
            assert_eq!(unit(a.to_array()), glam_unit(a).to_array());
            assert_eq!(dot(a.to_array(), b.to_array()), a.dot(b));
            let (ua, ub, un) = (glam_unit(a), glam_unit(b), glam_unit(near));
            let ours = slerp(ua.to_array(), ub.to_array(), u);
            assert_eq!(ours, glam_slerp(ua, ub, u).to_array());
            let ours = slerp(ua.to_array(), un.to_array(), u);
            assert_eq!(ours, glam_slerp(ua, un, u).to_array());
        }
    }

    #[test]
    fn cubic_keys_hit_values_and_follow_hermite() {
        let keys = Keys {
            interpolation: Interpolation::CubicSpline,
            times: &[0.0f64, 2.0],
            values: &[9.0, 0.0, 1.0, 0.0, 1.0, 9.0],
            components: 1,
        };
        let mut out = [f64::NAN];
        keys.sample(2.0, &mut out);
        assert_eq!(out, [1.0]);
        keys.sample(0.5, &mut out);
        let u = 0.25;
        let expect = (u * u * u - 2.0 * u * u + u) * 2.0 + (-2.0 * u * u * u + 3.0 * u * u);
        assert!((out[0] - expect).abs() < 1e-12);
    }
}
