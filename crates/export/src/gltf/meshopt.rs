//! `EXT_meshopt_compression` for animation data: what the filters keep of a value (for the
//! key reducer to measure) and the compressed buffer views.
//!
//! The extension (Khronos `EXT_meshopt_compression`) stores a buffer view's bytes encoded by
//! meshoptimizer's vertex codec (version 0, the one the extension defines) in buffer 0,
//! while the view itself points into a *fallback* buffer that has no data; the extension is
//! declared required, so readers without it refuse the file rather than read zeros.
//! Rotations go through the `QUATERNION` filter (three components of K bits and the index of
//! the fourth, decoded to 16-bit normalized components), translations and scales through
//! the `EXPONENTIAL` filter (a K-bit mantissa and an 8-bit exponent per component); key
//! times, vertex attributes and inverse bind matrices are encoded without a filter,
//! exactly, and triangle indices with the index codec (`TRIANGLES` mode).

/// Bits per quaternion component (the filter allows 4 to 16): 16, the precision of plain
/// 16-bit normalized rotations.
pub(crate) const QUAT_BITS: i32 = 16;
/// Mantissa bits of the exponential filter (1 to 24): 20, a relative error of 2^-20
/// (a micrometre at a metre), far under the bounds reduction uses.
pub(crate) const EXP_BITS: i32 = 20;
/// Fewer mantissa bits, for keys whose rounding at 16 bits is still small against the
/// bound (a relative 2^-16: 15 micrometres at a metre), as gltfpack writes translations.
pub(crate) const EXP_BITS_SHORT: i32 = 16;
/// The element sizes this writer compresses (the codec takes multiples of 4 up to 256):
/// vertex attributes and animation keys, and 64 for matrices (inverse bind matrices).
pub(crate) const STRIDES: [usize; 5] = [4, 8, 12, 16, 64];
/// The vertex codec version `EXT_meshopt_compression` defines.
const CODEC_VERSION: i32 = 0;

/// A rotation key (xyzw, any length) as a reader gets it back through the `QUATERNION`
/// filter: 16-bit normalized components, as [`meshopt::decode_filter_quat`] writes them,
/// read as `c / 32767` (the sign may differ from the input's: the same rotation).
///
/// ```
/// let q = rigport_export::meshopt_rotation_as_written([0.0, 0.6, 0.0, 0.8]);
/// // The same rotation, up to sign, within the 16-bit grid's steps.
/// let near = |s: f32| q.iter().zip([0.0, 0.6, 0.0, 0.8]).all(|(a, b)| (a - s * b).abs() < 1e-4);
/// assert!(near(1.0) || near(-1.0), "{q:?}");
/// ```
pub fn rotation_as_written(q: [f32; 4]) -> [f32; 4] {
    let mut encoded = [encode_rotation(q)];
    meshopt::decode_filter_quat(&mut encoded);
    rigport_model::quantize::rotation_from_i16(encoded[0])
}

/// Rotation keys (xyzw, any length) as a reader gets them back through the `QUATERNION`
/// filter with `bits` (4 to 16, clamped) per stored component, the precision the key
/// reducer picks per track. Fewer bits leave the high bits of the stored integers equal
/// from key to key, which the vertex codec packs away. Below 16 bits the filter's own
/// rounding is written (one encoding and one decoding for the whole track).
///
/// ```
/// use rigport_export::meshopt_rotations_as_written_bits as written;
/// let q = [0.1f32, 0.6, -0.2, 0.76811457];
/// // The rotation angle between `p` and `q` (either sign), in f64.
/// let angle = |p: [f32; 4]| {
///     let (mut minus, mut plus) = (0.0f64, 0.0f64);
///     for (a, b) in p.iter().zip(q) {
///         minus += (f64::from(*a) - f64::from(b)).powi(2);
///         plus += (f64::from(*a) + f64::from(b)).powi(2);
///     }
///     let (lo, hi) = (minus.min(plus).sqrt(), minus.max(plus).sqrt());
///     4.0 * lo.atan2(hi)
/// };
/// // Each bit fewer about doubles the error: 16 bits within 1e-4 rad, 10 within 5e-3.
/// let (fine, coarse) = (written(&[q], 16)[0], written(&[q], 10)[0]);
/// assert!(angle(fine) < 1e-4 && angle(coarse) < 5e-3 && angle(coarse) > angle(fine));
/// ```
pub fn rotations_as_written_bits(keys: &[[f32; 4]], bits: u8) -> Vec<[f32; 4]> {
    let mut encoded = encode_rotations(keys, bits);
    meshopt::decode_filter_quat(&mut encoded);
    encoded
        .into_iter()
        .map(rigport_model::quantize::rotation_from_i16)
        .collect()
}

/// The `QUATERNION` filter's encodings of `keys` with `bits` per component: at 16 bits each
/// key's [`encode_rotation`], below it the filter's own rounding.
fn encode_rotations(keys: &[[f32; 4]], bits: u8) -> Vec<[i16; 4]> {
    let bits = i32::from(bits).clamp(4, QUAT_BITS);
    if bits == QUAT_BITS {
        return keys.iter().map(|&q| encode_rotation(q)).collect();
    }
    let units: Vec<[f32; 4]> = keys.iter().map(|&q| unit(q)).collect();
    meshopt::encode_filter_quat(&units, bits)
}

/// The `QUATERNION` filter's encoding of `q` at 16 bits: of the encodings whose three
/// stored components are within one step of the filter's own, the one that decodes to the
/// 16-bit quaternion whose length is nearest 1 (nearest to `q` among equals). Readers
/// compose the decoded quaternion without normalizing it (three.js), and a length off 1
/// scales the joint by its square (see `rigport_model::quantize::rotation_to_i16`).
fn encode_rotation(q: [f32; 4]) -> [i16; 4] {
    let u = unit(q);
    let [first] = meshopt::encode_filter_quat(&[u], QUAT_BITS)[..] else {
        return [0, 0, 0, 0];
    };
    let short_max = 32767.0f64;
    let mut best = first;
    let mut best_key = (f64::INFINITY, f64::INFINITY);
    for k in 0..27i32 {
        let mut c = first;
        let mut valid = true;
        for (i, ci) in c.iter_mut().take(3).enumerate() {
            let step = (k / 3i32.pow(i as u32)) % 3 - 1;
            let v = i32::from(*ci) + step;
            if v.abs() > 32767 {
                valid = false;
            }
            *ci = v.clamp(-32767, 32767) as i16;
        }
        if !valid {
            continue;
        }
        let mut decoded = [c];
        meshopt::decode_filter_quat(&mut decoded);
        let d = decoded[0].map(f64::from);
        let length = (d.iter().map(|x| x * x).sum::<f64>() - short_max * short_max).abs();
        // Distance to `q` up to sign (the filter may flip it).
        let dot: f64 = d.iter().zip(u).map(|(a, b)| a * f64::from(b)).sum();
        let distance = short_max * short_max - dot.abs();
        if (length, distance) < best_key {
            best_key = (length, distance);
            best = c;
        }
    }
    best
}

/// A translation or scale key as a reader gets it back through the `EXPONENTIAL` filter.
///
/// ```
/// let v = rigport_export::meshopt_vector_as_written([1.0, -0.25, 3.1]);
/// assert_eq!(v[..2], [1.0, -0.25]);
/// assert!((v[2] - 3.1).abs() < 3.1 / (1 << 19) as f32);
/// ```
pub fn vector_as_written(v: [f32; 3]) -> [f32; 3] {
    vector_at_bits(v, EXP_BITS)
}

/// [`vector_as_written`] at 16 mantissa bits (`GltfOptions::vector_bits` 16).
///
/// ```
/// let v = rigport_export::meshopt_vector_as_written_16([1.0, -0.25, 3.1]);
/// assert_eq!(v[..2], [1.0, -0.25]);
/// assert!((v[2] - 3.1).abs() < 3.1 / (1 << 15) as f32 && v[2] != 3.1);
/// ```
pub fn vector_as_written_16(v: [f32; 3]) -> [f32; 3] {
    vector_at_bits(v, EXP_BITS_SHORT)
}

/// `v` as a reader gets it back through the `EXPONENTIAL` filter at `bits`.
fn vector_at_bits(v: [f32; 3], bits: i32) -> [f32; 3] {
    let mut encoded = meshopt::encode_filter_exp(&[v], bits, meshopt::EncodeExpMode::Separate);
    meshopt::decode_filter_exp(&mut encoded);
    let [c] = encoded[..] else { return v };
    c.map(f32::from_bits)
}

/// `q / |q|` in `f64` (the identity for a zero quaternion, which validation rules out).
fn unit(q: [f32; 4]) -> [f32; 4] {
    let len = q.iter().map(|&c| f64::from(c).powi(2)).sum::<f64>().sqrt();
    if len > 0.0 && len.is_finite() {
        q.map(|c| (f64::from(c) / len) as f32)
    } else {
        [0.0, 0.0, 0.0, 1.0]
    }
}

/// Appends `encoded` to `bin` (4-byte aligned) and returns the extension object of view
/// `view`: `count` elements of `stride` bytes, decoded in `mode`.
fn append(
    bin: &mut Vec<u8>,
    view: usize,
    encoded: &[u8],
    (stride, count): (usize, usize),
    mode: &str,
) -> CompressedView {
    let pad = bin.len().wrapping_neg() % 4;
    bin.resize(bin.len() + pad, 0);
    let offset = bin.len();
    bin.extend_from_slice(encoded);
    let mut extension = serde_json::json!({
        "buffer": 0,
        "byteLength": encoded.len(),
        "byteStride": stride,
        "count": count,
        "mode": mode,
    });
    if offset > 0 {
        extension["byteOffset"] = offset.into();
    }
    CompressedView { view, extension }
}

/// A view's filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Filter {
    /// Bytes as they are (key times).
    None,
    /// `QUATERNION`: 16-bit normalized rotations, 8-byte stride.
    Quaternion,
    /// `EXPONENTIAL`: floats, 4 bytes per component.
    Exponential,
    /// `OCTAHEDRAL`: unit vectors as 8-bit normalized components, 4-byte stride (normals).
    Octahedral,
}

impl Filter {
    fn name(self) -> &'static str {
        match self {
            Filter::None => "NONE",
            Filter::Quaternion => "QUATERNION",
            Filter::Exponential => "EXPONENTIAL",
            Filter::Octahedral => "OCTAHEDRAL",
        }
    }
}

/// The encoded bytes of elements of `stride` bytes (4, 8, 12 or 16: [`STRIDES`]), `raw`
/// being their filtered (pre-codec) bytes, little-endian. The codec reports no error but
/// for sizes it computes itself; an empty result would only make the view unreadable, and
/// the tests decode every view.
fn encode(raw: &[u8], stride: usize) -> Vec<u8> {
    // The codec wants elements of one size: feed it as [u32; N] rows (every stride here
    // is a multiple of 4).
    fn rows<const N: usize>(raw: &[u8]) -> Vec<u8> {
        let rows: Vec<[u32; N]> = raw
            .chunks_exact(4 * N)
            .map(|row| {
                std::array::from_fn(|i| {
                    u32::from_le_bytes([row[4 * i], row[4 * i + 1], row[4 * i + 2], row[4 * i + 3]])
                })
            })
            .collect();
        meshopt::encode_vertex_buffer_level(&rows, 2, Some(CODEC_VERSION)).unwrap_or_default()
    }
    match stride {
        4 => rows::<1>(raw),
        8 => rows::<2>(raw),
        12 => rows::<3>(raw),
        16 => rows::<4>(raw),
        _ => {
            debug_assert_eq!(stride, 64, "strides are STRIDES");
            rows::<16>(raw)
        }
    }
}

/// Filtered bytes of rotation keys (flat xyzw) with `bits` per stored component.
pub(crate) fn quaternions(values: &[f32], bits: u8) -> Vec<u8> {
    let keys: Vec<[f32; 4]> = values
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    encode_rotations(&keys, bits)
        .iter()
        .flatten()
        .flat_map(|c| c.to_le_bytes())
        .collect()
}

/// Filtered bytes of three-component float keys (flat) with `bits` of mantissa.
pub(crate) fn exponential(values: &[f32], bits: i32) -> Vec<u8> {
    let vectors: Vec<[f32; 3]> = values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    meshopt::encode_filter_exp(&vectors, bits, meshopt::EncodeExpMode::Separate)
        .iter()
        .flatten()
        .flat_map(|c| c.to_le_bytes())
        .collect()
}

/// Filtered bytes of unit vectors (normals) through the `OCTAHEDRAL` filter at 8 bits:
/// 4 bytes each, decoded to 8-bit normalized `x, y, z` (and a fourth byte), as gltfpack
/// writes normals. A point on the octahedron rounds more evenly over directions than each
/// component on its own, and its two stored bytes pack smaller from vertex to vertex.
pub(crate) fn octahedral(normals: &[[f32; 3]]) -> Vec<u8> {
    let vectors: Vec<[f32; 4]> = normals.iter().map(|n| [n[0], n[1], n[2], 0.0]).collect();
    meshopt::encode_filter_oct::<i8>(&vectors, 8)
        .iter()
        .flatten()
        .map(|c| c.to_le_bytes()[0])
        .collect()
}

/// The bytes meshoptimizer's vertex codec makes of one animation accessor on its own, as
/// this writer encodes it: rotation keys (4 components, flat xyzw) through the `QUATERNION`
/// filter at `bits` (0: 16), translations or scales (3) through the `EXPONENTIAL` filter at
/// `bits` (0: 20 mantissa bits), key times (1) as they are; other component counts, 4
/// bytes a value. A view of many accessors encodes to about the sum of theirs.
///
/// ```
/// // 120 keys of a slow turn pack far smaller than their 960 filtered bytes.
/// let keys: Vec<f32> = (0..120)
///     .flat_map(|k| {
///         let a = 0.01 * k as f32;
///         [0.0, (0.5 * a).sin(), 0.0, (0.5 * a).cos()]
///     })
///     .collect();
/// let bytes = rigport_export::meshopt_encoded_bytes(&keys, 4, 12);
/// assert!(bytes > 0 && bytes < 400, "{bytes}");
/// ```
pub fn encoded_bytes(values: &[f32], components: usize, bits: u8) -> usize {
    match components {
        4 => encode(&quaternions(values, if bits == 0 { 16 } else { bits }), 8).len(),
        3 => {
            let bits = if bits == 0 { EXP_BITS } else { i32::from(bits) };
            encode(&exponential(values, bits), 12).len()
        }
        1 => encode(&floats(values), 4).len(),
        _ => 4 * values.len(),
    }
}

/// Raw bytes of floats.
pub(crate) fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// One compressed view, for the JSON: the view's index and its extension object.
#[derive(Clone, Debug)]
pub(crate) struct CompressedView {
    /// Index in `bufferViews`.
    pub view: usize,
    /// `EXT_meshopt_compression` of the view.
    pub extension: serde_json::Value,
}

/// Animation data of one stride and filter, gathered into one view.
#[derive(Clone, Debug)]
pub(crate) struct Group {
    pub stride: usize,
    pub filter: Filter,
    /// The filtered bytes, accessor after accessor.
    pub raw: Vec<u8>,
    /// The accessors that read it (indices in `accessors`).
    pub accessors: Vec<usize>,
}

/// The state of a compressed export: views written so far and the fallback buffer's size.
#[derive(Clone, Debug, Default)]
pub(crate) struct Compressed {
    pub views: Vec<CompressedView>,
    /// Animation groups not yet written.
    pub groups: Vec<Group>,
    /// Bytes of the fallback buffer (buffer 1): the decoded views, 4-byte aligned.
    pub fallback_len: usize,
}

impl Compressed {
    /// Appends `raw` to the group of `stride` and `filter` for `accessor`; returns its byte
    /// offset in the group.
    pub(crate) fn group(
        &mut self,
        stride: usize,
        filter: Filter,
        raw: &[u8],
        accessor: usize,
    ) -> usize {
        let at = match self
            .groups
            .iter()
            .position(|g| g.stride == stride && g.filter == filter)
        {
            Some(at) => at,
            None => {
                self.groups.push(Group {
                    stride,
                    filter,
                    raw: Vec::new(),
                    accessors: Vec::new(),
                });
                self.groups.len() - 1
            }
        };
        let group = &mut self.groups[at];
        let offset = group.raw.len();
        group.raw.extend_from_slice(raw);
        group.accessors.push(accessor);
        offset
    }

    /// Encodes triangle-list `indices` with the index codec (`TRIANGLES` mode) into `bin`
    /// and returns the fallback range `(byte_offset, byte_length)` of the view the caller
    /// pushes as `view`, whose indices are `stride` (2 or 4) bytes each. `None` when the
    /// list is not whole triangles or the codec fails (the caller writes it plainly).
    pub(crate) fn push_indices(
        &mut self,
        bin: &mut Vec<u8>,
        view: usize,
        indices: &[u32],
        stride: usize,
    ) -> Option<(usize, usize)> {
        if indices.is_empty() || indices.len() % 3 != 0 || !matches!(stride, 2 | 4) {
            return None;
        }
        let vertex_count = indices.iter().max().map_or(0, |&m| m as usize + 1);
        let encoded = meshopt::encode_index_buffer(indices, vertex_count).ok()?;
        let extension = append(bin, view, &encoded, (stride, indices.len()), "TRIANGLES");
        self.views.push(extension);
        Some(self.reserve(indices.len() * stride))
    }

    /// Reserves `len` decoded bytes in the fallback buffer (4-byte aligned) and returns
    /// their range `(byte_offset, byte_length)`.
    fn reserve(&mut self, len: usize) -> (usize, usize) {
        let at = self.fallback_len;
        self.fallback_len += len.next_multiple_of(4);
        (at, len)
    }

    /// Encodes `raw` (filtered bytes, `count` elements of `stride`) into `bin` (4-byte
    /// aligned) and returns the fallback range `(byte_offset, byte_length)` of the view the
    /// caller pushes as `view`; `None` (nothing written) for unfiltered bytes the codec
    /// does not make smaller (short runs of key times), which the caller writes as they are.
    pub(crate) fn push(
        &mut self,
        bin: &mut Vec<u8>,
        view: usize,
        raw: &[u8],
        stride: usize,
        filter: Filter,
    ) -> Option<(usize, usize)> {
        let count = raw.len() / stride.max(1);
        let encoded = encode(raw, stride);
        if filter == Filter::None && encoded.len() >= raw.len() {
            return None;
        }
        let mut extension = append(bin, view, &encoded, (stride, count), "ATTRIBUTES");
        if filter != Filter::None {
            extension.extension["filter"] = filter.name().into();
        }
        self.views.push(extension);
        Some(self.reserve(raw.len()))
    }
}
