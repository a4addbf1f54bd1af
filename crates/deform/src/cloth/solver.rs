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
        capsules: &[Capsule],
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
        self.collide(capsules, params.thickness);
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
    pub(crate) fn relax(&mut self, capsules: &[Capsule], thickness: f64, iterations: u32) {
        self.collide(capsules, thickness);
        for _ in 0..iterations {
            project(&mut self.x, &self.inv_mass, &self.stretch, 0.0);
            self.collide(capsules, thickness);
        }
        self.prev.copy_from_slice(&self.x);
        self.v.iter_mut().for_each(|v| *v = Vec3::ZERO);
    }

    /// Pushes free particles out of every capsule grown by `thickness`; repeated (at most
    /// 8 passes) while a push moved a particle into another capsule.
    pub(crate) fn collide(&mut self, capsules: &[Capsule], thickness: f64) {
        for i in 0..self.x.len() {
            self.contact[i] = Vec3::ZERO;
            if !self.collides[i] {
                continue;
            }
            for _ in 0..8 {
                let mut moved = false;
                for c in capsules {
                    if c.push_out(&mut self.x[i], thickness, self.fallback[i]) {
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
        }
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
        for _ in 0..600 {
            s.substep(1.0 / 600.0, &params, &[Vec3::ZERO], &[]);
        }
        assert_eq!(s.x[0], Vec3::ZERO);
        for c in &s.stretch {
            let len = (s.x[c.i as usize] - s.x[c.j as usize]).length();
            assert!((len - c.rest).abs() < 0.02 * c.rest, "{len} vs {}", c.rest);
        }
        assert!(s.x[1].y < -0.5, "the free corner swings down: {}", s.x[1]);
    }
}
