//! Bones through the garment's faces: the capsules' axes kept out of the garment's
//! triangles, not only its vertices out of the capsules.
//!
//! Vertex collisions alone let a thin limb pass between a garment's vertices: a hand
//! hanging beside a flared skirt (its edges 4-5 cm long, the hand's capsule 2-3 cm
//! across) slips through a triangle, ends up inside the skirt and drags it up as the arm
//! swings (the demo's skirt on the cgspeed walk tore to 140% stretch that way). Here every
//! triangle near a capsule is held at least the capsule's radius from its axis: the
//! closest points of the axis segment and the triangle are found by alternating
//! projection (the two are convex, so it converges to the closest pair; three rounds are
//! within a fraction of a millimetre for garment-sized triangles), and a triangle closer
//! than the radius is moved away along the line between them, each vertex by its
//! barycentric share, as a position-based point-triangle contact with the body point
//! fixed (Müller et al. 2007, "Position Based Dynamics", section 4.3). The axis moves
//! under a millimetre per substep, so a triangle is pushed before the axis can cross it,
//! and the side each keeps is the side it started on.

use glam::DVec3 as Vec3;

use super::attach::closest_on_triangle;
use super::collide::Capsule;

/// Alternating projections between a capsule's axis and a triangle.
const ROUNDS: usize = 3;

/// The least barycentric share of the contact point that particles free to move must
/// hold for a triangle to be pushed.
const MIN_SHARE: f64 = 0.5;

/// A garment's triangles and, per triangle, a radius around its centroid that holds it
/// however it stretches (for the quick rejection).
#[derive(Clone, Debug, Default)]
pub(crate) struct Faces {
    triangles: Vec<[u32; 3]>,
    reach: Vec<f64>,
}

impl Faces {
    /// The faces of `triangles` over rest `positions`.
    pub(crate) fn new(triangles: &[[u32; 3]], positions: &[Vec3]) -> Self {
        let reach = triangles
            .iter()
            .map(|t| {
                let c = centroid(positions, t);
                // Twice the rest size: the limits fail a simulation stretched 50%.
                2.0 * t
                    .iter()
                    .map(|&i| positions[i as usize].distance(c))
                    .fold(0.0, f64::max)
            })
            .collect();
        Self {
            triangles: triangles.to_vec(),
            reach,
        }
    }

    /// Moves the triangles of `x` that come closer than a capsule's radius to its axis
    /// away from it (particles with `inv_mass` 0 stay), recording the push direction as
    /// each moved particle's `contact` normal.
    pub(crate) fn push(
        &self,
        x: &mut [Vec3],
        inv_mass: &[f64],
        contact: &mut [Vec3],
        capsules: &[Capsule],
    ) {
        let (lo, hi) = x.iter().fold(
            (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        for cap in capsules {
            let r = cap.radius;
            let (clo, chi) = (cap.a.min(cap.b) - r, cap.a.max(cap.b) + r);
            if clo.cmpgt(hi).any() || chi.cmplt(lo).any() {
                continue;
            }
            for (t, &reach) in self.triangles.iter().zip(&self.reach) {
                let c = centroid(x, t);
                if (c - cap.axis_point(c)).length() > r + reach {
                    continue;
                }
                let [a, b, d] = t.map(|i| x[i as usize]);
                let mut on_axis = cap.axis_point(c);
                let mut w = [1.0 / 3.0; 3];
                for _ in 0..ROUNDS {
                    w = closest_on_triangle(
                        on_axis.as_vec3(),
                        a.as_vec3(),
                        b.as_vec3(),
                        d.as_vec3(),
                    )
                    .map(f64::from);
                    on_axis = cap.axis_point(a * w[0] + b * w[1] + d * w[2]);
                }
                let q = a * w[0] + b * w[1] + d * w[2];
                let gap = q - on_axis;
                let dist = gap.length();
                if dist >= r || dist < r * 1e-6 {
                    continue;
                }
                let n = gap / dist;
                let (share, weight) = t.iter().zip(w).fold((0.0, 0.0), |(s, k), (&i, wi)| {
                    let m = inv_mass[i as usize];
                    (s + m * wi, k + m * wi * wi)
                });
                // Mostly held by particles that stay (pins and their neighbours): the
                // few that may move would be thrown far (by `1 / share`) to clear it.
                if share < MIN_SHARE {
                    continue;
                }
                // Slightly beyond the radius, so rounding cannot leave it inside.
                let lambda = (r * (1.0 + 1e-6) - dist) / weight;
                for (&i, wi) in t.iter().zip(w) {
                    let i = i as usize;
                    if inv_mass[i] > 0.0 && wi > 0.0 {
                        x[i] += n * (lambda * inv_mass[i] * wi);
                        contact[i] = n;
                    }
                }
            }
        }
    }
}

fn centroid(x: &[Vec3], t: &[u32; 3]) -> Vec3 {
    (x[t[0] as usize] + x[t[1] as usize] + x[t[2] as usize]) / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bone_between_the_vertices_pushes_the_face() {
        // A large triangle in the plane y = 0, a capsule of radius 0.1 lying across it
        // 0.05 above, far from every vertex.
        let mut x = vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        let faces = Faces::new(&[[0, 1, 2]], &x);
        let cap = Capsule {
            a: Vec3::new(-0.5, 0.05, 0.0),
            b: Vec3::new(0.5, 0.05, 0.0),
            radius: 0.1,
        };
        let mut contact = vec![Vec3::ZERO; 3];
        faces.push(&mut x, &[1.0, 1.0, 1.0], &mut contact, &[cap]);
        // The face moved down, away from the axis, to the radius.
        let w = closest_on_triangle(
            glam::Vec3::new(0.0, 0.05, 0.0),
            x[0].as_vec3(),
            x[1].as_vec3(),
            x[2].as_vec3(),
        );
        let q = x[0] * f64::from(w[0]) + x[1] * f64::from(w[1]) + x[2] * f64::from(w[2]);
        let d = (q - cap.axis_point(q)).length();
        assert!(d >= 0.1 - 1e-4, "{d}");
        assert!(x.iter().all(|p| p.y < 0.0), "{x:?}");
        assert!(contact.iter().all(|n| n.y < -0.99));
    }

    #[test]
    fn pinned_vertices_stay_and_far_faces_are_left_alone() {
        let mut x = vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        let faces = Faces::new(&[[0, 1, 2]], &x);
        let near = Capsule {
            a: Vec3::new(-0.5, 0.05, 0.0),
            b: Vec3::new(0.5, 0.05, 0.0),
            radius: 0.1,
        };
        let mut contact = vec![Vec3::ZERO; 3];
        faces.push(&mut x, &[0.0, 0.0, 1.0], &mut contact, &[near]);
        assert_eq!(x[0], Vec3::new(-1.0, 0.0, -1.0));
        assert!(x[2].y < 0.0);
        let before = x.clone();
        let far = Capsule {
            a: Vec3::new(-0.5, 3.0, 0.0),
            b: Vec3::new(0.5, 3.0, 0.0),
            radius: 0.1,
        };
        faces.push(&mut x, &[1.0; 3], &mut contact, &[far]);
        assert_eq!(x, before);
    }
}
