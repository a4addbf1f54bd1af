//! The character's body: its parts (sizes of an average adult) and the distance field they
//! make, sampled on a grid one `y` slice at a time.

use glam::Vec3;

use crate::sdf::{smin, Prim, Shape};
/// A body part's shape, model space, metres (left side for limbs).
pub(crate) enum PartShape {
    /// Round cone: `a`, radius at `a`, `b`, radius at `b`.
    Cone([f32; 3], f32, [f32; 3], f32),
    /// Axis-aligned ellipsoid: center, radii.
    Ellipsoid([f32; 3], [f32; 3]),
}

/// One body part of the character.
pub(crate) struct Part {
    shape: PartShape,
    /// See [`Prim::squash`]; `[1.0; 3]` for none.
    squash: [f32; 3],
    /// See [`Prim::blend`].
    blend: f32,
}

pub(crate) const fn part(shape: PartShape, squash: [f32; 3], blend: f32) -> Part {
    Part {
        shape,
        squash,
        blend,
    }
}

use PartShape::{Cone, Ellipsoid};

/// No squash.
pub(crate) const ROUND: [f32; 3] = [1.0, 1.0, 1.0];

/// Torso, neck and head, in smooth-union order. Sizes follow an average adult.
pub(crate) const CENTER_PARTS: [Part; 7] = [
    // Pelvis, belly (the waist), chest (widest at the armpits, flatter front to back).
    part(
        Cone([-0.06, 0.93, 0.0], 0.11, [0.06, 0.93, 0.0], 0.11),
        [1.0, 1.0, 1.15],
        0.05,
    ),
    part(
        Cone([0.0, 0.97, 0.0], 0.12, [0.0, 1.20, 0.0], 0.115),
        [1.0, 1.0, 1.25],
        0.08,
    ),
    part(
        Cone([0.0, 1.16, 0.005], 0.12, [0.0, 1.34, 0.0], 0.155),
        [1.0, 1.0, 1.45],
        0.07,
    ),
    // Neck, skull, chin and jaw, nose (the face looks along +Z).
    part(
        Cone([0.0, 1.40, -0.01], 0.058, [0.0, 1.58, 0.0], 0.05),
        ROUND,
        0.04,
    ),
    part(
        Ellipsoid([0.0, 1.648, 0.012], [0.08, 0.102, 0.098]),
        ROUND,
        0.04,
    ),
    part(
        Cone([0.0, 1.63, 0.02], 0.062, [0.0, 1.58, 0.05], 0.032),
        ROUND,
        0.03,
    ),
    part(
        Ellipsoid([0.0, 1.638, 0.106], [0.016, 0.026, 0.022]),
        ROUND,
        0.02,
    ),
];

/// Left arm and leg (+X), in smooth-union order; each is added for both sides, the right
/// mirrored in `x`.
pub(crate) const LIMB_PARTS: [Part; 9] = [
    // Shoulder, upper arm, forearm, mitten hand (flat, palm down), thumb (forward).
    part(
        Cone([0.05, 1.40, 0.0], 0.062, [0.18, 1.42, 0.0], 0.058),
        ROUND,
        0.05,
    ),
    part(
        Cone([0.17, 1.42, 0.0], 0.058, [0.46, 1.42, 0.0], 0.043),
        ROUND,
        0.04,
    ),
    part(
        Cone([0.46, 1.42, 0.0], 0.043, [0.70, 1.42, 0.0], 0.03),
        ROUND,
        0.03,
    ),
    part(
        Cone([0.75, 1.42, 0.0], 0.042, [0.83, 1.42, 0.0], 0.038),
        [1.0, 2.0, 1.0],
        0.03,
    ),
    part(
        Cone([0.74, 1.415, 0.03], 0.021, [0.795, 1.415, 0.075], 0.017),
        ROUND,
        0.02,
    ),
    // Thigh, shin, calf, foot (a flat sole on y = 0, toes along +Z).
    part(
        Cone([0.095, 0.92, 0.0], 0.08, [0.095, 0.50, 0.0], 0.055),
        ROUND,
        0.04,
    ),
    part(
        Cone([0.095, 0.50, 0.0], 0.052, [0.095, 0.085, 0.0], 0.035),
        ROUND,
        0.03,
    ),
    part(
        Ellipsoid([0.095, 0.36, -0.018], [0.048, 0.10, 0.045]),
        ROUND,
        0.03,
    ),
    part(
        Cone([0.095, 0.035, -0.035], 0.035, [0.10, 0.028, 0.15], 0.028),
        [0.75, 1.0, 1.0],
        0.03,
    ),
];

/// The character's distance field and the sampling grid around it.
pub(crate) struct Body {
    pub(crate) prims: Vec<Prim>,
    /// Grid: point `(i, j, k)` is at `origin + cell * (i, j, k)`.
    pub(crate) origin: Vec3,
    pub(crate) cell: f32,
    pub(crate) dims: [usize; 3],
}

/// Value of the field where no primitive is evaluated: outside, far from the surface.
pub(crate) const FAR: f32 = 1.0;

impl Body {
    pub(crate) fn new(cell: f32) -> Body {
        let mut prims = Vec::new();
        let mut add = |part: &Part, mirror: f32| {
            let m = |v: [f32; 3]| Vec3::new(v[0] * mirror, v[1], v[2]).to_array();
            let shape = match part.shape {
                PartShape::Cone(a, ra, b, rb) => Shape::round_cone(m(a), ra, m(b), rb),
                PartShape::Ellipsoid(c, r) => Shape::ellipsoid(m(c), r),
            };
            let squash = Vec3::from_array(part.squash);
            prims.push(Prim {
                shape,
                squash: (squash != Vec3::ONE).then_some(squash),
                center: shape.center(),
                inv_lipschitz: 1.0 / squash.max_element(),
                blend: part.blend,
                lo: Vec3::ZERO,
                hi: Vec3::ZERO,
            });
        };
        for part in &CENTER_PARTS {
            add(part, 1.0);
        }
        for part in &LIMB_PARTS {
            add(part, 1.0);
            add(part, -1.0);
        }

        // Culling boxes: a point outside a part's box grown by `blend + 3 cells` (in the
        // part's squashed metric) is at least that far from the part, so the smooth minimum
        // there is exactly the minimum of the other parts wherever the field is within
        // 3 cells of zero, which is everywhere surface nets reads it.
        let mut lo = Vec3::splat(f32::MAX);
        let mut hi = Vec3::splat(f32::MIN);
        let mut max_blend = 0.0f32;
        for prim in &mut prims {
            let (slo, shi) = prim.shape.bounds();
            let (c, s) = (prim.center, prim.squash.unwrap_or(Vec3::ONE));
            let (plo, phi) = (c + (slo - c) / s, c + (shi - c) / s);
            let grow = (prim.blend + 3.0 * cell) * s.max_element() / s.min_element();
            prim.lo = plo - Vec3::splat(grow);
            prim.hi = phi + Vec3::splat(grow);
            lo = lo.min(plo);
            hi = hi.max(phi);
            max_blend = max_blend.max(prim.blend);
        }
        // The grid's boundary must be outside: a smooth union bulges at most blend / 4 past
        // its parts, so 2 cells more than the largest blend is plenty.
        let pad = Vec3::splat(max_blend + 2.0 * cell);
        let origin = lo - pad;
        let extent = (hi + pad - origin) / cell;
        let dims = [extent.x, extent.y, extent.z].map(|e| e.ceil() as usize + 1);
        Body {
            prims,
            origin,
            cell,
            dims,
        }
    }

    /// The parts whose culling box contains `p`, into `near` (cleared first).
    pub(crate) fn parts_near(&self, p: Vec3, near: &mut Vec<usize>) {
        near.clear();
        near.extend((0..self.prims.len()).filter(|&i| self.prims[i].contains(p)));
    }

    /// The field at `p` from the parts in `near` only: negative inside, about the distance to
    /// the surface near it. Exact (the same as on the grid) wherever it is within 2 cells of
    /// zero when `near` is [`Body::parts_near`] of a point at most half a cell from `p`.
    pub(crate) fn eval(&self, near: &[usize], p: Vec3) -> f32 {
        near.iter().fold(FAR, |d, &i| {
            let prim = &self.prims[i];
            smin(d, prim.distance(p), prim.blend)
        })
    }

    /// Gradient of [`Body::eval`] at `p` by central differences a quarter cell wide.
    pub(crate) fn gradient(&self, near: &[usize], p: Vec3) -> Vec3 {
        let e = 0.25 * self.cell;
        let axis = |v: Vec3| self.eval(near, p + v * e) - self.eval(near, p - v * e);
        Vec3::new(axis(Vec3::X), axis(Vec3::Y), axis(Vec3::Z)) / (2.0 * e)
    }

    /// Fills `slice` (`nx * nz`, index `i + nx * k`) with the field on grid slice `j`,
    /// evaluating each part only inside its culling box.
    pub(crate) fn eval_slice(&self, j: usize, slice: &mut [f32]) {
        let [nx, _, nz] = self.dims;
        slice.fill(FAR);
        let y = self.origin.y + self.cell * j as f32;
        let to_index = |v: f32, o: f32| (v - o) / self.cell;
        for prim in &self.prims {
            if y < prim.lo.y || y > prim.hi.y {
                continue;
            }
            let i0 = to_index(prim.lo.x, self.origin.x).ceil().max(0.0) as usize;
            let i1 = (to_index(prim.hi.x, self.origin.x).floor() as usize).min(nx - 1);
            let k0 = to_index(prim.lo.z, self.origin.z).ceil().max(0.0) as usize;
            let k1 = (to_index(prim.hi.z, self.origin.z).floor() as usize).min(nz - 1);
            for k in k0..=k1 {
                let z = self.origin.z + self.cell * k as f32;
                for i in i0..=i1 {
                    let p = Vec3::new(self.origin.x + self.cell * i as f32, y, z);
                    let d = &mut slice[i + nx * k];
                    *d = smin(*d, prim.distance(p), prim.blend);
                }
            }
        }
    }
}
