//! Values as the USD writer hands them to `rigport-usd`'s sink: `-0` written as `0` (so
//! the same stage gives the same bytes whatever the sign of a zero), matrices transposed to
//! USD's row vectors, scales rounded to half precision.

use glam::DMat4;

/// `x` with `-0` made `0` (`x + 0.0` is `+0` for both zeros and `x` otherwise).
pub(super) fn zero(x: f32) -> f32 {
    x + 0.0
}

/// Every component through [`zero`].
pub(super) fn zeroed<const N: usize>(v: [f32; N]) -> [f32; N] {
    v.map(zero)
}

/// A `matrix4d` in USD's row-vector convention, its rows in order (`-0` as `0`).
///
/// rigport matrices act on column vectors (`p' = M p`, translation in the last column);
/// USD's act on row vectors (`p' = p M`, translation in the last row), so the USD matrix is
/// the transpose. Its rows are therefore glam's columns, in glam's storage order.
pub(super) fn rows(m: &DMat4) -> [f64; 16] {
    m.to_cols_array().map(|x| x + 0.0)
}

/// The nearest IEEE 754 half-precision value of `x`, as an `f32` (round to nearest, ties to
/// even; overflow to infinity). SkelAnimation `scales` are `half3[]` (UsdSkel schema), so
/// this is what a reader gets back.
pub(super) fn to_half(x: f32) -> f32 {
    if !x.is_finite() || x == 0.0 {
        return x;
    }
    let a = x.abs();
    // Half: 10 fraction bits, exponents -14..=15, subnormals down to 2^-24.
    const MAX_HALF: f32 = 65504.0;
    // Values at or above the midpoint between 65504 and 2^16 round to infinity.
    if a >= 65520.0 {
        return f32::INFINITY.copysign(x);
    }
    // The binary exponent, read from the bits (exact, unlike log2); subnormal halfs share
    // the exponent -14.
    let exp = (((a.to_bits() >> 23) & 0xff) as i32 - 127).max(-14);
    // Spacing of halfs at this magnitude: 2^(exp - 10), a power of two, so `a / ulp` is
    // exact.
    let ulp = 2f32.powi(exp - 10);
    let q = a / ulp;
    let r = q.round();
    // `round` sends ties away from zero; IEEE wants ties to even.
    let r = if q - q.floor() == 0.5 && r % 2.0 != 0.0 {
        r - 1.0
    } else {
        r
    };
    (r * ulp).min(MAX_HALF).copysign(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrices_are_transposed() {
        let m = DMat4::from_translation(glam::DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(&rows(&m)[12..], &[1.0, 2.0, 3.0, 1.0]);
        assert_eq!(zero(-0.0).to_bits(), 0.0f32.to_bits());
    }

    #[test]
    fn half_rounding() {
        assert_eq!(to_half(1.0), 1.0);
        assert_eq!(to_half(0.5), 0.5);
        // 1.2 lies between halfs 1.19921875 and 1.2001953125; the latter is nearer.
        assert_eq!(to_half(1.2), 1.200_195_3);
        assert_eq!(to_half(-1.2), -1.200_195_3);
        // Ties to even: 1 + 2^-11 is halfway between 1 and 1 + 2^-10.
        assert_eq!(to_half(1.0 + 2f32.powi(-11)), 1.0);
        assert_eq!(
            to_half(1.0 + 3.0 * 2f32.powi(-11)),
            1.0 + 2.0 * 2f32.powi(-10)
        );
        assert_eq!(to_half(65504.0), 65504.0);
        assert_eq!(to_half(1e6), f32::INFINITY);
        // Subnormal halfs: multiples of 2^-24.
        assert_eq!(to_half(2f32.powi(-24)), 2f32.powi(-24));
        assert_eq!(to_half(2f32.powi(-26)), 0.0);
        // Every half survives.
        for bits in (0_u32..0x7c00).step_by(7) {
            let h = half_bits_to_f32(bits as u16);
            assert_eq!(to_half(h), h, "{bits:#x}");
        }
    }

    /// Reference decoder of half bit patterns (positive, finite).
    fn half_bits_to_f32(bits: u16) -> f32 {
        let exp = i32::from((bits >> 10) & 0x1f);
        let frac = f32::from(bits & 0x3ff);
        if exp == 0 {
            frac * 2f32.powi(-24)
        } else {
            (1.0 + frac / 1024.0) * 2f32.powi(exp - 15)
        }
    }
}
