//! The XPBD solver (Macklin, Müller, Chentanez 2016, "XPBD: Position-Based Simulation of
//! Compliant Constrained Dynamics"; with small steps, one iteration per substep, Macklin et
//! al. 2019, "Small Steps in Physics Simulation"): stretch constraints on the garment's
//! edges, bending constraints between the far vertices of triangle pairs, gravity, velocity
//! damping, pins, and capsule collisions.
//!
//! State is `f64`: with substeps of 1e-4 s a velocity step `g h²` (1e-7 m) is below
//! `f32`'s spacing at 4 m (4.8e-7), so `f32` positions would not fall at all.
//!
//! Everything runs serially in a fixed order (Gauss-Seidel over constraints sorted by
//! vertex indices), so the result is the same bytes on every run and thread count.

use std::collections::BTreeMap;

use glam::DVec3 as Vec3;

use super::collide::Capsule;
use super::faces::Faces;
use super::surface::{Posed, Surface};

/// What the garment collides with during one substep.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Collider<'a> {
    /// The capsules (the coarse phase: they also catch a particle too deep in the body
    /// for the surface search to reach).
    pub(crate) capsules: &'a [Capsule],
    /// The skinned body surface at the substep's time, when collisions are on.
    pub(crate) surface: Option<(&'a Surface, Posed<'a>)>,
    /// The rest of the body (the parts the garment is not made to meet, such as a hand
    /// swinging beside a skirt), at the same time: a particle inside it goes onto its skin,
    /// or half way when the skin it would go onto lies within the gap of `surface`.
    pub(crate) others: Option<(&'a Surface, Posed<'a>)>,
    /// How far beyond the thickness a particle may be and still be pushed out of the
    /// surface (how deep below it the surface search reaches).
    pub(crate) reach: f32,
}

/// A distance constraint between particles `i` and `j`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Distance {
    pub(crate) i: u32,
    pub(crate) j: u32,
    pub(crate) rest: f64,
}

/// Material and world parameters of one solve (model units, seconds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Params {
    pub(crate) gravity: Vec3,
    pub(crate) damping: f64,
    pub(crate) stretch_compliance: f64,
    pub(crate) bend_compliance: f64,
    pub(crate) thickness: f64,
    pub(crate) iterations: u32,
}

/// Particle state and constraints.
#[derive(Clone, Debug)]
pub(crate) struct Solver {
    pub(crate) x: Vec<Vec3>,
    prev: Vec<Vec3>,
    pub(crate) v: Vec<Vec3>,
    inv_mass: Vec<f64>,
    pub(crate) stretch: Vec<Distance>,
    bend: Vec<Distance>,
    /// Pinned particles, ascending.
    pinned: Vec<u32>,
    /// Per particle: a direction to push along when it sits on a capsule's axis.
    fallback: Vec<Vec3>,
    /// Per particle: the outward normal of its last contact this substep (zero: none).
    contact: Vec<Vec3>,
    /// Per particle: whether it collides (free and not next to a pin).
    collides: Vec<bool>,
    /// Per particle: the shortest path along the garment's edges to a pin (rest lengths;
    /// infinite when no pin is connected).
    from_pin: Vec<f64>,
    /// The triangles, kept off the capsules' axes (`faces`).
    faces: Faces,
    /// Per particle: its inverse mass in those face contacts (0 for the particles that do
    /// not collide).
    face_mass: Vec<f64>,
}

/// Two particle indices, the smaller first.
pub(crate) type Pair = (u32, u32);

/// Unique edges (sorted `(min, max)`) and, for edges shared by two triangles, the two
/// vertices opposite them.
pub(crate) fn topology(triangles: &[[u32; 3]]) -> (Vec<Pair>, Vec<Pair>) {
    let mut opposite: BTreeMap<(u32, u32), Vec<u32>> = BTreeMap::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            if a == b {
                continue;
            }
            opposite.entry((a.min(b), a.max(b))).or_default().push(o);
        }
    }
    let edges = opposite.keys().copied().collect();
    let bends = opposite
        .values()
        .filter_map(|o| match o.as_slice() {
            [p, q] if p != q => Some(((*p).min(*q), (*p).max(*q))),
            _ => None,
        })
        .collect();
    (edges, bends)
}

impl Solver {
    /// A solver at `positions` (at rest, velocity zero) with constraints from
    /// `triangles`; rest lengths are measured at `positions`.
    pub(crate) fn new(positions: &[glam::Vec3], triangles: &[[u32; 3]], pinned: &[u32]) -> Self {
        let positions: Vec<Vec3> = positions.iter().map(|p| p.as_dvec3()).collect();
        let n = positions.len();
        let (edges, bends) = topology(triangles);
        let dist = |(i, j): (u32, u32)| Distance {
            i,
            j,
            rest: (positions[i as usize] - positions[j as usize]).length(),
        };
        let mut inv_mass = vec![1.0; n];
        for &p in pinned {
            if let Some(w) = inv_mass.get_mut(p as usize) {
                *w = 0.0;
            }
        }
        // Particles one edge from a pin do not collide: the pin sits on the skin, inside
        // the collision thickness, and holding its neighbour outside that shell while the
        // edge between them is inextensible is impossible; every substep would then push
        // them apart by a fixed amount, a force growing as 1/h² (the cloth gains energy).
        let mut collides = inv_mass.iter().map(|&w| w > 0.0).collect::<Vec<bool>>();
        for &(i, j) in &edges {
            let (i, j) = (i as usize, j as usize);
            if inv_mass[i] == 0.0 {
                collides[j] = false;
            }
            if inv_mass[j] == 0.0 {
                collides[i] = false;
            }
        }
        let mut pinned = pinned.to_vec();
        pinned.sort_unstable();
        pinned.dedup();
        // Outward hint for points on a capsule axis: the garment's normal at the vertex.
        let mut fallback = vec![Vec3::ZERO; n];
        for t in triangles {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let nrm = (b - a).cross(c - a);
            for &i in t {
                fallback[i as usize] += nrm;
            }
        }
        for f in &mut fallback {
            *f = f.try_normalize().unwrap_or(Vec3::Y);
        }
        let from_pin = distances_from(&pinned, &edges, &positions);
        let faces = Faces::new(triangles, &positions);
        let face_mass = collides
            .iter()
            .map(|&c| if c { 1.0 } else { 0.0 })
            .collect();
        let stretch = edges.into_iter().map(dist).collect();
        let bend = bends.into_iter().map(dist).collect();
        Self {
            x: positions.clone(),
            prev: positions,
            v: vec![Vec3::ZERO; n],
            inv_mass,
            stretch,
            bend,
            pinned,
            fallback,
            contact: vec![Vec3::ZERO; n],
            collides,
            from_pin,
            faces,
            face_mass,
        }
    }

    /// Pinned particle indices, ascending.
    pub(crate) fn pinned(&self) -> &[u32] {
        &self.pinned
    }

    /// Whether particle `i` moves freely.
    pub(crate) fn is_free(&self, i: usize) -> bool {
        self.inv_mass.get(i).is_some_and(|&w| w > 0.0)
    }

    /// Whether particle `i` collides (free and not one edge from a pin).
    pub(crate) fn collides(&self, i: usize) -> bool {
        self.collides.get(i).copied().unwrap_or(false)
    }

    /// One substep of length `h` seconds: pinned particles go to `pin_targets` (one per
    /// [`Solver::pinned`] entry), free ones integrate, then constraints and collisions.
    pub(crate) fn substep(
        &mut self,
        h: f64,
        params: &Params,
        pin_targets: &[Vec3],
        collider: &Collider<'_>,
    ) {
        let damp = (-params.damping * h).exp();
        for i in 0..self.x.len() {
            self.prev[i] = self.x[i];
            if self.inv_mass[i] > 0.0 {
                self.v[i] = (self.v[i] + params.gravity * h) * damp;
                self.x[i] += self.v[i] * h;
            }
        }
        for (&p, &t) in self.pinned.iter().zip(pin_targets) {
            self.x[p as usize] = t;
        }
        let stretch_alpha = params.stretch_compliance / (h * h);
        let bend_alpha = params.bend_compliance / (h * h);
        for _ in 0..params.iterations.max(1) {
            project(&mut self.x, &self.inv_mass, &self.stretch, stretch_alpha);
            project(&mut self.x, &self.inv_mass, &self.bend, bend_alpha);
        }
        // Velocities come from the constrained positions, before the collision push:
        // pins, inextensible edges and a collider with a thickness can ask for
        // incompatible positions next to a pin, and a push counted as velocity would then
        // be a kick of a fixed size every substep, an energy gain growing as 1/h. A
        // contact instead only removes the velocity into the collider (inelastic).
        let inv_h = 1.0 / h;
        for i in 0..self.x.len() {
            self.v[i] = (self.x[i] - self.prev[i]) * inv_h;
        }
        self.collide(collider, params.thickness);
        for (v, n) in self.v.iter_mut().zip(&self.contact) {
            let vn = v.dot(*n);
            if vn < 0.0 {
                *v -= *n * vn;
            }
        }
    }

    /// Makes the starting shape consistent without moving in time: `iterations` rounds of
    /// the stretch and bending projections (fully stiff) and the collision push, so a
    /// garment pushed out of the body at the start spreads the push over its edges instead
    /// of starting stretched. Velocities stay zero.
    pub(crate) fn relax(&mut self, collider: &Collider<'_>, thickness: f64, iterations: u32) {
        self.collide(collider, thickness);
        for _ in 0..iterations {
            project(&mut self.x, &self.inv_mass, &self.stretch, 0.0);
            self.collide(collider, thickness);
        }
        self.prev.copy_from_slice(&self.x);
        self.v.iter_mut().for_each(|v| *v = Vec3::ZERO);
    }

    /// Pushes free particles out of every capsule grown by `thickness` (repeated, at most
    /// 8 passes, while a push moved a particle into another capsule), then out of the body
    /// surface: to `thickness` above it, or onto it for particles one edge from a pin (a
    /// pin sits on the skin, so its neighbour cannot keep a thickness away while the edge
    /// between them is inextensible).
    pub(crate) fn collide(&mut self, collider: &Collider<'_>, thickness: f64) {
        for i in 0..self.x.len() {
            self.contact[i] = Vec3::ZERO;
            if self.inv_mass[i] <= 0.0 {
                continue;
            }
            let passes = if self.collides[i] { 8 } else { 0 };
            // With the surface, the capsules only keep particles out of the body's core
            // (they sit inside the skin): grown by the thickness, two limbs' capsules
            // overlap where cloth is pinched between them and would throw it to and fro.
            let grow = if collider.surface.is_some() {
                0.0
            } else {
                thickness
            };
            for _ in 0..passes {
                let mut moved = false;
                for c in collider.capsules {
                    if c.push_out(&mut self.x[i], grow, self.fallback[i]) {
                        moved = true;
                        self.contact[i] = (self.x[i] - c.axis_point(self.x[i]))
                            .try_normalize()
                            .unwrap_or(self.fallback[i]);
                    }
                }
                if !moved {
                    break;
                }
            }
            if let Some((surface, posed)) = &collider.surface {
                let gap = if self.collides[i] {
                    thickness.min(GAP_PER_LENGTH * self.from_pin[i])
                } else {
                    0.0
                };
                self.collide_surface(i, surface, posed, gap, collider);
                if let Some((others, posed_others)) = &collider.others {
                    self.collide_others(
                        i,
                        others,
                        posed_others,
                        (surface, posed),
                        (gap, thickness),
                    );
                }
            }
        }
        self.faces.push(
            &mut self.x,
            &self.face_mass,
            &mut self.contact,
            collider.capsules,
        );
    }

    /// Moves particle `i` to `gap` outside the surface when it is closer (or inside, at
    /// most `reach` below the gap). A particle pinched between two parts of the body
    /// closer than twice the gap (cloth between an arm and a hip) goes half way between
    /// them instead: pushed out of one into the other's gap, it would be pushed back the
    /// next substep, and a particle jumping to and fro by centimetres every substep pumps
    /// energy into its neighbours.
    fn collide_surface(
        &mut self,
        i: usize,
        surface: &Surface,
        posed: &Posed<'_>,
        gap: f64,
        collider: &Collider<'_>,
    ) {
        let query = |p: glam::Vec3, max: f32| surface.nearest(posed, p, max);
        let Some(hit) = query(self.x[i].as_vec3(), gap as f32 + collider.reach) else {
            return;
        };
        if f64::from(hit.signed) >= gap {
            return;
        }
        let out = hit.out.as_dvec3();
        // Slightly beyond the gap, so rounding cannot leave the point inside.
        let target = hit.point.as_dvec3() + out * (gap * (1.0 + 1e-6));
        self.contact[i] = out;
        if gap > 0.0 {
            if let Some(other) = query(target.as_vec3(), gap as f32) {
                if f64::from(other.signed) < gap && other.out.dot(hit.out) < 0.0 {
                    self.x[i] = (hit.point.as_dvec3() + other.point.as_dvec3()) * 0.5;
                    return;
                }
            }
        }
        self.x[i] = target;
    }
}

impl Solver {
    /// Moves particle `i`, when it is more than [`OTHERS_ALLOW`] of the `thickness` deep in
    /// another part of the body (`others`, searched twice the thickness deep: deeper, the
    /// nearest skin may be the far side of a hand), [`OTHERS_SHARE`] of the way back to
    /// that depth. When that point is within `gap` of a part the garment lies on (`near`:
    /// cloth between a hand and a hip) the goal is half way between the two instead, as in
    /// [`Solver::collide_surface`]'s pinch.
    fn collide_others(
        &mut self,
        i: usize,
        others: &Surface,
        posed: &Posed<'_>,
        near: (&Surface, &Posed<'_>),
        (gap, thickness): (f64, f64),
    ) {
        // Twice the thickness deep at most (the start's reach is unbounded, and a part's
        // cut edges make far points look inside).
        let reach = (2.0 * thickness) as f32;
        let Some(hit) = others.nearest(posed, self.x[i].as_vec3(), reach) else {
            return;
        };
        let allow = OTHERS_ALLOW * thickness;
        if f64::from(hit.signed) >= -allow {
            return;
        }
        let out = hit.out.as_dvec3();
        let onto = hit.point.as_dvec3() - out * allow;
        self.contact[i] = out;
        let pinch = near
            .0
            .nearest_closed(near.1, onto.as_vec3(), gap.max(0.0) as f32)
            .filter(|n| f64::from(n.signed) < gap && n.out.dot(hit.out) < 0.0);
        let goal = match pinch {
            Some(n) => (onto + n.point.as_dvec3()) * 0.5,
            None => onto,
        };
        self.x[i] = self.x[i].lerp(goal, OTHERS_SHARE);
    }
}

/// How deep inside a part of the body it is not made to meet (a hand) a particle may be,
/// as a fraction of the thickness, before the part pushes it.
const OTHERS_ALLOW: f64 = 0.75;

/// The share of the way to the allowed depth a particle in another part goes per substep:
/// the rest is left to the next substeps, so the cloth's edges spread the push.
const OTHERS_SHARE: f64 = 0.5;

/// How far from the body surface a particle is kept, per unit of its distance along the
/// garment from the nearest pin, at most (the thickness caps it). A pin sits on the skin;
/// a particle two edges from it, held a full thickness off a body that bulges under it
/// (a hip as the thigh swings), asks more than its inextensible edges can give, and the
/// push and the edges then fight every substep, pumping energy into the garment.
const GAP_PER_LENGTH: f64 = 0.25;

/// Shortest paths along `edges` (lengths at `positions`) from any of `sources`
/// (Dijkstra; infinite where none reaches).
fn distances_from(sources: &[u32], edges: &[Pair], positions: &[Vec3]) -> Vec<f64> {
    let n = positions.len();
    let mut adjacent: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    for &(i, j) in edges {
        let (i, j) = (i as usize, j as usize);
        let d = (positions[i] - positions[j]).length();
        adjacent[i].push((j, d));
        adjacent[j].push((i, d));
    }
    let mut dist = vec![f64::INFINITY; n];
    let mut heap = std::collections::BinaryHeap::new();
    for &s in sources {
        if let Some(d) = dist.get_mut(s as usize) {
            *d = 0.0;
            heap.push(std::cmp::Reverse((Ordered(0.0), s as usize)));
        }
    }
    while let Some(std::cmp::Reverse((Ordered(d), i))) = heap.pop() {
        if d > dist[i] {
            continue;
        }
        for &(j, w) in &adjacent[i] {
            if d + w < dist[j] {
                dist[j] = d + w;
                heap.push(std::cmp::Reverse((Ordered(d + w), j)));
            }
        }
    }
    dist
}

/// An `f64` ordered by `total_cmp`, for the heap.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Ordered(f64);

impl Eq for Ordered {}

impl PartialOrd for Ordered {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ordered {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// One Gauss-Seidel pass over distance constraints with compliance `alpha` (already
/// divided by the substep squared); the Lagrange multiplier starts at zero each substep.
fn project(x: &mut [Vec3], w: &[f64], constraints: &[Distance], alpha: f64) {
    for c in constraints {
        let (i, j) = (c.i as usize, c.j as usize);
        let wsum = w[i] + w[j];
        if wsum <= 0.0 {
            continue;
        }
        let d = x[i] - x[j];
        let len = d.length();
        if len <= f64::MIN_POSITIVE {
            continue;
        }
        let n = d / len;
        let lambda = -(len - c.rest) / (wsum + alpha);
        x[i] += n * (lambda * w[i]);
        x[j] -= n * (lambda * w[j]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two unit boxes side by side along x: the body part a garment lies on (`near`, x in
    /// 0..1) and another (`others`, from `x0`), as one closed body's parts.
    fn two_parts(x0: f32) -> (Vec<glam::Vec3>, Vec<glam::Vec3>, Surface, Surface) {
        let (corners, a) = super::super::surface::tests::cube(false);
        let mut p = corners.clone();
        p.extend(corners.iter().map(|c| *c + glam::Vec3::X * x0));
        let b: Vec<[u32; 3]> = a.iter().map(|t| t.map(|v| v + 8)).collect();
        let whole = Surface::new(&p, &[a.clone(), b.clone()].concat());
        let mut normals = Vec::new();
        whole.normals(&p, &mut normals);
        let near = Surface::new(&p, &a);
        let others = Surface::new(&p, &b).inside_as(&whole);
        (p, normals, near, others)
    }

    /// A particle at `x` (y = z = 0.5) after one push of `others` (thickness 0.2, so it
    /// may be 0.15 deep; `gap` from `near`).
    fn pushed(x0: f32, x: f64, gap: f64) -> f64 {
        let (p, normals, near, others) = two_parts(x0);
        let posed = Posed::at(&p, &normals);
        let mut solver = Solver::new(&[glam::Vec3::new(x as f32, 0.5, 0.5)], &[], &[]);
        solver.collide_others(0, &others, &posed, (&near, &posed), (gap, 0.2));
        let at = solver.x[0];
        assert!(
            (at.y - 0.5).abs() < 1e-6 && (at.z - 0.5).abs() < 1e-6,
            "{at}"
        );
        at.x
    }

    #[test]
    fn another_part_pushes_only_past_the_allowed_depth_and_halves_a_pinch() {
        // 0.1 inside the other box (at 1.2): within 3/4 of the thickness, left alone.
        assert!((pushed(1.2, 1.3, 0.2) - 1.3).abs() < 1e-6);
        // 0.25 inside: half way back to 0.15 deep (1.35).
        assert!((pushed(1.2, 1.45, 0.2) - 1.4).abs() < 1e-6);
        // The other box at 1.05: 0.15 deep is 0.2 from the near box, within its gap of
        // 0.3, so the goal is half way between the near skin (1.0) and that point (1.2).
        assert!((pushed(1.05, 1.3, 0.3) - 1.2).abs() < 1e-6);
        // With a gap of 0.1 there is no pinch: half way to 1.2.
        assert!((pushed(1.05, 1.3, 0.1) - 1.25).abs() < 1e-6);
        // Deeper than twice the thickness (0.45 in a box 1 wide): out of reach.
        assert!((pushed(1.05, 1.5, 0.1) - 1.5).abs() < 1e-6);
    }

    #[test]
    fn topology_of_a_quad() {
        let (edges, bends) = topology(&[[0, 1, 2], [2, 1, 3]]);
        assert_eq!(edges, vec![(0, 1), (0, 2), (1, 2), (1, 3), (2, 3)]);
        assert_eq!(bends, vec![(0, 3)]);
    }

    #[test]
    fn a_hanging_pair_keeps_its_length() {
        let mut s = Solver::new(
            &[glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
            &[[0, 1, 2]],
            &[0],
        );
        let params = Params {
            gravity: Vec3::new(0.0, -9.81, 0.0),
            damping: 0.5,
            stretch_compliance: 0.0,
            bend_compliance: 0.0,
            thickness: 0.0,
            iterations: 1,
        };
        let none = Collider {
            others: None,
            capsules: &[],
            surface: None,
            reach: 0.0,
        };
        for _ in 0..600 {
            s.substep(1.0 / 600.0, &params, &[Vec3::ZERO], &none);
        }
        assert_eq!(s.x[0], Vec3::ZERO);
        for c in &s.stretch {
            let len = (s.x[c.i as usize] - s.x[c.j as usize]).length();
            assert!((len - c.rest).abs() < 0.02 * c.rest, "{len} vs {}", c.rest);
        }
        assert!(s.x[1].y < -0.5, "the free corner swings down: {}", s.x[1]);
    }
}
