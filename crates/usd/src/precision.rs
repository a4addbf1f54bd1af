//! The precision of USD value types: which store `half` or `float` numbers, and the
//! rounding to binary16.

/// Whether a value type stores IEEE half floats (`half`, `half3[]`, `quath`,
/// `texCoord2h`, ...), whose values must be rounded as USD rounds them when it reads them.
pub fn is_half_type(type_name: &str) -> bool {
    let base = type_name.trim_end_matches("[]");
    base.starts_with("half")
        || base == "quath"
        || (base.ends_with('h')
            && base
                .chars()
                .rev()
                .nth(1)
                .is_some_and(|c| c.is_ascii_digit()))
}

/// Whether a value type stores IEEE single floats (`float`, `float3[]`, `point3f`,
/// `normal3f[]`, `quatf`, `texCoord2f`, ...).
pub fn is_float_type(type_name: &str) -> bool {
    let base = type_name.trim_end_matches("[]");
    base.starts_with("float")
        || base == "quatf"
        || (base.ends_with('f')
            && base
                .chars()
                .rev()
                .nth(1)
                .is_some_and(|c| c.is_ascii_digit()))
}

/// `x` rounded to the nearest IEEE 754 binary16 value (ties to even), as a `half`
/// attribute holds it; magnitudes beyond the largest half round to infinity.
pub fn round_to_half(x: f32) -> f32 {
    if !x.is_finite() || x == 0.0 {
        return x;
    }
    // 65520 is halfway between the largest half (65504) and the next power of two: from
    // there on, rounding gives infinity.
    if x.abs() >= 65520.0 {
        return f32::INFINITY.copysign(x);
    }
    let exponent = ((x.abs().to_bits() >> 23) & 0xff) as i32 - 127;
    // Halves have 10 fraction bits; below 2^-14 they are subnormal with a fixed step 2^-24.
    let step = 2f32.powi(exponent.max(-14) - 10);
    (x / step).round_ties_even() * step
}
