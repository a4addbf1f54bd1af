//! The built-in demo character of `rigport demo`: a procedural humanoid in Pinocchio's layout.
//!
//! [`character`] builds, from no input files, what a Pinocchio run would leave on disk for a
//! human figure: a joint tree (`skeleton.out`), a closed triangle mesh (the OBJ) and one dense
//! weight row per vertex with one column per **bone** (`attachment.out`). Turning it into an
//! [`Asset`](rigport_model::Asset) is the Pinocchio importer's job, exactly as for files.
//!
//! # How it is made
//! 1. **Skeleton**: a fixed table of 24 joints, about 1.75 m tall, standing on `y = 0`,
//!    facing +Z, in a T-pose (arms along ±X, so hands are far from the hips). Left is +X;
//!    the right side is the left side mirrored in `x`.
//! 2. **Body**: a signed distance field, the polynomial smooth minimum (Quilez, "smooth
//!    minimum", <https://iquilezles.org/articles/smin/>) of 25 round cones (capsules whose
//!    radius varies along the axis) and ellipsoids laid along the bones: pelvis, waist and a
//!    wider chest, tapering limbs, a head with chin and nose, flat feet and mitten hands.
//! 3. **Polygonization**: naive *surface nets* (Gibson 1998, "Constrained elastic surface
//!    nets"), chosen over marching cubes because it needs no case tables and gives fewer,
//!    better-shaped triangles: one vertex per grid cell that the surface crosses (the mean of
//!    the crossings on its 12 edges), one quad per grid edge that the surface crosses
//!    (joining the 4 cells around that edge), split along its shorter diagonal. Grid faces
//!    with an ambiguous (checkerboard) sign pattern, which would make an edge that 4 quads
//!    share, are removed first by moving one near-zero sample to the surface (see
//!    `remove_ambiguous_faces`). Every vertex is then moved onto the surface by one Newton
//!    step and gets the field's normalized gradient as its normal. The grid is swept one `y`
//!    slice at a time (memory `O(nx * nz)`), and each primitive is evaluated only inside its
//!    bounding box grown by its blend radius plus 3 cells, which leaves every value near the
//!    surface exact. The result is indexed (vertices shared), closed and 2-manifold (every
//!    edge in exactly two triangles), and wound counter-clockwise seen from outside.
//! 4. **Weights** (see `skin_weights`): per vertex and bone the distance to the bone's
//!    segment; bones of limbs (center, each arm, each leg) clearly farther than the nearest
//!    limb are masked out, so a thigh never pulls the other thigh nor a hand the hips; weight
//!    `1 / e²` tapering to zero at twice the nearest distance; the best 4 minus the 5th (so
//!    the cut is continuous too), normalized. Every step is continuous in the vertex
//!    position, so the weights vary smoothly over the surface; the root carries none.
//!
//! Everything is single-threaded, iterates in index order and uses only `+ - * /`, `sqrt`,
//! `min`/`max`/`abs`/`floor` on `f32` (exactly rounded by IEEE 754; Rust never fuses them into
//! FMA, and glam's `Vec3` is scalar code): the output is bit-identical on every run and every
//! machine.

use glam::Vec3;
use rigport_model::Mesh;

/// The demo character's raw data, in Pinocchio's layout.
///
/// Model space, metres, +Y up, facing +Z, left = +X. Sizes: `J` joints, `J - 1` bones, `V`
/// vertices; bone `k - 1` (a weight column) runs from `joint_parents[k]` to joint `k`, rotates
/// about its head (the parent joint) and is independent of bones sharing its parent.
#[derive(Clone, Debug, PartialEq)]
pub struct DemoRig {
    /// The body: `V` positions, `V` unit normals, counter-clockwise triangles, no UVs,
    /// `source_vertex` the identity, name `"demo"`.
    pub mesh: Mesh,
    /// `J` joint positions, model space (Pinocchio's `skeleton.out`).
    pub joint_positions: Vec<Vec3>,
    /// `J` parents; joint 0 (`"hips"`) is the root, every parent comes before its children.
    pub joint_parents: Vec<Option<usize>>,
    /// `J` joint names (`"hips"`, `"spine"`, ..., `"toe_r"`), unique; `_l` is +X.
    pub joint_names: Vec<String>,
    /// `V` rows of `J - 1` weights (Pinocchio's `attachment.out`): column `k - 1` is the bone
    /// ending at joint `k`. Every weight is finite and `>= 0`, at most 4 per row are non-zero
    /// and every row sums to 1 (within 1e-6 in `f32`).
    pub bone_weights: Vec<Vec<f32>>,
}

/// The largest useful `detail` for [`character`]; larger values are clamped to it.
///
/// The vertex count grows as `detail²`: 8 gives about 680 000 vertices (some 7 s, 250 MB).
pub const MAX_DETAIL: u32 = 8;

/// Grid cell edge length at detail 1, metres. Chosen so that detail 1 has about 10 000
/// vertices, the narrowest gap that must stay open (between the knees, about 8 cm) is 5 cells
/// wide and the thinnest part (the thumb, about 3 cm) 2 cells thick.
const BASE_CELL: f32 = 0.015;

/// Builds the demo character.
///
/// `detail` sets the grid resolution: cell size `15 mm / detail`. 1 is the default (about
/// 10 000 vertices and 20 000 triangles, 20 to 30 ms in a release build); 0 is treated as 1
/// and values above [`MAX_DETAIL`] as [`MAX_DETAIL`]. The result depends on nothing but
/// `detail`: two calls return equal rigs, on any machine.
pub fn character(detail: u32) -> DemoRig {
    let detail = detail.clamp(1, MAX_DETAIL);
    let cell = BASE_CELL / detail as f32;
    let (joint_positions, joint_parents, joint_names) = skeleton();
    let body = Body::new(cell);
    let (mut positions, triangles) = surface_nets(&body);
    let normals = snap_to_surface(&body, &mut positions);
    let bone_weights = skin_weights(&joint_positions, &joint_parents, &joint_names, &positions);
    let source_vertex = (0..positions.len() as u32).collect();
    DemoRig {
        mesh: Mesh {
            name: "demo".to_owned(),
            positions,
            normals: Some(normals),
            triangles,
            source_vertex,
            ..Mesh::default()
        },
        joint_positions,
        joint_parents,
        joint_names,
        bone_weights,
    }
}

// ---------------------------------------------------------------------------------------
// Skeleton

/// Joint table: name, parent name, position. Left side only for the limbs (+X); the right
/// side is generated by mirroring. Proportions follow an average adult (about 7.5 heads).
const CENTER_JOINTS: [(&str, Option<&str>, [f32; 3]); 6] = [
    ("hips", None, [0.0, 0.98, 0.0]),
    ("spine", Some("hips"), [0.0, 1.10, 0.0]),
    ("chest", Some("spine"), [0.0, 1.36, 0.0]),
    ("neck", Some("chest"), [0.0, 1.49, 0.0]),
    ("head", Some("neck"), [0.0, 1.58, 0.0]),
    ("head_top", Some("head"), [0.0, 1.75, 0.0]),
];

/// Left limbs; names get `_l` / `_r`, a parent without a side suffix is a center joint.
const LIMB_JOINTS: [(&str, &str, [f32; 3]); 9] = [
    ("shoulder", "chest", [0.06, 1.44, 0.0]),
    ("upper_arm", "shoulder_", [0.18, 1.42, 0.0]),
    ("forearm", "upper_arm_", [0.46, 1.42, 0.0]),
    ("hand", "forearm_", [0.71, 1.42, 0.0]),
    ("fingertip", "hand_", [0.87, 1.42, 0.0]),
    ("thigh", "hips", [0.095, 0.92, 0.0]),
    ("shin", "thigh_", [0.095, 0.50, 0.0]),
    ("foot", "shin_", [0.095, 0.085, 0.0]),
    ("toe", "foot_", [0.10, 0.02, 0.16]),
];

/// Joint positions, parents and names, parents first: the 6 center joints, the left arm,
/// the right arm, the left leg, the right leg.
fn skeleton() -> (Vec<Vec3>, Vec<Option<usize>>, Vec<String>) {
    let mut positions = Vec::new();
    let mut parents = Vec::new();
    let mut names: Vec<String> = Vec::new();
    let index_of = |names: &[String], name: &str| names.iter().position(|n| n == name);
    for (name, parent, p) in CENTER_JOINTS {
        parents.push(parent.and_then(|q| index_of(&names, q)));
        names.push(name.to_owned());
        positions.push(Vec3::from_array(p));
    }
    // Arms (first 5 limb joints) for both sides, then legs, so each limb is contiguous.
    for range in [0..5, 5..9] {
        for (side, mirror) in [("l", 1.0), ("r", -1.0)] {
            for &(name, parent, [x, y, z]) in &LIMB_JOINTS[range.clone()] {
                let parent = if parent.ends_with('_') {
                    format!("{parent}{side}")
                } else {
                    parent.to_owned()
                };
                parents.push(index_of(&names, &parent));
                names.push(format!("{name}_{side}"));
                positions.push(Vec3::new(x * mirror, y, z));
            }
        }
    }
    (positions, parents, names)
}

/// For each bone (column `k - 1` for joint `k`), the limbs it belongs to, as a bit mask.
///
/// The limbs are the center (bit 0: the joints without a side suffix, hips to head) and each
/// arm and leg (the side joints, one bit per joint that hangs off the center). A bone belongs
/// to the limb of its end joint and to the limb of its head joint, so the bones that attach
/// a limb (chest -> shoulder, hips -> thigh) belong to both.
fn bone_limbs(parents: &[Option<usize>], names: &[String]) -> Vec<u32> {
    let joints = parents.len();
    let is_center = |j: usize| !(names[j].ends_with("_l") || names[j].ends_with("_r"));
    // Limb bit of each joint (parents come first, so the parent's is already known).
    let mut limb = vec![1u32; joints];
    let mut next = 1;
    for j in 0..joints {
        if let Some(p) = parents[j].filter(|_| !is_center(j)) {
            limb[j] = if is_center(p) {
                next += 1;
                1 << (next - 1).min(31)
            } else {
                limb[p]
            };
        }
    }
    (1..joints)
        .map(|b| limb[b] | parents[b].map_or(0, |p| limb[p]))
        .collect()
}

// ---------------------------------------------------------------------------------------
// Body: signed distance field

/// A primitive's shape, in its own (un-squashed) space, with the constants its distance
/// needs precomputed.
#[derive(Clone, Copy, Debug)]
enum Shape {
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
    fn round_cone(a: [f32; 3], r1: f32, b: [f32; 3], r2: f32) -> Shape {
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

    fn ellipsoid(center: [f32; 3], radii: [f32; 3]) -> Shape {
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
    fn distance(&self, p: Vec3) -> f32 {
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
    fn bounds(&self) -> (Vec3, Vec3) {
        match *self {
            Shape::RoundCone { a, ba, r1, r2, .. } => {
                let r = Vec3::splat(r1.max(r2));
                (a.min(a + ba) - r, a.max(a + ba) + r)
            }
            Shape::Ellipsoid { center, radii, .. } => (center - radii, center + radii),
        }
    }

    fn center(&self) -> Vec3 {
        match *self {
            Shape::RoundCone { a, ba, .. } => a + ba * 0.5,
            Shape::Ellipsoid { center, .. } => center,
        }
    }
}

/// Polynomial smooth minimum with blend radius `k` (Quilez): equals `min(a, b)` when the two
/// differ by `k` or more, and is at most `k / 4` below it.
fn smin(a: f32, b: f32, k: f32) -> f32 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

/// `3t² - 2t³` of `t` clamped to `0..=1`.
fn smoothstep(t: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// One body part of the distance field.
#[derive(Clone, Copy, Debug)]
struct Prim {
    shape: Shape,
    /// Per-axis scale applied about `center` before measuring: 1.3 in `z` makes the part
    /// 1.3 times thinner front to back. `None` for no scaling.
    squash: Option<Vec3>,
    /// The shape's center and `1 / max(squash)`.
    center: Vec3,
    inv_lipschitz: f32,
    /// Smooth-min blend radius with everything before it, metres.
    blend: f32,
    /// Bounds grown so that outside them the part cannot change the field near the surface.
    lo: Vec3,
    hi: Vec3,
}

impl Prim {
    /// Signed distance, scaled so that the field stays 1-Lipschitz (a lower bound when
    /// squashed).
    fn distance(&self, p: Vec3) -> f32 {
        match self.squash {
            None => self.shape.distance(p),
            Some(s) => {
                let q = self.center + (p - self.center) * s;
                self.shape.distance(q) * self.inv_lipschitz
            }
        }
    }

    fn contains(&self, p: Vec3) -> bool {
        p.x >= self.lo.x
            && p.x <= self.hi.x
            && p.y >= self.lo.y
            && p.y <= self.hi.y
            && p.z >= self.lo.z
            && p.z <= self.hi.z
    }
}

/// A body part's shape, model space, metres (left side for limbs).
enum PartShape {
    /// Round cone: `a`, radius at `a`, `b`, radius at `b`.
    Cone([f32; 3], f32, [f32; 3], f32),
    /// Axis-aligned ellipsoid: center, radii.
    Ellipsoid([f32; 3], [f32; 3]),
}

/// One body part of the character.
struct Part {
    shape: PartShape,
    /// See [`Prim::squash`]; `[1.0; 3]` for none.
    squash: [f32; 3],
    /// See [`Prim::blend`].
    blend: f32,
}

const fn part(shape: PartShape, squash: [f32; 3], blend: f32) -> Part {
    Part {
        shape,
        squash,
        blend,
    }
}

use PartShape::{Cone, Ellipsoid};

/// No squash.
const ROUND: [f32; 3] = [1.0, 1.0, 1.0];

/// Torso, neck and head, in smooth-union order. Sizes follow an average adult.
const CENTER_PARTS: [Part; 7] = [
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
const LIMB_PARTS: [Part; 9] = [
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
struct Body {
    prims: Vec<Prim>,
    /// Grid: point `(i, j, k)` is at `origin + cell * (i, j, k)`.
    origin: Vec3,
    cell: f32,
    dims: [usize; 3],
}

/// Value of the field where no primitive is evaluated: outside, far from the surface.
const FAR: f32 = 1.0;

impl Body {
    fn new(cell: f32) -> Body {
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
    fn parts_near(&self, p: Vec3, near: &mut Vec<usize>) {
        near.clear();
        near.extend((0..self.prims.len()).filter(|&i| self.prims[i].contains(p)));
    }

    /// The field at `p` from the parts in `near` only: negative inside, about the distance to
    /// the surface near it. Exact (the same as on the grid) wherever it is within 2 cells of
    /// zero when `near` is [`Body::parts_near`] of a point at most half a cell from `p`.
    fn eval(&self, near: &[usize], p: Vec3) -> f32 {
        near.iter().fold(FAR, |d, &i| {
            let prim = &self.prims[i];
            smin(d, prim.distance(p), prim.blend)
        })
    }

    /// Gradient of [`Body::eval`] at `p` by central differences a quarter cell wide.
    fn gradient(&self, near: &[usize], p: Vec3) -> Vec3 {
        let e = 0.25 * self.cell;
        let axis = |v: Vec3| self.eval(near, p + v * e) - self.eval(near, p - v * e);
        Vec3::new(axis(Vec3::X), axis(Vec3::Y), axis(Vec3::Z)) / (2.0 * e)
    }

    /// Fills `slice` (`nx * nz`, index `i + nx * k`) with the field on grid slice `j`,
    /// evaluating each part only inside its culling box.
    fn eval_slice(&self, j: usize, slice: &mut [f32]) {
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

// ---------------------------------------------------------------------------------------
// Surface nets

/// Polygonizes the zero set of `body` on its grid: shared vertices and counter-clockwise
/// (seen from outside, where the field is positive) triangles.
fn surface_nets(body: &Body) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let [nx, ny, nz] = body.dims;
    let (cx, cz) = (nx - 1, nz - 1);
    let mut lower = vec![FAR; nx * nz];
    let mut upper = vec![FAR; nx * nz];
    // `lower < 0`, `upper < 0`: inside.
    let mut in_lower = vec![false; nx * nz];
    let mut in_upper = vec![false; nx * nz];
    // Per row `k` of a slice, the first and last `i` of an inside point, `(usize::MAX, 0)`
    // if none: most of the grid is outside, and only rows and spans near inside points can
    // hold crossings.
    let mut spans_lower = vec![(usize::MAX, 0); nz];
    let mut spans_upper = vec![(usize::MAX, 0); nz];
    let classify = |field: &[f32], inside: &mut [bool], spans: &mut [(usize, usize)]| {
        inside
            .iter_mut()
            .zip(field)
            .for_each(|(b, v)| *b = *v < 0.0);
        for (row, span) in inside.chunks_exact(nx).zip(spans) {
            let first = row.iter().position(|b| *b);
            let last = row.iter().rposition(|b| *b);
            *span = (first.unwrap_or(usize::MAX), last.unwrap_or(0));
        }
    };
    // Vertex of each cell in the previous and the current cell layer (u32::MAX: none).
    let mut prev = vec![u32::MAX; cx * cz];
    let mut cur = vec![u32::MAX; cx * cz];
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    body.eval_slice(0, &mut lower);
    classify(&lower, &mut in_lower, &mut spans_lower);
    for j in 0..ny - 1 {
        body.eval_slice(j + 1, &mut upper);
        classify(&upper, &mut in_upper, &mut spans_upper);
        remove_ambiguous_faces(
            nx,
            &in_lower,
            &spans_lower,
            &mut upper,
            &mut in_upper,
            &spans_upper,
        );
        // Cell vertices of layer j (between slices j and j + 1). Corner `c` of a cell is
        // at offset `(c & 1, c >> 1 & 1, c >> 2 & 1)`.
        cur.fill(u32::MAX);
        for k in 0..cz {
            let (lo, hi) = union(&[
                spans_lower[k],
                spans_lower[k + 1],
                spans_upper[k],
                spans_upper[k + 1],
            ]);
            // Cell i has corners i and i + 1.
            for i in lo.saturating_sub(1)..=hi.min(cx - 1) {
                let (p0, p1) = (i + nx * k, i + nx * (k + 1));
                let mask = in_lower[p0] as u8
                    | (in_lower[p0 + 1] as u8) << 1
                    | (in_upper[p0] as u8) << 2
                    | (in_upper[p0 + 1] as u8) << 3
                    | (in_lower[p1] as u8) << 4
                    | (in_lower[p1 + 1] as u8) << 5
                    | (in_upper[p1] as u8) << 6
                    | (in_upper[p1 + 1] as u8) << 7;
                if mask == 0 || mask == u8::MAX {
                    continue;
                }
                let corner = [
                    lower[p0],
                    lower[p0 + 1],
                    upper[p0],
                    upper[p0 + 1],
                    lower[p1],
                    lower[p1 + 1],
                    upper[p1],
                    upper[p1 + 1],
                ];
                let mut sum = Vec3::ZERO;
                let mut count = 0.0f32;
                for c in 0..8 {
                    for bit in [1, 2, 4] {
                        let d = c | bit;
                        if c & bit != 0 || (mask >> c & 1) == (mask >> d & 1) {
                            continue;
                        }
                        // Keep crossings off the corners so that vertices of neighbouring
                        // cells never coincide (no zero-area triangles).
                        let t = (corner[c] / (corner[c] - corner[d])).clamp(0.01, 0.99);
                        let offset = |b: usize| ((c & b) != 0) as u8 as f32;
                        let mut q = Vec3::new(offset(1), offset(2), offset(4));
                        match bit {
                            1 => q.x = t,
                            2 => q.y = t,
                            _ => q.z = t,
                        }
                        sum += q;
                        count += 1.0;
                    }
                }
                let local = Vec3::new(i as f32, j as f32, k as f32) + sum / count;
                cur[i + cx * k] = positions.len() as u32;
                positions.push(body.origin + local * body.cell);
            }
        }
        let cell = |layer: &[u32], i: usize, k: usize| layer[i + cx * k];
        // Edges along y between slices j and j + 1: the 4 cells around are in layer j.
        for k in 1..nz - 1 {
            let (lo, hi) = union(&[spans_lower[k], spans_upper[k]]);
            for i in lo.max(1)..=hi.min(nx - 2) {
                let (a, b) = (in_lower[i + nx * k], in_upper[i + nx * k]);
                if a != b {
                    let quad = [
                        cell(&cur, i - 1, k - 1),
                        cell(&cur, i - 1, k),
                        cell(&cur, i, k),
                        cell(&cur, i, k - 1),
                    ];
                    push_quad(&mut triangles, &positions, quad, a);
                }
            }
        }
        // Edges along x and z in slice j: the cells around are in layers j - 1 and j.
        if j >= 1 {
            for k in 0..nz {
                let (lo, hi) = union(&[spans_lower[k], spans_lower[(k + 1).min(nz - 1)]]);
                for i in lo.saturating_sub(1)..=hi.min(nx - 1) {
                    let a = in_lower[i + nx * k];
                    if i + 1 < nx && k >= 1 && k < nz - 1 && a != in_lower[i + 1 + nx * k] {
                        let quad = [
                            cell(&prev, i, k - 1),
                            cell(&cur, i, k - 1),
                            cell(&cur, i, k),
                            cell(&prev, i, k),
                        ];
                        push_quad(&mut triangles, &positions, quad, a);
                    }
                    if k + 1 < nz && i >= 1 && i < nx - 1 && a != in_lower[i + nx * (k + 1)] {
                        let quad = [
                            cell(&prev, i - 1, k),
                            cell(&prev, i, k),
                            cell(&cur, i, k),
                            cell(&cur, i - 1, k),
                        ];
                        push_quad(&mut triangles, &positions, quad, a);
                    }
                }
            }
        }
        std::mem::swap(&mut lower, &mut upper);
        std::mem::swap(&mut in_lower, &mut in_upper);
        std::mem::swap(&mut spans_lower, &mut spans_upper);
        std::mem::swap(&mut prev, &mut cur);
    }
    (positions, triangles)
}

/// The smallest range holding all of `spans` (each `(first, last)`, empty if `first > last`).
fn union(spans: &[(usize, usize)]) -> (usize, usize) {
    spans
        .iter()
        .fold((usize::MAX, 0), |(lo, hi), s| (lo.min(s.0), hi.max(s.1)))
}

/// Removes every ambiguous grid face (two diagonally opposite corners inside, the other two
/// outside) that has a corner in slice `upper`, by moving inside points of `upper` onto the
/// surface (value 0, which counts as outside).
///
/// With one vertex per cell, surface nets joins the two cells on either side of an
/// ambiguous face by one mesh edge that 4 quads use: a non-manifold edge. On this smooth
/// field such faces only appear where a saddle of the surface (a blend between two parts)
/// lies almost exactly in a grid plane, so all four corner values are within a rounding
/// error of zero and nudging one of them changes the shape by nothing visible. Only points
/// of `upper` change (the lower slice is final), and each change turns an inside point
/// outside, so the loop ends. `spans_*` are the inside spans per row (see [`surface_nets`]);
/// they stay valid (supersets) as points turn outside.
fn remove_ambiguous_faces(
    nx: usize,
    in_lower: &[bool],
    spans_lower: &[(usize, usize)],
    upper: &mut [f32],
    in_upper: &mut [bool],
    spans_upper: &[(usize, usize)],
) {
    let nz = in_lower.len() / nx;
    // The candidate that is least inside (closest to the surface) moves; ties: lowest index.
    let flip = |points: &[usize], upper: &mut [f32], in_upper: &mut [bool]| {
        let least_inside = points
            .iter()
            .copied()
            .filter(|&p| in_upper[p])
            .max_by(|&a, &b| upper[a].total_cmp(&upper[b]).then(b.cmp(&a)));
        if let Some(p) = least_inside {
            upper[p] = 0.0;
            in_upper[p] = false;
        }
    };
    let mut changed = true;
    while changed {
        changed = false;
        for k in 0..nz {
            let k1 = (k + 1).min(nz - 1);
            let (lo, hi) = union(&[
                spans_lower[k],
                spans_lower[k1],
                spans_upper[k],
                spans_upper[k1],
            ]);
            for i in lo.saturating_sub(1)..=hi.min(nx - 1) {
                let a = i + nx * k;
                let b = a + nx;
                // Vertical face with normal z: (i, k) and (i + 1, k) in both slices.
                if i + 1 < nx {
                    let (l0, l1, u0, u1) =
                        (in_lower[a], in_lower[a + 1], in_upper[a], in_upper[a + 1]);
                    if l0 == u1 && l1 == u0 && l0 != l1 {
                        flip(&[a, a + 1], upper, in_upper);
                        changed = true;
                    }
                }
                if k + 1 < nz {
                    // Vertical face with normal x: (i, k) and (i, k + 1) in both slices.
                    let (l0, l1, u0, u1) = (in_lower[a], in_lower[b], in_upper[a], in_upper[b]);
                    if l0 == u1 && l1 == u0 && l0 != l1 {
                        flip(&[a, b], upper, in_upper);
                        changed = true;
                    }
                    // Horizontal face in `upper`.
                    if i + 1 < nx {
                        let (u00, u10) = (in_upper[a], in_upper[a + 1]);
                        let (u01, u11) = (in_upper[b], in_upper[b + 1]);
                        if u00 == u11 && u10 == u01 && u00 != u10 {
                            flip(&[a, a + 1, b, b + 1], upper, in_upper);
                            changed = true;
                        }
                    }
                }
            }
        }
    }
}

/// Adds a quad as two triangles split along its shorter diagonal. `quad` is counter-clockwise
/// seen from the edge's positive end; `outward_positive` says that end is outside.
fn push_quad(tris: &mut Vec<[u32; 3]>, pos: &[Vec3], quad: [u32; 4], outward_positive: bool) {
    // The grid's boundary is outside (see `Body::new`), so every crossed edge is interior
    // and its 4 cells all have vertices.
    if quad.contains(&u32::MAX) {
        debug_assert!(false, "crossed edge on the grid boundary");
        return;
    }
    let [a, b, c, d] = if outward_positive {
        quad
    } else {
        [quad[3], quad[2], quad[1], quad[0]]
    };
    let p = |v: u32| pos[v as usize];
    if p(a).distance_squared(p(c)) <= p(b).distance_squared(p(d)) {
        tris.extend([[a, b, c], [a, c, d]]);
    } else {
        tris.extend([[a, b, d], [b, c, d]]);
    }
}

/// Moves each vertex onto the zero set by one Newton step (at most half a cell, so the
/// mesh cannot fold) and returns the unit normals: the field's gradient where the vertex
/// was, which a step that short leaves unchanged to well under a degree on this smooth field.
fn snap_to_surface(body: &Body, positions: &mut [Vec3]) -> Vec<Vec3> {
    let max_step = 0.5 * body.cell;
    let mut near = Vec::with_capacity(body.prims.len());
    positions
        .iter_mut()
        .map(|p| {
            body.parts_near(*p, &mut near);
            let g = body.gradient(&near, *p);
            let g2 = g.length_squared();
            if g2 > 1e-12 {
                let step = g * (body.eval(&near, *p) / g2);
                *p -= step.clamp_length_max(max_step);
            }
            g.try_normalize().unwrap_or(Vec3::Y)
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// Skin weights

/// A limb's claim on a vertex fades out over this many metres as the limb's nearest bone
/// gets farther than the nearest bone of any limb. Smaller than the gap between the thighs
/// a hand's width below the crotch, so each thigh stays off the other.
const LIMB_BLEND: f32 = 0.04;
/// A bone's distance is measured to the bone without this fraction at its head: bones that
/// share a head (chest -> neck and both shoulders) are then no longer equally near to every
/// point around it, and a bone acts less behind its pivot, where it moves skin the wrong way.
const HEAD_TRIM: f32 = 0.25;
/// A bone's weight tapers to zero at this multiple of the nearest effective bone distance.
const REACH: f32 = 2.0;
/// Influences kept per vertex (glTF's one `JOINTS_0` set).
const MAX_INFLUENCES: usize = 4;

/// Distance from `p` to the segment `a`..`b`.
fn segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// One dense row of `J - 1` bone weights per vertex.
///
/// Per vertex: `d` = distance to each bone (trimmed at its head, see [`HEAD_TRIM`]); each
/// limb's claim `1 - smoothstep((d_limb - d_nearest) / LIMB_BLEND)`; a bone's mask, the best
/// claim of its limbs; effective distance `e = d / mask`; weight `taper(e / e_min) / e²`
/// with `taper` falling from 1 to 0 between ratio 1 and [`REACH`]; the best
/// [`MAX_INFLUENCES`] minus the next one, normalized. Every step is continuous in the vertex
/// position, so the weights vary smoothly over the surface.
fn skin_weights(
    joints: &[Vec3],
    parents: &[Option<usize>],
    names: &[String],
    positions: &[Vec3],
) -> Vec<Vec<f32>> {
    let bones = joints.len() - 1;
    let limbs = bone_limbs(parents, names);
    let segments: Vec<(Vec3, Vec3)> = (1..joints.len())
        .map(|j| {
            let tail = joints[j];
            let head = parents[j].map_or(tail, |p| joints[p]);
            (head + (tail - head) * HEAD_TRIM, tail)
        })
        .collect();
    let mut dist = vec![0.0f32; bones];
    let mut scored: Vec<(f32, usize)> = Vec::with_capacity(bones);
    positions
        .iter()
        .map(|&p| {
            for (d, &(a, b)) in dist.iter_mut().zip(&segments) {
                *d = segment_distance(p, a, b).max(1e-4);
            }
            let nearest = dist.iter().copied().fold(f32::MAX, f32::min);
            // Claim of each limb (indexed by bit), from its nearest bone.
            let mut limb_dist = [f32::MAX; 32];
            for (&d, &l) in dist.iter().zip(&limbs) {
                let mut bits = l;
                while bits != 0 {
                    let i = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    limb_dist[i] = limb_dist[i].min(d);
                }
            }
            let claim = limb_dist.map(|d| 1.0 - smoothstep((d - nearest) / LIMB_BLEND));
            scored.clear();
            for (b, (&d, &l)) in dist.iter().zip(&limbs).enumerate() {
                let mut bits = l;
                let mut mask = 0.0f32;
                while bits != 0 {
                    mask = mask.max(claim[bits.trailing_zeros() as usize]);
                    bits &= bits - 1;
                }
                if mask > 0.0 {
                    scored.push((d / mask, b));
                }
            }
            // The nearest bone has mask 1, so `scored` is never empty and e_min is positive.
            let e_min = scored.iter().map(|s| s.0).fold(f32::MAX, f32::min);
            for s in &mut scored {
                let taper = 1.0 - smoothstep((s.0 / e_min - 1.0) / (REACH - 1.0));
                s.0 = taper / (s.0 * s.0);
            }
            // Best first; ties by bone index so the order never depends on anything else.
            scored.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
            let cut = scored.get(MAX_INFLUENCES).map_or(0.0, |s| s.0);
            let mut row = vec![0.0f32; bones];
            let mut sum = 0.0f32;
            for &(w, b) in scored.iter().take(MAX_INFLUENCES) {
                row[b] = w - cut;
                sum += w - cut;
            }
            if sum > 0.0 && sum.is_finite() {
                row.iter_mut().for_each(|w| *w /= sum);
            } else if let Some(&(_, b)) = scored.first() {
                // Only when 5 bones tie exactly: the first of them takes the vertex.
                row.fill(0.0);
                row[b] = 1.0;
            }
            row
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::OnceLock;

    /// The rigs of detail 1 and 2, built once for all tests (debug builds are slow).
    fn built(detail: u32) -> &'static DemoRig {
        static RIGS: [OnceLock<DemoRig>; 2] = [OnceLock::new(), OnceLock::new()];
        RIGS[detail as usize - 1].get_or_init(|| character(detail))
    }

    fn signed_volume(mesh: &Mesh) -> f32 {
        let p = |i: u32| mesh.positions[i as usize].as_dvec3();
        let v: f64 = mesh
            .triangles
            .iter()
            .map(|&[a, b, c]| p(a).dot(p(b).cross(p(c))) / 6.0)
            .sum();
        v as f32
    }

    fn joint(rig: &DemoRig, name: &str) -> usize {
        rig.joint_names.iter().position(|n| n == name).unwrap()
    }

    #[test]
    fn is_deterministic() {
        assert_eq!(&character(1), built(1));
        assert_eq!(&character(0), built(1), "detail 0 means 1");
    }

    #[test]
    fn skeleton_is_a_pinocchio_humanoid() {
        let rig = built(1);
        let n = rig.joint_names.len();
        assert_eq!(n, 24);
        assert_eq!(rig.joint_positions.len(), n);
        assert_eq!(rig.joint_parents.len(), n);
        assert_eq!(rig.joint_parents[0], None);
        for (j, p) in rig.joint_parents.iter().enumerate().skip(1) {
            assert!(p.is_some_and(|p| p < j), "joint {j} parent {p:?}");
        }
        let mut names = rig.joint_names.clone();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), n, "unique names");
        let chain = |first: &str, side: &str, rest: &[&str]| {
            let mut names = vec![first.to_owned()];
            names.extend(rest.iter().map(|n| format!("{n}{side}")));
            for w in names.windows(2) {
                assert_eq!(
                    rig.joint_parents[joint(rig, &w[1])],
                    Some(joint(rig, &w[0]))
                );
            }
        };
        chain("hips", "", &["spine", "chest", "neck", "head", "head_top"]);
        for side in ["_l", "_r"] {
            let arm = ["shoulder", "upper_arm", "forearm", "hand", "fingertip"];
            chain("chest", side, &arm);
            chain("hips", side, &["thigh", "shin", "foot", "toe"]);
        }
        // Left is +X, mirrored exactly.
        let (l, r) = (joint(rig, "hand_l"), joint(rig, "hand_r"));
        assert!(rig.joint_positions[l].x > 0.5);
        assert_eq!(
            rig.joint_positions[r],
            rig.joint_positions[l] * Vec3::new(-1.0, 1.0, 1.0)
        );
        // The toes point forward (+Z).
        assert!(rig.joint_positions[joint(rig, "toe_l")].z > 0.1);
    }

    #[test]
    fn mesh_size_and_shape() {
        let rig = built(1);
        let mesh = &rig.mesh;
        let v = mesh.vertex_count();
        assert!((5_000..=15_000).contains(&v), "{v} vertices");
        assert_eq!(mesh.name, "demo");
        assert_eq!(mesh.source_vertex, (0..v as u32).collect::<Vec<_>>());
        assert_eq!(mesh.normals.as_ref().map(Vec::len), Some(v));
        let (lo, hi) = mesh.bounds().unwrap();
        assert!((hi.y - lo.y - 1.75).abs() < 0.1, "height {}", hi.y - lo.y);
        assert!(lo.y.abs() < 0.01, "feet at y = {}", lo.y);
        assert!(hi.x > 0.8 && lo.x < -0.8, "arms along x: {lo} {hi}");
        // The finer grid makes the same body.
        let fine = built(2);
        assert!(fine.mesh.vertex_count() > 3 * v);
        let (flo, fhi) = fine.mesh.bounds().unwrap();
        assert!((flo - lo).abs().max_element() < 0.01 && (fhi - hi).abs().max_element() < 0.01);
    }

    #[test]
    fn mesh_is_closed_outward_and_clean() {
        for detail in [1, 2] {
            let mesh = &built(detail).mesh;
            // Closed and consistently wound: every directed edge once, and its reverse once.
            let mut edges: Vec<(u32, u32)> = mesh
                .triangles
                .iter()
                .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
                .collect();
            edges.sort_unstable();
            let n = edges.len();
            edges.dedup();
            assert_eq!(
                edges.len(),
                n,
                "detail {detail}: a directed edge is used twice"
            );
            for &(a, b) in &edges {
                assert!(edges.binary_search(&(b, a)).is_ok(), "open edge {a}-{b}");
            }
            assert!(signed_volume(mesh) > 0.03, "volume {}", signed_volume(mesh));
            // Every vertex used, no zero-area triangle, normals agree with the winding.
            let mut used = vec![false; mesh.vertex_count()];
            let normals = mesh.normals.as_ref().unwrap();
            let mut disagree = 0;
            for &[a, b, c] in &mesh.triangles {
                let p = |i: u32| mesh.positions[i as usize];
                let n = (p(b) - p(a)).cross(p(c) - p(a));
                assert!(n.length() > 1e-10, "degenerate triangle {a} {b} {c}");
                for v in [a, b, c] {
                    used[v as usize] = true;
                    if n.dot(normals[v as usize]) < 0.0 {
                        disagree += 1;
                    }
                }
            }
            assert!(used.iter().all(|u| *u));
            assert!(
                disagree * 1000 < mesh.triangles.len(),
                "{disagree} flipped corners"
            );
        }
    }

    #[test]
    fn weight_rows_are_normalized() {
        let rig = built(1);
        assert_eq!(rig.bone_weights.len(), rig.mesh.vertex_count());
        for row in &rig.bone_weights {
            assert_eq!(row.len(), rig.joint_names.len() - 1);
            assert!(row.iter().all(|w| w.is_finite() && *w >= 0.0), "{row:?}");
            assert!(row.iter().filter(|w| **w > 0.0).count() <= MAX_INFLUENCES);
            let sum: f32 = row.iter().sum();
            assert!((sum - 1.0).abs() <= 1e-6, "sum {sum}");
        }
    }

    #[test]
    fn hands_belong_to_their_arm() {
        let rig = built(1);
        for s in ["l", "r"] {
            let hand = rig.joint_positions[joint(rig, &format!("hand_{s}"))];
            let nearest = (0..rig.mesh.vertex_count())
                .min_by(|&a, &b| {
                    let d = |v: usize| rig.mesh.positions[v].distance_squared(hand);
                    d(a).total_cmp(&d(b))
                })
                .unwrap();
            let row = &rig.bone_weights[nearest];
            let best = (0..row.len())
                .max_by(|&a, &b| row[a].total_cmp(&row[b]))
                .unwrap();
            // Column k - 1 is the bone ending at joint k: forearm_s -> hand_s, hand_s -> tip.
            let wrist_bones = [
                joint(rig, &format!("hand_{s}")),
                joint(rig, &format!("fingertip_{s}")),
            ];
            assert!(
                wrist_bones.contains(&(best + 1)),
                "{s}: best bone {}",
                best + 1
            );
            // Every vertex beyond the elbow is weighted to that arm only.
            let elbow = rig.joint_positions[joint(rig, &format!("forearm_{s}"))];
            let arm: Vec<usize> = ["upper_arm", "forearm", "hand", "fingertip"]
                .iter()
                .map(|n| joint(rig, &format!("{n}_{s}")) - 1)
                .collect();
            for (p, row) in rig.mesh.positions.iter().zip(&rig.bone_weights) {
                if p.x.abs() > elbow.x.abs() + 0.05 && p.x * elbow.x > 0.0 {
                    let on_arm: f32 = arm.iter().map(|&b| row[b]).sum();
                    assert!(on_arm > 0.999, "{s} {p}: {row:?}");
                }
            }
        }
    }

    #[test]
    fn head_has_no_leg_or_arm_weight() {
        let rig = built(1);
        let neck = rig.joint_positions[joint(rig, "head")];
        let foreign: Vec<usize> = (1..rig.joint_names.len())
            .filter(|&j| {
                [
                    "thigh",
                    "shin",
                    "foot",
                    "toe",
                    "forearm",
                    "hand",
                    "fingertip",
                ]
                .iter()
                .any(|n| rig.joint_names[j].starts_with(n))
            })
            .map(|j| j - 1)
            .collect();
        let mut head_vertices = 0;
        for (p, row) in rig.mesh.positions.iter().zip(&rig.bone_weights) {
            if p.y > neck.y {
                head_vertices += 1;
                assert!(foreign.iter().all(|&b| row[b] == 0.0), "{p}: {row:?}");
            }
        }
        assert!(head_vertices > 300);
    }

    #[test]
    fn legs_keep_to_themselves() {
        // Below the crotch (at 0.80 m) no vertex of one leg moves with the other leg.
        let rig = built(1);
        for (side, other) in [(1.0, "_r"), (-1.0, "_l")] {
            let bones: Vec<usize> = ["thigh", "shin", "foot", "toe"]
                .iter()
                .map(|n| joint(rig, &format!("{n}{other}")) - 1)
                .collect();
            for (p, row) in rig.mesh.positions.iter().zip(&rig.bone_weights) {
                if p.y < 0.75 && p.x * side > 0.0 {
                    assert!(bones.iter().all(|&b| row[b] == 0.0), "{p}: {row:?}");
                }
            }
        }
    }

    #[test]
    fn weights_are_smooth_over_edges() {
        // Continuous weights: the largest change across a mesh edge is bounded and shrinks
        // as the edges do. The largest steps sit in the tightest creases (front of the
        // ankle, the crotch, where the two legs part); measured 0.56 and 0.42.
        for (detail, limit) in [(1, 0.6), (2, 0.45)] {
            let rig = built(detail);
            let mut jumps = Vec::new();
            for t in &rig.mesh.triangles {
                for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                    let (ra, rb) = (&rig.bone_weights[a as usize], &rig.bone_weights[b as usize]);
                    let diff = ra.iter().zip(rb).map(|(x, y)| (x - y).abs());
                    jumps.push(diff.fold(0.0, f32::max));
                }
            }
            let worst = jumps.iter().copied().fold(0.0, f32::max);
            assert!(
                worst < limit,
                "detail {detail}: weight jump {worst} across an edge"
            );
            let large = jumps.iter().filter(|j| **j > 0.3).count();
            assert!(
                large * 50 < jumps.len(),
                "detail {detail}: {large} jumps over 0.3"
            );
        }
    }

    /// Writes `rigport_demo.obj` and orthographic views `rigport_demo_*.pgm` (front and side
    /// shaded by normal; front with one bone's weights as brightness) to the temp directory
    /// (`/tmp`), to look at: `cargo test -p rigport-import --release -- --ignored dump_for`.
    #[test]
    #[ignore = "writes files to the temp directory for a visual check"]
    fn dump_for_visual_check() {
        use std::fmt::Write as _;
        let rig = built(1);
        let mesh = &rig.mesh;
        let dir = std::env::temp_dir();
        let mut obj = String::new();
        for p in &mesh.positions {
            writeln!(obj, "v {} {} {}", p.x, p.y, p.z).unwrap();
        }
        for n in mesh.normals.as_ref().unwrap() {
            writeln!(obj, "vn {} {} {}", n.x, n.y, n.z).unwrap();
        }
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| i + 1);
            writeln!(obj, "f {a}//{a} {b}//{b} {c}//{c}").unwrap();
        }
        std::fs::write(dir.join("rigport_demo.obj"), obj).unwrap();
        // Orthographic z-buffered rasterizer: front (+Z towards the viewer) or side (from
        // -X, the character's right).
        let render = |name: &str, side: bool, shade: &dyn Fn(usize, Vec3) -> f32| {
            let (w, h, scale) = (400usize, 400usize, 400.0 / 2.0);
            let mut img = vec![0u8; w * h];
            let mut depth = vec![f32::MIN; w * h];
            let project = |p: Vec3| {
                let (u, d) = if side { (p.z, -p.x) } else { (p.x, p.z) };
                (u * scale + w as f32 / 2.0, (1.9 - p.y) * scale, d)
            };
            for t in &mesh.triangles {
                let [a, b, c] = t.map(|i| project(mesh.positions[i as usize]));
                let area = (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
                if area.abs() < 1e-9 {
                    continue;
                }
                let x0 = a.0.min(b.0).min(c.0).floor().max(0.0) as usize;
                let x1 = (a.0.max(b.0).max(c.0).ceil() as usize).min(w - 1);
                let y0 = a.1.min(b.1).min(c.1).floor().max(0.0) as usize;
                let y1 = (a.1.max(b.1).max(c.1).ceil() as usize).min(h - 1);
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                        let l1 = ((b.0 - px) * (c.1 - py) - (c.0 - px) * (b.1 - py)) / area;
                        let l2 = ((c.0 - px) * (a.1 - py) - (a.0 - px) * (c.1 - py)) / area;
                        let l3 = 1.0 - l1 - l2;
                        if l1 < 0.0 || l2 < 0.0 || l3 < 0.0 {
                            continue;
                        }
                        let d = l1 * a.2 + l2 * b.2 + l3 * c.2;
                        if d > depth[x + w * y] {
                            depth[x + w * y] = d;
                            let verts = t.map(|i| i as usize);
                            let k = [l1, l2, l3]
                                .iter()
                                .enumerate()
                                .max_by(|p, q| p.1.total_cmp(q.1))
                                .unwrap()
                                .0;
                            let n = mesh.normals.as_ref().unwrap();
                            let nn = n[verts[0]] * l1 + n[verts[1]] * l2 + n[verts[2]] * l3;
                            let v = shade(verts[k], nn.normalize());
                            img[x + w * y] = (v.clamp(0.0, 1.0) * 255.0) as u8;
                        }
                    }
                }
            }
            let mut out = format!("P5 {w} {h} 255\n").into_bytes();
            out.extend(img);
            std::fs::write(dir.join(format!("rigport_demo_{name}.pgm")), out).unwrap();
        };
        let light = Vec3::new(0.4, 0.5, 1.0).normalize();
        let light_side = Vec3::new(-1.0, 0.5, 0.4).normalize();
        render("front", false, &|_, n| 0.15 + 0.85 * n.dot(light).max(0.0));
        render("side", true, &|_, n| {
            0.15 + 0.85 * n.dot(light_side).max(0.0)
        });
        for name in [
            "forearm_l",
            "shin_l",
            "spine",
            "neck",
            "thigh_l",
            "upper_arm_l",
        ] {
            let b = joint(rig, name) - 1;
            render(&format!("w_{name}"), false, &|v, n| {
                0.1 + 0.2 * n.dot(light).max(0.0) + 0.7 * rig.bone_weights[v][b]
            });
        }
    }
}
