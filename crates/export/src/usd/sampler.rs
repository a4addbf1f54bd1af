//! The USD writer's view of a track: its keys in `f64`, sampled by the one keyframe
//! interpolation of `rigport_model::interp` (the evaluator's, in `f64`).
//!
//! Rotation keys are normalized and made sign-continuous first, cubic tangents flipping
//! with their value, exactly as the glTF exporter writes them, so a USD file and a glTF
//! file of one asset show the same motion.

use rigport_model::interp::Keys;
use rigport_model::{Interpolation, Track, TrackTarget};

/// A track prepared for sampling. It borrows the track's `f32` keys and converts the one or
/// two keys around a sample time to `f64` when sampling, so a clip of millions of keys
/// costs one flag per rotation key, not a second copy of its keys.
#[derive(Clone, Debug)]
pub(crate) struct Sampler<'a> {
    track: &'a Track,
    components: usize,
    rotation: bool,
    /// Per rotation key: whether its normalized quaternion (and its tangents) is negated to
    /// be sign-continuous with the key before. Empty for other tracks.
    flipped: Vec<bool>,
}

impl<'a> Sampler<'a> {
    /// Prepares `track`, which must satisfy [`rigport_model::Asset::validate`] (value count
    /// matching the keys) with non-degenerate rotation keys.
    pub(crate) fn new(track: &'a Track) -> Self {
        let components = track.components();
        let rotation = matches!(track.target, TrackTarget::Rotation(_));
        let mut flipped = Vec::new();
        if rotation {
            flipped.reserve_exact(track.times.len());
            let mut previous: Option<[f64; 4]> = None;
            for k in 0..track.times.len() {
                let q = key_quat(track, k);
                let flip = previous.is_some_and(|p| dot(p, q) < 0.0);
                flipped.push(flip);
                previous = Some(if flip { q.map(|c| -c) } else { q });
            }
        }
        Self {
            track,
            components,
            rotation,
            flipped,
        }
    }

    /// Floats per sampled value.
    #[cfg(test)]
    pub(crate) fn components(&self) -> usize {
        self.components
    }

    /// Writes the value at `t` seconds into `out` (`components()` floats; a shorter `out`
    /// gets a prefix). A track without keys leaves `out` unchanged.
    pub(crate) fn sample(&self, t: f64, out: &mut [f64]) {
        let track_times = &self.track.times;
        if track_times.is_empty() {
            return;
        }
        // The keys around `t`: the span `locate` finds depends on these alone (one key
        // before the first or after the last).
        let after = track_times.partition_point(|&x| f64::from(x) <= t);
        let first = after.saturating_sub(1);
        let last = after.min(track_times.len() - 1);
        let times = [f64::from(track_times[first]), f64::from(track_times[last])];
        let mut values = Vec::with_capacity(2 * self.stride());
        for k in first..=last {
            self.push_key(k, &mut values);
        }
        let keys = Keys {
            interpolation: self.track.interpolation,
            times: &times[..=last - first],
            values: &values,
            components: self.components,
        };
        if self.rotation {
            let q = keys.sample_rotation(t);
            for (o, c) in out.iter_mut().zip(q) {
                *o = c;
            }
        } else {
            keys.sample(t, out);
        }
    }

    /// Floats per key in the track's layout.
    fn stride(&self) -> usize {
        match self.track.interpolation {
            Interpolation::CubicSpline => 3 * self.components,
            _ => self.components,
        }
    }

    /// Appends key `k`'s floats in `f64` in the track's layout (`[in, value, out]` for
    /// cubic splines) to `out`, a rotation normalized and sign-continuous, its tangents
    /// flipped with it.
    fn push_key(&self, k: usize, out: &mut Vec<f64>) {
        let stride = self.stride();
        let start = out.len();
        out.extend(
            (self.track.values)
                .get(k * stride..(k + 1) * stride)
                .unwrap_or_default()
                .iter()
                .map(|&v| f64::from(v)),
        );
        let key = &mut out[start..];
        if self.rotation && key.len() == stride {
            let cubic = self.track.interpolation == Interpolation::CubicSpline;
            let offset = if cubic { 4 } else { 0 };
            let mut q = key_quat(self.track, k);
            if self.flipped.get(k).copied().unwrap_or(false) {
                q = q.map(|x| -x);
                if cubic {
                    for i in (0..4).chain(8..12) {
                        key[i] = -key[i];
                    }
                }
            }
            key[offset..offset + 4].copy_from_slice(&q);
        }
    }
}

/// Rotation key `k`'s value (xyzw) in `f64`, normalized (as is, when of zero length).
fn key_quat(track: &Track, k: usize) -> [f64; 4] {
    let cubic = track.interpolation == Interpolation::CubicSpline;
    let (stride, offset) = if cubic { (12, 4) } else { (4, 0) };
    let at = |i: usize| {
        (track.values)
            .get(k * stride + offset + i)
            .map_or(0.0, |&v| f64::from(v))
    };
    let q = [at(0), at(1), at(2), at(3)];
    let len = dot(q, q).sqrt();
    if len > 0.0 {
        q.map(|c| c / len)
    } else {
        q
    }
}

/// Dot product of two quaternions.
pub(crate) fn dot(a: [f64; 4], b: [f64; 4]) -> f64 {
    a.iter().zip(&b).map(|(x, y)| x * y).sum()
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

    /// The first four floats as a quaternion.
    fn quat(v: &[f64]) -> [f64; 4] {
        std::array::from_fn(|k| v[k])
    }

    fn at(s: &Sampler, t: f64) -> Vec<f64> {
        let mut out = vec![f64::NAN; s.components()];
        s.sample(t, &mut out);
        out
    }

    #[test]
    fn linear_step_and_clamping() {
        let tr = TrackTarget::Translation(JointIndex(0));
        let lin_track = track(
            tr,
            Interpolation::Linear,
            &[1.0, 3.0],
            &[0.0, 0.0, 0.0, 2.0, 4.0, 6.0],
        );
        let lin = Sampler::new(&lin_track);
        assert_eq!(at(&lin, 0.0), vec![0.0, 0.0, 0.0]);
        assert_eq!(at(&lin, 2.0), vec![1.0, 2.0, 3.0]);
        assert_eq!(at(&lin, 9.0), vec![2.0, 4.0, 6.0]);
        let step_track = track(
            tr,
            Interpolation::Step,
            &[0.0, 1.0],
            &[1.0, 1.0, 1.0, 5.0, 5.0, 5.0],
        );
        let step = Sampler::new(&step_track);
        assert_eq!(at(&step, 0.999), vec![1.0; 3]);
        assert_eq!(at(&step, 1.0), vec![5.0; 3]);
    }

    #[test]
    fn slerp_takes_the_short_arc_and_hits_keys() {
        let a = Quat::from_rotation_z(0.2);
        let b = -Quat::from_rotation_z(1.0); // stored with the other sign
        let rot = TrackTarget::Rotation(JointIndex(0));
        let values: Vec<f32> = [a, b * 3.0].iter().flat_map(|q| q.to_array()).collect();
        let s_track = track(rot, Interpolation::Linear, &[0.0, 1.0], &values);
        let s = Sampler::new(&s_track);
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
        let q: [f64; 4] =
            rigport_model::interp::slerp([0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1e-12, 1.0], 0.5);
        assert!(q.iter().all(|c| c.is_finite()));
    }

    #[test]
    fn cubic_hermite_matches_the_formula() {
        // One component (morph weight): keys (t=0: v=0, out=1), (t=2: in=0, v=1).
        let w = TrackTarget::MorphWeights(rigport_model::MeshIndex(0));
        let s_track = track(
            w,
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &[9.0, 0.0, 1.0, 0.0, 1.0, 9.0],
        );
        let s = Sampler::new(&s_track);
        assert_eq!(s.components(), 1);
        let t = 0.5_f64;
        let u = t / 2.0;
        let expect = (u * u * u - 2.0 * u * u + u) * 2.0 * 1.0 + (-2.0 * u * u * u + 3.0 * u * u);
        assert!((at(&s, t)[0] - expect).abs() < 1e-12);
        assert_eq!(at(&s, 2.0), vec![1.0]);
        assert_eq!(at(&s, 0.0), vec![0.0]);
    }
}
