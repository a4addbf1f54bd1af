//! Colliders: capsules along the skeleton's bones, with radii fitted at rest to the skinned
//! vertices each bone carries, and the projection that keeps garment vertices outside them.

use glam::{DVec3, Mat4, Vec3};
use rigport_model::Asset;

use super::attach::closest_on_triangle;

/// A capsule between two joints: every point within `radius` of the segment from joint
/// `from`'s origin to joint `to`'s origin (model space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoneCapsule {
    /// The joint at the bone's head (the one whose weights the fit used).
    pub from: usize,
    /// The child joint at the bone's tail.
    pub to: usize,
    /// Radius, model units.
    pub radius: f32,
}

/// A capsule placed in space: segment `a`-`b` and radius (`f64`, as the solver's state).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Capsule {
    /// One end of the axis.
    pub a: DVec3,
    /// The other end.
    pub b: DVec3,
    /// Radius.
    pub radius: f64,
}

impl Capsule {
    /// The capsule of `bone` for joint model matrices `joint_model`.
    pub fn place(bone: &BoneCapsule, joint_model: &[Mat4]) -> Self {
        let at = |j: usize| {
            joint_model
                .get(j)
                .map_or(DVec3::ZERO, |m| m.w_axis.truncate().as_dvec3())
        };
        Self {
            a: at(bone.from),
            b: at(bone.to),
            radius: f64::from(bone.radius),
        }
    }

    /// The point of the axis nearest to `p`.
    pub fn axis_point(&self, p: DVec3) -> DVec3 {
        let ab = self.b - self.a;
        let len2 = ab.length_squared();
        let t = if len2 > 0.0 {
            ((p - self.a).dot(ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        self.a + ab * t
    }

    /// How deep `p` is inside the capsule grown by `thickness` (positive inside).
    pub fn depth(&self, p: DVec3, thickness: f64) -> f64 {
        self.radius + thickness - (p - self.axis_point(p)).length()
    }

    /// Moves `p` to the surface of the capsule grown by `thickness` when inside, along
    /// the direction from the axis (`fallback` when `p` lies on the axis). Returns whether
    /// it moved.
    pub fn push_out(&self, p: &mut DVec3, thickness: f64, fallback: DVec3) -> bool {
        let c = self.axis_point(*p);
        let d = *p - c;
        let r = self.radius + thickness;
        let len = d.length();
        if len >= r {
            return false;
        }
        let dir = if len > r * 1e-6 { d / len } else { fallback };
        // Slightly beyond the surface, so rounding cannot leave the point inside.
        *p = c + dir * (r * (1.0 + 1e-6));
        true
    }
}

/// Points sampled along each bone (at `(k + 0.5) / AXIS_SAMPLES` of its length) to fit
/// its radius.
const AXIS_SAMPLES: usize = 8;

/// Which of the sorted per-sample radii is the bone's: a low quantile, so a capsule stays
/// inside the skin where the body narrows (a wrist, a waist) without one thin spot
/// deciding.
const RADIUS_QUANTILE: f32 = 0.25;

/// Fits one capsule per (joint, child) pair of `asset`'s skeleton whose joint carries
/// skinned vertices (rest model space; `scale` is the body's size, for tolerances).
///
/// Each skinned vertex belongs to its highest-weight joint and to the nearest of that
/// joint's child segments; each triangle to the bones of its vertices. At
/// `AXIS_SAMPLES` points along the bone the distance to the nearest of its triangles is
/// the radius of the largest ball there inside the skin; the capsule's radius is the
/// `RADIUS_QUANTILE` of those. (The distance to the nearest *vertex* would overshoot
/// flat sides: a box arm's corners are 1.41 times farther than its faces.) Bones shorter
/// than 1e-6 of `scale`, or with fewer than 3 triangles, get no capsule. Skips mesh
/// `skip`. Output is sorted by (joint, child).
pub fn fit_capsules(asset: &Asset, skip: Option<usize>, scale: f32) -> Vec<BoneCapsule> {
    let rest = asset.skeleton.model_rest_matrices();
    let n = rest.len();
    let origin = |j: usize| rest.get(j).map_or(Vec3::ZERO, |m| m.w_axis.truncate());
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (j, joint) in asset.skeleton.joints().iter().enumerate() {
        if let Some(p) = joint.parent {
            let p = p.get();
            if p < n && (origin(j) - origin(p)).length() > 1e-6 * scale {
                children[p].push(j);
            }
        }
    }
    // Per bone (joint, child index): the triangles it carries.
    let mut tris: Vec<Vec<Vec<[Vec3; 3]>>> =
        children.iter().map(|c| vec![Vec::new(); c.len()]).collect();
    for skin in &asset.skins {
        if Some(skin.mesh.get()) == skip {
            continue;
        }
        let Some(mesh) = asset.meshes.get(skin.mesh.get()) else {
            continue;
        };
        let bone_of: Vec<Option<(usize, usize)>> = skin
            .influences
            .rows()
            .zip(&mesh.positions)
            .map(|(row, &p)| {
                let best = row
                    .iter()
                    .fold(None::<&rigport_model::Influence>, |b, i| match b {
                        Some(b) if b.weight >= i.weight => Some(b),
                        _ => Some(i),
                    })?;
                let j = skin.joints.get(best.joint as usize)?.get();
                let mut nearest: Option<(usize, f64)> = None;
                for (k, &c) in children.get(j)?.iter().enumerate() {
                    let axis = Capsule {
                        a: origin(j).as_dvec3(),
                        b: origin(c).as_dvec3(),
                        radius: 0.0,
                    };
                    let d = (p.as_dvec3() - axis.axis_point(p.as_dvec3())).length();
                    if nearest.is_none_or(|(_, nd)| d < nd) {
                        nearest = Some((k, d));
                    }
                }
                nearest.map(|(k, _)| (j, k))
            })
            .collect();
        for t in &mesh.triangles {
            let [Some(&a), Some(&b), Some(&c)] = t.map(|i| mesh.positions.get(i as usize)) else {
                continue;
            };
            let mut bones: Vec<(usize, usize)> = t
                .iter()
                .filter_map(|&i| bone_of.get(i as usize).copied().flatten())
                .collect();
            bones.sort_unstable();
            bones.dedup();
            for (j, k) in bones {
                tris[j][k].push([a, b, c]);
            }
        }
    }
    let mut out = Vec::new();
    for (j, kids) in children.iter().enumerate() {
        for (k, &c) in kids.iter().enumerate() {
            let carried = &tris[j][k];
            if carried.len() < 3 {
                continue;
            }
            let (a, b) = (origin(j), origin(c));
            let mut radii: Vec<f32> = (0..AXIS_SAMPLES)
                .map(|s| {
                    let p = a.lerp(b, (s as f32 + 0.5) / AXIS_SAMPLES as f32);
                    carried
                        .iter()
                        .map(|[ta, tb, tc]| {
                            let w = closest_on_triangle(p, *ta, *tb, *tc);
                            (*ta * w[0] + *tb * w[1] + *tc * w[2] - p).length()
                        })
                        .fold(f32::INFINITY, f32::min)
                })
                .collect();
            radii.sort_by(f32::total_cmp);
            let q = ((radii.len() - 1) as f32 * RADIUS_QUANTILE).round() as usize;
            let radius = radii.get(q).copied().unwrap_or(0.0);
            if radius.is_finite() && radius > 0.0 {
                out.push(BoneCapsule {
                    from: j,
                    to: c,
                    radius,
                });
            }
        }
    }
    out
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_out_reaches_the_grown_surface() {
        let cap = Capsule {
            a: DVec3::ZERO,
            b: DVec3::Z * 2.0,
            radius: 0.5,
        };
        let mut p = DVec3::new(0.1, 0.0, 1.0);
        assert!(cap.push_out(&mut p, 0.1, DVec3::X));
        assert!(cap.depth(p, 0.1) <= 0.0);
        assert!((p.x - 0.6).abs() < 1e-5);
        let mut q = DVec3::new(0.0, 0.0, 2.3);
        assert!(cap.push_out(&mut q, 0.0, DVec3::X));
        assert!((q.z - 2.5).abs() < 1e-5, "{q}");
        let mut far = DVec3::new(3.0, 0.0, 0.0);
        assert!(!cap.push_out(&mut far, 0.1, DVec3::X));
    }
}
