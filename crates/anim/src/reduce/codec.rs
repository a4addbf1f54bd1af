//! How a writer stores key values, for the reducer to measure what a reader gets.

use rigport_model::quantize::component_as_i16;
use rigport_model::Track;

/// A track's rotation keys (xyzw) as read back when written with the given bits per
/// component.
pub type RotationAtBits = fn(&[[f32; 4]], u8) -> Vec<[f32; 4]>;

/// The precisions besides its default in which a writer can store a rotation track.
#[derive(Clone, Copy, Debug)]
pub struct RotationBits {
    /// The track's keys as read back at the given bits per component.
    pub written: RotationAtBits,
    /// The bits per component the reducer may pick, fewest first (all under the default).
    pub choices: &'static [u8],
    /// The bytes of one LINEAR key written at the given bits, before any compression.
    pub key_bytes: fn(u8) -> usize,
}

/// How a writer stores key values, as functions from a value to what a reader gets back.
#[derive(Clone, Copy, Debug)]
pub struct Codec {
    /// A LINEAR or STEP rotation key (xyzw, any length) as read back.
    pub rotation: fn([f32; 4]) -> [f32; 4],
    /// A LINEAR or STEP translation or scale key as read back (`None`: exactly).
    pub vector: Option<fn([f32; 3]) -> [f32; 3]>,
    /// Lower precisions for LINEAR and STEP rotation tracks (`rotation` is the writer's
    /// default): the reducer then picks the fewest bits per rotation track that its
    /// tolerance allows ([`super::ReduceStats`] `rotation_bits`). `None`: one precision
    /// for every track.
    pub rotation_bits: Option<RotationBits>,
    /// What a kept key's time of its own weighs, in bytes, against a key's value as written
    /// (8 for a 16-bit rotation), when the reducer weighs key removal (times of its own)
    /// against a uniform rate (times shared): 4 for a float as it is; more when a
    /// compressor packs a uniform track's small steps from key to key into far fewer bytes
    /// than the jumps between removed keys and their off-grid times.
    pub key_time_bytes: usize,
}

impl Codec {
    /// Rotations as 16-bit normalized integers (core glTF), other values exact.
    pub const I16: Codec = Codec {
        rotation: rigport_model::quantize::rotation_as_i16,
        vector: None,
        rotation_bits: None,
        key_time_bytes: 4,
    };

    /// [`Codec::I16`], and 8-bit normalized components (4 bytes a key instead of 8) for the
    /// rotation tracks whose tolerance allows them: core glTF's two rotation precisions.
    pub const CORE: Codec = Codec {
        rotation_bits: Some(RotationBits {
            written: core_rotations_at_bits,
            choices: &[8],
            key_bytes: core_key_bytes,
        }),
        ..Codec::I16
    };
}

/// Rotation keys as core glTF stores them at `bits`: 8-bit normalized components under 16
/// bits, 16-bit ones otherwise.
fn core_rotations_at_bits(keys: &[[f32; 4]], bits: u8) -> Vec<[f32; 4]> {
    let encode = if bits < 16 {
        rigport_model::quantize::rotation_as_i8
    } else {
        rigport_model::quantize::rotation_as_i16
    };
    keys.iter().map(|&q| encode(q)).collect()
}

/// A core glTF rotation key's bytes at `bits` (see [`core_rotations_at_bits`]).
fn core_key_bytes(bits: u8) -> usize {
    if bits < 16 {
        4
    } else {
        8
    }
}

/// A LINEAR or STEP rotation track (xyzw keys) as `written` reads it back at `bits` per
/// component.
pub(super) fn rotations_at_bits(track: &Track, written: RotationAtBits, bits: u8) -> Track {
    let keys: Vec<[f32; 4]> = track
        .values
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    let mut out = track.clone();
    for (chunk, w) in out.values.chunks_exact_mut(4).zip(written(&keys, bits)) {
        chunk.copy_from_slice(&w);
    }
    out
}

/// A cubic track's values as `codec` stores them (`None`: exactly): rotations (`rotation`) as 16-bit
/// normalized components when every value and tangent fits in `[-1, 1]` (else floats),
/// translations and scales through the codec's vector rounding.
pub(super) fn cubic_as_written(track: &Track, rotation: bool, codec: &Codec) -> Option<Track> {
    let mut written = track.clone();
    match rotation {
        true => {
            if track.values.iter().any(|v| v.abs() > 1.0) {
                return None;
            }
            for v in &mut written.values {
                *v = component_as_i16(*v);
            }
        }
        false => {
            let vector = codec.vector?;
            for chunk in written.values.chunks_exact_mut(3) {
                chunk.copy_from_slice(&vector([chunk[0], chunk[1], chunk[2]]));
            }
        }
    }
    Some(written)
}
