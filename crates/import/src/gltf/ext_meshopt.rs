//! `EXT_meshopt_compression`: buffer views whose bytes are stored encoded by
//! meshoptimizer's codecs in another buffer, decoded (the `meshopt` crate, the library
//! gltfpack encodes with) into their own buffer before anything reads them. That buffer is
//! usually a *fallback* without data (no `uri`, `"fallback": true`), so it starts as zeros
//! of its `byteLength`.
//!
//! Modes (the extension's `mode`): `ATTRIBUTES` (the vertex codec, `byteStride` bytes per
//! element, a multiple of 4), `TRIANGLES` (the index codec) and `INDICES` (the index
//! sequence codec), 2 or 4 bytes per index. Filters, applied after decoding: `NONE`,
//! `OCTAHEDRAL` (8- or 16-bit normalized unit vectors), `QUATERNION` (16-bit normalized
//! quaternions) and `EXPONENTIAL` (floats from an exponent and a mantissa).

use std::borrow::Cow;

use serde_json::Value;

/// One compressed buffer view: where its encoded bytes are and how to decode them.
#[derive(Clone, Debug)]
struct Compressed {
    /// The view's index, its buffer and byte offset (where the decoded bytes go).
    view: usize,
    target: usize,
    target_offset: usize,
    /// The encoded bytes: buffer, offset, length.
    source: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: String,
    filter: String,
}

/// The buffers without data and the compressed views of a document.
#[derive(Clone, Debug, Default)]
pub(super) struct Meshopt {
    fallback: Vec<usize>,
    views: Vec<Compressed>,
}

/// A problem with the extension's fields or data: the JSON pointer and what is wrong.
pub(super) type Fault = (String, String);

fn field(v: &Value, name: &str, at: &str) -> Result<usize, Fault> {
    v.get(name)
        .and_then(Value::as_u64)
        .map(|n| n as usize)
        .ok_or_else(|| {
            (
                format!("{at}/{name}"),
                format!("{name} is missing or not a count"),
            )
        })
}

impl Meshopt {
    /// The extension's buffers and views in the document's JSON (empty when it has none).
    pub(super) fn of(json: &Value) -> Result<Self, Fault> {
        let ext = |v: &Value| v.get("extensions")?.get("EXT_meshopt_compression").cloned();
        let mut out = Self::default();
        for (i, b) in json["buffers"].as_array().into_iter().flatten().enumerate() {
            if ext(b).and_then(|e| e.get("fallback").and_then(Value::as_bool)) == Some(true) {
                out.fallback.push(i);
            }
        }
        for (i, v) in json["bufferViews"]
            .as_array()
            .into_iter()
            .flatten()
            .enumerate()
        {
            let Some(e) = ext(v) else { continue };
            let at = format!("/bufferViews/{i}/extensions/EXT_meshopt_compression");
            let text = |name: &str, default: &str| {
                e.get(name)
                    .map_or(Some(default.to_owned()), |x| x.as_str().map(str::to_owned))
                    .ok_or_else(|| (format!("{at}/{name}"), format!("{name} is not a string")))
            };
            out.views.push(Compressed {
                view: i,
                target: field(v, "buffer", &format!("/bufferViews/{i}"))?,
                target_offset: v.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize,
                source: field(&e, "buffer", &at)?,
                offset: e.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize,
                length: field(&e, "byteLength", &at)?,
                stride: field(&e, "byteStride", &at)?,
                count: field(&e, "count", &at)?,
                mode: text("mode", "")?,
                filter: text("filter", "NONE")?,
            });
        }
        Ok(out)
    }

    /// Whether buffer `i` is a fallback (its bytes come from decoding).
    pub(super) fn is_fallback(&self, i: usize) -> bool {
        self.fallback.contains(&i)
    }

    /// Decodes every compressed view into its buffer.
    pub(super) fn decode(&self, buffers: &mut [Cow<'_, [u8]>]) -> Result<(), Fault> {
        for c in &self.views {
            let at = format!("/bufferViews/{}/extensions/EXT_meshopt_compression", c.view);
            let encoded = buffers
                .get(c.source)
                .and_then(|b| b.get(c.offset..c.offset.checked_add(c.length)?))
                .ok_or_else(|| {
                    (
                        at.clone(),
                        "the encoded bytes lie outside their buffer".into(),
                    )
                })?
                .to_vec();
            let bad = |m: String| (at.clone(), m);
            let mut bytes = decode_view(&encoded, c).map_err(bad)?;
            filter(&mut bytes, c).map_err(|m| (format!("{at}/filter"), m))?;
            let target = buffers
                .get_mut(c.target)
                .ok_or_else(|| (at.clone(), format!("buffer {} does not exist", c.target)))?
                .to_mut();
            let end = c.target_offset + bytes.len();
            let slot = target.get_mut(c.target_offset..end).ok_or_else(|| {
                (
                    at.clone(),
                    format!(
                        "the decoded {} bytes do not fit in buffer {}",
                        bytes.len(),
                        c.target
                    ),
                )
            })?;
            slot.copy_from_slice(&bytes);
        }
        Ok(())
    }
}

/// Vertex elements of `K` 32-bit words, decoded, as bytes.
fn vertices<const K: usize>(encoded: &[u8], count: usize) -> Result<Vec<u8>, String>
where
    [u32; K]: Default,
{
    let words: Vec<[u32; K]> = meshopt::decode_vertex_buffer(encoded, count)
        .map_err(|e| format!("the vertex codec cannot decode it: {e}"))?;
    Ok(words
        .iter()
        .flatten()
        .flat_map(|w| w.to_le_bytes())
        .collect())
}

fn decode_view(encoded: &[u8], c: &Compressed) -> Result<Vec<u8>, String> {
    match (c.mode.as_str(), c.stride) {
        ("ATTRIBUTES", 4) => vertices::<1>(encoded, c.count),
        ("ATTRIBUTES", 8) => vertices::<2>(encoded, c.count),
        ("ATTRIBUTES", 12) => vertices::<3>(encoded, c.count),
        ("ATTRIBUTES", 16) => vertices::<4>(encoded, c.count),
        ("ATTRIBUTES", 20) => vertices::<5>(encoded, c.count),
        ("ATTRIBUTES", 24) => vertices::<6>(encoded, c.count),
        ("ATTRIBUTES", 28) => vertices::<7>(encoded, c.count),
        ("ATTRIBUTES", 32) => vertices::<8>(encoded, c.count),
        ("ATTRIBUTES", 36) => vertices::<9>(encoded, c.count),
        ("ATTRIBUTES", 40) => vertices::<10>(encoded, c.count),
        ("ATTRIBUTES", 44) => vertices::<11>(encoded, c.count),
        ("ATTRIBUTES", 48) => vertices::<12>(encoded, c.count),
        ("ATTRIBUTES", 52) => vertices::<13>(encoded, c.count),
        ("ATTRIBUTES", 56) => vertices::<14>(encoded, c.count),
        ("ATTRIBUTES", 60) => vertices::<15>(encoded, c.count),
        ("ATTRIBUTES", 64) => vertices::<16>(encoded, c.count),
        ("TRIANGLES", 2) => le16(meshopt::decode_index_buffer(encoded, c.count)),
        ("TRIANGLES", 4) => le32(meshopt::decode_index_buffer(encoded, c.count)),
        ("INDICES", 2) => le16(meshopt::decode_index_sequence(encoded, c.count)),
        ("INDICES", 4) => le32(meshopt::decode_index_sequence(encoded, c.count)),
        (mode, stride) => Err(format!(
            "mode {mode:?} with byteStride {stride} is not decoded (ATTRIBUTES with a multiple \
             of 4 up to 64 bytes, TRIANGLES and INDICES with 2 or 4)"
        )),
    }
}

/// Little-endian bytes of decoded 16-bit indices.
fn le16<E: std::fmt::Display>(decoded: Result<Vec<u16>, E>) -> Result<Vec<u8>, String> {
    let v = decoded.map_err(|e| format!("the index codec cannot decode it: {e}"))?;
    Ok(v.iter().flat_map(|x| x.to_le_bytes()).collect())
}

/// Little-endian bytes of decoded 32-bit indices.
fn le32<E: std::fmt::Display>(decoded: Result<Vec<u32>, E>) -> Result<Vec<u8>, String> {
    let v = decoded.map_err(|e| format!("the index codec cannot decode it: {e}"))?;
    Ok(v.iter().flat_map(|x| x.to_le_bytes()).collect())
}

/// Applies the view's filter to its decoded bytes in place.
fn filter(bytes: &mut [u8], c: &Compressed) -> Result<(), String> {
    match (c.filter.as_str(), c.stride) {
        ("NONE", _) => {}
        ("OCTAHEDRAL", 4) => {
            let mut v: Vec<[i8; 4]> = bytes
                .chunks_exact(4)
                .map(|b| [b[0], b[1], b[2], b[3]].map(|x| x as i8))
                .collect();
            meshopt::decode_filter_oct(&mut v);
            for (dst, src) in bytes.chunks_exact_mut(4).zip(&v) {
                dst.copy_from_slice(&src.map(|x| x as u8));
            }
        }
        ("OCTAHEDRAL", 8) | ("QUATERNION", 8) => {
            let mut v: Vec<[i16; 4]> = bytes
                .chunks_exact(8)
                .map(|b| std::array::from_fn(|k| i16::from_le_bytes([b[2 * k], b[2 * k + 1]])))
                .collect();
            if c.filter == "QUATERNION" {
                meshopt::decode_filter_quat(&mut v);
            } else {
                meshopt::decode_filter_oct(&mut v);
            }
            for (dst, src) in bytes.chunks_exact_mut(8).zip(&v) {
                for (k, x) in src.iter().enumerate() {
                    dst[2 * k..2 * k + 2].copy_from_slice(&x.to_le_bytes());
                }
            }
        }
        ("EXPONENTIAL", s) if s % 4 == 0 => {
            // Each 32-bit component is decoded on its own.
            let mut v: Vec<[u32; 1]> = bytes
                .chunks_exact(4)
                .map(|b| [u32::from_le_bytes([b[0], b[1], b[2], b[3]])])
                .collect();
            meshopt::decode_filter_exp(&mut v);
            for (dst, src) in bytes.chunks_exact_mut(4).zip(&v) {
                dst.copy_from_slice(&src[0].to_le_bytes());
            }
        }
        (f, s) => {
            return Err(format!(
                "filter {f:?} with byteStride {s} is not decoded (NONE, OCTAHEDRAL with 4 or 8, \
                 QUATERNION with 8, EXPONENTIAL with a multiple of 4)"
            ))
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A document's JSON with buffer 0 (the encoded bytes) and buffer 1 (the fallback), and
    /// one compressed view.
    fn json(encoded: usize, decoded: usize, view: Value) -> Value {
        serde_json::json!({
            "buffers": [
                {"byteLength": encoded},
                {"byteLength": decoded, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
            ],
            "bufferViews": [view]
        })
    }

    #[test]
    fn vertices_and_quaternions_decode_into_the_fallback_buffer() {
        let vertices: Vec<[u32; 3]> = (0..50u32).map(|i| [i, i * 7, u32::MAX - i]).collect();
        let encoded = meshopt::encode_vertex_buffer(&vertices).unwrap();
        let quats = meshopt::encode_filter_quat(&[[0.0, 0.6, 0.0, 0.8]; 4], 16);
        let encoded_quats = meshopt::encode_vertex_buffer(&quats).unwrap();
        for (bytes, stride, count, filter) in [
            (encoded, 12, 50, "NONE"),
            (encoded_quats, 8, 4, "QUATERNION"),
        ] {
            let view = serde_json::json!({"buffer": 1, "byteOffset": 4, "byteLength": stride * count,
                "extensions": {"EXT_meshopt_compression": {"buffer": 0, "byteLength": bytes.len(),
                "byteStride": stride, "count": count, "mode": "ATTRIBUTES", "filter": filter}}});
            let m = Meshopt::of(&json(bytes.len(), 4 + stride * count, view)).unwrap();
            assert!(m.is_fallback(1) && !m.is_fallback(0));
            let mut buffers = vec![
                Cow::Borrowed(&bytes[..]),
                Cow::Owned(vec![0; 4 + stride * count]),
            ];
            m.decode(&mut buffers).unwrap();
            let out = &buffers[1][4..];
            if filter == "NONE" {
                let want: Vec<u8> = vertices
                    .iter()
                    .flatten()
                    .flat_map(|w| w.to_le_bytes())
                    .collect();
                assert_eq!(out, &want[..]);
            } else {
                // 16-bit normalized xyzw: (0, 0.6, 0, 0.8) up to sign.
                let q: Vec<f32> = out[..8]
                    .chunks(2)
                    .map(|b| f32::from(i16::from_le_bytes([b[0], b[1]])) / 32767.0)
                    .collect();
                let s = q[3].signum();
                for (a, b) in q.iter().zip([0.0, 0.6, 0.0, 0.8]) {
                    assert!((a - s * b).abs() < 1e-4, "{q:?}");
                }
            }
        }
    }

    #[test]
    fn bad_views_name_their_json_pointer() {
        let view = |ext: Value| {
            serde_json::json!({"buffer": 1, "byteLength": 8,
            "extensions": {"EXT_meshopt_compression": ext}})
        };
        // Encoded bytes past the end of buffer 0.
        let m = Meshopt::of(&json(
            4,
            8,
            view(
                serde_json::json!({"buffer": 0, "byteLength": 40, "byteStride": 4, "count": 2,
                "mode": "ATTRIBUTES"}),
            ),
        ))
        .unwrap();
        let mut buffers = vec![Cow::Owned(vec![0u8; 4]), Cow::Owned(vec![0; 8])];
        let (at, message) = m.decode(&mut buffers).unwrap_err();
        assert_eq!(at, "/bufferViews/0/extensions/EXT_meshopt_compression");
        assert!(message.contains("outside"), "{message}");
        // An unknown filter.
        let m = Meshopt::of(&json(
            4,
            8,
            view(
                serde_json::json!({"buffer": 0, "byteLength": 4, "byteStride": 4, "count": 2,
                "mode": "ATTRIBUTES", "filter": "SPIRAL"}),
            ),
        ))
        .unwrap();
        let mut buffers = vec![Cow::Owned(vec![0u8; 4]), Cow::Owned(vec![0; 8])];
        let (at, _) = m.decode(&mut buffers).unwrap_err();
        assert!(
            at.ends_with("/filter") || at.ends_with("EXT_meshopt_compression"),
            "{at}"
        );
        // A missing count.
        let (at, _) = Meshopt::of(&json(
            4,
            8,
            view(
                serde_json::json!({"buffer": 0, "byteLength": 4, "byteStride": 4,
                "mode": "ATTRIBUTES"}),
            ),
        ))
        .unwrap_err();
        assert_eq!(
            at,
            "/bufferViews/0/extensions/EXT_meshopt_compression/count"
        );
    }
}
