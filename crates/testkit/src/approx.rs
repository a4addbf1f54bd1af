//! Approximate asserts that print both values and the difference (as glam's do).

/// Asserts `|actual - expected| <= tol`; `what` names the value in the failure message.
///
/// # Panics
/// The difference is larger than `tol`, or either value is NaN.
#[track_caller]
pub fn assert_close(actual: f64, expected: f64, tol: f64, what: &str) {
    let diff = (actual - expected).abs();
    assert!(
        diff <= tol,
        "{what}: {actual} vs expected {expected}: difference {diff} > {tol}"
    );
}

/// Asserts two equally long slices agree element-wise within `tol`; the message names the
/// first element that does not.
///
/// # Panics
/// The lengths differ, or an element differs by more than `tol`.
#[track_caller]
pub fn assert_all_close(actual: &[f32], expected: &[f32], tol: f32, what: &str) {
    assert_eq!(actual.len(), expected.len(), "{what}: lengths differ");
    for (i, (a, e)) in actual.iter().zip(expected).enumerate() {
        let diff = (a - e).abs();
        assert!(
            diff <= tol,
            "{what}[{i}]: {a} vs expected {e}: difference {diff} > {tol}"
        );
    }
}
