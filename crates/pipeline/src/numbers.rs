//! The one check of each kind of number a command takes (a frame rate, a distance, ...), so
//! every option of that kind accepts and refuses the same text with the same words. Each
//! is a `clap` value parser as much as a plain function.

/// A finite number that `ok` accepts, else "expected `expected`".
fn number(text: &str, ok: fn(f32) -> bool, expected: &str) -> Result<f32, String> {
    let v = text.trim().parse::<f32>().ok();
    v.filter(|v| v.is_finite() && ok(*v))
        .ok_or_else(|| format!("expected {expected}"))
}

/// A frame rate: a positive, finite number of frames per second.
///
/// ```
/// use rigport_pipeline::numbers::frame_rate;
/// assert_eq!(frame_rate("29.97"), Ok(29.97));
/// assert_eq!(frame_rate("0"), Err("expected a positive frame rate".into()));
/// ```
///
/// # Errors
/// Anything else.
pub fn frame_rate(text: &str) -> Result<f32, String> {
    number(text, |v| v > 0.0, "a positive frame rate")
}

/// A distance that may be 0.
///
/// ```
/// use rigport_pipeline::numbers::distance;
/// assert_eq!(distance("0"), Ok(0.0));
/// assert!(distance("-1").is_err() && distance("inf").is_err());
/// ```
///
/// # Errors
/// A negative, infinite or unreadable number.
pub fn distance(text: &str) -> Result<f32, String> {
    number(text, |v| v >= 0.0, "a distance >= 0")
}

/// A number that may be 0.
///
/// ```
/// assert_eq!(rigport_pipeline::numbers::non_negative("0.5"), Ok(0.5));
/// ```
///
/// # Errors
/// A negative, infinite or unreadable number.
pub fn non_negative(text: &str) -> Result<f32, String> {
    number(text, |v| v >= 0.0, "a number >= 0")
}

/// A positive distance or factor.
///
/// ```
/// assert!(rigport_pipeline::numbers::positive("0").is_err());
/// ```
///
/// # Errors
/// Zero, a negative, infinite or unreadable number.
pub fn positive(text: &str) -> Result<f32, String> {
    number(text, |v| v > 0.0, "a positive number")
}

/// A point or offset: three finite numbers separated by commas (`X,Y,Z`).
///
/// ```
/// use rigport_pipeline::numbers::point;
/// use rigport_model::glam::Vec3;
/// assert_eq!(point("0, -1.5,2"), Ok(Vec3::new(0.0, -1.5, 2.0)));
/// assert!(point("1,2").is_err());
/// ```
///
/// # Errors
/// Not three finite numbers.
pub fn point(text: &str) -> Result<rigport_model::glam::Vec3, String> {
    let v: Vec<f32> = text
        .split(',')
        .map(|t| t.trim().parse::<f32>().ok().filter(|v| v.is_finite()))
        .collect::<Option<_>>()
        .unwrap_or_default();
    match v.as_slice() {
        &[x, y, z] => Ok(rigport_model::glam::Vec3::new(x, y, z)),
        _ => Err("expected X,Y,Z: three numbers separated by commas".into()),
    }
}
