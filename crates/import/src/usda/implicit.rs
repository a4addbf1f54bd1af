//! UsdGeom's implicit surfaces (`Cube`, `Sphere`, `Cylinder`, `Capsule`, `Cone`) as
//! polygon meshes, so they are imported like Meshes (skinned, rigidly bound through
//! constant influences as Pixar's bake tests do, or static) rather than left out.
//!
//! Sizes follow the schemas' attributes and fallbacks (`size` 2; `radius` 1, `height` 2,
//! `axis` "Z"; the Capsule's `radius` 0.5 and `height` 1, the length of its cylinder part),
//! centred on the origin as UsdGeom defines them. Round surfaces get [`SEGMENTS`] segments
//! around and [`RINGS`] rings from pole to pole; each flat face has its own points, so its
//! normals are the face's. Faces wind counter-clockwise seen from outside.

use std::f64::consts::PI;

use super::stage::Prim;
use super::values::{self, number, token};

/// Segments around the axis of round surfaces.
pub(super) const SEGMENTS: usize = 32;
/// Rings from pole to pole of spheres (capsules: of their two caps together).
pub(super) const RINGS: usize = 16;

/// A tessellated surface: points, per-point unit normals and polygons.
pub(super) struct Surface {
    pub(super) points: Vec<[f64; 3]>,
    pub(super) normals: Vec<[f64; 3]>,
    pub(super) counts: Vec<i64>,
    pub(super) indices: Vec<i64>,
}

/// Whether `type_name` is an implicit surface rigport tessellates.
pub(super) fn is_implicit(type_name: Option<&str>) -> bool {
    matches!(
        type_name,
        Some("Cube" | "Sphere" | "Cylinder" | "Capsule" | "Cone")
    )
}

impl Surface {
    fn new() -> Self {
        Self {
            points: Vec::new(),
            normals: Vec::new(),
            counts: Vec::new(),
            indices: Vec::new(),
        }
    }

    fn point(&mut self, p: [f64; 3], n: [f64; 3]) -> i64 {
        self.points.push(p);
        self.normals.push(n);
        self.points.len() as i64 - 1
    }

    fn face(&mut self, corners: &[i64]) {
        self.counts.push(corners.len() as i64);
        self.indices.extend_from_slice(corners);
    }

    /// A surface of revolution about +Z: `profile` from bottom to top as (radius, z,
    /// normal radial part, normal z part); a zero radius is a pole (one point per segment,
    /// so every face stays a quad or triangle with its own normal direction).
    fn revolve(&mut self, profile: &[(f64, f64, f64, f64)]) {
        let first = self.points.len() as i64;
        let ring = SEGMENTS as i64;
        for &(r, z, nr, nz) in profile {
            for s in 0..SEGMENTS {
                let a = 2.0 * PI * s as f64 / SEGMENTS as f64;
                let (c, si) = (a.cos(), a.sin());
                self.point([r * c, r * si, z], [nr * c, nr * si, nz]);
            }
        }
        let pole = |k: usize| profile.get(k).is_some_and(|p| p.0.abs() < 1e-12);
        for k in 0..profile.len().saturating_sub(1) {
            let base = first + k as i64 * ring;
            for s in 0..ring {
                let a = base + s;
                let b = base + (s + 1) % ring;
                // At a pole the ring's points coincide: triangles, not degenerate quads.
                if pole(k) {
                    self.face(&[a, b + ring, a + ring]);
                } else if pole(k + 1) {
                    self.face(&[a, b, a + ring]);
                } else {
                    self.face(&[a, b, b + ring, a + ring]);
                }
            }
        }
    }

    /// A flat disc of radius `r` at height `z`, facing +Z (`up`) or -Z.
    fn disc(&mut self, r: f64, z: f64, up: bool) {
        let n = [0.0, 0.0, if up { 1.0 } else { -1.0 }];
        let corners: Vec<i64> = (0..SEGMENTS)
            .map(|s| {
                let a = 2.0 * PI * s as f64 / SEGMENTS as f64;
                self.point([r * a.cos(), r * a.sin(), z], n)
            })
            .collect();
        if up {
            self.face(&corners);
        } else {
            let reversed: Vec<i64> = corners.into_iter().rev().collect();
            self.face(&reversed);
        }
    }

    /// Rotates +Z onto `axis` ("X": z -> x, "Y": z -> y), keeping the winding.
    fn turn_to_axis(&mut self, axis: &str) {
        let turn = |p: &mut [f64; 3]| {
            let [x, y, z] = *p;
            *p = match axis {
                // Cyclic permutations are rotations.
                "X" => [z, x, y],
                "Y" => [y, z, x],
                _ => [x, y, z],
            };
        };
        self.points.iter_mut().for_each(turn);
        self.normals.iter_mut().for_each(turn);
    }
}

/// The tessellated surface of an implicit prim, or an error message naming the bad
/// attribute; `None` when `prim` is not an implicit surface.
pub(super) fn tessellate(prim: &Prim<'_>) -> Result<Option<Surface>, String> {
    if !is_implicit(prim.type_name) {
        return Ok(None);
    }
    let num = |name: &str, fallback: f64| -> Result<f64, String> {
        match prim.prop(name).and_then(values::static_value) {
            None => Ok(fallback),
            Some((v, _)) => number(v)
                .filter(|x| x.is_finite() && *x >= 0.0)
                .ok_or_else(|| format!("{name} must be a finite, non-negative number")),
        }
    };
    let axis = match prim.prop("axis").and_then(values::static_value) {
        None => "Z",
        Some((v, _)) => match token(v) {
            Some(a @ ("X" | "Y" | "Z")) => a,
            other => return Err(format!("axis {:?} is not X, Y or Z", other.unwrap_or("?"))),
        },
    };
    let mut s = Surface::new();
    match prim.type_name {
        Some("Cube") => {
            let h = num("size", 2.0)? / 2.0;
            // Each face: its normal axis `k` and sign; corners counter-clockwise from outside.
            for k in 0..3 {
                for sign in [1.0, -1.0] {
                    let (u, v) = ((k + 1) % 3, (k + 2) % 3);
                    let mut n = [0.0; 3];
                    n[k] = sign;
                    let corner = |a: f64, b: f64| {
                        let mut p = [0.0; 3];
                        p[k] = sign * h;
                        p[u] = a * h;
                        p[v] = b * h;
                        p
                    };
                    let quad = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
                    let mut ids: Vec<i64> = quad
                        .iter()
                        .map(|&(a, b)| s.point(corner(a, b), n))
                        .collect();
                    if sign < 0.0 {
                        ids.reverse();
                    }
                    s.face(&ids);
                }
            }
        }
        Some("Sphere") => {
            let r = num("radius", 1.0)?;
            let profile: Vec<(f64, f64, f64, f64)> = (0..=RINGS)
                .map(|k| {
                    let phi = -PI / 2.0 + PI * k as f64 / RINGS as f64;
                    (r * phi.cos(), r * phi.sin(), phi.cos(), phi.sin())
                })
                .collect();
            s.revolve(&profile);
        }
        Some("Capsule") => {
            let r = num("radius", 0.5)?;
            let half = num("height", 1.0)? / 2.0;
            let half_rings = RINGS / 2;
            let mut profile = Vec::new();
            for k in 0..=half_rings {
                let phi = -PI / 2.0 + PI / 2.0 * k as f64 / half_rings as f64;
                profile.push((r * phi.cos(), r * phi.sin() - half, phi.cos(), phi.sin()));
            }
            for k in 0..=half_rings {
                let phi = PI / 2.0 * k as f64 / half_rings as f64;
                profile.push((r * phi.cos(), r * phi.sin() + half, phi.cos(), phi.sin()));
            }
            s.revolve(&profile);
        }
        Some("Cylinder") => {
            let r = num("radius", 1.0)?;
            let half = num("height", 2.0)? / 2.0;
            s.revolve(&[(r, -half, 1.0, 0.0), (r, half, 1.0, 0.0)]);
            s.disc(r, half, true);
            s.disc(r, -half, false);
        }
        _ => {
            // Cone: apex at +height/2, base at -height/2.
            let r = num("radius", 1.0)?;
            let h = num("height", 2.0)?;
            let len = (r * r + h * h).sqrt().max(f64::MIN_POSITIVE);
            let (nr, nz) = (h / len, r / len);
            s.revolve(&[(r, -h / 2.0, nr, nz), (0.0, h / 2.0, nr, nz)]);
            s.disc(r, -h / 2.0, false);
        }
    }
    s.turn_to_axis(axis);
    Ok(Some(s))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every face's corners wind counter-clockwise around its outward normal.
    fn outward(s: &Surface) {
        let mut start = 0usize;
        for &c in &s.counts {
            let f = &s.indices[start..start + c as usize];
            start += c as usize;
            let p = |i: i64| glam::DVec3::from_array(s.points[i as usize]);
            let mut area = glam::DVec3::ZERO;
            for k in 1..f.len() - 1 {
                area += (p(f[k]) - p(f[0])).cross(p(f[k + 1]) - p(f[0]));
            }
            let centre = f.iter().map(|&i| p(i)).sum::<glam::DVec3>() / f.len() as f64;
            if area.length() > 1e-12 {
                assert!(area.dot(centre) > 0.0, "face {f:?} winds inward");
            }
        }
    }

    #[test]
    fn surfaces_wind_outward_and_fit_their_sizes() {
        for (src, extent) in [
            ("def Cube \"C\" { double size = 4 }", 2.0),
            ("def Sphere \"S\" { double radius = 3 }", 3.0),
            ("def Cylinder \"Y\" { double radius = 1 \n double height = 6 }", 3.0),
            ("def Capsule \"P\" { double radius = 1 \n double height = 2 }", 2.0),
            ("def Cone \"N\" { double radius = 1 \n double height = 5 \n uniform token axis = \"X\" }", 2.5),
        ] {
            let text = format!("#usda 1.0\n{src}\n");
            let layer = rigport_usd::parse::parse(&text, std::path::Path::new("t.usda"))
                .expect("parses");
            let stage = super::super::stage::Stage::compose(&layer.root, None);
            let prim = &stage.prims[0];
            let s = tessellate(prim).unwrap().unwrap();
            outward(&s);
            let max = s.points.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
            assert!((max - extent).abs() < 1e-9, "{src}: {max}");
        }
    }
}
