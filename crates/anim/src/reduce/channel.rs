//! The joint tracks a reduction samples: validated, one per joint and property, with the
//! values a reader sees.

use glam::Quat;
use rigport_model::{Clip, Interpolation, Skeleton, Track, TrackTarget};

use super::codec::{cubic_as_written, rotations_at_bits, Codec, RotationBits};
use super::curve::{quat_at, rotation_angle};
use super::error::{ReduceError, TrackProblem};

/// Which joint property a track animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Translation,
    Rotation,
    Scale,
}

impl Kind {
    pub(super) fn slot(self) -> usize {
        match self {
            Kind::Translation => 0,
            Kind::Rotation => 1,
            Kind::Scale => 2,
        }
    }
}

/// One sampled joint track (the first of the clip for its joint and property).
pub(super) struct Channel<'a> {
    pub(super) joint: usize,
    pub(super) kind: Kind,
    /// Index in `clip.tracks`.
    pub(super) track: usize,
    pub(super) original: &'a Track,
    /// The original as a reader sees it when that differs (16-bit rotations).
    pub(super) as_written: Option<Track>,
    /// LINEAR with more than two keys: keys can go.
    pub(super) reducible: bool,
    /// Try a lower uniform rate besides key removal (`simplify`).
    pub(super) decimate: bool,
    /// Try a CUBICSPLINE fit besides LINEAR keys (`simplify`).
    pub(super) cubic: bool,
    /// How the writer stores values (`None`: exactly), for the cubic fit's rounding.
    pub(super) codec: Option<Codec>,
    /// Bytes of one key's value as written (the simplifier's cost model).
    pub(super) value_bytes: usize,
    /// What a key's own time weighs against `value_bytes` ([`Codec::key_time_bytes`]).
    pub(super) time_bytes: usize,
    /// Local tolerance: length unit (translation), radians (rotation), scale units (scale).
    pub(super) eps: f32,
    /// The kept keys (indices into the original), `None` while every key is.
    pub(super) kept: Option<Vec<usize>>,
    /// The kept keys of `as_written` (or the original), the track sampled while reduced.
    pub(super) reduced: Option<Track>,
    /// The cubic track chosen instead of kept LINEAR keys, as handed to the writer
    /// (`reduced` is it as the writer stores it).
    pub(super) fitted: Option<Track>,
    /// Normalized rotation keys as written (rotation channels only), for the simplifier.
    pub(super) quats: Vec<Quat>,
    /// The bits per component `as_written` holds (`Codec::rotation_bits`); `None`: the
    /// codec's default.
    pub(super) bits: Option<u8>,
    /// `as_written` and `quats` at the codec's default, while `bits` holds others.
    pub(super) default: Option<(Option<Track>, Vec<Quat>)>,
}

impl Channel<'_> {
    /// Writes this rotation channel with the fewest bits within `share` of its tolerance
    /// (see [`fewest_bits`]), or at the codec's default when none fits.
    pub(super) fn choose_bits(&mut self, share: f32) {
        match fewest_bits(self, share) {
            Some((bits, written, quats)) => {
                if self.default.is_none() {
                    self.default = Some((self.as_written.take(), std::mem::take(&mut self.quats)));
                }
                if let Some(codec) = self.codec.and_then(|c| c.rotation_bits) {
                    self.value_bytes = (codec.key_bytes)(bits);
                }
                self.bits = Some(bits);
                self.as_written = Some(written);
                self.quats = quats;
            }
            None => self.default_bits(),
        }
    }

    /// Back to the codec's default precision.
    pub(super) fn default_bits(&mut self) {
        if let Some((written, quats)) = self.default.take() {
            self.as_written = written;
            self.quats = quats;
        }
        if self.bits.take().is_some() {
            self.value_bytes = DEFAULT_ROTATION_BYTES;
        }
    }
}

impl Channel<'_> {
    /// The track as a reader sees it now.
    pub(super) fn current(&self) -> &Track {
        self.reduced
            .as_ref()
            .or(self.as_written.as_ref())
            .unwrap_or(self.original)
    }
}

/// Validates every joint track and keeps the first per joint and property.
/// With a `codec`, LINEAR and STEP values are read as it stores them.
pub(super) fn collect_channels<'a>(
    clip: &'a Clip,
    skeleton: &Skeleton,
    codec: Option<&Codec>,
    decimate: bool,
    cubic: bool,
) -> Result<Vec<Channel<'a>>, ReduceError> {
    let joints = skeleton.len();
    let mut seen = vec![[false; 3]; joints];
    let mut out = Vec::new();
    for (ti, track) in clip.tracks.iter().enumerate() {
        let (joint, kind) = match track.target {
            TrackTarget::Translation(j) => (j, Kind::Translation),
            TrackTarget::Rotation(j) => (j, Kind::Rotation),
            TrackTarget::Scale(j) => (j, Kind::Scale),
            TrackTarget::MorphWeights(_) => continue,
        };
        let bad = |problem| ReduceError::BadTrack {
            clip: clip.name.clone(),
            track: ti,
            problem,
        };
        let Some(slot) = seen.get_mut(joint.get()) else {
            return Err(ReduceError::UnknownJoint {
                clip: clip.name.clone(),
                track: ti,
                joint,
                joints,
            });
        };
        if track.times.is_empty() {
            return Err(bad(TrackProblem::NoKeys));
        }
        if let Some(key) = track.times.iter().enumerate().position(|(k, t)| {
            !t.is_finite() || (k > 0 && track.times.get(k - 1).is_some_and(|p| t <= p))
        }) {
            return Err(bad(TrackProblem::Times { key }));
        }
        let comps = if kind == Kind::Rotation { 4 } else { 3 };
        let per_key = if track.interpolation == Interpolation::CubicSpline {
            3 * comps
        } else {
            comps
        };
        let expected = track.times.len() * per_key;
        if track.values.len() != expected {
            return Err(bad(TrackProblem::ValueCount {
                expected,
                found: track.values.len(),
            }));
        }
        if track.values.iter().any(|v| !v.is_finite()) {
            return Err(bad(TrackProblem::NonFinite));
        }
        let mut quats = Vec::new();
        if kind == Kind::Rotation {
            let offset = if track.interpolation == Interpolation::CubicSpline {
                4
            } else {
                0
            };
            for (key, chunk) in track.values.chunks_exact(per_key).enumerate() {
                let q = quat_at(chunk, offset);
                if !q.is_finite() {
                    return Err(bad(TrackProblem::ZeroRotation { key }));
                }
                quats.push(q);
            }
        }
        if std::mem::replace(&mut slot[kind.slot()], true) {
            continue;
        }
        let is_cubic = track.interpolation == Interpolation::CubicSpline;
        let as_written = codec.and_then(|codec| {
            if is_cubic {
                cubic_as_written(track, kind == Kind::Rotation, codec)
            } else {
                as_written(track, kind, codec)
            }
        });
        if let Some(written) = as_written
            .as_ref()
            .filter(|_| kind == Kind::Rotation && !is_cubic)
        {
            for (q, chunk) in quats.iter_mut().zip(written.values.chunks_exact(4)) {
                *q = quat_at(chunk, 0);
            }
        }
        let rounded = as_written.is_some() && kind == Kind::Rotation && !is_cubic;
        out.push(Channel {
            joint: joint.get(),
            kind,
            track: ti,
            original: track,
            as_written,
            reducible: track.interpolation == Interpolation::Linear && track.times.len() > 2,
            decimate,
            cubic,
            codec: codec.copied(),
            value_bytes: if rounded {
                DEFAULT_ROTATION_BYTES
            } else {
                4 * comps
            },
            time_bytes: codec.map_or(4, |c| c.key_time_bytes),
            eps: 0.0,
            kept: None,
            reduced: None,
            fitted: None,
            quats,
            bits: None,
            default: None,
        });
    }
    Ok(out)
}

/// The fewest of the codec's bits ([`RotationBits::choices`]) whose rounding of every key
/// of `chan` (a reducible LINEAR rotation track) stays within `share` of its tolerance (its
/// angle, plus twice the written length's distance to 1, which a reader's composition turns
/// into a scale), and the keys as written with them; `None` when the codec has one
/// precision, or the default is needed.
pub(super) fn fewest_bits(chan: &Channel, share: f32) -> Option<(u8, Track, Vec<Quat>)> {
    let RotationBits {
        written, choices, ..
    } = chan.codec?.rotation_bits?;
    let track = chan.original;
    // Reducible tracks only: a track the tightening cannot reach keeps the default.
    if chan.kind != Kind::Rotation || !chan.reducible || !chan.eps.is_finite() {
        return None;
    }
    let limit = share * chan.eps;
    let originals: Vec<Quat> = track
        .values
        .chunks_exact(4)
        .map(|c| quat_at(c, 0))
        .collect();
    choices.iter().find_map(|&bits| {
        let out = rotations_at_bits(track, written, bits);
        let mut quats = Vec::with_capacity(originals.len());
        for (w, q) in out.values.chunks_exact(4).zip(&originals) {
            let r = quat_at(w, 0);
            // A reader composes the written quaternion as it is: a length off 1 scales the
            // joint by its square, moving a point at unit distance by twice the difference.
            let length = glam::Vec4::from_slice(w).length();
            if rotation_angle(*q, r) + 2.0 * (length - 1.0).abs() > limit {
                return None;
            }
            quats.push(r);
        }
        Some((bits, out, quats))
    })
}

/// The bytes of a rotation key at the codec's default precision (16-bit components).
const DEFAULT_ROTATION_BYTES: usize = 8;

/// A LINEAR or STEP track's values as `codec` stores them (`None`: stored exactly).
pub(super) fn as_written(track: &Track, kind: Kind, codec: &Codec) -> Option<Track> {
    let mut written = track.clone();
    match kind {
        Kind::Rotation => {
            for chunk in written.values.chunks_exact_mut(4) {
                let q = (codec.rotation)([chunk[0], chunk[1], chunk[2], chunk[3]]);
                chunk.copy_from_slice(&q);
            }
        }
        Kind::Translation | Kind::Scale => {
            let vector = codec.vector?;
            for chunk in written.values.chunks_exact_mut(3) {
                let v = vector([chunk[0], chunk[1], chunk[2]]);
                chunk.copy_from_slice(&v);
            }
        }
    }
    Some(written)
}
