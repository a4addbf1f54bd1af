//! `<geometry><mesh>`: its primitives (`<triangles>`, `<polylist>`, `<polygons>`,
//! `<trifans>`, `<tristrips>`; lines are not surfaces and are skipped) read through their
//! shared `<input offset>` indices, one [`Part`] per material symbol.
//!
//! | COLLADA | model |
//! |---|---|
//! | `VERTEX` (the `<vertices>` inputs: `POSITION`, and `NORMAL`/`TEXCOORD` when given per vertex) | positions; the `<vertices>` index is [`Mesh::source_vertex`] (what skin weights and morph targets index) |
//! | `NORMAL` | normals (all primitives of a part must have them, else none) |
//! | `TEXCOORD` of every `set`, in set order | `uvs`, `extra_uvs` (v flipped to glTF's top-left origin) |
//! | `COLOR` | not kept (the model has no vertex colours), with a W004 warning |
//! | a polygon of n corners | its fan from the first corner; sizes kept in [`Mesh::polygons`] |
//!
//! Corners become one vertex per unique index tuple within a primitive element.

use std::collections::HashMap;

use rigport_model::glam::{DMat4, DVec2, DVec3, Vec2};
use rigport_model::Mesh;

use super::xml::{child, children, Doc, Node, Source};
use crate::{ImportError, Problem};

/// The triangles of one material symbol, positions and normals in the geometry's space.
pub(super) struct Part {
    /// The primitives' `material` symbol.
    pub(super) symbol: Option<String>,
    /// The `TEXCOORD` set numbers, in the order of the UV sets.
    pub(super) uv_sets: Vec<u32>,
    positions: Vec<DVec3>,
    normals: Option<Vec<DVec3>>,
    uvs: Vec<Vec<DVec2>>,
    triangles: Vec<[u32; 3]>,
    polygons: Vec<u32>,
    source_vertex: Vec<u32>,
}

impl Part {
    /// The part as a mesh, its points through `m` (normals through its inverse transpose).
    pub(super) fn mesh(&self, m: &DMat4) -> Mesh {
        let normal_m = m.inverse().transpose();
        let mut uvs = self.uvs.iter().map(|set| {
            set.iter()
                .map(|t| Vec2::new(t.x as f32, (1.0 - t.y) as f32))
                .collect::<Vec<_>>()
        });
        let polygons = if self.polygons.iter().all(|&n| n == 3) {
            Vec::new()
        } else {
            self.polygons.clone()
        };
        Mesh {
            positions: self
                .positions
                .iter()
                .map(|p| m.transform_point3(*p).as_vec3())
                .collect(),
            normals: self.normals.as_ref().map(|n| {
                n.iter()
                    .map(|n| {
                        normal_m
                            .transform_vector3(*n)
                            .as_vec3()
                            .normalize_or(rigport_model::glam::Vec3::Y)
                    })
                    .collect()
            }),
            uvs: uvs.next(),
            extra_uvs: uvs.collect(),
            triangles: self.triangles.clone(),
            polygons,
            source_vertex: self.source_vertex.clone(),
            ..Mesh::default()
        }
    }
}

/// A geometry's parts, and what of it is not kept (the element, what).
pub(super) struct Geometry {
    pub(super) parts: Vec<Part>,
    pub(super) lost: Vec<(String, String)>,
}

/// The `POSITION` source of a `<mesh>`'s `<vertices>`.
///
/// # Errors
/// No `<vertices>` or no `POSITION` input; a bad source.
pub(super) fn positions(doc: &Doc, mesh: Node) -> Result<Vec<DVec3>, ImportError> {
    let vertices = child(mesh, "vertices").ok_or_else(|| doc.invalid(mesh, "has no <vertices>"))?;
    let input = children(vertices, "input")
        .find(|i| i.attribute("semantic") == Some("POSITION"))
        .ok_or_else(|| doc.invalid(vertices, "has no POSITION input"))?;
    let source = doc.source(doc.link(input, "source", "source")?)?;
    Ok((0..source.count).map(|i| source.vec3(i)).collect())
}

/// Reads `<geometry>` `geometry` (a `<mesh>`; other kinds such as `<spline>` have no
/// parts).
///
/// # Errors
/// A missing source, a count that does not match, an index past its source.
pub(super) fn read(doc: &Doc, geometry: Node) -> Result<Geometry, ImportError> {
    let Some(mesh) = child(geometry, "mesh") else {
        return Ok(Geometry {
            parts: Vec::new(),
            lost: Vec::new(),
        });
    };
    let positions = positions(doc, mesh)?;
    let vertices = child(mesh, "vertices").ok_or_else(|| doc.invalid(mesh, "has no <vertices>"))?;
    let mut per_vertex: Vec<(String, u32, Source)> = Vec::new();
    for input in children(vertices, "input") {
        let semantic = input.attribute("semantic").unwrap_or("");
        if matches!(semantic, "NORMAL" | "TEXCOORD") {
            let source = doc.source(doc.link(input, "source", "source")?)?;
            per_vertex.push((semantic.to_string(), set_of(input), source));
        }
    }
    let mut parts: Vec<Part> = Vec::new();
    for prim in mesh.children().filter(Node::is_element) {
        let polygons = match prim.tag_name().name() {
            "triangles" | "polylist" | "polygons" | "trifans" | "tristrips" => corners(doc, prim)?,
            _ => continue,
        };
        let symbol = prim.attribute("material").map(str::to_string);
        let index = match parts.iter().position(|p| p.symbol == symbol) {
            Some(i) => i,
            None => {
                parts.push(Part {
                    symbol,
                    uv_sets: Vec::new(),
                    positions: Vec::new(),
                    normals: Some(Vec::new()),
                    uvs: Vec::new(),
                    triangles: Vec::new(),
                    polygons: Vec::new(),
                    source_vertex: Vec::new(),
                });
                parts.len() - 1
            }
        };
        add_primitive(
            doc,
            prim,
            &polygons,
            &positions,
            &per_vertex,
            &mut parts[index],
        )?;
    }
    parts.retain(|p| !p.triangles.is_empty());
    let mut lost = Vec::new();
    let colors = mesh
        .descendants()
        .find(|n| n.tag_name().name() == "input" && n.attribute("semantic") == Some("COLOR"));
    if let Some(input) = colors {
        lost.push((
            doc.at(input).to_string(),
            "vertex colours (COLOR) are not kept: rigport's meshes have none".to_string(),
        ));
    }
    if let Some(h) = mesh.descendants().find(|n| n.tag_name().name() == "h") {
        lost.push((
            doc.at(h).to_string(),
            "polygon holes (<h>) are not kept: each polygon is its outer ring".to_string(),
        ));
    }
    Ok(Geometry { parts, lost })
}

/// An input's `set` (0 when absent).
fn set_of(input: Node) -> u32 {
    input
        .attribute("set")
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or(0)
}

/// A primitive's polygons as lists of corner starts (index into `<p>` values, in units of
/// the stride), its `<p>` values, and the `<p>` element of each polygon (for locations).
struct Corners<'a, 'i> {
    stride: usize,
    /// Per polygon: its `<p>` element, the index of its first corner in `values` (in
    /// corners) and its corner count; `strip` for a triangle strip.
    polygons: Vec<(Node<'a, 'i>, usize, usize, bool)>,
    values: Vec<i64>,
}

/// The corners of `prim`.
fn corners<'a, 'i>(doc: &Doc<'a, 'i>, prim: Node<'a, 'i>) -> Result<Corners<'a, 'i>, ImportError> {
    let stride = children(prim, "input")
        .filter_map(|i| i.attribute("offset")?.trim().parse::<usize>().ok())
        .max()
        .map_or(1, |m| m + 1);
    let tag = prim.tag_name().name();
    let mut out = Corners {
        stride,
        polygons: Vec::new(),
        values: Vec::new(),
    };
    // `<polygons>` writes holes as `<ph><p>..</p><h>..</h></ph>`: the outer ring is kept.
    let rings: Vec<Node> = prim
        .children()
        .filter(Node::is_element)
        .filter_map(|c| match c.tag_name().name() {
            "p" => Some(c),
            "ph" => child(c, "p"),
            _ => None,
        })
        .collect();
    let count: Option<usize> = prim.attribute("count").and_then(|c| c.trim().parse().ok());
    match tag {
        "triangles" | "polylist" => {
            let Some(p) = rings.first().copied() else {
                return Ok(out);
            };
            out.values = doc.ints(p)?;
            let sizes: Vec<usize> = if tag == "triangles" {
                vec![3; count.unwrap_or(out.values.len() / (3 * stride))]
            } else {
                let vcount =
                    child(prim, "vcount").ok_or_else(|| doc.invalid(prim, "has no <vcount>"))?;
                let sizes: Vec<usize> = doc
                    .ints(vcount)?
                    .into_iter()
                    .map(|n| usize::try_from(n).unwrap_or(0))
                    .collect();
                if let Some(count) = count.filter(|&c| c != sizes.len()) {
                    return Err(ImportError::count(
                        doc.at(vcount),
                        "polygon sizes",
                        sizes.len(),
                        count,
                    ));
                }
                sizes
            };
            let corners: usize = sizes.iter().sum();
            if corners.checked_mul(stride) != Some(out.values.len()) {
                return Err(ImportError::count(
                    doc.at(p),
                    "indices",
                    out.values.len(),
                    format!("{corners} corners x {stride} inputs"),
                ));
            }
            let mut at = 0;
            for n in sizes {
                out.polygons.push((p, at, n, false));
                at += n;
            }
        }
        _ => {
            for p in rings {
                let values = doc.ints(p)?;
                if values.len() % stride != 0 {
                    return Err(ImportError::count(
                        doc.at(p),
                        "indices",
                        values.len(),
                        format!("a multiple of {stride} inputs"),
                    ));
                }
                let at = out.values.len() / stride;
                out.polygons
                    .push((p, at, values.len() / stride, tag == "tristrips"));
                out.values.extend(values);
            }
        }
    }
    Ok(out)
}

/// Adds one primitive's triangles to `part`.
fn add_primitive(
    doc: &Doc,
    prim: Node,
    corners: &Corners,
    positions: &[DVec3],
    per_vertex: &[(String, u32, Source)],
    part: &mut Part,
) -> Result<(), ImportError> {
    // (offset, source, per vertex) for the normals and each UV set.
    let mut vertex_offset = None;
    let mut normal: Option<(usize, Source)> = None;
    let mut uvs: Vec<(u32, usize, Source)> = Vec::new();
    for input in children(prim, "input") {
        let offset = input
            .attribute("offset")
            .and_then(|o| o.trim().parse().ok())
            .unwrap_or(0);
        match input.attribute("semantic").unwrap_or("") {
            "VERTEX" => vertex_offset = Some(offset),
            "NORMAL" => normal = Some((offset, doc.source(doc.link(input, "source", "source")?)?)),
            "TEXCOORD" => uvs.push((
                set_of(input),
                offset,
                doc.source(doc.link(input, "source", "source")?)?,
            )),
            _ => {}
        }
    }
    let vertex_offset = vertex_offset.ok_or_else(|| doc.invalid(prim, "has no VERTEX input"))?;
    // Inputs given per vertex are indexed by the vertex index.
    let mut normal_source = normal.map(|(o, s)| (Some(o), s));
    for (semantic, set, source) in per_vertex {
        if semantic == "NORMAL" && normal_source.is_none() {
            normal_source = Some((None, source.clone()));
        } else if semantic == "TEXCOORD" && !uvs.iter().any(|u| u.0 == *set) {
            uvs.push((*set, usize::MAX, source.clone()));
        }
    }
    uvs.sort_by_key(|u| u.0);
    for (set, ..) in &uvs {
        if !part.uv_sets.contains(set) {
            part.uv_sets.push(*set);
            part.uv_sets.sort_unstable();
            // A set that earlier primitives lacked: zeros for their vertices.
            let at = part.uv_sets.iter().position(|s| s == set).unwrap_or(0);
            part.uvs.insert(at, vec![DVec2::ZERO; part.positions.len()]);
        }
    }
    if normal_source.is_none() {
        part.normals = None;
    }
    let mut seen: HashMap<Vec<u32>, u32> = HashMap::new();
    let stride = corners.stride;
    let mut vertex_of = |p: Node, corner: usize, part: &mut Part| -> Result<u32, ImportError> {
        let index = |offset: usize, count: usize, what: &'static str, plural: &'static str| {
            let i = corners
                .values
                .get(corner * stride + offset)
                .copied()
                .unwrap_or(-1);
            match usize::try_from(i) {
                Ok(u) if u < count => Ok(u),
                _ => Err(doc.error(
                    p,
                    Problem::IndexOutOfRange {
                        what,
                        plural,
                        index: i,
                        count,
                    },
                )),
            }
        };
        let v = index(vertex_offset, positions.len(), "vertex", "vertices")?;
        let mut key = vec![v as u32];
        let n = match &normal_source {
            Some((Some(o), s)) => index(*o, s.count, "normal", "normals")?,
            Some((None, s)) => index(vertex_offset, s.count, "normal", "normals")?,
            None => 0,
        };
        key.push(n as u32);
        let mut uv_index = Vec::with_capacity(uvs.len());
        for (_, o, s) in &uvs {
            let o = if *o == usize::MAX { vertex_offset } else { *o };
            let t = index(o, s.count, "texture coordinate", "texture coordinates")?;
            key.push(t as u32);
            uv_index.push(t);
        }
        if let Some(&out) = seen.get(&key) {
            return Ok(out);
        }
        let out = part.positions.len() as u32;
        part.positions.push(positions[v]);
        part.source_vertex.push(v as u32);
        if let (Some(normals), Some((_, s))) = (part.normals.as_mut(), &normal_source) {
            normals.push(s.vec3(n));
        }
        for (k, set) in part.uv_sets.iter().enumerate() {
            let t = uvs
                .iter()
                .zip(&uv_index)
                .find(|((s, ..), _)| s == set)
                .map_or(DVec2::ZERO, |((_, _, src), &t)| {
                    DVec2::new(src.float(t, 0), src.float(t, 1))
                });
            part.uvs[k].push(t);
        }
        seen.insert(key, out);
        Ok(out)
    };
    for &(p, first, n, strip) in &corners.polygons {
        if n < 3 {
            continue;
        }
        let mut ids = Vec::with_capacity(n);
        for c in first..first + n {
            ids.push(vertex_of(p, c, part)?);
        }
        if strip {
            for k in 0..n - 2 {
                let t = if k % 2 == 0 {
                    [ids[k], ids[k + 1], ids[k + 2]]
                } else {
                    [ids[k + 1], ids[k], ids[k + 2]]
                };
                part.triangles.push(t);
                part.polygons.push(3);
            }
        } else {
            for k in 1..n - 1 {
                part.triangles.push([ids[0], ids[k], ids[k + 1]]);
            }
            part.polygons.push(n as u32);
        }
    }
    Ok(())
}
