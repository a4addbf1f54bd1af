//! A small private track sampler (the exporter does not depend on the evaluator).
//!
//! Semantics are glTF 2.0's (§3.11 "Animations" and Appendix C "Interpolation"), the
//! model's own: before the first key the first value holds, after the last key the last;
//! STEP holds each key's value until the next key; LINEAR lerps vectors and slerps
//! rotations along the shortest arc; CUBICSPLINE is the cubic Hermite spline with tangents
//! scaled by the key interval, rotations normalized afterwards. At a key time the key's
//! value is returned exactly.
//!
//! Rotation keys are normalized and made sign-continuous first, cubic tangents flipping
//! with their value, exactly as the glTF exporter writes them, so a USD file and a glTF
//! file of one asset show the same motion. Arithmetic is scalar `f64`.

use rigport_model::{Interpolation, Track, TrackTarget};

/// A track prepared for sampling.
#[derive(Clone, Debug)]
pub(crate) struct Sampler {
    interpolation: Interpolation,
    times: Vec<f64>,
    /// Flat values in the track's layout (`[in, value, out]` per key for cubic splines).
    values: Vec<f64>,
    components: usize,
    rotation: bool,
}

impl Sampler {
    /// Prepares `track`, which must satisfy [`rigport_model::Asset::validate`] (value count
    /// matching the keys) with non-degenerate rotation keys.
    pub(crate) fn new(track: &Track) -> Self {
        let components = track.components();
        let rotation = matches!(track.target, TrackTarget::Rotation(_));
        let mut values: Vec<f64> = track.values.iter().map(|&v| f64::from(v)).collect();
        let cubic = track.interpolation == Interpolation::CubicSpline;
        if rotation {
            let (stride, offset) = if cubic { (12, 4) } else { (4, 0) };
            let mut previous: Option<[f64; 4]> = None;
            for key in values.chunks_exact_mut(stride) {
                let mut q = [
                    key[offset],
                    key[offset + 1],
                    key[offset + 2],
                    key[offset + 3],
                ];
                let len = dot(q, q).sqrt();
                if len > 0.0 {
                    q = q.map(|c| c / len);
                }
                let flip = previous.is_some_and(|p| dot(p, q) < 0.0);
                if flip {
                    q = q.map(|c| -c);
                    if cubic {
                        for k in (0..4).chain(8..12) {
                            key[k] = -key[k];
                        }
                    }
                }
                key[offset..offset + 4].copy_from_slice(&q);
                previous = Some(q);
            }
        }
        Self {
            interpolation: track.interpolation,
            times: track.times.iter().map(|&t| f64::from(t)).collect(),
            values,
            components,
            rotation,
        }
    }

    /// Floats per sampled value.
    #[cfg(test)]
    pub(crate) fn components(&self) -> usize {
        self.components
    }

    /// The value of key `k` (the middle element of a cubic key).
    fn key(&self, k: usize) -> &[f64] {
        let c = self.components;
        let start = match self.interpolation {
            Interpolation::CubicSpline => (3 * k + 1) * c,
            _ => k * c,
        };
        self.values.get(start..start + c).unwrap_or(&[])
    }

    /// Writes the value at `t` seconds into `out` (`components()` floats; a shorter `out`
    /// gets a prefix). A track without keys leaves `out` unchanged.
    pub(crate) fn sample(&self, t: f64, out: &mut [f64]) {
        let n = self.times.len();
        if n == 0 {
            return;
        }
        // Keys at or before t.
        let after = self.times.partition_point(|&k| k <= t);
        let copy = |out: &mut [f64], src: &[f64]| {
            for (o, s) in out.iter_mut().zip(src) {
                *o = *s;
            }
        };
        if after == 0 {
            return copy(out, self.key(0));
        }
        let i = after - 1;
        if after == n || self.times[i] == t || self.interpolation == Interpolation::Step {
            return copy(out, self.key(i));
        }
        let (t0, t1) = (self.times[i], self.times[i + 1]);
        let dt = t1 - t0;
        let s = (t - t0) / dt;
        let c = self.components;
        match self.interpolation {
            Interpolation::Step => copy(out, self.key(i)),
            Interpolation::Linear if self.rotation => {
                let (a, b) = (quat(self.key(i)), quat(self.key(i + 1)));
                copy(out, &slerp(a, b, s));
            }
            Interpolation::Linear => {
                let (a, b) = (self.key(i), self.key(i + 1));
                for (o, (x, y)) in out.iter_mut().zip(a.iter().zip(b)) {
                    *o = x + (y - x) * s;
                }
            }
            Interpolation::CubicSpline => {
                let (s2, s3) = (s * s, s * s * s);
                let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h10 = s3 - 2.0 * s2 + s;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = s3 - s2;
                let at = |k: usize, part: usize| {
                    let start = (3 * k + part) * c;
                    self.values.get(start..start + c).unwrap_or(&[])
                };
                // Key i's value and out-tangent, key i+1's in-tangent and value.
                let (v0, b0, a1, v1) = (at(i, 1), at(i, 2), at(i + 1, 0), at(i + 1, 1));
                for (k, o) in out.iter_mut().enumerate().take(c) {
                    let g = |v: &[f64]| v.get(k).copied().unwrap_or(0.0);
                    *o = h00 * g(v0) + h10 * dt * g(b0) + h01 * g(v1) + h11 * dt * g(a1);
                }
                if self.rotation && out.len() >= 4 {
                    let q = quat(out);
                    let len = dot(q, q).sqrt();
                    if len > 0.0 {
                        copy(out, &q.map(|x| x / len));
                    }
                }
            }
        }
    }
}

/// The first four floats as a quaternion (zeros when shorter).
fn quat(v: &[f64]) -> [f64; 4] {
    std::array::from_fn(|k| v.get(k).copied().unwrap_or(0.0))
}

/// Dot product of two quaternions.
pub(crate) fn dot(a: [f64; 4], b: [f64; 4]) -> f64 {
    a.iter().zip(&b).map(|(x, y)| x * y).sum()
}

/// Shortest-arc spherical interpolation of unit quaternions, `s` in `[0, 1]`.
///
/// The angle comes from `2·atan2(|b − a|, |b + a|)`, accurate at every angle (acos of the
/// dot product loses half the digits near 0); below 1e-9 rad, where the sine weights are
/// 0/0-prone, a normalized lerp is exact to f64 precision.
pub(crate) fn slerp(a: [f64; 4], b: [f64; 4], s: f64) -> [f64; 4] {
    let b = if dot(a, b) < 0.0 { b.map(|c| -c) } else { b };
    let diff: [f64; 4] = std::array::from_fn(|k| b[k] - a[k]);
    let sum: [f64; 4] = std::array::from_fn(|k| b[k] + a[k]);
    let half = dot(diff, diff).sqrt().atan2(dot(sum, sum).sqrt());
    let theta = 2.0 * half;
    let (wa, wb) = if theta < 1e-9 {
        (1.0 - s, s)
    } else {
        let sin = theta.sin();
        (((1.0 - s) * theta).sin() / sin, (s * theta).sin() / sin)
    };
    let q: [f64; 4] = std::array::from_fn(|k| wa * a[k] + wb * b[k]);
    let len = dot(q, q).sqrt();
    if len > 0.0 {
        q.map(|c| c / len)
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rigport_model::glam::Quat;
    use rigport_model::JointIndex;

    fn track(
        target: TrackTarget,
        interpolation: Interpolation,
        times: &[f32],
        values: &[f32],
    ) -> Track {
        Track {
            target,
            interpolation,
            times: times.to_vec(),
            values: values.to_vec(),
        }
    }

    fn at(s: &Sampler, t: f64) -> Vec<f64> {
        let mut out = vec![f64::NAN; s.components()];
        s.sample(t, &mut out);
        out
    }

    #[test]
    fn linear_step_and_clamping() {
        let tr = TrackTarget::Translation(JointIndex(0));
        let lin = Sampler::new(&track(
            tr,
            Interpolation::Linear,
            &[1.0, 3.0],
            &[0.0, 0.0, 0.0, 2.0, 4.0, 6.0],
        ));
        assert_eq!(at(&lin, 0.0), vec![0.0, 0.0, 0.0]);
        assert_eq!(at(&lin, 2.0), vec![1.0, 2.0, 3.0]);
        assert_eq!(at(&lin, 9.0), vec![2.0, 4.0, 6.0]);
        let step = Sampler::new(&track(
            tr,
            Interpolation::Step,
            &[0.0, 1.0],
            &[1.0, 1.0, 1.0, 5.0, 5.0, 5.0],
        ));
        assert_eq!(at(&step, 0.999), vec![1.0; 3]);
        assert_eq!(at(&step, 1.0), vec![5.0; 3]);
    }

    #[test]
    fn slerp_takes_the_short_arc_and_hits_keys() {
        let a = Quat::from_rotation_z(0.2);
        let b = -Quat::from_rotation_z(1.0); // stored with the other sign
        let rot = TrackTarget::Rotation(JointIndex(0));
        let values: Vec<f32> = [a, b * 3.0].iter().flat_map(|q| q.to_array()).collect();
        let s = Sampler::new(&track(rot, Interpolation::Linear, &[0.0, 1.0], &values));
        let mid = at(&s, 0.5);
        let expect = Quat::from_rotation_z(0.6);
        let sign = if mid[3] < 0.0 { -1.0 } else { 1.0 };
        for (k, e) in expect.to_array().iter().enumerate() {
            assert!((sign * mid[k] - f64::from(*e)).abs() < 1e-6, "{mid:?}");
        }
        // The second key comes back unit length and sign-continuous with the first.
        let end = at(&s, 1.0);
        assert!((dot(quat(&end), quat(&end)) - 1.0).abs() < 1e-12);
        assert!(dot(quat(&at(&s, 0.0)), quat(&end)) > 0.0);
        // Tiny angles: no 0/0.
        let q = slerp([0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1e-12, 1.0], 0.5);
        assert!(q.iter().all(|c| c.is_finite()));
    }

    #[test]
    fn cubic_hermite_matches_the_formula() {
        // One component (morph weight): keys (t=0: v=0, out=1), (t=2: in=0, v=1).
        let w = TrackTarget::MorphWeights(rigport_model::MeshIndex(0));
        let s = Sampler::new(&track(
            w,
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &[9.0, 0.0, 1.0, 0.0, 1.0, 9.0],
        ));
        assert_eq!(s.components(), 1);
        let t = 0.5_f64;
        let u = t / 2.0;
        let expect = (u * u * u - 2.0 * u * u + u) * 2.0 * 1.0 + (-2.0 * u * u * u + 3.0 * u * u);
        assert!((at(&s, t)[0] - expect).abs() < 1e-12);
        assert_eq!(at(&s, 2.0), vec![1.0]);
        assert_eq!(at(&s, 0.0), vec![0.0]);
    }
}
