//! Signed distance primitives: round cones and ellipsoids, the smooth minimum that blends
//! them, and a squashed, culled body part (`Prim`).

use glam::Vec3;
/// A primitive's shape, in its own (un-squashed) space, with the constants its distance
/// needs precomputed.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Shape {
    /// A capsule whose radius goes linearly from `r1` at `a` to `r2` at `a + ba`.
    RoundCone {
        a: Vec3,
        ba: Vec3,
        r1: f32,
        r2: f32,
        /// `|ba|²`, its inverse, `r1 - r2` and `|ba|² - (r1 - r2)²`.
        l2: f32,
        il2: f32,
        rr: f32,
        a2: f32,
    },
    /// An axis-aligned ellipsoid.
    Ellipsoid {
        center: Vec3,
        radii: Vec3,
        /// `1 / radii` and `1 / radii²`.
        inv_r: Vec3,
        inv_r2: Vec3,
    },
}

impl Shape {
    pub(crate) fn round_cone(a: [f32; 3], r1: f32, b: [f32; 3], r2: f32) -> Shape {
        let (a, b) = (Vec3::from_array(a), Vec3::from_array(b));
        let ba = b - a;
        let l2 = ba.length_squared();
        let rr = r1 - r2;
        Shape::RoundCone {
            a,
            ba,
            r1,
            r2,
            l2,
            il2: 1.0 / l2,
            rr,
            a2: l2 - rr * rr,
        }
    }

    pub(crate) fn ellipsoid(center: [f32; 3], radii: [f32; 3]) -> Shape {
        let radii = Vec3::from_array(radii);
        Shape::Ellipsoid {
            center: Vec3::from_array(center),
            radii,
            inv_r: radii.recip(),
            inv_r2: (radii * radii).recip(),
        }
    }

    /// Signed distance: exact for round cones (Quilez, "distance functions", `sdRoundCone`
    /// between two points), a close bound for ellipsoids (Quilez's `k0 * (k0 - 1) / k1`).
    pub(crate) fn distance(&self, p: Vec3) -> f32 {
        match *self {
            Shape::RoundCone {
                a,
                ba,
                r1,
                r2,
                l2,
                il2,
                rr,
                a2,
            } => {
                let pa = p - a;
                let y = pa.dot(ba);
                let z = y - l2;
                let xv = pa * l2 - ba * y;
                let x2 = xv.length_squared();
                let y2 = y * y * l2;
                let z2 = z * z * l2;
                let k = rr.signum() * rr * rr * x2;
                if z.signum() * a2 * z2 > k {
                    (x2 + z2).sqrt() * il2 - r2
                } else if y.signum() * a2 * y2 < k {
                    (x2 + y2).sqrt() * il2 - r1
                } else {
                    ((x2 * a2 * il2).sqrt() + y * rr) * il2 - r1
                }
            }
            Shape::Ellipsoid {
                center,
                radii,
                inv_r,
                inv_r2,
            } => {
                let q = p - center;
                let k0 = (q * inv_r).length();
                let k1 = (q * inv_r2).length();
                if k1 > 1e-12 {
                    k0 * (k0 - 1.0) / k1
                } else {
                    -radii.min_element()
                }
            }
        }
    }

    /// Axis-aligned bounds.
    pub(crate) fn bounds(&self) -> (Vec3, Vec3) {
        match *self {
            Shape::RoundCone { a, ba, r1, r2, .. } => {
                let r = Vec3::splat(r1.max(r2));
                (a.min(a + ba) - r, a.max(a + ba) + r)
            }
            Shape::Ellipsoid { center, radii, .. } => (center - radii, center + radii),
        }
    }

    pub(crate) fn center(&self) -> Vec3 {
        match *self {
            Shape::RoundCone { a, ba, .. } => a + ba * 0.5,
            Shape::Ellipsoid { center, .. } => center,
        }
    }
}

/// Polynomial smooth minimum with blend radius `k` (Quilez): equals `min(a, b)` when the two
/// differ by `k` or more, and is at most `k / 4` below it.
pub(crate) fn smin(a: f32, b: f32, k: f32) -> f32 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

/// `3t² - 2t³` of `t` clamped to `0..=1`.
pub(crate) fn smoothstep(t: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// One body part of the distance field.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Prim {
    pub(crate) shape: Shape,
    /// Per-axis scale applied about `center` before measuring: 1.3 in `z` makes the part
    /// 1.3 times thinner front to back. `None` for no scaling.
    pub(crate) squash: Option<Vec3>,
    /// The shape's center and `1 / max(squash)`.
    pub(crate) center: Vec3,
    pub(crate) inv_lipschitz: f32,
    /// Smooth-min blend radius with everything before it, metres.
    pub(crate) blend: f32,
    /// Bounds grown so that outside them the part cannot change the field near the surface.
    pub(crate) lo: Vec3,
    pub(crate) hi: Vec3,
}

impl Prim {
    /// Signed distance, scaled so that the field stays 1-Lipschitz (a lower bound when
    /// squashed).
    pub(crate) fn distance(&self, p: Vec3) -> f32 {
        match self.squash {
            None => self.shape.distance(p),
            Some(s) => {
                let q = self.center + (p - self.center) * s;
                self.shape.distance(q) * self.inv_lipschitz
            }
        }
    }

    pub(crate) fn contains(&self, p: Vec3) -> bool {
        p.x >= self.lo.x
            && p.x <= self.hi.x
            && p.y >= self.lo.y
            && p.y <= self.hi.y
            && p.z >= self.lo.z
            && p.z <= self.hi.z
    }
}
