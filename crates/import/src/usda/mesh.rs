//! `Mesh` prims: topology (n-gons to triangle fans, orientation), primvars of any
//! interpolation, normals and UVs (splitting points into further vertices where values
//! differ), the geom bind transform, and static (unskinned) meshes moved to model space.

use std::collections::HashMap;

use glam::{DMat3, DMat4, DVec3};
use rigport_model::glam::{Vec2, Vec3};
use rigport_model::{Mesh, SkinBinding};

use super::blend::PointMap;
use super::implicit::tessellate;
use super::importer::{Importer, Interp, Primvar, SkelData};
use super::shapes::Channel;
use super::stage::Prim;
use super::values::{self, is_half_type, matrix, numbers, round_to_half, token, tuples};
use super::xform::usd_matrix;
use crate::ImportError;

/// A mesh, its skin when bound, its blend-shape channels, for a static mesh under
/// time-sampled transforms the prims whose ops are animated (its points are then in the
/// prim's own space: `root_motion.rs` attaches it to a joint that carries the motion), and
/// the times (seconds) of its time-sampled points, which are its last morph targets
/// (`points.rs`).
pub(super) type ImportedMesh = (
    Mesh,
    Option<SkinBinding>,
    Vec<Channel>,
    Vec<String>,
    Option<Vec<f32>>,
);

impl<'l> Importer<'l, '_> {
    /// A primvar of `N`-tuples (`N = 1` reads plain numbers) with its indices.
    fn primvar<const N: usize>(
        &self,
        prim: &Prim<'l>,
        name: &str,
        default_interp: Interp,
    ) -> Result<Option<Primvar<N>>, ImportError> {
        let Some(prop) = prim.prop(name) else {
            return Ok(None);
        };
        let Some((value, _)) = values::static_value(prop) else {
            return Ok(None);
        };
        let half = prop.type_name.is_some_and(is_half_type);
        let mut values: Vec<[f64; N]> = if N == 1 {
            numbers(value).map(|v| {
                v.into_iter()
                    .map(|x| {
                        let mut a = [0.0; N];
                        if let Some(s) = a.first_mut() {
                            *s = x;
                        }
                        a
                    })
                    .collect()
            })
        } else {
            tuples::<N>(value)
        }
        .ok_or_else(|| {
            self.err_at(
                prop.line,
                &prim.path,
                format!(
                    "{name} must be an array of {N}-component values, not {}",
                    prop.type_name.unwrap_or("?")
                ),
            )
        })?;
        if half {
            for v in &mut values {
                for x in v.iter_mut() {
                    *x = f64::from(round_to_half(*x as f32));
                }
            }
        }
        if values.iter().flatten().any(|x| !x.is_finite()) {
            return Err(self.err(&prim.path, format!("{name} holds a non-finite value")));
        }
        let interp = match prop.meta("interpolation").map(token) {
            None => default_interp,
            Some(Some("constant")) => Interp::Constant,
            Some(Some("uniform")) => Interp::Uniform,
            Some(Some("vertex" | "varying")) => Interp::Vertex,
            Some(Some("faceVarying")) => Interp::FaceVarying,
            Some(other) => {
                return Err(self.err(
                    &prim.path,
                    format!(
                        "{name} has an unknown interpolation {:?}",
                        other.unwrap_or("?")
                    ),
                ))
            }
        };
        let indices = match self.int_list(prim, &format!("{name}:indices"))? {
            None => None,
            Some(ix) => Some(
                ix.into_iter()
                    .map(|i| {
                        usize::try_from(i)
                            .ok()
                            .filter(|&i| i < values.len())
                            .ok_or_else(|| {
                                self.err(
                                    &prim.path,
                                    format!(
                                        "{name}:indices holds {i}, out of range for {} values",
                                        values.len()
                                    ),
                                )
                            })
                    })
                    .collect::<Result<Vec<_>, _>>()?,
            ),
        };
        Ok(Some(Primvar {
            values,
            indices,
            interp,
        }))
    }

    /// Checks that a primvar has one element per interpolation site.
    fn check_primvar<const N: usize>(
        &self,
        prim: &str,
        name: &str,
        pv: &Primvar<N>,
        faces: usize,
        points: usize,
        corners: usize,
    ) -> Result<(), ImportError> {
        let (expected, what) = match pv.interp {
            Interp::Constant => (1, "constant interpolation"),
            Interp::Uniform => (faces, "faces (uniform interpolation)"),
            Interp::Vertex => (points, "points (vertex interpolation)"),
            Interp::FaceVarying => (corners, "face corners (faceVarying interpolation)"),
        };
        let found = pv.indices.as_ref().map_or(pv.values.len(), Vec::len);
        if found != expected {
            return Err(self.err(
                prim,
                format!("{name} has {found} elements for {expected} {what}"),
            ));
        }
        Ok(())
    }

    /// The mesh's `float[]` primvars with vertex interpolation (other than the ones read
    /// elsewhere), by name without `primvars:`, one value per output vertex (through
    /// `source_vertex`). Primvars of other shapes are left out.
    fn vertex_values(
        &self,
        prim: &Prim<'l>,
        points: usize,
        faces: usize,
        corners: usize,
        source_vertex: &[u32],
    ) -> Result<Vec<(String, Vec<f32>)>, ImportError> {
        let mut out = Vec::new();
        for (name, prop) in &prim.props {
            let Some(short) = name.strip_prefix("primvars:") else {
                continue;
            };
            if short.contains(':') || prop.type_name != Some("float[]") {
                continue;
            }
            let Some(pv) = self.primvar::<1>(prim, name, Interp::Constant)? else {
                continue;
            };
            if pv.interp != Interp::Vertex
                || self
                    .check_primvar(&prim.path, name, &pv, faces, points, corners)
                    .is_err()
            {
                continue;
            }
            let values = source_vertex
                .iter()
                .map(|&p| pv.at(0, 0, p as usize)[0] as f32)
                .collect();
            out.push((short.to_string(), values));
        }
        Ok(out)
    }

    /// Builds one Mesh prim (and its skin when `skel` is given).
    pub(super) fn mesh(
        &mut self,
        index: usize,
        skel: Option<&SkelData>,
    ) -> Result<Option<ImportedMesh>, ImportError> {
        let prim = self.prim(index).clone();
        let path = prim.path.clone();
        // An implicit surface (Cube, Sphere, ...) arrives tessellated (`implicit.rs`).
        let surface = tessellate(&prim).map_err(|e| self.err(&path, e))?;
        let (points, counts, indices) = match &surface {
            Some(s) => (
                s.points.clone(),
                Some(s.counts.clone()),
                Some(s.indices.clone()),
            ),
            None => {
                // Time-sampled points play as morph targets (`points.rs`): no warning that
                // only the first sample is used.
                let points_attr = if Self::has_point_samples(&prim) {
                    prim.prop("points")
                        .and_then(|p| values::static_value(p).map(|(v, _)| (v, p.clone())))
                } else {
                    self.static_attr(&prim, "points")
                };
                let Some((points_value, points_prop)) = points_attr else {
                    if !self.behind_arc(index).is_empty() && skel.is_some() {
                        return Err(self.err(
                            &path,
                            format!("the bound Mesh has no points{}", self.behind_arc(index)),
                        ));
                    }
                    self.incomplete(&path, "a Mesh without points: not imported");
                    return Ok(None);
                };
                let half = points_prop.type_name.is_some_and(is_half_type);
                let mut points = tuples::<3>(points_value).ok_or_else(|| {
                    self.err_at(points_prop.line, &path, "points must be a point3f[]")
                })?;
                if half {
                    for p in &mut points {
                        for x in p.iter_mut() {
                            *x = f64::from(round_to_half(*x as f32));
                        }
                    }
                }
                if points.iter().flatten().any(|x| !x.is_finite()) {
                    return Err(self.err(&path, "points holds a non-finite value"));
                }
                let counts = self.int_list(&prim, "faceVertexCounts")?;
                let indices = self.int_list(&prim, "faceVertexIndices")?;
                (points, counts, indices)
            }
        };
        let n_points = points.len();
        let sampled_rest =
            (surface.is_none() && Self::has_point_samples(&prim)).then(|| points.clone());
        let (counts, indices) = match (counts, indices) {
            (Some(c), Some(i)) => (c, i),
            (None, None) => (Vec::new(), Vec::new()),
            (Some(_), None) => {
                return Err(self.err(&path, "faceVertexCounts without faceVertexIndices"))
            }
            (None, Some(_)) => {
                return Err(self.err(&path, "faceVertexIndices without faceVertexCounts"))
            }
        };
        let mut total = 0usize;
        for (f, &c) in counts.iter().enumerate() {
            let c = usize::try_from(c)
                .map_err(|_| self.err(&path, format!("faceVertexCounts[{f}] is negative ({c})")))?;
            total = total.saturating_add(c);
        }
        if total != indices.len() {
            return Err(self.err(
                &path,
                format!(
                    "faceVertexCounts add up to {total} but faceVertexIndices has {} entries",
                    indices.len()
                ),
            ));
        }
        let corner_points: Vec<usize> = indices
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                usize::try_from(i).ok().filter(|&i| i < n_points).ok_or_else(|| {
                    self.err(
                        &path,
                        format!("faceVertexIndices[{k}] = {i} is out of range for {n_points} points"),
                    )
                })
            })
            .collect::<Result<_, _>>()?;
        let n_faces = counts.len();
        let n_corners = corner_points.len();
        let left_handed = match prim.prop("orientation").and_then(values::static_value) {
            Some((v, _)) => token(v) == Some("leftHanded"),
            None => false,
        };

        let normals_name = if prim.prop("primvars:normals").is_some() {
            "primvars:normals"
        } else {
            "normals"
        };
        // UsdGeomPointBased: `normals` interpolates per vertex unless it says otherwise;
        // a primvar's fallback interpolation is constant.
        let normals_default = if normals_name == "normals" {
            Interp::Vertex
        } else {
            Interp::Constant
        };
        let normals = match &surface {
            Some(s) => Some(Primvar {
                values: s.normals.clone(),
                indices: None,
                interp: Interp::Vertex,
            }),
            None => self.primvar::<3>(&prim, normals_name, normals_default)?,
        };
        let uv_name = if prim.prop("primvars:st").is_some() {
            Some("primvars:st".to_string())
        } else {
            prim.props
                .iter()
                .find(|(n, p)| {
                    n.starts_with("primvars:")
                        && !n.ends_with(":indices")
                        && p.type_name.is_some_and(|t| t.starts_with("texCoord2"))
                })
                .map(|(n, _)| n.to_string())
        };
        let uvs = match &uv_name {
            Some(name) => self.primvar::<2>(&prim, name, Interp::Constant)?,
            None => None,
        };
        // One UV set is imported; further texCoord2 primvars are a loss, said with a code.
        let other_uvs: Vec<&str> = prim
            .props
            .iter()
            .filter(|(n, p)| {
                n.starts_with("primvars:")
                    && !n.ends_with(":indices")
                    && Some(*n) != uv_name.as_deref()
                    && p.type_name.is_some_and(|t| t.starts_with("texCoord2"))
            })
            .map(|(n, _)| *n)
            .collect();
        if !other_uvs.is_empty() {
            let list = other_uvs.join(", ");
            self.incomplete(
                &path,
                format!("only one UV set is imported; {list} left out"),
            );
        }
        // Display colour and opacity: what a viewer shows without a material.
        let shown: Vec<&str> = ["primvars:displayColor", "primvars:displayOpacity"]
            .into_iter()
            .filter(|n| prim.prop(n).is_some())
            .collect();
        if !shown.is_empty() {
            let list = shown.join(", ");
            self.incomplete(
                &path,
                format!("{list} not imported: rigport's meshes have no vertex colours"),
            );
        }
        if let Some(pv) = &normals {
            self.check_primvar(&path, normals_name, pv, n_faces, n_points, n_corners)?;
        }
        if let (Some(pv), Some(name)) = (&uvs, &uv_name) {
            self.check_primvar(&path, name, pv, n_faces, n_points, n_corners)?;
        }

        // geomBindTransform: into skeleton space at bind time.
        let geom_bind = match (skel, prim.prop("primvars:skel:geomBindTransform")) {
            (Some(_), Some(prop)) => match values::static_value(prop) {
                Some((v, _)) => {
                    let m = matrix(v).map(|r| usd_matrix(&r)).ok_or_else(|| {
                        self.err_at(
                            prop.line,
                            &path,
                            "primvars:skel:geomBindTransform must be a matrix4d",
                        )
                    })?;
                    if !m.is_finite() {
                        return Err(
                            self.err(&path, "primvars:skel:geomBindTransform is not finite")
                        );
                    }
                    m
                }
                None => DMat4::IDENTITY,
            },
            _ => DMat4::IDENTITY,
        };
        let normal_matrix = DMat3::from_mat4(geom_bind).inverse().transpose();
        let to_normal = |n: [f64; 3]| -> Vec3 {
            let v = if normal_matrix.is_finite() {
                normal_matrix * DVec3::from_array(n)
            } else {
                DVec3::from_array(n)
            };
            v.try_normalize().map_or(Vec3::Y, |v| v.as_vec3())
        };
        let to_uv = |t: [f64; 2]| Vec2::new(t[0] as f32, (1.0 - t[1]) as f32);

        // Output vertices: points first, then splits.
        let mut positions: Vec<Vec3> = points
            .iter()
            .map(|p| geom_bind.transform_point3(DVec3::from_array(*p)).as_vec3())
            .collect();
        let mut source_vertex: Vec<u32> = (0..n_points as u32).collect();
        let mut out_normals: Option<Vec<Vec3>> = normals.as_ref().map(|_| vec![Vec3::Y; n_points]);
        let mut out_uvs: Option<Vec<Vec2>> = uvs.as_ref().map(|_| vec![Vec2::ZERO; n_points]);
        let per_point = normals.as_ref().is_none_or(Primvar::per_point)
            && uvs.as_ref().is_none_or(Primvar::per_point);
        let mut corner_vertex: Vec<u32> = Vec::with_capacity(n_corners);
        {
            // The face of each corner.
            let mut face_of = Vec::with_capacity(n_corners);
            for (f, &c) in counts.iter().enumerate() {
                face_of.extend(std::iter::repeat_n(f, c as usize));
            }
            let attrs = |k: usize, p: usize| {
                let f = face_of.get(k).copied().unwrap_or(0);
                (
                    normals.as_ref().map(|pv| to_normal(pv.at(f, k, p))),
                    uvs.as_ref().map(|pv| to_uv(pv.at(f, k, p))),
                )
            };
            if per_point {
                for p in 0..n_points {
                    let (n, t) = attrs(0, p);
                    if let (Some(out), Some(n)) = (&mut out_normals, n) {
                        out[p] = n;
                    }
                    if let (Some(out), Some(t)) = (&mut out_uvs, t) {
                        out[p] = t;
                    }
                }
                corner_vertex.extend(corner_points.iter().map(|&p| p as u32));
            } else {
                let mut assigned = vec![false; n_points];
                let mut splits: HashMap<(usize, [u32; 5]), u32> = HashMap::new();
                let bits = |n: Option<Vec3>, t: Option<Vec2>| {
                    let n = n.unwrap_or(Vec3::ZERO);
                    let t = t.unwrap_or(Vec2::ZERO);
                    [n.x, n.y, n.z, t.x, t.y].map(f32::to_bits)
                };
                for (k, &p) in corner_points.iter().enumerate() {
                    let (n, t) = attrs(k, p);
                    if !assigned[p] {
                        assigned[p] = true;
                        if let (Some(out), Some(n)) = (&mut out_normals, n) {
                            out[p] = n;
                        }
                        if let (Some(out), Some(t)) = (&mut out_uvs, t) {
                            out[p] = t;
                        }
                        corner_vertex.push(p as u32);
                        continue;
                    }
                    let have = bits(
                        out_normals.as_ref().map(|o| o[p]),
                        out_uvs.as_ref().map(|o| o[p]),
                    );
                    let want = bits(n, t);
                    if have == want {
                        corner_vertex.push(p as u32);
                        continue;
                    }
                    let v = *splits.entry((p, want)).or_insert_with(|| {
                        let v = positions.len() as u32;
                        positions.push(positions[p]);
                        source_vertex.push(p as u32);
                        if let (Some(out), Some(n)) = (&mut out_normals, n) {
                            out.push(n);
                        }
                        if let (Some(out), Some(t)) = (&mut out_uvs, t) {
                            out.push(t);
                        }
                        v
                    });
                    corner_vertex.push(v);
                }
            }
        }
        let mut triangles = Vec::with_capacity(n_corners);
        let mut start = 0usize;
        let mut degenerate = 0usize;
        // Face sizes, so a USD writer can give the polygons back (triangles are their fans).
        let mut polygons: Vec<u32> = Vec::with_capacity(n_faces);
        for &c in &counts {
            let c = c as usize;
            let face = corner_vertex.get(start..start + c).unwrap_or_default();
            start += c;
            if c < 3 {
                degenerate += 1;
                continue;
            }
            polygons.push(c as u32);
            for k in 1..c - 1 {
                let (a, b, d) = (face[0], face[k], face[k + 1]);
                triangles.push(if left_handed { [a, d, b] } else { [a, b, d] });
            }
        }
        if polygons.iter().all(|&c| c == 3) {
            polygons.clear();
        }
        if degenerate > 0 {
            self.repaired(
                &path,
                format!("{degenerate} face(s) with fewer than 3 vertices skipped"),
            );
        }
        let mesh = Mesh {
            name: prim.name.to_string(),
            positions,
            normals: out_normals,
            uvs: out_uvs,
            triangles,
            source_vertex: source_vertex.clone(),
            morph_targets: Vec::new(),
            morph_weights: Vec::new(),
            attached_to: None,
            vertex_values: self.vertex_values(
                &prim,
                n_points,
                n_faces,
                n_corners,
                &source_vertex,
            )?,
            polygons,
            ..Default::default()
        };
        let mut mesh = mesh;
        // Blend-shape offsets are in the points' space: deltas take the linear part of
        // whatever moves the points (geomBindTransform, or the static mesh's transform).
        let mut linear = DMat3::from_mat4(geom_bind);
        let mut moving = Vec::new();
        let skin = match skel {
            Some(skel) => Some(self.skin(index, skel, n_points, &mesh.source_vertex)?),
            None => {
                // UsdSkel ignores a skinned mesh's own transform; a static mesh keeps it:
                // its points go to model space (the skeleton's), which the scene frame
                // places in the stage. Under time-sampled transforms they stay in the
                // prim's own space, and a joint carries the motion (`root_motion.rs`).
                let (world, animated) = self.world(index)?;
                let m = if animated.is_empty() {
                    self.skel_world.inverse() * world
                } else {
                    moving = animated;
                    DMat4::IDENTITY
                };
                linear = DMat3::from_mat4(m);
                if m != DMat4::IDENTITY {
                    for p in &mut mesh.positions {
                        *p = m.transform_point3(p.as_dvec3()).as_vec3();
                    }
                    let n = DMat3::from_mat4(m).inverse().transpose();
                    if let Some(normals) = &mut mesh.normals {
                        for v in normals {
                            *v = (n * v.as_dvec3()).normalize_or_zero().as_vec3();
                        }
                    }
                    if m.determinant() < 0.0 {
                        for t in &mut mesh.triangles {
                            t.swap(1, 2);
                        }
                    }
                }
                None
            }
        };
        let vertex_normals = normals.as_ref().is_some_and(|n| n.interp == Interp::Vertex);
        let map = PointMap {
            points: n_points,
            source_vertex: &mesh.source_vertex,
            linear,
            vertex_normals,
        };
        let (mut targets, channels) = self.blend_shapes(&prim, &map)?;
        let mut sample_times = None;
        if let Some(rest) = sampled_rest {
            if channels.is_empty() {
                if let Some((samples, seconds)) = self.point_samples(&prim, &rest, &map)? {
                    targets.extend(samples);
                    sample_times = Some(seconds);
                }
            } else {
                self.incomplete(
                    &path,
                    "time-sampled points on a mesh with blend shapes are not imported (the \
                     first sample is used)",
                );
            }
        }
        mesh.morph_targets = targets;
        Ok(Some((mesh, skin, channels, moving, sample_times)))
    }

    // -----------------------------------------------------------------------------------
    // Skin
    // -----------------------------------------------------------------------------------
}
