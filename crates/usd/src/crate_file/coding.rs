//! The two compression layers of a crate file: `TfFastCompression` (LZ4 blocks, possibly
//! split into chunks) and `Usd_IntegerCompression` (delta coding with 2-bit size codes,
//! then LZ4), as described in OpenUSD's `pxr/base/tf/fastCompression.cpp` and
//! `pxr/usd/usd/integerCoding.cpp`.
//!
//! Every read is bounds-checked; a corrupt stream is an error, never a panic.

/// Why a compressed stream could not be decoded (the caller adds the byte offset).
#[derive(Debug, thiserror::Error)]
pub enum CodingError {
    /// The LZ4 data decompresses to another size than the stream declares.
    #[error("LZ4 data decompresses to {found} bytes, {expected} expected")]
    Size {
        /// Bytes decompressed.
        found: usize,
        /// Bytes declared.
        expected: usize,
    },
    /// No bytes where some are declared.
    #[error("an empty compressed buffer")]
    Empty,
    /// An LZ4 block that does not decode (`chunk` numbers it in a chunked buffer).
    #[error(fmt = corrupt_lz4)]
    CorruptLz4 {
        /// The chunk, in a chunked buffer.
        chunk: Option<i8>,
        /// The decoder's reason.
        error: lz4_flex::block::DecompressError,
    },
    /// A negative chunk count.
    #[error("a negative LZ4 chunk count {0}")]
    NegativeChunks(i8),
    /// A chunk without its size.
    #[error("LZ4 chunk {0} has no size")]
    ChunkWithoutSize(i8),
    /// A chunk with a negative size.
    #[error("LZ4 chunk {0} has a negative size")]
    NegativeChunkSize(i8),
    /// A chunk past the end of the data.
    #[error("LZ4 chunk {0} ends past the compressed data")]
    ChunkPastEnd(i8),
    /// Integer codes shorter than their count needs.
    #[error("the integer codes end early")]
    IntegersEndEarly,
}

fn corrupt_lz4(
    chunk: &Option<i8>,
    error: &lz4_flex::block::DecompressError,
    f: &mut std::fmt::Formatter<'_>,
) -> std::fmt::Result {
    match chunk {
        Some(k) => write!(f, "corrupt LZ4 data in chunk {k} ({error})"),
        None => write!(f, "corrupt LZ4 data ({error})"),
    }
}

/// Decompresses a `TfFastCompression` buffer holding exactly `out_len` bytes.
///
/// The first byte counts chunks: 0 means the rest is one LZ4 block; otherwise each chunk
/// is an `i32` size followed by an LZ4 block.
pub(crate) fn decompress(input: &[u8], out_len: usize) -> Result<Vec<u8>, CodingError> {
    let out = decompress_prefix(input, out_len)?;
    if out.len() != out_len {
        return Err(CodingError::Size {
            found: out.len(),
            expected: out_len,
        });
    }
    Ok(out)
}

/// Decompresses a `TfFastCompression` buffer of at most `max_len` bytes; returns what was
/// written.
pub(crate) fn decompress_prefix(input: &[u8], max_len: usize) -> Result<Vec<u8>, CodingError> {
    // An LZ4 block expands at most about 255 times (a match of 255-length runs per byte):
    // no corrupt size makes this allocate more than the input can fill.
    let out_len = max_len.min(input.len().saturating_mul(256).saturating_add(64));
    let mut out = vec![0_u8; out_len];
    let Some((&first, mut rest)) = input.split_first() else {
        return if out_len == 0 {
            Ok(out)
        } else {
            Err(CodingError::Empty)
        };
    };
    // `TfFastCompression` stores the chunk count in a (signed) `char`.
    let chunks = first as i8;
    let written = if chunks == 0 {
        lz4_flex::block::decompress_into(rest, &mut out)
            .map_err(|error| CodingError::CorruptLz4 { chunk: None, error })?
    } else if chunks < 0 {
        return Err(CodingError::NegativeChunks(chunks));
    } else {
        let mut written = 0;
        for k in 0..chunks {
            let (size, after) = rest
                .split_first_chunk::<4>()
                .ok_or(CodingError::ChunkWithoutSize(k))?;
            let size = usize::try_from(i32::from_le_bytes(*size))
                .map_err(|_| CodingError::NegativeChunkSize(k))?;
            let chunk = after.get(..size).ok_or(CodingError::ChunkPastEnd(k))?;
            rest = after.get(size..).unwrap_or_default();
            let target = out.get_mut(written..).unwrap_or_default();
            written += lz4_flex::block::decompress_into(chunk, target).map_err(|error| {
                CodingError::CorruptLz4 {
                    chunk: Some(k),
                    error,
                }
            })?;
        }
        written
    };
    out.truncate(written);
    Ok(out)
}

/// The width of the integers of a compressed stream: 32-bit streams use 8/16/32-bit
/// deltas, 64-bit streams 16/32/64-bit deltas.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Width {
    /// `int32_t` / `uint32_t` values.
    W32,
    /// `int64_t` / `uint64_t` values.
    W64,
}

impl Width {
    fn bytes(self) -> usize {
        match self {
            Self::W32 => 4,
            Self::W64 => 8,
        }
    }
}

/// The largest encoded size of `count` integers (`_GetEncodedBufferSize`): the common
/// value, 2 bits of code per integer, and at most one full integer each.
pub(crate) fn encoded_size(count: usize, width: Width) -> Option<usize> {
    if count == 0 {
        return Some(0);
    }
    let codes = count.checked_mul(2)?.checked_add(7)? / 8;
    width
        .bytes()
        .checked_add(codes)?
        .checked_add(count.checked_mul(width.bytes())?)
}

/// Decodes `count` delta-coded integers (already LZ4-decompressed) as `i64`; 32-bit
/// streams wrap as `int32_t` arithmetic does.
pub(crate) fn decode_ints(
    data: &[u8],
    count: usize,
    width: Width,
) -> Result<Vec<i64>, CodingError> {
    if count == 0 {
        return Ok(Vec::new());
    }
    let w = width.bytes();
    let short = || CodingError::IntegersEndEarly;
    let common = read_int(data, 0, w).ok_or_else(short)?;
    let codes_len = (count * 2).div_ceil(8);
    let codes = data.get(w..w + codes_len).ok_or_else(short)?;
    let mut at = w + codes_len;
    // Small and medium sizes: 1 and 2 bytes for 32-bit streams, 2 and 4 for 64-bit ones.
    let (small, medium) = match width {
        Width::W32 => (1, 2),
        Width::W64 => (2, 4),
    };
    let mut out = Vec::with_capacity(count);
    let mut prev: i64 = 0;
    for i in 0..count {
        let code = (codes.get(i / 4).copied().unwrap_or(0) >> (2 * (i % 4))) & 3;
        let delta = match code {
            0 => common,
            1..=3 => {
                let n = [0, small, medium, w][usize::from(code)];
                let v = read_int(data, at, n).ok_or_else(short)?;
                at += n;
                v
            }
            _ => 0,
        };
        prev = match width {
            Width::W32 => i64::from((prev as i32).wrapping_add(delta as i32)),
            Width::W64 => prev.wrapping_add(delta),
        };
        out.push(prev);
    }
    Ok(out)
}

/// A little-endian signed integer of `n` bytes (1, 2, 4 or 8) at `at`, sign-extended.
fn read_int(data: &[u8], at: usize, n: usize) -> Option<i64> {
    let b = data.get(at..at.checked_add(n)?)?;
    Some(match n {
        1 => i64::from(b[0] as i8),
        2 => i64::from(i16::from_le_bytes([b[0], b[1]])),
        4 => i64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        _ => i64::from_le_bytes(b.try_into().ok()?),
    })
}

/// An IEEE 754 binary16 value as `f32` (exact).
pub(crate) fn half_to_f32(bits: u16) -> f32 {
    let sign = if bits & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = i32::from((bits >> 10) & 0x1f);
    let fraction = f32::from(bits & 0x3ff);
    match exponent {
        0 => sign * fraction * 2f32.powi(-24),
        31 if fraction == 0.0 => sign * f32::INFINITY,
        31 => f32::NAN,
        e => sign * (1.0 + fraction / 1024.0) * 2f32.powi(e - 15),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The example of `integerCoding.cpp`'s comment, encoded by hand.
    #[test]
    fn decodes_the_documented_example() {
        // input [123, 124, 125, 100125, 100125, 100126, 100126]
        // deltas [123, 1, 1, 100000, 0, 1, 0], common value 1.
        let mut data = 1_i32.to_le_bytes().to_vec();
        // codes: 01 00 00 11 | 01 00 01 (xx): byte 0 = 0b11_00_00_01, byte 1 = 0b00_01_00_01.
        data.extend([0b1100_0001, 0b0001_0001]);
        data.push(123);
        data.extend(100_000_i32.to_le_bytes());
        data.extend([0, 0]);
        let got = decode_ints(&data, 7, Width::W32).unwrap();
        assert_eq!(got, [123, 124, 125, 100_125, 100_125, 100_126, 100_126]);
        assert!(decode_ints(&data[..data.len() - 1], 7, Width::W32).is_err());
    }

    #[test]
    fn lz4_round_trip_and_corruption() {
        let raw: Vec<u8> = (0..1000_u32).flat_map(|i| (i % 7).to_le_bytes()).collect();
        let mut packed = vec![0_u8];
        packed.extend(lz4_flex::block::compress(&raw));
        assert_eq!(decompress(&packed, raw.len()).unwrap(), raw);
        assert!(decompress(&packed, raw.len() + 1).is_err());
        assert!(decompress(&packed[..packed.len() / 2], raw.len()).is_err());
        // Two chunks.
        let (a, b) = raw.split_at(1500);
        let mut chunked = vec![2_u8];
        for part in [a, b] {
            let c = lz4_flex::block::compress(part);
            chunked.extend((c.len() as i32).to_le_bytes());
            chunked.extend(c);
        }
        assert_eq!(decompress(&chunked, raw.len()).unwrap(), raw);
        assert!(decompress(&[0xff, 1, 2], 10).is_err());
    }

    #[test]
    fn halves() {
        assert_eq!(half_to_f32(0x3c00), 1.0);
        assert_eq!(half_to_f32(0xc000), -2.0);
        assert_eq!(half_to_f32(0x3c66), 1.099_609_4);
        assert_eq!(half_to_f32(0x0001), 2f32.powi(-24));
        assert_eq!(half_to_f32(0x7c00), f32::INFINITY);
        assert!(half_to_f32(0x7e00).is_nan());
    }
}
