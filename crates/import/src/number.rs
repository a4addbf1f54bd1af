//! Decimal text to `f32`, bit for bit as `str::parse::<f32>` gives it, with a fast path
//! for the plain decimals that mocap and mesh files are made of.
//!
//! `str::parse::<f32>` is correctly rounded (Rust's `dec2flt`, Eisel-Lemire with a big-
//! decimal fallback), so any other route must give exactly the nearest `f32` with ties to
//! even. The fast path is Clinger's ("How to read floating point numbers accurately",
//! PLDI 1990): when the digits form an integer `m` that is exact in the floating type and
//! `10^k` is exact too, one IEEE multiplication or division rounds `m * 10^±k` correctly.
//! Everything the fast path cannot vouch for (more than 8 significant digits, exponents
//! out of range, `inf`, `nan`, junk) goes to `str::parse`.

/// Exact powers of ten in `f32` (10^10 = 2^10 * 9765625 still fits the 24-bit mantissa).
const POW10_F32: [f32; 11] = [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10];

/// Exact powers of ten in `f64` up to the largest [`scaled`] divides by.
const POW10_F64: [f64; 13] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12,
];

/// `10^-k` rounded to `f64`, for k up to 10 (see [`scaled`] for why that is exact enough).
const INV_POW10_F64: [f64; 11] = [
    1e0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10,
];

/// The largest mantissa the fast path takes: 2^24, exact in `f32`.
const MAX_MANTISSA: u64 = 1 << 24;

/// Parses a float exactly as `token.parse::<f32>()` does (`None` where that fails).
///
/// Short plain decimals (`-0.0881862`, `0.9825`, `12`, `5.1072e-06`: an integer of
/// digits <= 2^24 and a net power of ten from 10^-12 to 10^10) take the fast path
/// ([`scaled`]); anything else goes to `str::parse`. Property tests compare the two.
#[inline]
pub(crate) fn parse_f32(token: &str) -> Option<f32> {
    match scan(token.as_bytes()) {
        (len, Some(value)) if len == token.len() => Some(value),
        _ => token.parse().ok(),
    }
}

/// Splits the token at the start of `text` (up to the first ASCII white space, where
/// `split_ascii_whitespace` cuts) and parses it as [`parse_f32`] does, in one pass over
/// its bytes when the fast path applies. `text` should not start with white space (the
/// token is then empty, and so not a number).
///
/// Returns the token and its value (`None` where `str::parse::<f32>` fails).
#[inline(always)]
pub(crate) fn leading_f32(text: &str) -> (&str, Option<f32>) {
    let bytes = text.as_bytes();
    let (mut len, value) = scan(bytes);
    if let Some(value) = value {
        if bytes.get(len).is_none_or(u8::is_ascii_whitespace) {
            // The token ends at an ASCII byte (or the end), hence a char boundary.
            return (text.get(..len).unwrap_or(text), Some(value));
        }
    }
    // The slow path: find the token's end, let `str::parse` decide.
    while bytes.get(len).is_some_and(|b| !b.is_ascii_whitespace()) {
        len += 1;
    }
    let token = text.get(..len).unwrap_or(text);
    (token, token.parse().ok())
}

/// The value of one ASCII digit.
#[inline(always)]
fn digit(b: Option<&u8>) -> Option<u64> {
    let d = b?.wrapping_sub(b'0');
    (d < 10).then_some(u64::from(d))
}

/// `10^n` for the digit counts [`digit_run`] folds in at once.
const POW10_U64: [u64; 9] = [
    1,
    10,
    100,
    1_000,
    10_000,
    100_000,
    1_000_000,
    10_000_000,
    100_000_000,
];

/// Reads the ASCII digits from `bytes[i]` on into `mantissa` (`mantissa * 10 + digit`
/// each, wrapping); returns the index after the last digit.
///
/// Eight bytes at a time where eight are left (SWAR, as in Lemire's "Number parsing at
/// a gigabyte per second", 2021): the run's length comes from one mask of the bytes that
/// are not digits, and its value from three multiplications instead of one per digit.
#[inline(always)]
fn digit_run(bytes: &[u8], mut i: usize, mantissa: &mut u64) -> usize {
    while let Some(chunk) = bytes.get(i..i + 8) {
        let Ok(chunk) = <[u8; 8]>::try_from(chunk) else {
            break;
        };
        // Byte k of `x` is bytes[i + k]: the first digit is the least significant byte.
        let x = u64::from_le_bytes(chunk);
        let values = x.wrapping_sub(0x3030_3030_3030_3030);
        // A byte's high bit is set in `values` when it is below b'0' (or >= 0xB0), in
        // `x + 0x46..` when it is above b'9' (and below 0xBA). Borrows and carries only
        // reach bytes after the first non-digit, which are not read.
        let not_digit = (values | x.wrapping_add(0x4646_4646_4646_4646)) & 0x8080_8080_8080_8080;
        let n = (not_digit.trailing_zeros() / 8) as usize;
        if n == 0 {
            return i;
        }
        // The run's digits moved to the top bytes: leading zeros below them.
        let v = values << (64 - 8 * n as u32);
        // Pairs, then quadruples, then all eight (most significant digit first in value).
        let v = (v.wrapping_mul(10) + (v >> 8)) & 0x00FF_00FF_00FF_00FF;
        let v = (v.wrapping_mul(100) + (v >> 16)) & 0x0000_FFFF_0000_FFFF;
        let v = (v.wrapping_mul(10_000) + (v >> 32)) & 0xFFFF_FFFF;
        *mantissa = mantissa.wrapping_mul(POW10_U64[n]).wrapping_add(v);
        i += n;
        if n < 8 {
            return i;
        }
    }
    while let Some(d) = digit(bytes.get(i)) {
        *mantissa = mantissa.wrapping_mul(10).wrapping_add(d);
        i += 1;
    }
    i
}

/// Reads the longest prefix of `bytes` shaped like `[+-]digits[.digits][(e|E)[+-]digits]`
/// (at least one mantissa digit). Returns how many bytes it read and the value when the
/// prefix is such a number and the fast path can vouch for it ([`scaled`]); the caller
/// checks that the token ends there.
///
/// Always inlined: the BVH motion loop calls it once per value, and keeping the value in
/// registers instead of a returned struct measured a few percent faster on the kick file.
#[inline(always)]
fn scan(bytes: &[u8]) -> (usize, Option<f32>) {
    let (negative, mut i) = match bytes.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    };
    // Wrapping: more than 19 digits (which could wrap) are rejected below.
    let mut mantissa = 0_u64;
    let int_start = i;
    i = digit_run(bytes, i, &mut mantissa);
    let mut digits = i - int_start;
    let mut decimals = 0_usize;
    if bytes.get(i) == Some(&b'.') {
        i += 1;
        let frac_start = i;
        i = digit_run(bytes, i, &mut mantissa);
        decimals = i - frac_start;
        digits += decimals;
    }
    if digits == 0 {
        return (i, None);
    }
    let mut exponent = 0_i64;
    if matches!(bytes.get(i), Some(b'e' | b'E')) {
        i += 1;
        let negative_exponent = match bytes.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let exp_start = i;
        while let Some(d) = digit(bytes.get(i)) {
            // Saturated far beyond any exponent the fast path takes.
            exponent = (exponent * 10 + d as i64).min(1_000_000);
            i += 1;
        }
        if i == exp_start {
            return (i, None);
        }
        if negative_exponent {
            exponent = -exponent;
        }
    }
    if digits > 19 {
        return (i, None);
    }
    let power = exponent - i64::try_from(decimals).unwrap_or(i64::MAX);
    let value = scaled(mantissa, power);
    (i, value.map(|v| if negative { -v } else { v }))
}

/// `mantissa * 10^power` correctly rounded to `f32`, when that is cheap and provably
/// exact; `None` otherwise (a mantissa above 2^24, a power outside -12..=10).
///
/// Exact because (Clinger's fast path): with `m <= 2^24` and `10^k` (k <= 10) exact in
/// `f32`, `m * 10^k` and `m / 10^k` are single correctly rounded `f32` operations. For
/// k = 11 and 12, `m / 10^k` is computed in `f64` (both operands exact) and rounded
/// again to `f32`; that double rounding is harmless: it could only differ if the `f64`
/// quotient landed on an `f32` midpoint `c * 2^t` (c < 2^25) the exact quotient is not
/// on, but then `|m / 10^k - c * 2^t| >= 2^t / 5^k`, a relative gap above
/// `2^-25 / 5^12 > 2^-53`, more than the `f64` rounding error. For k <= 10 the same gap
/// is at least `2^-25 / 5^10 > 2^-49`, so `m * fl(10^-k)` in `f64` (two roundings, within
/// `2^-52` of the exact quotient) rounds to the same `f32`; and `m / 10^k` (m <= 2^24) is
/// never exactly a midpoint, which would need 25 significant bits. (One-off runs over every
/// mantissa 1..=2^24 with k = 1..=12 agreed with `str::parse` too.)
#[inline(always)]
fn scaled(mantissa: u64, power: i64) -> Option<f32> {
    if mantissa == 0 {
        // `0`, `0.000`, `0e99`: zero whatever the power (the caller adds the sign).
        return Some(0.0);
    }
    if mantissa > MAX_MANTISSA {
        return None;
    }
    let k = usize::try_from(power.unsigned_abs()).ok()?;
    // Exact: the mantissa is at most 2^24.
    let m = mantissa as f32;
    if power >= 0 {
        Some(m * POW10_F32.get(k)?)
    } else if let Some(scale) = INV_POW10_F64.get(k) {
        // A multiplication (lower latency than a division): within 2^-52 of m / 10^k,
        // and no f32 midpoint lies that close (see above), so it rounds the same.
        Some((mantissa as f64 * scale) as f32)
    } else {
        Some((mantissa as f64 / POW10_F64.get(k)?) as f32)
    }
}

/// An unsigned decimal (`12`, `0.9991`, `.5`, `3.`) read one byte at a time, for
/// parsers that cut their own tokens (the Pinocchio weight rows). No sign, no exponent:
/// those make [`Decimal::push`] refuse, and the caller takes [`parse_f32`].
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Decimal {
    mantissa: u64,
    significant: u32,
    decimals: i64,
    any_digit: bool,
    dot: bool,
}

impl Decimal {
    /// Takes the next byte; `false` when it is neither a digit nor the first `.`, or the
    /// number has more than 8 significant digits (then the caller takes the slow path).
    #[inline]
    pub(crate) fn push(&mut self, b: u8) -> bool {
        match b {
            b'0'..=b'9' => {
                self.any_digit = true;
                if self.mantissa != 0 || b != b'0' {
                    self.significant += 1;
                    if self.significant > 8 {
                        return false;
                    }
                    self.mantissa = self.mantissa * 10 + u64::from(b - b'0');
                }
                if self.dot {
                    self.decimals = self.decimals.saturating_add(1);
                }
                true
            }
            b'.' if !self.dot => {
                self.dot = true;
                true
            }
            _ => false,
        }
    }

    /// The value, the same `f32` as `str::parse` ([`scaled`]); `None` without any digit,
    /// or when the fast path cannot vouch for it (too many decimals, a mantissa above 2^24).
    #[inline]
    pub(crate) fn value(&self) -> Option<f32> {
        if !self.any_digit {
            return None;
        }
        scaled(self.mantissa, -self.decimals)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Our value and `str::parse`'s, as bits (so `-0.0` and `0.0` differ).
    fn both(token: &str) -> (Option<u32>, Option<u32>) {
        (
            parse_f32(token).map(f32::to_bits),
            token.parse::<f32>().ok().map(f32::to_bits),
        )
    }

    /// The fast path's value for the whole token (`None`: `str::parse` decides).
    fn fast(token: &str) -> Option<f32> {
        match scan(token.as_bytes()) {
            (len, value) if len == token.len() => value,
            _ => None,
        }
    }

    /// [`Decimal`] fed every byte of `token`: its value, or `None` where it refuses.
    fn decimal(token: &str) -> Option<u32> {
        let mut number = Decimal::default();
        token
            .bytes()
            .all(|b| number.push(b))
            .then(|| number.value())
            .flatten()
            .map(f32::to_bits)
    }

    /// `leading_f32` on `token` followed by white space and more text.
    fn leading(token: &str) -> (String, Option<u32>) {
        let text = format!("{token} \t9 junk");
        let (t, v) = leading_f32(&text);
        (t.to_string(), v.map(f32::to_bits))
    }

    const EDGE_CASES: [&str; 52] = [
        "0",
        "-0",
        "+0",
        "0.9825",
        "-0.0881862",
        "1.",
        ".5",
        ".",
        "-",
        "+",
        "",
        "+1",
        "+-1",
        "-+1",
        "1e3",
        "1e",
        "1e+",
        "1e-",
        "e5",
        ".e5",
        "1.e5",
        "1e5e5",
        "1e--5",
        "5.1072e-06",
        "-5.51765e-07",
        "-1.3905e-06",
        "1E10",
        "16777216e-12",
        "16777217e-12",
        "9999999e-13",
        "0e999999999999",
        "-0e-99999",
        "1e99999999999",
        "0.00000000001",
        "0.0000000001",
        "0.000000000001",
        "16777217",
        "16777216",
        "99999999",
        "9999999",
        "0.1234567",
        "0.12345678",
        "nan",
        "inf",
        "-infinity",
        "1..2",
        "--1",
        "0x1",
        "-.",
        "00000000000012",
        "3.4028235e38",
        "1.17549435e-38",
    ];

    #[test]
    fn edge_cases_equal_str_parse() {
        for token in EDGE_CASES {
            let (ours, std) = both(token);
            assert_eq!(ours, std, "{token:?}");
            if let Some(bits) = decimal(token) {
                assert_eq!(Some(bits), std, "Decimal {token:?}");
            }
            let (t, v) = leading(token);
            if !token.is_empty() {
                assert_eq!(t, token);
                assert_eq!(v, std, "leading {token:?}");
            }
        }
    }

    #[test]
    fn fast_path_takes_the_common_shapes() {
        // Not a correctness property (the slow path is correct too) but the point of the
        // module: these must not fall back to `str::parse`.
        for token in [
            "-4.54261",
            "109.754",
            "5.1072e-06",
            "-5.51765e-07",
            "0",
            "-0",
            "12",
        ] {
            assert!(fast(token).is_some(), "{token}");
        }
        for token in ["nan", "123456789", "1e-13", "1e11", "0x1"] {
            assert!(fast(token).is_none(), "{token}");
        }
    }

    #[test]
    fn leading_token_stops_at_ascii_white_space_only() {
        for sep in [" ", "\t", "\r", "\n", "\x0c"] {
            let text = format!("1.5{sep}2");
            assert_eq!(leading_f32(&text), ("1.5", Some(1.5)));
        }
        // A vertical tab is not ASCII white space to `split_ascii_whitespace` either.
        assert_eq!(leading_f32("1.5\x0b2"), ("1.5\x0b2", None));
        assert_eq!(leading_f32("1.5é 2"), ("1.5é", None));
        assert_eq!(leading_f32(""), ("", None));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(4096))]

        #[test]
        fn plain_decimals_equal_str_parse(
            digits in "[0-9]{0,9}",
            dot in 0_usize..11,
            sign in "[-+]?",
        ) {
            let mut token = digits.clone();
            if dot <= token.len() {
                token.insert(dot, '.');
            }
            token.insert_str(0, &sign);
            let (ours, std) = both(&token);
            proptest::prop_assert_eq!(ours, std, "{}", token);
            // Where `Decimal` takes an unsigned token, it agrees too.
            if let Some(bits) = decimal(&token) {
                proptest::prop_assert!(sign.is_empty(), "{}", token);
                proptest::prop_assert_eq!(Some(bits), std, "{}", token);
            }
        }

        #[test]
        fn decimals_with_exponents_equal_str_parse(
            int in "[0-9]{0,10}",
            frac in "[0-9]{0,10}",
            sign in "[-+]?",
            exp_sign in "[-+]?",
            exp in 0_u32..48,
            marker in "[eE]",
        ) {
            let token = format!("{sign}{int}.{frac}{marker}{exp_sign}{exp}");
            let (ours, std) = both(&token);
            proptest::prop_assert_eq!(ours, std, "{}", token);
            let (t, v) = leading(&token);
            proptest::prop_assert_eq!(t, token.clone());
            proptest::prop_assert_eq!(v, std, "{}", token);
        }

        /// The double-rounded range (10^-11, 10^-12). A one-off exhaustive run over every
        /// mantissa 1..=2^24 with k = 1, 5, 10, 11 and 12 found no difference either.
        #[test]
        fn f64_divisions_equal_str_parse(m in 1..=MAX_MANTISSA, k in 11_u32..=12) {
            let token = format!("{m}e-{k}");
            let (ours, std) = both(&token);
            proptest::prop_assert_eq!(ours, std, "{}", token);
        }

        #[test]
        fn mantissas_near_two_to_the_24_equal_str_parse(
            m in (MAX_MANTISSA - 64)..(MAX_MANTISSA + 64),
            power in -14_i32..13,
        ) {
            let token = format!("{m}e{power}");
            let (ours, std) = both(&token);
            proptest::prop_assert_eq!(ours, std, "{}", token);
        }

        /// Tokens cut from longer lines, so that the eight-byte digit reads run past the
        /// token's end, into white space, other tokens or junk glued to the digits.
        #[test]
        fn tokens_within_lines_equal_str_parse(
            int in "[0-9]{0,21}",
            frac in "[0-9]{0,21}",
            sign in "[-+]?",
            glued in "|[-+.eEx/:]",
            tail in "|[ \t\r][-+0-9.eE a-z]{0,16}",
        ) {
            let token = format!("{sign}{int}.{frac}{glued}");
            let line = format!("{token}{tail}");
            let (t, v) = leading_f32(&line);
            proptest::prop_assert_eq!(t, token.as_str());
            let std = token.parse::<f32>().ok().map(f32::to_bits);
            proptest::prop_assert_eq!(v.map(f32::to_bits), std, "{}", line);
            proptest::prop_assert_eq!(parse_f32(&token).map(f32::to_bits), std, "{}", token);
        }

        #[test]
        fn any_short_text_equals_str_parse(token in "[-+0-9.eE]{0,14}|[-+0-9.eEa-z ]{0,6}") {
            let (ours, std) = both(&token);
            proptest::prop_assert_eq!(ours, std, "{}", token);
        }
    }
}
