//! Typed reads of parsed values: numbers, tuples, matrices, tokens, and the rounding of
//! `half` values.

use super::layer::Value;
pub use super::parse::narrow_to_type;
pub use super::precision::{is_float_type, is_half_type, round_to_half};
use super::stage::Prop;

/// A list of numbers (`int[]`, `float[]`).
pub fn numbers(v: &Value) -> Option<Vec<f64>> {
    match v {
        Value::List(items) => items
            .iter()
            .map(|i| match i {
                Value::Number(n) => Some(*n),
                _ => None,
            })
            .collect(),
        _ => None,
    }
}

/// One number.
pub fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Number(n) => Some(*n),
        _ => None,
    }
}

/// An `N`-tuple of numbers.
pub fn tuple<const N: usize>(v: &Value) -> Option<[f64; N]> {
    let Value::Tuple(items) = v else {
        return None;
    };
    if items.len() != N {
        return None;
    }
    let mut out = [0.0; N];
    for (o, i) in out.iter_mut().zip(items) {
        *o = number(i)?;
    }
    Some(out)
}

/// A list of `N`-tuples (`point3f[]`, `quatf[]`).
pub fn tuples<const N: usize>(v: &Value) -> Option<Vec<[f64; N]>> {
    match v {
        Value::List(items) => items.iter().map(tuple::<N>).collect(),
        _ => None,
    }
}

/// A `matrix4d` as its four rows, as written.
pub fn matrix(v: &Value) -> Option<[[f64; 4]; 4]> {
    let Value::Tuple(rows) = v else {
        return None;
    };
    if rows.len() != 4 {
        return None;
    }
    let mut out = [[0.0; 4]; 4];
    for (o, r) in out.iter_mut().zip(rows) {
        *o = tuple::<4>(r)?;
    }
    Some(out)
}

/// A `matrix4d[]`.
pub fn matrices(v: &Value) -> Option<Vec<[[f64; 4]; 4]>> {
    match v {
        Value::List(items) => items.iter().map(matrix).collect(),
        _ => None,
    }
}

/// A token or string.
pub fn token(v: &Value) -> Option<&str> {
    match v {
        Value::Str(s) | Value::Ident(s) => Some(s),
        _ => None,
    }
}

/// A `token[]` (quoted or bare items).
pub fn tokens(v: &Value) -> Option<Vec<&str>> {
    match v {
        Value::List(items) => items.iter().map(token).collect(),
        _ => None,
    }
}

/// The value of an attribute that rigport reads without time: its default, or else its
/// first time sample (and whether it had to take a sample).
pub fn static_value<'l>(prop: &Prop<'l>) -> Option<(&'l Value, bool)> {
    match prop.default {
        Some(v) if *v != Value::None => Some((v, false)),
        _ => prop
            .samples
            .as_ref()
            .and_then(|s| s.iter().find(|(_, v)| **v != Value::None))
            .map(|(_, v)| (*v, true)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_rounding_matches_ieee_binary16() {
        assert_eq!(round_to_half(1.0), 1.0);
        // 1.1 is not a half: the nearest is 1 + 102/1024.
        assert_eq!(round_to_half(1.1), 1.0 + 102.0 / 1024.0);
        assert_eq!(round_to_half(-2.0e-8), -0.0);
        assert_eq!(round_to_half(65504.0), 65504.0);
        assert_eq!(round_to_half(70000.0), f32::INFINITY);
        // Subnormal halves are multiples of 2^-24.
        let tiny = 3.0 * 2f32.powi(-24);
        assert_eq!(round_to_half(tiny + 2f32.powi(-27)), tiny);
        assert!(is_half_type("half3[]") && is_half_type("quath") && is_half_type("texCoord2h[]"));
        assert!(!is_half_type("float3[]") && !is_half_type("matrix4d[]") && !is_half_type("token"));
        assert!(is_float_type("float") && is_float_type("point3f[]") && is_float_type("quatf"));
        assert!(!is_float_type("half3[]") && !is_float_type("double3") && !is_float_type("token"));
        let mut v = Value::List(vec![Value::Tuple(vec![
            Value::Number(0.1),
            Value::Number(1.1),
        ])]);
        narrow_to_type(&mut v, "float2[]");
        assert_eq!(
            v,
            Value::List(vec![Value::Tuple(vec![
                Value::Number(f64::from(0.1_f32)),
                Value::Number(f64::from(1.1_f32))
            ])])
        );
    }
}
