//! Rotations as 16- or 8-bit normalized integers, as glTF stores animation outputs.
//!
//! glTF 2.0 §3.11 ("Animations", accessor types of `rotation` sampler outputs) allows
//! `SHORT` and `BYTE` normalized components for rotations in core glTF, no extension
//! needed; a reader decodes a component `c` as `max(c / 32767, -1)` or `max(c / 127, -1)`
//! (§3.11, "Animation Samplers", and §3.6.2.4 on normalized integers). The encoder and the key reducer call the same
//! functions, so the error a reducer measures is the error of the bytes written.

/// The largest magnitude of a `SHORT` normalized component.
const SHORT_MAX: f64 = 32767.0;
/// The largest magnitude of a `BYTE` normalized component.
const BYTE_MAX: f64 = 127.0;

/// `q` (xyzw, any non-zero length) normalized in `f64` and rounded to 16-bit normalized
/// components whose length is nearest 1 (see the body). Odd: `rotation_to_i16(-q) == -rotation_to_i16(q)` component by
/// component, so flipping a key's sign after encoding equals encoding the flipped key.
///
/// ```
/// use rigport_model::quantize::{rotation_from_i16, rotation_to_i16};
///
/// let q = [0.0, 0.6, 0.0, 0.8];
/// // Rounded, (0, 19660, 0, 26214) would be 1.2e-5 too long; this is 1e-9 off.
/// assert_eq!(rotation_to_i16(q), [0, 19661, 0, 26213]);
/// assert_eq!(rotation_to_i16([-0.0, -0.6, -0.0, -0.8]), [0, -19661, 0, -26213]);
/// let back = rotation_from_i16(rotation_to_i16(q));
/// assert!((back[1] - 0.6).abs() < 1.0 / 32767.0);
/// ```
pub fn rotation_to_i16(q: [f32; 4]) -> [i16; 4] {
    // Within ±32767: the casts are exact.
    nearest_length(q, SHORT_MAX, |c, r| {
        let length = (c.iter().map(|x| x * x).sum::<f64>() - SHORT_MAX * SHORT_MAX).abs();
        let distance: f64 = c.iter().zip(r).map(|(a, b)| (a - b).powi(2)).sum();
        Some((length, distance))
    })
    .map(|c| c as i16)
}

/// [`rotation_to_i16`] with 8-bit normalized components (`BYTE`, 4 bytes a key): a step of
/// 1/127. Of the candidates within one step of each component, the one that moves a point
/// at unit distance least (its angle, plus twice its length's distance to 1, which a
/// reader composes as a scale), among those within 0.75% of unit length (glTF-Validator
/// reports a rotation output more than 0.77% off).
///
/// ```
/// use rigport_model::quantize::{rotation_from_i8, rotation_to_i8};
///
/// let q = [0.0, 0.6, 0.0, 0.8];
/// // (0, 77, 0, 101) is within 0.003% of unit length but 0.016 rad off; this is 0.16%
/// // long and 0.006 rad off.
/// assert_eq!(rotation_to_i8(q), [0, 76, 0, 102]);
/// assert_eq!(rotation_to_i8([-0.0, -0.6, -0.0, -0.8]), [0, -76, 0, -102]);
/// let back = rotation_from_i8(rotation_to_i8(q));
/// let length = back.iter().map(|c| c * c).sum::<f32>().sqrt();
/// assert!((length - 1.0).abs() < 0.002 && (back[1] - 0.6).abs() < 1.0 / 127.0);
/// ```
pub fn rotation_to_i8(q: [f32; 4]) -> [i8; 4] {
    // Within ±127: the casts are exact.
    nearest_length(q, BYTE_MAX, |c, r| {
        let length = c.iter().map(|x| x * x).sum::<f64>().sqrt();
        let off = (length / BYTE_MAX - 1.0).abs();
        // The angle between unit quaternions is about twice their chord.
        let chord = c
            .iter()
            .zip(r)
            .map(|(a, b)| (a / length - b / BYTE_MAX).powi(2))
            .sum::<f64>()
            .sqrt();
        (off <= 0.0075).then_some((2.0 * chord + 2.0 * off, 0.0))
    })
    .map(|c| c as i8)
}

/// The rotation a reader decodes from 8-bit normalized components: `max(c / 127, -1)`
/// each (not renormalized).
pub fn rotation_from_i8(c: [i8; 4]) -> [f32; 4] {
    c.map(|c| (f64::from(c) / BYTE_MAX).max(-1.0) as f32)
}

/// [`rotation_from_i8`] of [`rotation_to_i8`]: the rotation a reader sees for `q`.
pub fn rotation_as_i8(q: [f32; 4]) -> [f32; 4] {
    rotation_from_i8(rotation_to_i8(q))
}

/// `q` normalized in `f64` and scaled to integers within `±max` (whole numbers as `f64`):
/// of the candidates within one step of each rounded component, the one with the least
/// `key(candidate, target)` (both as magnitudes; `None`: not a candidate), or the rounded
/// components when none is.
fn nearest_length(
    q: [f32; 4],
    max: f64,
    key: impl Fn(&[f64; 4], &[f64; 4]) -> Option<(f64, f64)>,
) -> [f64; 4] {
    let len = q
        .iter()
        .map(|&c| f64::from(c) * f64::from(c))
        .sum::<f64>()
        .sqrt();
    let len = if len > 0.0 && len.is_finite() {
        len
    } else {
        1.0
    };
    // |c / len| <= 1, so the rounded values are within ±max.
    let r = q.map(|c| f64::from(c) / len * max);
    // Readers compose the decoded quaternion as it is (three.js, as glTF's own sample
    // viewer: a matrix from x, y, z, w without normalizing), and a length off 1 scales
    // the joint by its square. So of the integers within one step of each rounded
    // component (exact zeros kept), `key` picks the one written (16 bits: the length
    // nearest 32767, the nearest to `q` among equals). In magnitudes, signs restored: odd
    // as promised.
    let target = r.map(f64::abs);
    let base = target.map(f64::round);
    // Each component's candidates: its rounding, and one step either way within [0, max]
    // (an exact zero stays).
    let options: [([f64; 3], usize); 4] = std::array::from_fn(|i| {
        let (mut values, mut len) = ([base[i]; 3], 1);
        if r[i] != 0.0 {
            for v in [base[i] - 1.0, base[i] + 1.0] {
                if (0.0..=max).contains(&v) {
                    values[len] = v;
                    len += 1;
                }
            }
        }
        (values, len)
    });
    let mut best = base;
    let mut best_key = (f64::INFINITY, f64::INFINITY);
    let [o0, o1, o2, o3] = options.map(|(values, len)| values.into_iter().take(len));
    for c0 in o0 {
        for c1 in o1.clone() {
            for c2 in o2.clone() {
                for c3 in o3.clone() {
                    let c = [c0, c1, c2, c3];
                    if let Some(k) = key(&c, &target).filter(|&k| k < best_key) {
                        best_key = k;
                        best = c;
                    }
                }
            }
        }
    }
    std::array::from_fn(|i| best[i].copysign(r[i]))
}

/// The rotation a reader decodes from 16-bit normalized components: `max(c / 32767, -1)`
/// each (not renormalized; a slerp renormalizes or not, as the reader does).
pub fn rotation_from_i16(c: [i16; 4]) -> [f32; 4] {
    c.map(|c| (f64::from(c) / SHORT_MAX).max(-1.0) as f32)
}

/// [`rotation_from_i16`] of [`rotation_to_i16`]: the rotation a reader sees for `q`.
pub fn rotation_as_i16(q: [f32; 4]) -> [f32; 4] {
    rotation_from_i16(rotation_to_i16(q))
}

/// One component of a CUBICSPLINE rotation output (a value's or a tangent's) as a 16-bit
/// normalized integer, rounded, component by component and not normalized (a tangent is a
/// derivative, not a rotation); `None` outside `[-1, 1]`, which a normalized short cannot
/// hold (a tangent is in units per second and can exceed it).
///
/// ```
/// use rigport_model::quantize::{component_as_i16, component_to_i16};
///
/// assert_eq!(component_to_i16(0.5), Some(16384));
/// assert_eq!(component_to_i16(-1.0), Some(-32767));
/// assert_eq!(component_to_i16(1.5), None);
/// assert!((component_as_i16(0.3) - 0.3).abs() <= 0.5 / 32767.0);
/// ```
pub fn component_to_i16(c: f32) -> Option<i16> {
    (c.abs() <= 1.0).then(|| (f64::from(c) * SHORT_MAX).round() as i16)
}

/// What a reader decodes for [`component_to_i16`] of `c` (`c` itself outside `[-1, 1]`,
/// where a writer keeps floats).
pub fn component_as_i16(c: f32) -> f32 {
    component_to_i16(c).map_or(c, |i| (f64::from(i) / SHORT_MAX).max(-1.0) as f32)
}

/// A uniform grid for a mesh's positions as 16-bit integers (`KHR_mesh_quantization`):
/// a position is stored as `q = round((p - origin) / step)`, each component in
/// `[-32767, 32767]`, and read back as `origin + step * q` (a writer folds that map into
/// the skin's inverse bind matrices). One step for every axis keeps the map a uniform
/// scale, so normals skinned with it keep their directions.
///
/// ```
/// use rigport_model::glam::Vec3;
/// use rigport_model::quantize::PositionGrid;
///
/// let points = [Vec3::new(-1.0, 0.0, 0.25), Vec3::new(1.0, 0.5, 0.0), Vec3::new(0.3, 0.1, 0.2)];
/// let grid = PositionGrid::new(&points).expect("finite");
/// assert_eq!(grid.encode(points[0])[0], -32767);
/// for &p in &points {
///     let back = grid.decode(grid.encode(p));
///     assert!(back.distance(p) <= grid.max_error());
/// }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionGrid {
    /// The point stored as `(0, 0, 0)`, in the mesh's space: the middle of the positions'
    /// bounding box ([`PositionGrid::new`]) or its lowest corner ([`PositionGrid::within`]).
    pub origin: glam::Vec3,
    /// The distance between grid points on every axis, in the mesh's length unit.
    pub step: f32,
}

/// The bounding box of `positions` (lowest and highest corner); `None` without positions
/// or with a non-finite one.
fn bounds(positions: &[glam::Vec3]) -> Option<(glam::Vec3, glam::Vec3)> {
    let first = *positions.first()?;
    let (lo, hi) = positions
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

impl PositionGrid {
    /// The grid spanning `positions`' bounding box with 65,534 steps along its longest
    /// side, centred on it; `None` without positions or with a non-finite one.
    pub fn new(positions: &[glam::Vec3]) -> Option<Self> {
        let (lo, hi) = bounds(positions)?;
        Some(Self::spanning(lo, hi))
    }

    /// [`PositionGrid::new`] over the box from `lo` to `hi`.
    fn spanning(lo: glam::Vec3, hi: glam::Vec3) -> Self {
        let extent = (hi - lo).max_element();
        // A single point (or a degenerate box): any step holds it exactly.
        let step = if extent > 0.0 {
            extent / (2.0 * SHORT_MAX as f32)
        } else {
            1.0
        };
        Self {
            origin: (lo + hi) * 0.5,
            step,
        }
    }

    /// The coarsest grid over `positions`' box whose [`PositionGrid::max_error`] is at most
    /// `error`, never finer than [`PositionGrid::new`]'s (which it is for an `error` that
    /// grid cannot meet, 0 included): fewer distinct integers leave less for a vertex codec
    /// to store (`EXT_meshopt_compression`). A coarser grid starts at the box's lowest
    /// corner when the box then fits in `0..=32767` steps, so that no stored integer
    /// changes sign from vertex to vertex (a sign flip changes every byte). `None` as for
    /// [`PositionGrid::new`].
    ///
    /// ```
    /// use rigport_model::glam::Vec3;
    /// use rigport_model::quantize::PositionGrid;
    ///
    /// let points = [Vec3::new(-1.0, 0.0, 0.25), Vec3::new(1.0, 0.5, 0.0)];
    /// let fine = PositionGrid::new(&points).expect("finite");
    /// let coarse = PositionGrid::within(&points, 1e-3).expect("finite");
    /// assert!(coarse.step > 10.0 * fine.step && coarse.max_error() <= 1e-3);
    /// // From the box's lowest corner: no negative integers.
    /// assert_eq!(coarse.encode(points[0]), [0, 0, (0.25 / coarse.step).round() as i16]);
    /// assert!(coarse.decode(coarse.encode(points[1])).distance(points[1]) <= 1e-3);
    /// assert_eq!(PositionGrid::within(&points, 0.0), Some(fine));
    /// ```
    pub fn within(positions: &[glam::Vec3], error: f32) -> Option<Self> {
        let (lo, hi) = bounds(positions)?;
        let fine = Self::spanning(lo, hi);
        // max_error is linear in the step: a + b * step.
        let root3 = 3f32.sqrt();
        let size = lo.abs().max_element().max(fine.origin.abs().max_element());
        let a = 2.0 * root3 * f32::EPSILON * size;
        let b = 0.5 * root3 + 2.0 * root3 * f32::EPSILON * SHORT_MAX as f32;
        // A hair under the solution, which f32 arithmetic may round up past `error`.
        let step = (error - a) / b * (1.0 - 1e-5);
        let from_corner = (hi - lo).max_element() / step <= SHORT_MAX as f32 - 1.0;
        let coarse = Self {
            origin: if from_corner { lo } else { fine.origin },
            step,
        };
        Some(coarse)
            .filter(|c| c.step > fine.step && c.max_error() <= error)
            .or(Some(fine))
    }

    /// The grid point nearest `p`, clamped to the 16-bit range.
    pub fn encode(&self, p: glam::Vec3) -> [i16; 3] {
        ((p - self.origin) / self.step)
            .to_array()
            .map(|c| c.round().clamp(-SHORT_MAX as f32, SHORT_MAX as f32) as i16)
    }

    /// The position a reader gets for `q`.
    pub fn decode(&self, q: [i16; 3]) -> glam::Vec3 {
        self.origin + glam::Vec3::from_array(q.map(f32::from)) * self.step
    }

    /// A bound on the distance between a position in the box and what a reader decodes:
    /// half a step on each axis (`step * √3 / 2`), plus two `f32` roundings of the
    /// decoded coordinates' size (a reader's matrix arithmetic).
    pub fn max_error(&self) -> f32 {
        let size = self.origin.abs().max_element() + SHORT_MAX as f32 * self.step;
        self.step * 0.5 * 3f32.sqrt() + 2.0 * 3f32.sqrt() * f32::EPSILON * size
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over many rotations, 8-bit keys stay within glTF-Validator's unit length (0.77%),
    /// and move a point at unit distance by under 0.02 (angle plus twice the length
    /// error); the encoding is odd.
    #[test]
    fn byte_rotations_keep_near_unit_length() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        let (mut worst_length, mut worst_move) = (0.0f64, 0.0f64);
        for _ in 0..20_000 {
            let q = [next(), next(), next(), next()];
            let n = q.iter().map(|c| c * c).sum::<f32>().sqrt();
            if n < 0.1 {
                continue;
            }
            let q = q.map(|c| c / n);
            let back = rotation_as_i8(q);
            let length = back
                .iter()
                .map(|&c| f64::from(c).powi(2))
                .sum::<f64>()
                .sqrt();
            let dot = back
                .iter()
                .zip(&q)
                .map(|(a, b)| f64::from(*a) * f64::from(*b));
            let dot = dot.sum::<f64>().abs() / length;
            let off = (length - 1.0).abs();
            worst_length = worst_length.max(off);
            worst_move = worst_move.max(2.0 * dot.min(1.0).acos() + 2.0 * off);
            assert_eq!(rotation_to_i8(q.map(|c| -c)), rotation_to_i8(q).map(|c| -c));
        }
        assert!(worst_length <= 0.0075, "{worst_length}");
        assert!(worst_move < 0.02, "{worst_move}");
    }
}
