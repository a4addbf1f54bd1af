//! Step 2's cubic representation: a CUBICSPLINE track (glTF 2.0 Appendix C) whose keys sit
//! at original key times, each with the original value and Hermite tangents fitted to the
//! original keys between it and its neighbours.
//!
//! Linear interpolation between keys `h` apart errs by about `h² |f''| / 8`, a cubic Hermite
//! with good tangents by about `h⁴ |f''''| / 384`: on smooth motion a cubic key covers
//! several times as many source frames, which pays for its three values (in-tangent, value,
//! out-tangent). glTF gives every key an in- and an out-tangent, so each segment's two
//! tangents are free: they are solved per segment by least squares over the original keys
//! inside it (values fixed at the ends), and a segment grows while its worst key stays
//! within the channel's tolerance.
//!
//! A reader evaluates a cubic rotation component by component with tangents scaled by the
//! key interval, then normalizes (three.js `GLTFCubicSplineQuaternionInterpolant`, glTF 2.0
//! Appendix C); the fit measures the same, on the values as the writer stores them
//! ([`cubic_as_written`](super::codec::cubic_as_written)). Consecutive key values keep a positive dot product, so the
//! writer's sign continuity never flips a key (flipping one key's value and tangents
//! changes the segments on both sides of it).

use glam::Vec4;
use rigport_model::quantize::component_as_i16;
use rigport_model::{Interpolation, Track};

use super::channel::{Channel, Kind};
use super::codec::cubic_as_written;
use super::codec::Codec;
use super::curve::{hermite, quat_at, sample_quat, sample_vec3};
use super::rate::{ladder, uniform_keys, CUBIC_SAMPLER_JSON, MAX_STEP, TIME_ACCESSOR_JSON};

/// A fitted cubic track: the original keys it keeps and the track as handed to the writer.
pub(super) struct CubicFit {
    /// Indices of the kept keys in the original track, increasing, first and last included.
    pub(super) kept: Vec<usize>,
    /// The CUBICSPLINE track (values before the writer's codec).
    pub(super) track: Track,
}

/// How the fit rounds what it writes while it grows segments.
#[derive(Clone, Copy)]
enum Rounding {
    /// Exact floats.
    Exact,
    /// Rotation components as 16-bit normalized integers, tangents clamped into `[-1, 1]`.
    I16,
    /// Translations and scales through the codec's vector rounding.
    Vector(fn([f32; 3]) -> [f32; 3]),
}

impl Rounding {
    fn apply(self, v: Vec4) -> Vec4 {
        match self {
            Rounding::Exact => v,
            Rounding::I16 => Vec4::from_array(v.to_array().map(component_as_i16)),
            Rounding::Vector(f) => glam::Vec3::from(f(v.truncate().to_array())).extend(0.0),
        }
    }

    fn clamp(self, v: Vec4) -> Vec4 {
        match self {
            Rounding::I16 => v.clamp(Vec4::splat(-1.0), Vec4::splat(1.0)),
            _ => v,
        }
    }
}

/// One channel's original keys as the fit reads them.
struct Samples<'a> {
    times: &'a [f32],
    /// Values (rotations sign-aligned to their predecessor, unit length; vectors with w 0).
    y: Vec<Vec4>,
    rotation: bool,
    /// The tolerance in the units compared: a chord `2 sin(θ/4)` for rotations, a distance
    /// otherwise.
    limit: f32,
}

impl<'a> Samples<'a> {
    fn new(chan: &'a Channel) -> Self {
        let track = chan.original;
        let rotation = chan.kind == Kind::Rotation;
        let mut y: Vec<Vec4> = if rotation {
            (0..track.times.len())
                .map(|k| Vec4::from(quat_at(&track.values, 4 * k)))
                .collect()
        } else {
            track
                .values
                .chunks_exact(3)
                .map(|c| Vec4::new(c[0], c[1], c[2], 0.0))
                .collect()
        };
        if rotation {
            for k in 1..y.len() {
                if y[k].dot(y[k - 1]) < 0.0 {
                    y[k] = -y[k];
                }
            }
        }
        let limit = if rotation {
            2.0 * (chan.eps.min(std::f32::consts::TAU) / 4.0).sin()
        } else {
            chan.eps
        };
        Self {
            times: &track.times,
            y,
            rotation,
            limit,
        }
    }

    /// The error of key `k`'s reconstruction `v`.
    fn error(&self, k: usize, v: Vec4) -> f32 {
        let o = self.y[k];
        if self.rotation {
            let q = v.normalize();
            (q - o).length().min((q + o).length())
        } else {
            (v - o).length()
        }
    }

    /// The out-tangent at `a` and in-tangent at `b` (units per second) of a segment from
    /// key `a` to key `b` that reproduces every key between within the limit, as rounded.
    fn segment(&self, a: usize, b: usize, rounding: Rounding) -> Option<(Vec4, Vec4)> {
        let (p0, p1) = (self.y[a], self.y[b]);
        if self.rotation && b > a + 1 && p0.dot(p1) <= 1e-3 {
            return None;
        }
        let (ta, tb) = (self.times[a], self.times[b]);
        let dt = tb - ta;
        let chord = (p1 - p0) / dt;
        // Least squares on the Hermite basis with the values fixed, a light pull towards the
        // chord's slope keeping the 2x2 system regular when a segment has one inner key.
        let ridge = 1e-4 * dt * dt;
        let (mut s00, mut s01, mut s11) = (ridge, 0.0f32, ridge);
        let (mut r0, mut r1) = (chord * ridge, chord * ridge);
        for k in a + 1..b {
            let [h00, h10, h01, h11] = hermite((self.times[k] - ta) / dt);
            let (c0, c1) = (h10 * dt, h11 * dt);
            let residual = self.y[k] - p0 * h00 - p1 * h01;
            s00 += c0 * c0;
            s01 += c0 * c1;
            s11 += c1 * c1;
            r0 += residual * c0;
            r1 += residual * c1;
        }
        let det = s00 * s11 - s01 * s01;
        let (m0, m1) = if b == a + 1 || det.abs() <= f32::EPSILON * s00 * s11 {
            (chord, chord)
        } else {
            ((r0 * s11 - r1 * s01) / det, (r1 * s00 - r0 * s01) / det)
        };
        let (m0, m1) = (rounding.clamp(m0), rounding.clamp(m1));
        let [q0, q1, n0, n1] = [p0, p1, m0, m1].map(|v| rounding.apply(v));
        for k in a + 1..b {
            let [h00, h10, h01, h11] = hermite((self.times[k] - ta) / dt);
            let v = q0 * h00 + n0 * (dt * h10) + q1 * h01 + n1 * (dt * h11);
            // NaN (a degenerate segment) fails too.
            let e = self.error(k, v);
            if e.is_nan() || e > self.limit {
                return None;
            }
        }
        Some((m0, m1))
    }

    /// Keys at `keys` (increasing, first and last of the track) with fitted tangents, or
    /// `None` when a segment does not fit.
    fn with_keys(&self, keys: &[usize], rounding: Rounding) -> Option<Vec<(Vec4, Vec4)>> {
        keys.windows(2)
            .map(|w| self.segment(w[0], w[1], rounding))
            .collect()
    }

    /// Greedy segments: from each key, the farthest next key that fits (doubling, then
    /// bisecting: the error grows with the segment, nearly always monotonically).
    fn adaptive(&self, rounding: Rounding) -> (Vec<usize>, Vec<(Vec4, Vec4)>) {
        let n = self.y.len();
        let mut keys = vec![0];
        let mut tangents = Vec::new();
        let mut a = 0;
        while a + 1 < n {
            let chord = (self.y[a + 1] - self.y[a]) / (self.times[a + 1] - self.times[a]);
            let mut good = (a + 1, (chord, chord));
            let mut bad = None;
            let mut step = 2;
            while bad.is_none() && good.0 + 1 < n {
                let b = (a + step).min(n - 1);
                match self.segment(a, b, rounding) {
                    Some(t) => good = (b, t),
                    None => bad = Some(b),
                }
                step *= 2;
            }
            if let Some(mut hi) = bad {
                while hi > good.0 + 1 {
                    let mid = (good.0 + hi) / 2;
                    match self.segment(a, mid, rounding) {
                        Some(t) => good = (mid, t),
                        None => hi = mid,
                    }
                }
            }
            keys.push(good.0);
            tangents.push(good.1);
            a = good.0;
        }
        (keys, tangents)
    }

    /// The CUBICSPLINE track with `keys` and per-segment `tangents`; the first in-tangent
    /// and the last out-tangent, which no segment uses, are zero.
    fn track(&self, chan: &Channel, keys: &[usize], tangents: &[(Vec4, Vec4)]) -> Track {
        let comps = if self.rotation { 4 } else { 3 };
        let mut values = Vec::with_capacity(keys.len() * 3 * comps);
        for (i, &k) in keys.iter().enumerate() {
            let in_t = if i == 0 {
                Vec4::ZERO
            } else {
                tangents[i - 1].1
            };
            let out_t = tangents.get(i).map_or(Vec4::ZERO, |t| t.0);
            for v in [in_t, self.y[k], out_t] {
                values.extend_from_slice(&v.to_array()[..comps]);
            }
        }
        Track {
            target: chan.original.target,
            interpolation: Interpolation::CubicSpline,
            times: keys.iter().map(|&k| self.times[k]).collect(),
            values,
        }
    }

    /// Whether `written` (a cubic track as a reader gets it) reproduces every original key
    /// within the limit, as the reducer samples it, with consecutive values not opposed.
    fn fits(&self, written: &Track) -> bool {
        let stride = if self.rotation { 12 } else { 9 };
        let comps = stride / 3;
        let value = |k: usize| {
            let v = &written.values[k * stride + comps..k * stride + 2 * comps];
            Vec4::new(v[0], v[1], v[2], v.get(3).copied().unwrap_or(0.0))
        };
        if self.rotation && (1..written.times.len()).any(|k| value(k).dot(value(k - 1)) < 0.0) {
            return false;
        }
        let mut cursor = 0;
        self.times.iter().enumerate().all(|(k, &t)| {
            let v = if self.rotation {
                Vec4::from(sample_quat(written, t, &mut cursor))
            } else {
                sample_vec3(written, t, &mut cursor).extend(0.0)
            };
            self.error(k, v) <= self.limit
        })
    }
}

/// Bytes of a cubic track's outputs as written: 16-bit rotations when
/// [`cubic_as_written`] rounds them, floats otherwise.
fn output_bytes(track: &Track, kind: Kind, codec: Option<&Codec>) -> usize {
    let short =
        kind == Kind::Rotation && codec.is_some() && track.values.iter().all(|v| v.abs() <= 1.0);
    track.values.len() * if short { 2 } else { 4 }
}

/// The fewest-bytes cubic fit of `chan` within its tolerance whose bytes (its time
/// accessor counted unless `uniform`, and its sampler's interpolation) are under `budget`: adaptive keys, or every `k`-th key
/// (sharing times with other channels of the same rate). `None` when none is smaller.
pub(super) fn fit_cubic(chan: &Channel, budget: usize) -> Option<(CubicFit, bool)> {
    let n = chan.original.times.len();
    if n <= 2 {
        return None;
    }
    let samples = Samples::new(chan);
    let codec = chan.codec.as_ref();
    let roundings: &[Rounding] = match (chan.kind, codec) {
        (Kind::Rotation, Some(_)) => &[Rounding::I16, Rounding::Exact],
        (Kind::Rotation, None) => &[Rounding::Exact],
        (
            _,
            Some(Codec {
                vector: Some(f), ..
            }),
        ) => &[Rounding::Vector(*f)],
        _ => &[Rounding::Exact],
    };
    let mut best: Option<(CubicFit, bool)> = None;
    let mut best_bytes = budget;
    // The fit with `keys` and `tangents` when it is fewer bytes than `under` and fits as
    // written.
    let candidate = |keys: Vec<usize>, tangents: &[(Vec4, Vec4)], uniform: bool, under: usize| {
        let track = samples.track(chan, &keys, tangents);
        let value_bytes = output_bytes(&track, chan.kind, codec) + CUBIC_SAMPLER_JSON;
        let times = 4 * keys.len() + TIME_ACCESSOR_JSON;
        let bytes = value_bytes + if uniform { 0 } else { times };
        if bytes >= under {
            return None;
        }
        let written = codec.and_then(|c| cubic_as_written(&track, chan.kind == Kind::Rotation, c));
        samples.fits(written.as_ref().unwrap_or(&track)).then_some((
            bytes,
            CubicFit { kept: keys, track },
            uniform,
        ))
    };
    let mut widest = 1;
    for &rounding in roundings {
        let (keys, tangents) = samples.adaptive(rounding);
        widest = widest.max((n - 1) / (keys.len() - 1).max(1));
        if let Some((bytes, fit, uniform)) = candidate(keys, &tangents, false, best_bytes) {
            best_bytes = bytes;
            best = Some((fit, uniform));
        }
    }
    if chan.decimate {
        // A uniform rate needs more keys than the greedy segments; from their mean spacing
        // down, the first step that fits (every channel of that rate shares its times).
        let (comps, per) = match (chan.kind, codec) {
            (Kind::Rotation, Some(_)) => (4, 2),
            (Kind::Rotation, None) => (4, 4),
            _ => (3, 4),
        };
        let narrowest_bytes = 3 * comps * per;
        let steps = (2..=widest.min(MAX_STEP)).rev();
        for step in steps.filter(|&k| ladder(k)) {
            let keys = uniform_keys(n, step);
            if keys.len() * narrowest_bytes >= best_bytes {
                break;
            }
            let fitted = roundings.iter().find_map(|&r| samples.with_keys(&keys, r));
            if let Some(tangents) = fitted {
                if let Some((_, fit, uniform)) = candidate(keys, &tangents, true, best_bytes) {
                    best = Some((fit, uniform));
                }
                break;
            }
        }
    }
    best
}
