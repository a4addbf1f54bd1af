//! Attachments: a point of the body surface named by a triangle and barycentric weights,
//! found once at rest (the nearest point of the surface) and evaluated on every skinned
//! frame, so that a pinned garment vertex moves with the skin exactly.

use glam::Vec3;

/// A point on a triangle mesh: `bary[0] * p[a] + bary[1] * p[b] + bary[2] * p[c]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The triangle's vertex indices (into the body's concatenated vertices).
    pub triangle: [u32; 3],
    /// Barycentric weights, non-negative, summing to 1.
    pub bary: [f32; 3],
}

impl SurfacePoint {
    /// The point on the surface whose vertex positions are `positions`.
    ///
    /// Sums the three weighted vertices in a fixed order (`a`, `b`, `c`) in `f32`; checkers
    /// evaluating the same triangle get the same point to rounding.
    pub fn eval(&self, positions: &[Vec3]) -> Vec3 {
        let p = |k: usize| {
            positions
                .get(self.triangle[k] as usize)
                .copied()
                .unwrap_or(Vec3::ZERO)
        };
        p(0) * self.bary[0] + p(1) * self.bary[1] + p(2) * self.bary[2]
    }
}

/// The point of triangle `(a, b, c)` nearest to `p`, as barycentric weights (Ericson,
/// *Real-Time Collision Detection*, 5.1.5, region by region, so a degenerate triangle
/// still gives a point on it).
pub fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> [f32; 3] {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = va + vb + vc;
    if denom.abs() <= f32::MIN_POSITIVE || !denom.is_finite() {
        return [1.0, 0.0, 0.0];
    }
    let v = vb / denom;
    let w = vc / denom;
    [1.0 - v - w, v, w]
}

/// The nearest point of the surface (`positions`, `triangles`) to `p`, with its distance.
/// Ties go to the first triangle, so the binding is deterministic. `None` without
/// triangles.
pub fn nearest_point(
    p: Vec3,
    positions: &[Vec3],
    triangles: &[[u32; 3]],
) -> Option<(SurfacePoint, f32)> {
    let mut best: Option<(SurfacePoint, f32)> = None;
    for tri in triangles {
        let [Some(&a), Some(&b), Some(&c)] = tri.map(|i| positions.get(i as usize)) else {
            continue;
        };
        let bary = closest_on_triangle(p, a, b, c);
        let sp = SurfacePoint {
            triangle: *tri,
            bary,
        };
        let d = (sp.eval(positions) - p).length();
        if best.is_none_or(|(_, bd)| d < bd) {
            best = Some((sp, d));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_point_regions() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let at = |p: Vec3| {
            let w = closest_on_triangle(p, a, b, c);
            a * w[0] + b * w[1] + c * w[2]
        };
        assert_eq!(at(Vec3::new(0.25, 0.25, 1.0)), Vec3::new(0.25, 0.25, 0.0));
        assert_eq!(at(Vec3::new(-1.0, -1.0, 0.0)), a);
        assert_eq!(at(Vec3::new(2.0, -1.0, 0.0)), b);
        assert_eq!(at(Vec3::new(0.5, -1.0, 0.0)), Vec3::new(0.5, 0.0, 0.0));
        assert!((at(Vec3::new(1.0, 1.0, 0.0)) - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
        // A degenerate triangle still yields a point on it.
        let w = closest_on_triangle(Vec3::ONE, a, a, a);
        assert_eq!(w.iter().sum::<f32>(), 1.0);
    }

    #[test]
    fn binding_follows_the_surface() {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)];
        let tris = [[0, 1, 2], [1, 3, 2]];
        let (sp, d) = nearest_point(Vec3::new(0.9, 0.8, 0.1), &positions, &tris).unwrap();
        assert!((d - 0.1).abs() < 1e-6);
        let moved: Vec<Vec3> = positions.iter().map(|p| *p + Vec3::Z * 2.0).collect();
        assert!((sp.eval(&moved) - Vec3::new(0.9, 0.8, 2.0)).length() < 1e-6);
    }
}
