//! Wavefront OBJ meshes: every group and object merged into one triangle [`Mesh`].
//!
//! What is read: `v` (positions; a 4th `w` value and 3 extra vertex-colour values are
//! accepted and ignored), `vt` (1 to 3 values; `v' = 1 - v` converts to glTF's top-left
//! origin), `vn` (normalized on import) and `f` (any arity, `v`, `v/vt`, `v//vn`, `v/vt/vn`
//! corners, negative indices relative to the elements read so far, positive indices may
//! point forwards). Polygons are triangulated as fans from their first corner, as tobj and
//! most readers do (correct for convex polygons). `g`, `o` and `s` are accepted and
//! ignored. `mtllib` and `usemtl` are recorded ([`MaterialUse`]); [`import`] then loads the
//! libraries with [`crate::mtl`] (a missing `.mtl` or texture is a warning, not an error):
//! one material used makes it the mesh's, several split the mesh into one mesh per
//! material (`<stem>_<material>`, each keeping [`Mesh::source_vertex`]). `l`, `p` and
//! free-form elements are skipped with a [`Warning::Note`].
//!
//! # Vertex numbering
//! Per-vertex data of other formats (Pinocchio's `attachment.out`) is keyed by the OBJ's
//! global `v` numbering, so the output keeps it: output vertex `i` is `v` line `i` for every
//! `v` line (referenced by a face or not), carrying the texture coordinate and normal of the
//! first face corner that uses it. A corner that pairs the same position with a different
//! texture coordinate or normal becomes an extra output vertex appended after all of them.
//! [`Mesh::source_vertex`] maps every output vertex to its `v` line (0-based), so it is the
//! identity when nothing splits.
//!
//! # Why not tobj
//! The `tobj` crate renumbers positions per object in first-use order and drops the `v`
//! lines no face uses, in both of its index modes, and its errors carry no line. The
//! numbering above cannot be recovered from its output, so this module parses the (small)
//! OBJ subset itself and reports `file:line: problem`; the tests compare its triangles
//! with tobj's on the fixtures and the corpus.

use std::collections::HashMap;
use std::path::Path;

use glam::{Vec2, Vec3};
use rigport_model::{Asset, Mesh, Warning};

use crate::problem::{Limit, Missing, Rule};
use crate::text::{self, Lines};
use crate::{read_file, ImportError, Imported, Location, Problem};

/// The problem of an OBJ without faces (a point cloud): rigport refuses it for every
/// command and output format alike.
pub const NO_FACES: &str = "no faces: rigport needs triangles to skin";

/// Marks a missing texture-coordinate or normal index in a face corner.
const NONE: u32 = u32::MAX;

/// Reads an OBJ file into an asset holding one mesh and no skeleton.
///
/// The asset and the mesh are named after the file stem. Lengths stay in the file's unit.
///
/// # Errors
/// The file cannot be read, or [`parse`] fails.
pub fn import(path: &Path) -> Result<Imported, ImportError> {
    let bytes = read_file(path)?;
    let (mesh, mut warnings, used) = parse_with_materials(&bytes, path)?;
    let mut asset = Asset {
        name: mesh.name.clone(),
        meshes: vec![mesh],
        ..Asset::default()
    };
    apply_materials(&mut asset, path, &used, true, &mut warnings);
    crate::check_asset(&asset, || Location::file(path))?;
    Ok(Imported { asset, warnings })
}

/// Parses OBJ text into one triangle mesh named after `path`'s stem.
///
/// `path` is used for the name and in error locations only; nothing is opened. Output
/// vertices start with one per `v` line in file order (see the module docs), and
/// [`Mesh::source_vertex`] gives each output vertex's 0-based `v` line index.
/// `normals` is `Some` when any face corner names a normal (corners without one, and zero
/// normals, get area-weighted face normals); `uvs` is `Some` when any corner names a texture
/// coordinate (vertices without one get `(0, 0)`). Accepts LF and CRLF line ends and a
/// UTF-8 byte-order mark; comment and ignored lines may hold any bytes.
///
/// # Errors
/// At the first offending line (`file:line: problem`): a value that is not a number or is
/// not finite, a wrong value count, a malformed face corner, index 0, a negative index
/// reaching before the first element, a face with fewer than 3 corners, and (checked once
/// the whole file is read, at the face's line) an index past the last `v`/`vt`/`vn`. Bytes
/// that are not UTF-8 read as U+FFFD, so in a data line they fail as a bad number or index.
/// A file of blank and comment lines only is [`Problem::Empty`]; one without `v` lines or
/// without `f` lines is an error at the file (`cube.obj: no faces: ...`, see [`NO_FACES`]).
pub fn parse(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<Warning>), ImportError> {
    parse_with_materials(bytes, path).map(|(mesh, warnings, _)| (mesh, warnings))
}

/// The materials an OBJ names: its `mtllib` files and, per triangle of the mesh [`parse`]
/// gives, the `usemtl` in force.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MaterialUse {
    /// `mtllib` file names as written (relative to the OBJ's folder), in order.
    pub libraries: Vec<String>,
    /// Material names in order of first `usemtl`.
    pub names: Vec<String>,
    /// Per triangle, its index in `names`, or `u32::MAX` before any `usemtl`.
    pub triangle_material: Vec<u32>,
}

/// As [`parse`], also returning which materials the triangles use.
///
/// # Errors
/// As [`parse`].
pub fn parse_with_materials(
    bytes: &[u8],
    path: &Path,
) -> Result<(Mesh, Vec<Warning>, MaterialUse), ImportError> {
    let raw = Raw::read(bytes, path)?;
    raw.into_mesh(path)
}

/// Loads the materials `used` names (see [`crate::mtl`]) into `asset`, whose mesh 0 is the
/// OBJ's; nothing when none of them is found in a library. One material: it becomes mesh 0's. Several: with `split`, mesh 0 is replaced by
/// one mesh per material (triangles without `usemtl` get obj2gltf's default grey material),
/// each compacted and keeping [`Mesh::source_vertex`]; without `split` (a skinned mesh),
/// mesh 0 takes the material most of its triangles use, with a warning.
pub fn apply_materials(
    asset: &mut Asset,
    path: &Path,
    used: &MaterialUse,
    split: bool,
    warnings: &mut Vec<Warning>,
) {
    if used.names.is_empty() || asset.meshes.is_empty() {
        return;
    }
    let mut names = used.names.clone();
    let untagged = used.triangle_material.contains(&NONE);
    if untagged {
        names.push(String::new());
    }
    let (mut materials, images, found) =
        crate::mtl::load(path, &used.libraries, &used.names, warnings);
    if found == 0 {
        // Nothing to show (no library, or none of its materials): keep the viewer's default.
        return;
    }
    if untagged {
        materials.push(crate::mtl::convert(
            &crate::mtl::MtlMaterial::default_named(""),
            |_| None,
        ));
    }
    let slot = |m: u32| if m == NONE { names.len() as u32 - 1 } else { m };
    let mut counts = vec![0_usize; names.len()];
    for &m in &used.triangle_material {
        counts[slot(m) as usize] += 1;
    }
    let present: Vec<u32> = (0..names.len() as u32)
        .filter(|&k| counts[k as usize] > 0)
        .collect();
    asset.images = images;
    asset.materials = materials;
    if present.len() <= 1 || !split {
        let best = (0..counts.len()).max_by_key(|&k| (counts[k], std::cmp::Reverse(k)));
        if present.len() > 1 {
            warnings.push(Warning::Note {
                location: path.display().to_string(),
                message: format!(
                    "{} materials on one skinned mesh: it takes {:?}, the one most triangles use",
                    present.len(),
                    best.and_then(|k| names.get(k)).cloned().unwrap_or_default()
                ),
            });
        }
        asset.meshes[0].material = best.map(|k| rigport_model::MaterialIndex(k as u32));
        return;
    }
    let whole = asset.meshes.remove(0);
    let tri_slots: Vec<u32> = used.triangle_material.iter().map(|&m| slot(m)).collect();
    for &k in &present {
        let mut part = submesh(&whole, &tri_slots, k);
        let suffix = names[k as usize].as_str();
        part.name = if suffix.is_empty() {
            whole.name.clone()
        } else {
            format!("{}_{suffix}", whole.name)
        };
        part.material = Some(rigport_model::MaterialIndex(k));
        asset.meshes.push(part);
    }
}

/// The triangles of `mesh` whose slot is `k`, with only the vertices they use.
fn submesh(mesh: &Mesh, tri_slots: &[u32], k: u32) -> Mesh {
    let mut map = vec![u32::MAX; mesh.vertex_count()];
    let mut keep: Vec<usize> = Vec::new();
    let mut triangles = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if tri_slots.get(t) != Some(&k) {
            continue;
        }
        triangles.push(tri.map(|v| {
            let slot = &mut map[v as usize];
            if *slot == u32::MAX {
                *slot = keep.len() as u32;
                keep.push(v as usize);
            }
            *slot
        }));
    }
    let pick2 = |v: &Vec<Vec2>| keep.iter().map(|&i| v[i]).collect::<Vec<_>>();
    let pick3 = |v: &Vec<Vec3>| keep.iter().map(|&i| v[i]).collect::<Vec<_>>();
    Mesh {
        positions: pick3(&mesh.positions),
        normals: mesh.normals.as_ref().map(pick3),
        uvs: mesh.uvs.as_ref().map(pick2),
        triangles,
        source_vertex: keep.iter().map(|&i| mesh.source_vertex[i]).collect(),
        ..Mesh::default()
    }
}

/// Counts the `v` lines of an OBJ file without parsing them: the vertex count [`parse`]
/// gives for a well-formed file (its `source_vertex_count`), cheap enough to learn it
/// before parsing, e.g. to read per-vertex data in parallel. Same line rules as [`parse`]
/// (keyword `v` followed by white space, leading white space allowed).
pub fn count_vertex_lines(bytes: &[u8]) -> usize {
    // Every line end (LF, CRLF, a lone CR) cuts, as in [`crate::text::Lines`]; the empty
    // piece between CR and LF is no `v` line.
    bytes
        .split(|&b| b == b'\n' || b == b'\r')
        .filter(|line| {
            let start = line
                .iter()
                .position(|b| !b.is_ascii_whitespace())
                .unwrap_or(line.len());
            let line = &line[start..];
            line.len() > 1 && line[0] == b'v' && line[1].is_ascii_whitespace()
        })
        .count()
}

/// One face corner: 0-based `v`, `vt`, `vn` indices, [`NONE`] when absent.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Corner {
    v: u32,
    vt: u32,
    vn: u32,
}

/// A face: its corners are `corners[start..end]`, written on `line`.
#[derive(Clone, Copy, Debug)]
struct Face {
    line: usize,
    start: usize,
    end: usize,
}

/// The file as read, before vertices are built.
#[derive(Default)]
struct Raw {
    positions: Vec<Vec3>,
    texcoords: Vec<Vec2>,
    normals: Vec<Vec3>,
    corners: Vec<Corner>,
    faces: Vec<Face>,
    /// `l`, `p` and free-form curve/surface lines skipped.
    skipped: usize,
    /// Any line other than blank or comment seen.
    any_content: bool,
    /// `mtllib` names and `usemtl` names in first-use order.
    libraries: Vec<String>,
    material_names: Vec<String>,
    /// The `usemtl` in force (index in `material_names`, or NONE), and per face.
    current_material: u32,
    face_material: Vec<u32>,
}

impl Raw {
    fn read(bytes: &[u8], path: &Path) -> Result<Self, ImportError> {
        // One validation pass over the whole file. Bytes that are not UTF-8 (Latin-1 in
        // comments or names is common) become U+FFFD, which only a data line rejects.
        let text = match std::str::from_utf8(bytes) {
            Ok(text) => std::borrow::Cow::Borrowed(text),
            Err(_) => String::from_utf8_lossy(bytes),
        };
        let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
        // Reserve from the file size so the big arrays never reallocate: a `v` line takes
        // at least 8 bytes, a face corner at least 2. Capacity that stays unused costs
        // address space only (its pages are never touched).
        let mut raw = Raw {
            positions: Vec::with_capacity(text.len() / 8),
            corners: Vec::with_capacity(text.len() / 2),
            faces: Vec::with_capacity(text.len() / 8),
            current_material: NONE,
            ..Raw::default()
        };
        for (line_no, full) in Lines::new(text) {
            let line = full.trim_ascii();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            raw.any_content = true;
            let keyword_end = line
                .bytes()
                .position(|b| b.is_ascii_whitespace())
                .unwrap_or(line.len());
            // An ASCII byte is always a char boundary, so this never fails.
            let (keyword, rest) = line.split_at_checked(keyword_end).unwrap_or((line, ""));
            let at = || Location::line(path, line_no);
            let at_token = |token: &str| text::at(path, line_no, full, token);
            match keyword {
                "v" => {
                    let mut tokens = rest.split_ascii_whitespace();
                    let p = read_vec3(&mut tokens, "coordinate", &at, &at_token)?;
                    // `w` (a rational-curve weight, meaningless for polygons) and the
                    // common `r g b` vertex-colour extension are checked and ignored.
                    let mut extra = 0;
                    for token in tokens {
                        text::number::<f32>(token, "vertex value", || at_token(token))?;
                        extra += 1;
                    }
                    if extra > 4 {
                        return Err(ImportError::count(
                            at(),
                            "numbers on a `v` line",
                            3 + extra,
                            "at most 7",
                        ));
                    }
                    raw.positions.push(p);
                }
                "vt" => {
                    let mut values = [0.0_f32; 3];
                    let mut n = 0;
                    for token in rest.split_ascii_whitespace() {
                        let value = text::number(token, "texture coordinate", || at_token(token))?;
                        if let Some(slot) = values.get_mut(n) {
                            *slot = value;
                        }
                        n += 1;
                    }
                    if !(1..=3).contains(&n) {
                        return Err(ImportError::count(
                            at(),
                            "numbers on a `vt` line",
                            n,
                            "1 to 3",
                        ));
                    }
                    // OBJ puts the texture origin bottom-left, glTF top-left.
                    raw.texcoords.push(Vec2::new(values[0], 1.0 - values[1]));
                }
                "vn" => {
                    let mut tokens = rest.split_ascii_whitespace();
                    let n = read_vec3(&mut tokens, "normal coordinate", &at, &at_token)?;
                    if let Some(token) = tokens.next() {
                        return Err(ImportError::syntax(at(), "the end of the `vn` line", token));
                    }
                    raw.normals.push(n);
                }
                "f" => raw.read_face(rest, line_no, &at)?,
                "l" | "p" | "curv" | "curv2" | "surf" => raw.skipped += 1,
                "mtllib" if !rest.is_empty() => raw.libraries.push(rest.trim().to_string()),
                "usemtl" => {
                    let name = rest.trim();
                    let k = match raw.material_names.iter().position(|n| n == name) {
                        Some(k) => k,
                        None => {
                            raw.material_names.push(name.to_string());
                            raw.material_names.len() - 1
                        }
                    };
                    raw.current_material = k as u32;
                }
                // g, o, s, free-form attributes, unknown: ignored.
                _ => {}
            }
        }
        Ok(raw)
    }

    fn read_face(
        &mut self,
        text: &str,
        line: usize,
        at: &dyn Fn() -> Location,
    ) -> Result<(), ImportError> {
        let start = self.corners.len();
        let counts = [
            self.positions.len(),
            self.texcoords.len(),
            self.normals.len(),
        ];
        for token in text.split_ascii_whitespace() {
            // `v`, `v/vt`, `v//vn` or `v/vt/vn`, split by hand: this runs per corner.
            let mut parts = [""; 3];
            let mut n = 0;
            let mut start = 0;
            for (i, b) in token.bytes().enumerate() {
                if b == b'/' {
                    match parts.get_mut(n) {
                        Some(slot) if n < 2 => *slot = token.get(start..i).unwrap_or_default(),
                        _ => {
                            return Err(ImportError::syntax(
                                at(),
                                "a face corner v[/vt][/vn]",
                                token,
                            ))
                        }
                    }
                    n += 1;
                    start = i + 1;
                }
            }
            if let Some(slot) = parts.get_mut(n) {
                *slot = token.get(start..).unwrap_or_default();
            }
            if parts[0].is_empty() {
                return Err(ImportError::syntax(at(), "a vertex index", token));
            }
            let mut idx = [NONE; 3];
            for ((slot, part), count) in idx.iter_mut().zip(parts).zip(counts) {
                if !part.is_empty() {
                    *slot = resolve_index(part, count, token, at)?;
                }
            }
            self.corners.push(Corner {
                v: idx[0],
                vt: idx[1],
                vn: idx[2],
            });
        }
        let found = self.corners.len() - start;
        if found < 3 {
            return Err(ImportError::count(
                at(),
                "face corners",
                found,
                "at least 3",
            ));
        }
        self.faces.push(Face {
            line,
            start,
            end: self.corners.len(),
        });
        self.face_material.push(self.current_material);
        Ok(())
    }

    fn into_mesh(self, path: &Path) -> Result<(Mesh, Vec<Warning>, MaterialUse), ImportError> {
        if !self.any_content {
            return Err(ImportError::new(Location::file(path), Problem::Empty));
        }
        // Positive indices may point forwards, so ranges are checked once everything is read.
        let (nv, nt, nn) = (
            self.positions.len(),
            self.texcoords.len(),
            self.normals.len(),
        );
        let bad = |i: u32, n: usize| i != NONE && i as usize >= n;
        for face in &self.faces {
            for c in self.corners.get(face.start..face.end).unwrap_or_default() {
                if bad(c.v, nv) || bad(c.vt, nt) || bad(c.vn, nn) {
                    return Err(out_of_range(c, (nv, nt, nn), path, face.line));
                }
            }
        }
        if self.positions.is_empty() {
            return Err(ImportError::at(Location::file(path), Missing::Vertices));
        }
        // One decision for every output: a mesh without triangles has nothing to skin or
        // draw (glTF cannot even hold it), so it is refused here, where the file is known.
        if self.faces.is_empty() {
            return Err(ImportError::at(Location::file(path), Missing::Faces));
        }
        let location = path.display().to_string();
        let mut warnings = Vec::new();
        if self.skipped > 0 {
            warnings.push(Warning::Note {
                location: location.clone(),
                message: format!(
                    "skipped {} line, point or free-form elements (`l`, `p`, `curv`, `curv2`, `surf`): only faces are imported",
                    self.skipped
                ),
            });
        }

        // Output vertex i is `v` line i, with the attributes of the first corner using it.
        let n_src = self.positions.len();
        let mut first: Vec<Option<(u32, u32)>> = vec![None; n_src];
        for c in &self.corners {
            if let Some(slot @ None) = first.get_mut(c.v as usize) {
                *slot = Some((c.vt, c.vn));
            }
        }
        let Raw {
            positions,
            texcoords,
            normals,
            corners,
            faces,
            libraries,
            material_names,
            face_material,
            ..
        } = self;
        let mut triangle_material = Vec::new();
        let mut out_pos = positions;
        let mut out_attr: Vec<(u32, u32)> =
            first.iter().map(|f| f.unwrap_or((NONE, NONE))).collect();
        let mut source_vertex: Vec<u32> = (0..n_src as u32).collect();
        let mut splits: HashMap<Corner, u32> = HashMap::new();
        let mut triangles = Vec::with_capacity(corners.len().saturating_sub(2 * faces.len()));
        let mut face_vertices: Vec<u32> = Vec::new();
        for (fi, face) in faces.iter().enumerate() {
            face_vertices.clear();
            for c in corners.get(face.start..face.end).unwrap_or_default() {
                let out = if first.get(c.v as usize).copied().flatten() == Some((c.vt, c.vn)) {
                    c.v
                } else if let Some(&out) = splits.get(c) {
                    out
                } else {
                    let out = u32::try_from(out_pos.len())
                        .ok()
                        .filter(|&o| o != u32::MAX)
                        .ok_or_else(|| {
                            ImportError::at(Location::line(path, face.line), Limit::Vertices)
                        })?;
                    // The first n_src entries are the `v` lines, unchanged.
                    let p = out_pos.get(c.v as usize).copied().unwrap_or_default();
                    out_pos.push(p);
                    out_attr.push((c.vt, c.vn));
                    source_vertex.push(c.v);
                    splits.insert(*c, out);
                    out
                };
                face_vertices.push(out);
            }
            let material = face_material.get(fi).copied().unwrap_or(NONE);
            if let Some((&a, rest)) = face_vertices.split_first() {
                for pair in rest.windows(2) {
                    if let &[b, c] = pair {
                        triangles.push([a, b, c]);
                        if !material_names.is_empty() {
                            triangle_material.push(material);
                        }
                    }
                }
            }
        }

        let uvs = corners.iter().any(|c| c.vt != NONE).then(|| {
            out_attr
                .iter()
                .map(|&(vt, _)| texcoords.get(vt as usize).copied().unwrap_or(Vec2::ZERO))
                .collect::<Vec<_>>()
        });
        let missing_uv = uvs.is_some() && corners.iter().any(|c| c.vt == NONE);
        if missing_uv {
            warnings.push(Warning::Note {
                location: location.clone(),
                message: "some face corners have no texture coordinate; they get (0, 0)".into(),
            });
        }

        let mut mesh = Mesh {
            name: path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            positions: out_pos,
            normals: None,
            uvs,
            triangles,
            source_vertex,
            ..Mesh::default()
        };

        if corners.iter().any(|c| c.vn != NONE) {
            let given: Vec<Option<Vec3>> = out_attr
                .iter()
                .map(|&(_, vn)| normals.get(vn as usize).and_then(|n| n.try_normalize()))
                .collect();
            // Corners without a normal, and zero normals, take the smooth face normal.
            let zero = out_attr
                .iter()
                .zip(&given)
                .filter(|((_, vn), g)| *vn != NONE && g.is_none())
                .count();
            let computed = if given.iter().any(Option::is_none) {
                mesh.compute_normals()
            } else {
                Vec::new()
            };
            if zero > 0 {
                warnings.push(Warning::Repaired {
                    location: location.clone(),
                    message: format!(
                        "{zero} vertices had a zero-length normal; replaced by the area-weighted face normal"
                    ),
                });
            }
            if corners.iter().any(|c| c.vn == NONE) {
                warnings.push(Warning::Note {
                    location,
                    message:
                        "some face corners have no normal; they get the area-weighted face normal"
                            .into(),
                });
            }
            mesh.normals = Some(
                given
                    .iter()
                    .enumerate()
                    .map(|(v, g)| g.unwrap_or_else(|| computed.get(v).copied().unwrap_or(Vec3::Y)))
                    .collect(),
            );
        }
        let used = MaterialUse {
            libraries,
            names: material_names,
            triangle_material,
        };
        Ok((mesh, warnings, used))
    }
}

/// The error for a corner with an index past the last `v`, `vt` or `vn` line.
#[cold]
fn out_of_range(
    c: &Corner,
    (nv, nt, nn): (usize, usize, usize),
    path: &Path,
    line: usize,
) -> ImportError {
    let (index, count, what, plural) = if c.v as usize >= nv {
        (c.v, nv, "vertex", "vertices (`v` lines)")
    } else if c.vt != NONE && c.vt as usize >= nt {
        (
            c.vt,
            nt,
            "texture coordinate",
            "texture coordinates (`vt` lines)",
        )
    } else {
        (c.vn, nn, "normal", "normals (`vn` lines)")
    };
    ImportError::new(
        Location::line(path, line),
        Problem::IndexOutOfRange {
            what,
            plural,
            index: i64::from(index) + 1,
            count,
        },
    )
}

// The float reader moved to `crate::number` (shared with the BVH reader); re-exported
// here for the Pinocchio reader, which reaches it as `obj::parse_f32` / `obj::Decimal`.
pub(crate) use crate::number::{parse_f32, Decimal};

/// Parses three finite numbers (`what` they are, for the error).
fn read_vec3<'a>(
    tokens: &mut impl Iterator<Item = &'a str>,
    what: &'static str,
    at: &dyn Fn() -> Location,
    at_token: &dyn Fn(&str) -> Location,
) -> Result<Vec3, ImportError> {
    let mut v = [0.0_f32; 3];
    for (k, slot) in v.iter_mut().enumerate() {
        let Some(token) = tokens.next() else {
            return Err(ImportError::count(at(), "numbers", k, 3));
        };
        *slot = text::number(token, what, || at_token(token))?;
    }
    Ok(Vec3::from_array(v))
}

/// Resolves a 1-based or negative (relative) OBJ index to a 0-based one; `count` is how
/// many elements of that kind were read before this line.
fn resolve_index(
    part: &str,
    count: usize,
    token: &str,
    at: &dyn Fn() -> Location,
) -> Result<u32, ImportError> {
    // Fast path for the usual 1-based index of at most 9 digits (cannot overflow).
    if part.len() <= 9 && part.bytes().all(|b| b.is_ascii_digit()) {
        let x = part
            .bytes()
            .fold(0_u32, |acc, b| acc * 10 + u32::from(b - b'0'));
        if x > 0 {
            return Ok(x - 1);
        }
    }
    let x: i64 = text::number(part, "index", at)?;
    let resolved = match x {
        0 => return Err(ImportError::at(at(), Rule::ZeroIndex(token.to_string()))),
        x if x > 0 => x - 1,
        // -1 is the last element read so far.
        x => {
            let r = i64::try_from(count).unwrap_or(i64::MAX).saturating_add(x);
            if r < 0 {
                let token = token.to_string();
                return Err(ImportError::at(
                    at(),
                    Rule::RelativeIndex {
                        index: x,
                        token,
                        count,
                    },
                ));
            }
            r
        }
    };
    u32::try_from(resolved)
        .ok()
        .filter(|&r| r < NONE - 1)
        .ok_or_else(|| {
            let token = token.to_string();
            ImportError::at(at(), Limit::Index { index: x, token })
        })
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod material_tests {
    use super::*;

    #[test]
    fn mtllib_and_usemtl_become_materials_and_split_meshes() {
        let dir = tempfile::tempdir().expect("tempdir");
        let png = b"\x89PNG\r\n\x1a\nnot really a png";
        std::fs::write(dir.path().join("skin.png"), png).expect("png");
        std::fs::write(
            dir.path().join("rig.mtl"),
            "newmtl skin\nKd 1 0 0\nmap_Kd skin.png\nnewmtl cloth\nKd 0 0 1\nNs 500\n",
        )
        .expect("mtl");
        let obj = "mtllib rig.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
                   vt 1 1\nusemtl skin\nf 1/1 2/2 3/3\nusemtl cloth\nf 2/2 4/4 3/3\n";
        let path = dir.path().join("rig.obj");
        std::fs::write(&path, obj).expect("obj");
        let imported = import(&path).expect("import");
        let asset = imported.asset;
        assert_eq!(asset.materials.len(), 2);
        assert_eq!(asset.images.len(), 1);
        assert_eq!(asset.images[0].mime_type, "image/png");
        assert_eq!(asset.images[0].bytes, png);
        assert_eq!(asset.meshes.len(), 2, "one mesh per material");
        assert_eq!(asset.meshes[0].name, "rig_skin");
        assert_eq!(asset.meshes[0].source_vertex, [0, 1, 2]);
        assert_eq!(asset.meshes[1].source_vertex, [1, 3, 2]);
        let skin = &asset.materials[0];
        assert_eq!(skin.base_color_factor, [1.0; 4], "map_Kd: factor 1");
        assert!(skin.base_color_texture.is_some());
        assert_eq!(asset.materials[1].base_color_factor, [0.0, 0.0, 1.0, 1.0]);
        assert!((asset.materials[1].roughness_factor - 0.5).abs() < 1e-6);
        assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);

        // A missing library: no materials, one coded loss.
        std::fs::remove_file(dir.path().join("rig.mtl")).expect("rm");
        let imported = import(&path).expect("import");
        assert!(imported.asset.materials.is_empty());
        assert_eq!(imported.asset.meshes.len(), 1);
        assert!(matches!(
            imported.warnings[..],
            [Warning::Incomplete { .. }]
        ));
    }
}
