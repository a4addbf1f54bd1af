//! The compression layers a crate file writes, the inverses of the reader's `coding`:
//! `TfFastCompression` (one LZ4 block after a zero chunk-count byte) and
//! `Usd_IntegerCompression` (32-bit deltas with 2-bit size codes, then LZ4), and IEEE
//! binary16 encoding for `half` values.

/// `TfFastCompression::CompressToBuffer` for inputs under its 2 GB chunk size: a chunk
/// count of 0, then one LZ4 block.
pub(crate) fn fast_compress(data: &[u8]) -> Vec<u8> {
    let mut out = vec![0_u8];
    out.extend_from_slice(&lz4_flex::block::compress(data));
    out
}

/// `Usd_IntegerCompression::CompressToBuffer` for 32-bit integers: the most common delta
/// between neighbours (the first value's delta is from 0), a 2-bit code per integer (0:
/// the common delta, 1: an `i8`, 2: an `i16`, 3: an `i32` follows), the deltas that are
/// not the common one, all LZ4-compressed.
pub(crate) fn compress_ints(values: &[i32]) -> Vec<u8> {
    if values.is_empty() {
        return fast_compress(&[]);
    }
    let mut deltas = Vec::with_capacity(values.len());
    let mut prev = 0_i32;
    for &v in values {
        deltas.push(v.wrapping_sub(prev));
        prev = v;
    }
    // The most common delta (ties: the smallest, so the output is deterministic).
    let mut sorted = deltas.clone();
    sorted.sort_unstable();
    let (mut common, mut best) = (sorted[0], 0_usize);
    let mut run_start = 0;
    for i in 1..=sorted.len() {
        if i == sorted.len() || sorted[i] != sorted[run_start] {
            if i - run_start > best {
                best = i - run_start;
                common = sorted[run_start];
            }
            run_start = i;
        }
    }
    let mut raw = common.to_le_bytes().to_vec();
    let codes_at = raw.len();
    raw.resize(codes_at + (values.len() * 2).div_ceil(8), 0);
    for (i, &d) in deltas.iter().enumerate() {
        let code: u8 = if d == common {
            0
        } else if let Ok(small) = i8::try_from(d) {
            raw.extend_from_slice(&small.to_le_bytes());
            1
        } else if let Ok(medium) = i16::try_from(d) {
            raw.extend_from_slice(&medium.to_le_bytes());
            2
        } else {
            raw.extend_from_slice(&d.to_le_bytes());
            3
        };
        if let Some(byte) = raw.get_mut(codes_at + i / 4) {
            *byte |= code << (2 * (i % 4));
        }
    }
    fast_compress(&raw)
}

/// The binary16 bits of `x` rounded to the nearest half (ties to even), as USD's `GfHalf`
/// converts.
pub(crate) fn f32_to_half(x: f32) -> u16 {
    let sign: u16 = if x.is_sign_negative() { 0x8000 } else { 0 };
    if x.is_nan() {
        return sign | 0x7e00;
    }
    let r = crate::values::round_to_half(x).abs();
    if r == 0.0 {
        return sign;
    }
    if r.is_infinite() {
        return sign | 0x7c00;
    }
    let exponent = ((r.to_bits() >> 23) & 0xff) as i32 - 127;
    if exponent < -14 {
        // Subnormal: a multiple of 2^-24 (exact after rounding).
        return sign | (r * 2f32.powi(24)) as u16;
    }
    let fraction = ((r / 2f32.powi(exponent) - 1.0) * 1024.0) as u16;
    sign | (((exponent + 15) as u16) << 10) | fraction
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crate_file::coding_for_tests::{decode_ints, decompress, half_to_f32};

    #[test]
    fn integers_round_trip_through_the_reader() {
        let cases: Vec<Vec<i32>> = vec![
            vec![7],
            vec![0, 1, 2, 3, 4, 5, 6, 7, 8, 9],
            vec![-1, 300, -70000, i32::MAX, i32::MIN, 0, 0, 0, 5],
            (0..1000).map(|i| (i * 37) % 101 - 50).collect(),
        ];
        for values in cases {
            let packed = compress_ints(&values);
            let max = 4 + (values.len() * 2).div_ceil(8) + 4 * values.len();
            let raw = decompress(&packed, max).unwrap();
            let back = decode_ints(&raw, values.len()).unwrap();
            assert_eq!(
                back,
                values.iter().map(|&v| i64::from(v)).collect::<Vec<_>>()
            );
        }
    }

    #[test]
    fn halves_match_the_reader() {
        for x in [
            0.0_f32, -0.0, 1.0, -2.5, 0.1, 65504.0, 1e-7, 6.1e-5, 3.0e-6, 70000.0, -1e9,
        ] {
            let bits = f32_to_half(x);
            assert_eq!(half_to_f32(bits), crate::values::round_to_half(x), "{x}");
        }
        for bits in 0..0x7c00_u16 {
            assert_eq!(f32_to_half(half_to_f32(bits)), bits);
        }
    }
}
