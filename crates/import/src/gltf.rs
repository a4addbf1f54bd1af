//! glTF 2.0 importer: `.gltf` (with `data:` or external buffers) and `.glb`, to a rig
//! [`Asset`].
//!
//! How glTF maps onto the model:
//!
//! | glTF | model |
//! |---|---|
//! | every node of the default scene (of all scenes when `scene` is unset, of the whole file when there are no scenes) | one [`Joint`] each, parents first; the name is the node's, made unique and non-empty |
//! | node `matrix` or TRS | [`Joint::rest_local`] |
//! | each triangle primitive of a node's mesh | one [`Mesh`] (`<mesh>` or `<mesh>_<primitive>`), positions as stored |
//! | node with mesh and skin | a [`SkinBinding`]; the mesh is in bind space (glTF ignores the node's transform) |
//! | node with mesh and no skin | [`Mesh::attached_to`] = that node's joint, positions in node space |
//! | animation | one [`Clip`], one [`Track`] per channel (per primitive mesh for `weights`) |
//!
//! Lengths are metres (glTF 2.0 §3.4), so [`Asset::meters_per_unit`] is `Some(1.0)`.
//! Triangle strips and fans become triangle lists; points and lines are skipped with a
//! warning. Every accessor is range-checked before it is read, so no input makes this
//! module panic.

use std::borrow::Cow;
use std::collections::{BTreeSet, HashMap, HashSet};
use std::path::{Path, PathBuf};

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::animation::util::ReadOutputs;
use ::gltf::animation::{Interpolation as GltfInterpolation, Property};
use ::gltf::mesh::util::{ReadIndices, ReadJoints, ReadTexCoords, ReadWeights};
use ::gltf::mesh::Mode;
use ::gltf::Semantic;
use rigport_model::glam::{Mat4, Quat, Vec2, Vec3};
use rigport_model::{
    parents_first_order, Asset, Clip, Influence, Influences, Interpolation, Joint, JointIndex,
    Mesh, MeshIndex, MorphTarget, Skeleton, SkeletonProblem, SkinBinding, Track, TrackTarget,
    Transform, Warning,
};

use crate::{read_file, ImportError, Imported, Location, Problem};

/// Largest `|length - 1|` of a rotation quaternion accepted without a warning: the
/// Khronos glTF-Validator's unit-quaternion tolerance (also in `FORMATS.md`).
const UNIT_QUAT_TOLERANCE: f32 = 0.00769;

/// Largest `|Σ weights - 1|` of a vertex reported as normalized. The validator's own bound
/// is 2e-7 per non-zero weight; 1e-3 only flags rows that are visibly off.
const WEIGHT_SUM_TOLERANCE: f32 = 1e-3;

/// Largest element difference between a node `matrix` and its TRS decomposition (relative
/// to the largest element of its 3x3 part, at least 1) before the matrix counts as sheared.
const MATRIX_TOLERANCE: f32 = 1e-5;

/// Largest size in bytes of an accessor without a `bufferView` (zeros, optionally with
/// sparse values): its size is not bounded by the file's bytes, so it is capped to keep
/// hostile files from exhausting memory. 256 MiB is 22 million `VEC3` floats.
const MAX_ZERO_FILLED_BYTES: usize = 1 << 28;

/// Imports a `.gltf` or `.glb` file; external buffers are read relative to its folder.
///
/// Returns the asset (valid by [`Asset::validate`]) and the warnings of every lossy or
/// repairing step (renamed nodes, sheared matrices, skipped primitives, weights that do not
/// sum to 1, ...).
///
/// # Errors
/// The file or one of its buffers cannot be read; a broken GLB container (with the byte
/// offset); JSON syntax (with line and column); a glTF schema violation or out-of-range
/// data (with the JSON path, e.g. `/meshes/0/primitives/0/attributes/JOINTS_0`).
pub fn import(path: &Path) -> Result<Imported, ImportError> {
    let bytes = read_file(path)?;
    import_slice(&bytes, path)
}

/// Imports glTF from bytes: a `.glb` if they start with the `glTF` magic, else JSON.
///
/// `path` names the input in errors and warnings, and relative buffer URIs are resolved
/// against its folder (`data:` URIs and the GLB `BIN` chunk need no file system).
///
/// # Errors
/// As [`import`].
pub fn import_slice(bytes: &[u8], path: &Path) -> Result<Imported, ImportError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(ImportError::new(Location::file(path), Problem::Empty));
    }
    let mut warnings = Vec::new();
    let is_glb = bytes.starts_with(b"glTF");
    let (json, blob) = if is_glb {
        split_glb(bytes, path, &mut warnings)?
    } else {
        (bytes, None)
    };
    let document = parse_document(json, path, is_glb, &mut warnings)?;
    let buffers = load_buffers(&document, blob, path)?;
    let mut importer = Importer {
        path,
        doc: &document,
        buffers: &buffers,
        warnings,
    };
    let asset = importer.run()?;
    Ok(Imported {
        asset,
        warnings: importer.warnings,
    })
}

// ---------------------------------------------------------------------------------------
// Container, JSON and buffers
// ---------------------------------------------------------------------------------------

fn le_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a GLB into its JSON chunk and optional BIN chunk (glTF 2.0 §4.4).
fn split_glb<'b>(
    bytes: &'b [u8],
    path: &Path,
    warnings: &mut Vec<Warning>,
) -> Result<(&'b [u8], Option<&'b [u8]>), ImportError> {
    let truncated = |offset: usize, msg: String| {
        ImportError::new(Location::byte(path, offset as u64), Problem::Truncated(msg))
    };
    let invalid =
        |offset: usize, msg: String| ImportError::invalid(Location::byte(path, offset as u64), msg);
    let (Some(version), Some(length)) = (le_u32(bytes, 4), le_u32(bytes, 8)) else {
        return Err(truncated(
            bytes.len(),
            format!(
                "the GLB header needs 12 bytes, the file has {}",
                bytes.len()
            ),
        ));
    };
    if version != 2 {
        return Err(invalid(
            4,
            format!("GLB container version {version}; only version 2 is supported"),
        ));
    }
    let total = length as usize;
    if total > bytes.len() {
        return Err(truncated(
            8,
            format!(
                "the GLB header declares {total} bytes, but the file holds only {}",
                bytes.len()
            ),
        ));
    }
    if total < bytes.len() {
        warnings.push(Warning::Note {
            location: Location::byte(path, total as u64).to_string(),
            message: format!(
                "{} bytes after the declared GLB length ignored",
                bytes.len() - total
            ),
        });
    }
    let mut json: Option<&[u8]> = None;
    let mut bin: Option<&[u8]> = None;
    let mut pos = 12usize;
    while pos < total {
        let (Some(chunk_len), Some(kind)) = (le_u32(bytes, pos), bytes.get(pos + 4..pos + 8))
        else {
            return Err(truncated(
                pos,
                format!(
                    "a GLB chunk header needs 8 bytes, only {} remain",
                    total - pos
                ),
            ));
        };
        if pos + 8 > total {
            return Err(truncated(
                pos,
                format!(
                    "a GLB chunk header needs 8 bytes, only {} remain",
                    total - pos
                ),
            ));
        }
        let start = pos + 8;
        let end = match start.checked_add(chunk_len as usize) {
            Some(end) if end <= total => end,
            _ => {
                return Err(truncated(
                    pos,
                    format!(
                        "the {} chunk declares {chunk_len} bytes, but only {} remain",
                        String::from_utf8_lossy(kind).trim_end_matches('\0'),
                        total - start
                    ),
                ))
            }
        };
        let data = &bytes[start..end];
        match kind {
            b"JSON" if json.is_none() && pos == 12 => json = Some(data),
            b"JSON" => return Err(invalid(pos + 4, "a second JSON chunk".into())),
            _ if json.is_none() => {
                return Err(invalid(
                    pos + 4,
                    format!(
                        "the first GLB chunk must be JSON, found {:?}",
                        String::from_utf8_lossy(kind)
                    ),
                ))
            }
            b"BIN\0" if bin.is_none() => bin = Some(data),
            b"BIN\0" => return Err(invalid(pos + 4, "a second BIN chunk".into())),
            // glTF 2.0 §4.4.3.1: chunks of unknown types must be ignored.
            _ => {}
        }
        pos = end;
    }
    match json {
        Some(json) => Ok((json, bin)),
        None => Err(truncated(total, "the GLB has no JSON chunk".into())),
    }
}

/// Splits a `gltf-json` path with a value (`extensionsRequired[0] = "KHR_x"`) into the path
/// and the value.
fn split_path_value(gltf_path: &str) -> (&str, Option<&str>) {
    match gltf_path.split_once(" = \"") {
        Some((at, value)) => (at, Some(value.trim_end_matches('"'))),
        None => (gltf_path, None),
    }
}

/// A `gltf-json` path (`meshes[0].attributes["POSITION"]`) as a JSON pointer
/// (`/meshes/0/attributes/POSITION`, RFC 6901 escapes).
fn json_pointer(gltf_path: &str) -> String {
    let mut out = String::new();
    let mut segment = String::new();
    let flush = |segment: &mut String, out: &mut String| {
        if !segment.is_empty() {
            out.push('/');
            out.push_str(&segment.replace('~', "~0").replace('/', "~1"));
            segment.clear();
        }
    };
    let mut chars = gltf_path.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '.' => flush(&mut segment, &mut out),
            '[' => {
                flush(&mut segment, &mut out);
                if chars.peek() == Some(&'"') {
                    chars.next();
                    while let Some(k) = chars.next() {
                        if k == '"' && chars.peek() == Some(&']') {
                            chars.next();
                            break;
                        }
                        segment.push(k);
                    }
                } else {
                    for k in chars.by_ref() {
                        if k == ']' {
                            break;
                        }
                        segment.push(k);
                    }
                }
                flush(&mut segment, &mut out);
            }
            c => segment.push(c),
        }
    }
    flush(&mut segment, &mut out);
    if out.is_empty() {
        out.push('/');
    }
    out
}

/// Parses and validates the glTF JSON (what `gltf::Gltf::from_slice` does, plus a check
/// its validation needs first).
fn parse_document(
    json: &[u8],
    path: &Path,
    is_glb: bool,
    warnings: &mut Vec<Warning>,
) -> Result<::gltf::Document, ImportError> {
    use ::gltf::json::validation::{Checked, Error as SchemaError, Validate};
    let root: ::gltf::json::Root = ::gltf::json::deserialize::from_slice(json).map_err(|e| {
        let mut message = e.to_string();
        let suffix = format!(" at line {} column {}", e.line(), e.column());
        if let Some(stripped) = message.strip_suffix(&suffix) {
            message = stripped.to_string();
        }
        if is_glb {
            message = format!("in the GLB JSON chunk: {message}");
        }
        let location = if e.line() > 0 {
            Location::line_column(path, e.line(), e.column())
        } else {
            Location::file(path)
        };
        let problem = if e.is_eof() {
            Problem::Truncated(message)
        } else {
            Problem::Invalid(message)
        };
        ImportError::new(location, problem)
    })?;
    // gltf-json 1.4's primitive validation indexes `accessors` with the POSITION index
    // before that index is checked: check it first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = prim.attributes.get(&Checked::Valid(Semantic::Positions));
            if position.is_some_and(|index| index.value() >= root.accessors.len()) {
                return Err(ImportError::invalid(
                    Location::json(
                        path,
                        format!("/meshes/{m}/primitives/{p}/attributes/POSITION"),
                    ),
                    "index out of range",
                ));
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(&root, ::gltf::json::Path::new, &mut |at, error| {
        let at = at();
        // glTF 2.0 §3.6.2.1: an accessor without bufferView (and without sparse) is all
        // zeros; gltf-json 1.4 reports it as missing, rigport reads it as zeros.
        let zero_filled = error == SchemaError::Missing
            && at.as_str().starts_with("accessors[")
            && at.as_str().ends_with("].bufferView");
        if !zero_filled {
            errors.push((at, error));
        }
    });
    // A required extension the gltf crate does not know blocks the import only if it
    // changes geometry, skins or animation; material and texture ones do not concern a rig.
    let mut kept = Vec::new();
    for (at, error) in errors {
        let (at_path, value) = split_path_value(at.as_str());
        let material_only = [
            "KHR_materials_",
            "KHR_texture_",
            "EXT_texture_",
            "MSFT_texture_",
        ]
        .iter()
        .any(|prefix| value.is_some_and(|v| v.starts_with(prefix)));
        if error == SchemaError::Unsupported && material_only {
            warnings.push(Warning::Note {
                location: Location::json(path, json_pointer(at_path)).to_string(),
                message: format!(
                    "required extension {} only affects materials; ignored",
                    value.unwrap_or_default()
                ),
            });
        } else {
            kept.push((at, error));
        }
    }
    if let Some((first_path, first)) = kept.first() {
        let (at_path, value) = split_path_value(first_path.as_str());
        let what = match first {
            SchemaError::IndexOutOfBounds => "index out of range".to_string(),
            SchemaError::Invalid => "invalid value".to_string(),
            SchemaError::Missing => "required value missing".to_string(),
            SchemaError::Oversize => "size exceeds this system's limits".to_string(),
            SchemaError::Unsupported => format!(
                "required extension {} is not supported",
                value.unwrap_or_default()
            ),
        };
        let more = match kept.len() {
            1 => String::new(),
            n => format!(" (and {} more glTF schema problems)", n - 1),
        };
        return Err(ImportError::invalid(
            Location::json(path, json_pointer(at_path)),
            format!("{what}{more}"),
        ));
    }
    Ok(::gltf::Document::from_json_without_validation(root))
}

/// Decodes standard base64 (RFC 4648 §4), padding optional; `None` on any other byte.
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    fn value(c: u8) -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    }
    let bytes = text.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(bytes.len() / 4 * 3 + 3);
    for chunk in bytes.chunks(4) {
        let mut acc = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            acc |= value(c)? << (18 - 6 * k);
        }
        let produced = match chunk.len() {
            4 => 3,
            3 => 2,
            2 => 1,
            _ => return None,
        };
        out.extend_from_slice(&acc.to_be_bytes()[1..1 + produced]);
    }
    Some(out)
}

/// Percent-decodes a URI path (RFC 3986 §2.1); `None` if the result is not UTF-8.
fn percent_decode(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match (bytes[i], hex) {
            (b'%', Some(b)) => {
                out.push(b);
                i += 3;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8(out).ok()
}

fn read_uri(uri: &str, path: &Path, at: &str) -> Result<Vec<u8>, ImportError> {
    let err = |msg: String| ImportError::invalid(Location::json(path, at), msg);
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((meta, payload)) = rest.split_once(',') else {
            return Err(err("malformed data URI: no ','".into()));
        };
        if !meta.ends_with(";base64") {
            return Err(err(format!("data URI {meta:?} is not base64-encoded")));
        }
        return decode_base64(payload).ok_or_else(|| err("data URI holds invalid base64".into()));
    }
    let file_part = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"));
    let relative = match file_part {
        Some(p) => p,
        None => {
            let scheme_end = uri.find(':');
            let first_slash = uri.find('/');
            if let Some(colon) = scheme_end {
                if first_slash.is_none_or(|s| colon < s) {
                    return Err(err(format!(
                        "buffer URI {uri:?}: only data: URIs and files are supported"
                    )));
                }
            }
            uri
        }
    };
    let decoded = percent_decode(relative)
        .ok_or_else(|| err(format!("buffer URI {uri:?} is not UTF-8 once decoded")))?;
    let base = path.parent().unwrap_or(Path::new(""));
    let file: PathBuf = base.join(decoded);
    std::fs::read(&file)
        .map_err(|e| err(format!("cannot read buffer file {}: {e}", file.display())))
}

fn load_buffers<'b>(
    doc: &::gltf::Document,
    mut blob: Option<&'b [u8]>,
    path: &Path,
) -> Result<Vec<Cow<'b, [u8]>>, ImportError> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let at = format!("/buffers/{}", buffer.index());
        let data: Cow<'b, [u8]> = match buffer.source() {
            ::gltf::buffer::Source::Bin => Cow::Borrowed(blob.take().ok_or_else(|| {
                ImportError::invalid(
                    Location::json(path, &at),
                    "has no uri, so it must be the GLB BIN chunk, but there is none",
                )
            })?),
            ::gltf::buffer::Source::Uri(uri) => {
                Cow::Owned(read_uri(uri, path, &format!("{at}/uri"))?)
            }
        };
        if data.len() < buffer.length() {
            return Err(ImportError::new(
                Location::json(path, &at),
                Problem::Truncated(format!(
                    "byteLength is {} but the data holds only {} bytes",
                    buffer.length(),
                    data.len()
                )),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------
// The document to the model
// ---------------------------------------------------------------------------------------

fn type_name(d: Dimensions) -> &'static str {
    match d {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

fn component_name(t: DataType) -> &'static str {
    match t {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    }
}

const FLOAT: &[DataType] = &[DataType::F32];
/// Float or normalized integers, as glTF allows for texture coordinates and weights.
const FLOAT_OR_UNORM: &[DataType] = &[DataType::F32, DataType::U8, DataType::U16];
/// Float or normalized integers of either sign (rotation and morph-weight outputs).
const FLOAT_OR_NORM: &[DataType] = &[
    DataType::F32,
    DataType::I8,
    DataType::U8,
    DataType::I16,
    DataType::U16,
];

/// The imported nodes as a skeleton.
struct SceneNodes {
    skeleton: Skeleton,
    /// Node indices in skeleton (parents-first) order.
    order: Vec<usize>,
    /// Each node's joint; `None` for nodes outside the imported scene and for
    /// `mesh_only` nodes.
    node_joint: Vec<Option<JointIndex>>,
    /// Skinned-mesh nodes that are not joints: leaves that no skin uses and no animation
    /// moves. glTF ignores a skinned mesh node's transform, so such a node carries nothing
    /// but its mesh; making it a joint would add a node on every round trip.
    /// `(node, parent joint)`.
    mesh_only: Vec<(usize, Option<JointIndex>)>,
}

/// A mesh's shared skin data, converted once per glTF skin.
#[derive(Clone)]
struct SkinData {
    joints: Vec<JointIndex>,
    inv_bind: Vec<Mat4>,
}

struct Importer<'a> {
    path: &'a Path,
    doc: &'a ::gltf::Document,
    buffers: &'a [Cow<'a, [u8]>],
    warnings: Vec<Warning>,
}

impl<'a> Importer<'a> {
    fn err(&self, at: impl Into<String>, message: impl Into<String>) -> ImportError {
        ImportError::invalid(Location::json(self.path, at), message)
    }

    fn note(&mut self, at: &str, message: String) {
        self.warnings.push(Warning::Note {
            location: Location::json(self.path, at).to_string(),
            message,
        });
    }

    fn repaired(&mut self, at: &str, message: String) {
        self.warnings.push(Warning::Repaired {
            location: Location::json(self.path, at).to_string(),
            message,
        });
    }

    /// The buffer lookup the `gltf` readers take.
    fn data(&self) -> impl Clone + Fn(::gltf::Buffer<'_>) -> Option<&'a [u8]> + 'a {
        let buffers = self.buffers;
        move |buffer: ::gltf::Buffer<'_>| buffers.get(buffer.index()).map(|b| &**b)
    }

    fn run(&mut self) -> Result<Asset, ImportError> {
        let SceneNodes {
            skeleton,
            order,
            node_joint,
            mesh_only,
        } = self.skeleton()?;
        let model_rest = skeleton.model_rest_matrices();
        let nodes: Vec<::gltf::Node<'a>> = self.doc.nodes().collect();
        let mut meshes: Vec<Mesh> = Vec::new();
        let mut skins: Vec<SkinBinding> = Vec::new();
        let mut node_meshes: Vec<Vec<MeshIndex>> = vec![Vec::new(); nodes.len()];
        let mut geometry: HashMap<(usize, usize), Option<Mesh>> = HashMap::new();
        let mut skin_data: HashMap<usize, SkinData> = HashMap::new();

        // Every joint node, then the skinned-mesh nodes that are not joints.
        let mesh_nodes = order
            .iter()
            .map(|&i| (i, None))
            .chain(mesh_only.iter().map(|&(i, parent)| (i, Some(parent))));
        for (node_index, mesh_only_parent) in mesh_nodes {
            let Some(node) = nodes.get(node_index) else {
                continue;
            };
            // The node's model-space rest matrix; its joint, when it is one.
            let (node_model, joint) = match mesh_only_parent {
                None => {
                    let Some(joint) = node_joint.get(node_index).copied().flatten() else {
                        continue;
                    };
                    (model_rest.get(joint.get()).copied(), Some(joint))
                }
                Some(parent) => {
                    let parent_model = parent
                        .and_then(|p| model_rest.get(p.get()).copied())
                        .unwrap_or(Mat4::IDENTITY);
                    let local = Mat4::from_cols_array_2d(&node.transform().matrix());
                    (Some(parent_model * local), None)
                }
            };
            let Some(mesh) = node.mesh() else {
                if node.skin().is_some() {
                    self.note(
                        &format!("/nodes/{node_index}/skin"),
                        "node has a skin but no mesh; skin ignored".into(),
                    );
                }
                continue;
            };
            let skin = node.skin();
            if skin.is_some() {
                let moved = node_model.is_some_and(|m| !m.abs_diff_eq(Mat4::IDENTITY, 1e-6));
                if moved {
                    self.note(
                        &format!("/nodes/{node_index}"),
                        "skinned mesh node has a transform or a transformed ancestor; glTF \
                         ignores it for skinned meshes, and so does rigport"
                            .into(),
                    );
                }
            }
            let primitive_count = mesh.primitives().len();
            let mesh_name = mesh
                .name()
                .filter(|n| !n.is_empty())
                .map_or_else(|| format!("mesh_{}", mesh.index()), str::to_string);
            for prim in mesh.primitives() {
                let base = format!("/meshes/{}/primitives/{}", mesh.index(), prim.index());
                let key = (mesh.index(), prim.index());
                let built = match geometry.get(&key) {
                    Some(built) => built.clone(),
                    None => {
                        let name = if primitive_count > 1 {
                            format!("{mesh_name}_{}", prim.index())
                        } else {
                            mesh_name.clone()
                        };
                        let built = self.primitive(&mesh, &prim, &base, name)?;
                        geometry.insert(key, built.clone());
                        built
                    }
                };
                let Some(mut model_mesh) = built else {
                    continue;
                };
                let (weights, weights_at) = match node.weights() {
                    Some(w) => (Some(w), format!("/nodes/{node_index}/weights")),
                    None => (mesh.weights(), format!("/meshes/{}/weights", mesh.index())),
                };
                model_mesh.morph_weights =
                    self.default_weights(weights, model_mesh.morph_targets.len(), &weights_at)?;
                let mesh_index = MeshIndex(meshes.len() as u32);
                let has_joints = prim.get(&Semantic::Joints(0)).is_some();
                match (&skin, has_joints) {
                    (Some(skin), true) => {
                        let data = match skin_data.get(&skin.index()) {
                            Some(d) => d.clone(),
                            None => {
                                let d = self.skin_data(skin, &node_joint)?;
                                skin_data.insert(skin.index(), d.clone());
                                d
                            }
                        };
                        let influences = self.influences(
                            &prim,
                            &base,
                            model_mesh.vertex_count(),
                            data.joints.len(),
                            skin.index(),
                        )?;
                        skins.push(SkinBinding {
                            method: Default::default(),
                            mesh: mesh_index,
                            joints: data.joints,
                            inv_bind: data.inv_bind,
                            influences,
                        });
                    }
                    (Some(_), false) => {
                        self.note(
                            &base,
                            format!(
                                "node {node_index} has a skin but this primitive has no \
                                 JOINTS_0; imported unskinned, attached to the node"
                            ),
                        );
                        model_mesh.attached_to = joint;
                    }
                    (None, has_joints) => {
                        if has_joints {
                            self.note(
                                &base,
                                format!(
                                    "primitive has JOINTS_0 but node {node_index} has no skin; \
                                     imported unskinned, attached to the node"
                                ),
                            );
                        }
                        model_mesh.attached_to = joint;
                    }
                }
                meshes.push(model_mesh);
                if let Some(list) = node_meshes.get_mut(node_index) {
                    list.push(mesh_index);
                }
            }
        }

        let clips = self.clips(&node_joint, &node_meshes, &meshes)?;
        let name = self
            .path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let asset = Asset {
            frame: Default::default(),
            name,
            skeleton,
            meshes,
            skins,
            clips,
            // glTF 2.0 §3.4: "The units for all linear distances are meters."
            meters_per_unit: Some(1.0),
            ik_handles: Vec::new(),
        };
        asset.validate().map_err(|problems| {
            ImportError::invalid(
                Location::file(self.path),
                problems
                    .iter()
                    .map(ToString::to_string)
                    .collect::<Vec<_>>()
                    .join("; "),
            )
        })?;
        Ok(asset)
    }

    // --- skeleton -----------------------------------------------------------------------

    /// Builds the skeleton of the imported nodes, checking that the children lists form a
    /// forest (one parent per node, no cycles).
    fn skeleton(&mut self) -> Result<SceneNodes, ImportError> {
        let nodes: Vec<::gltf::Node<'a>> = self.doc.nodes().collect();
        let n = nodes.len();
        let mut parent: Vec<Option<usize>> = vec![None; n];
        for node in &nodes {
            let p = node.index();
            for (k, child) in node.children().enumerate() {
                let c = child.index();
                let at = format!("/nodes/{p}/children/{k}");
                if c == p {
                    return Err(self.err(at, format!("node {p} lists itself as a child")));
                }
                let Some(slot) = parent.get_mut(c) else {
                    return Err(self.err(at, format!("node {c} does not exist")));
                };
                if let Some(q) = *slot {
                    return Err(self.err(
                        at,
                        format!(
                            "node {c} is already a child of node {q}; a glTF node has at most \
                             one parent"
                        ),
                    ));
                }
                *slot = Some(p);
            }
        }
        let full_order = parents_first_order(&parent).map_err(|problems| {
            match problems.iter().find_map(|p| match p {
                SkeletonProblem::Cycle { joints } => Some(joints.clone()),
                _ => None,
            }) {
                Some(cycle) => self.err(
                    format!("/nodes/{}/children", cycle.first().copied().unwrap_or(0)),
                    format!("nodes {cycle:?} form a cycle of children"),
                ),
                None => ImportError::new(
                    Location::json(self.path, "/nodes"),
                    Problem::Skeleton(problems),
                ),
            }
        })?;

        // Which nodes: the default scene's, else every scene's, else all.
        let scene_count = self.doc.scenes().count();
        let roots: Vec<usize> = match self.doc.default_scene() {
            Some(scene) => scene.nodes().map(|node| node.index()).collect(),
            None if scene_count > 0 => {
                self.note(
                    "/scenes",
                    format!("no default scene: importing the nodes of all {scene_count} scenes"),
                );
                self.doc
                    .scenes()
                    .flat_map(|s| s.nodes().map(|node| node.index()).collect::<Vec<_>>())
                    .collect()
            }
            None => {
                if n > 0 {
                    self.note("/nodes", "no scenes: importing every node".into());
                }
                (0..n).filter(|&i| parent[i].is_none()).collect()
            }
        };
        let mut selected = vec![false; n];
        let mut stack = roots.clone();
        while let Some(i) = stack.pop() {
            match selected.get_mut(i) {
                Some(s) if !*s => *s = true,
                _ => continue,
            }
            if let Some(node) = nodes.get(i) {
                stack.extend(node.children().map(|c| c.index()));
            }
        }
        let mut used = vec![false; n];
        for skin in self.doc.skins() {
            for j in skin.joints() {
                if let Some(u) = used.get_mut(j.index()) {
                    *u = true;
                }
            }
            if let Some(u) = skin.skeleton().and_then(|s| used.get_mut(s.index())) {
                *u = true;
            }
        }
        // From the JSON: the gltf crate's channel accessors unwrap unvalidated indices.
        for anim in &self.doc.as_json().animations {
            for ch in &anim.channels {
                if let Some(u) = used.get_mut(ch.target.node.value()) {
                    *u = true;
                }
            }
        }
        let mesh_only_node = |i: usize| {
            let node = &nodes[i];
            node.mesh().is_some_and(|m| {
                m.primitives()
                    .all(|p| p.get(&Semantic::Joints(0)).is_some())
            }) && node.skin().is_some()
                && node.children().len() == 0
                && !used[i]
        };
        let (order, mesh_only_nodes): (Vec<usize>, Vec<usize>) = full_order
            .into_iter()
            .filter(|&i| selected[i])
            .partition(|&i| !mesh_only_node(i));
        let mut node_joint: Vec<Option<JointIndex>> = vec![None; n];
        for (k, &i) in order.iter().enumerate() {
            node_joint[i] = Some(JointIndex(k as u32));
        }

        // Unique, non-empty names: authored names first (lowest node index wins), then
        // generated ones that avoid every authored name.
        let mut taken: HashSet<String> = HashSet::new();
        let mut names: Vec<Option<String>> = vec![None; n];
        for &i in &order {
            if let Some(name) = nodes[i].name().filter(|s| !s.is_empty()) {
                if taken.insert(name.to_string()) {
                    names[i] = Some(name.to_string());
                }
            }
        }
        let mut unnamed = 0usize;
        let mut missing: Vec<usize> = order
            .iter()
            .copied()
            .filter(|&i| names[i].is_none())
            .collect();
        missing.sort_unstable();
        for i in missing {
            let authored = nodes[i].name().filter(|s| !s.is_empty());
            let base = match authored {
                Some(name) => format!("{name}_{i}"),
                None => format!("node_{i}"),
            };
            let mut candidate = base.clone();
            let mut k = 1;
            while taken.contains(&candidate) {
                candidate = format!("{base}_{k}");
                k += 1;
            }
            taken.insert(candidate.clone());
            match authored {
                Some(name) => self.note(
                    &format!("/nodes/{i}/name"),
                    format!("duplicate node name {name:?}: joint renamed {candidate:?}"),
                ),
                None => {
                    unnamed += 1;
                    if candidate != base {
                        self.note(
                            &format!("/nodes/{i}/name"),
                            format!("unnamed node; {base:?} is taken, joint named {candidate:?}"),
                        );
                    }
                }
            }
            names[i] = Some(candidate);
        }
        if unnamed > 0 {
            self.note(
                "/nodes",
                format!("{unnamed} unnamed node(s): joints named node_<index>"),
            );
        }

        let mut joints = Vec::with_capacity(order.len());
        for &i in &order {
            let parent_joint = match parent[i] {
                Some(p) if selected[p] => node_joint[p],
                Some(p) => {
                    self.note(
                        &format!("/nodes/{i}"),
                        format!(
                            "scene root node {i} is a child of node {p}, which is not in the \
                             scene; imported as a root"
                        ),
                    );
                    None
                }
                None => None,
            };
            joints.push(Joint {
                name: names[i].take().unwrap_or_else(|| format!("node_{i}")),
                parent: parent_joint,
                rest_local: self.rest_local(&nodes[i])?,
            });
        }
        let skeleton = Skeleton::new(joints).map_err(|problems| {
            ImportError::new(
                Location::json(self.path, "/nodes"),
                Problem::Skeleton(problems),
            )
        })?;
        let mesh_only = mesh_only_nodes
            .into_iter()
            .map(|i| (i, parent[i].and_then(|p| node_joint[p])))
            .collect();
        Ok(SceneNodes {
            skeleton,
            order,
            node_joint,
            mesh_only,
        })
    }

    fn rest_local(&mut self, node: &::gltf::Node<'_>) -> Result<Transform, ImportError> {
        let i = node.index();
        match node.transform() {
            ::gltf::scene::Transform::Matrix { matrix } => {
                let at = format!("/nodes/{i}/matrix");
                let m = Mat4::from_cols_array_2d(&matrix);
                if !m.is_finite() {
                    return Err(self.err(at, "matrix is not finite"));
                }
                let mut t = Transform::from_mat4(&m);
                if !t.rotation.is_finite() {
                    // A zero scale leaves no rotation to recover.
                    t.rotation = Quat::IDENTITY;
                }
                let back = t.to_mat4();
                let diff = (back - m)
                    .to_cols_array()
                    .iter()
                    .fold(0.0f32, |a, v| a.max(v.abs()));
                let scale = [m.x_axis, m.y_axis, m.z_axis]
                    .iter()
                    .flat_map(|c| c.truncate().to_array())
                    .fold(1.0f32, |a, v| a.max(v.abs()));
                if !diff.is_finite() || diff > MATRIX_TOLERANCE * scale {
                    self.repaired(
                        &at,
                        format!(
                            "matrix is not a TRS (shear or projection): the nearest TRS differs \
                             by up to {diff:.3e}; kept the TRS"
                        ),
                    );
                }
                Ok(t)
            }
            ::gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => {
                let translation = Vec3::from(translation);
                let scale = Vec3::from(scale);
                let q = Quat::from_array(rotation);
                if !translation.is_finite() {
                    return Err(self.err(format!("/nodes/{i}/translation"), "not finite"));
                }
                if !scale.is_finite() {
                    return Err(self.err(format!("/nodes/{i}/scale"), "not finite"));
                }
                let len = q.length();
                if !(len > 1e-6 && len.is_finite()) {
                    return Err(self.err(
                        format!("/nodes/{i}/rotation"),
                        format!("rotation quaternion has length {len}"),
                    ));
                }
                if (len - 1.0).abs() > UNIT_QUAT_TOLERANCE {
                    self.repaired(
                        &format!("/nodes/{i}/rotation"),
                        format!("rotation quaternion has length {len}; normalized"),
                    );
                }
                Ok(Transform {
                    translation,
                    rotation: q / len,
                    scale,
                })
            }
        }
    }

    // --- accessors ----------------------------------------------------------------------

    /// Checks everything the `gltf` readers assume: element type, count, and that every
    /// byte read lies inside its buffer view and buffer. Returns the element count.
    fn check(
        &self,
        acc: &::gltf::Accessor<'_>,
        dims: Dimensions,
        types: &[DataType],
        at: &str,
    ) -> Result<usize, ImportError> {
        let what = format!("accessor {}", acc.index());
        if acc.dimensions() != dims || !types.contains(&acc.data_type()) {
            let allowed: Vec<&str> = types.iter().map(|t| component_name(*t)).collect();
            return Err(self.err(
                at,
                format!(
                    "{what} is {} of {}; expected {} of {}",
                    type_name(acc.dimensions()),
                    component_name(acc.data_type()),
                    type_name(dims),
                    allowed.join(" or ")
                ),
            ));
        }
        let count = acc.count();
        if count == 0 {
            return Err(self.err(at, format!("{what} has count 0")));
        }
        let elem = acc.size();
        match acc.view() {
            Some(view) => self.check_view_range(&view, acc.offset(), count, elem, at, &what)?,
            None if count.saturating_mul(elem) > MAX_ZERO_FILLED_BYTES => {
                return Err(self.err(
                    at,
                    format!(
                        "{what} has no bufferView and {count} elements of {elem} bytes; \
                         rigport accepts at most {MAX_ZERO_FILLED_BYTES} bytes"
                    ),
                ))
            }
            None => {}
        }
        if let Some(sparse) = acc.sparse() {
            let sparse_count = sparse.count();
            if sparse_count == 0 || sparse_count > count {
                return Err(self.err(
                    at,
                    format!("{what} has sparse.count {sparse_count} for {count} elements"),
                ));
            }
            let indices = sparse.indices();
            let index_size = match indices.index_type() {
                ::gltf::accessor::sparse::IndexType::U8 => 1,
                ::gltf::accessor::sparse::IndexType::U16 => 2,
                ::gltf::accessor::sparse::IndexType::U32 => 4,
            };
            self.check_view_range(
                &indices.view(),
                indices.offset(),
                sparse_count,
                index_size,
                at,
                &format!("{what} sparse indices"),
            )?;
            let values = sparse.values();
            self.check_view_range(
                &values.view(),
                values.offset(),
                sparse_count,
                elem,
                at,
                &format!("{what} sparse values"),
            )?;
        }
        Ok(count)
    }

    /// `count >= 1` elements of `elem` bytes from `offset` in `view`, strided as the view says.
    fn check_view_range(
        &self,
        view: &::gltf::buffer::View<'_>,
        offset: usize,
        count: usize,
        elem: usize,
        at: &str,
        what: &str,
    ) -> Result<(), ImportError> {
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(self.err(
                at,
                format!(
                    "{what}: buffer view {} has byteStride {stride}, less than the element \
                     size {elem}",
                    view.index()
                ),
            ));
        }
        let end = stride
            .checked_mul(count.saturating_sub(1))
            .and_then(|x| x.checked_add(elem))
            .and_then(|x| x.checked_add(offset));
        if end.is_none_or(|end| end > view.length()) {
            return Err(self.err(
                at,
                format!(
                    "{what} reads {count} elements of {elem} bytes (stride {stride}) from byte \
                     {offset} of buffer view {}, which holds {} bytes",
                    view.index(),
                    view.length()
                ),
            ));
        }
        let buffer = view.buffer().index();
        let buffer_len = self.buffers.get(buffer).map_or(0, |b| b.len());
        if view
            .offset()
            .checked_add(view.length())
            .is_none_or(|end| end > buffer_len)
        {
            return Err(self.err(
                at,
                format!(
                    "{what}: buffer view {} spans bytes {}..{} of buffer {buffer}, which holds \
                     {buffer_len} bytes",
                    view.index(),
                    view.offset(),
                    view.offset().saturating_add(view.length())
                ),
            ));
        }
        Ok(())
    }

    /// Whether the accessor has neither `bufferView` nor `sparse`: all zeros (glTF 2.0
    /// §3.6.2.1), which the `gltf` readers do not produce.
    fn zero_filled(acc: &::gltf::Accessor<'_>) -> bool {
        acc.view().is_none() && acc.sparse().is_none()
    }

    fn iter<T: ::gltf::accessor::Item>(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<::gltf::accessor::Iter<'a, T>, ImportError> {
        ::gltf::accessor::Iter::new(acc.clone(), self.data())
            .ok_or_else(|| self.err(at, format!("accessor {} data unavailable", acc.index())))
    }

    fn read_vec3(&self, acc: &::gltf::Accessor<'a>, at: &str) -> Result<Vec<Vec3>, ImportError> {
        let count = self.check(acc, Dimensions::Vec3, FLOAT, at)?;
        if Self::zero_filled(acc) {
            return Ok(vec![Vec3::ZERO; count]);
        }
        let values: Vec<Vec3> = self.iter::<[f32; 3]>(acc, at)?.map(Vec3::from).collect();
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(self.err(at, format!("element {k} is not finite: {}", values[k])));
        }
        Ok(values)
    }

    fn read_scalars(&self, acc: &::gltf::Accessor<'a>, at: &str) -> Result<Vec<f32>, ImportError> {
        let count = self.check(acc, Dimensions::Scalar, FLOAT, at)?;
        if Self::zero_filled(acc) {
            return Ok(vec![0.0; count]);
        }
        Ok(self.iter::<f32>(acc, at)?.collect())
    }

    fn read_tex_coords(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<Vec<Vec2>, ImportError> {
        let count = self.check(acc, Dimensions::Vec2, FLOAT_OR_UNORM, at)?;
        if Self::zero_filled(acc) {
            return Ok(vec![Vec2::ZERO; count]);
        }
        let read = match acc.data_type() {
            DataType::U8 => ReadTexCoords::U8(self.iter(acc, at)?),
            DataType::U16 => ReadTexCoords::U16(self.iter(acc, at)?),
            _ => ReadTexCoords::F32(self.iter(acc, at)?),
        };
        let values: Vec<Vec2> = read.into_f32().map(Vec2::from).collect();
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(self.err(at, format!("element {k} is not finite: {}", values[k])));
        }
        Ok(values)
    }

    fn read_indices(&self, acc: &::gltf::Accessor<'a>, at: &str) -> Result<Vec<u32>, ImportError> {
        let count = self.check(
            acc,
            Dimensions::Scalar,
            &[DataType::U8, DataType::U16, DataType::U32],
            at,
        )?;
        if Self::zero_filled(acc) {
            return Ok(vec![0; count]);
        }
        let read = match acc.data_type() {
            DataType::U8 => ReadIndices::U8(self.iter(acc, at)?),
            DataType::U16 => ReadIndices::U16(self.iter(acc, at)?),
            _ => ReadIndices::U32(self.iter(acc, at)?),
        };
        Ok(read.into_u32().collect())
    }

    fn read_joints(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<Vec<[u16; 4]>, ImportError> {
        let count = self.check(acc, Dimensions::Vec4, &[DataType::U8, DataType::U16], at)?;
        if Self::zero_filled(acc) {
            return Ok(vec![[0; 4]; count]);
        }
        let read = match acc.data_type() {
            DataType::U8 => ReadJoints::U8(self.iter(acc, at)?),
            _ => ReadJoints::U16(self.iter(acc, at)?),
        };
        Ok(read.into_u16().collect())
    }

    fn read_weights(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<Vec<[f32; 4]>, ImportError> {
        let count = self.check(acc, Dimensions::Vec4, FLOAT_OR_UNORM, at)?;
        if Self::zero_filled(acc) {
            return Ok(vec![[0.0; 4]; count]);
        }
        let read = match acc.data_type() {
            DataType::U8 => ReadWeights::U8(self.iter(acc, at)?),
            DataType::U16 => ReadWeights::U16(self.iter(acc, at)?),
            _ => ReadWeights::F32(self.iter(acc, at)?),
        };
        Ok(read.into_f32().collect())
    }

    // --- meshes -------------------------------------------------------------------------

    /// One primitive's geometry and morph targets; `None` for points and lines.
    fn primitive(
        &mut self,
        mesh: &::gltf::Mesh<'a>,
        prim: &::gltf::Primitive<'a>,
        base: &str,
        name: String,
    ) -> Result<Option<Mesh>, ImportError> {
        let mode = prim.mode();
        if matches!(
            mode,
            Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip
        ) {
            self.note(
                &format!("{base}/mode"),
                format!("{mode:?} primitive skipped: rigport imports triangles only"),
            );
            return Ok(None);
        }
        let pos_at = format!("{base}/attributes/POSITION");
        let Some(pos_acc) = prim.get(&Semantic::Positions) else {
            return Err(self.err(pos_at, "primitive has no POSITION"));
        };
        let positions = self.read_vec3(&pos_acc, &pos_at)?;
        let n = positions.len();
        if u32::try_from(n).is_err() {
            return Err(self.err(pos_at, format!("{n} vertices is too many")));
        }
        let count_check = |this: &Self, at: &str, found: usize| {
            if found == n {
                Ok(())
            } else {
                Err(this.err(at, format!("has {found} elements for {n} vertices")))
            }
        };

        let normals = match prim.get(&Semantic::Normals) {
            Some(acc) => {
                let at = format!("{base}/attributes/NORMAL");
                let normals = self.read_vec3(&acc, &at)?;
                count_check(self, &at, normals.len())?;
                Some(normals)
            }
            None => None,
        };
        let uvs = match prim.get(&Semantic::TexCoords(0)) {
            Some(acc) => {
                let at = format!("{base}/attributes/TEXCOORD_0");
                let uvs = self.read_tex_coords(&acc, &at)?;
                count_check(self, &at, uvs.len())?;
                Some(uvs)
            }
            None => None,
        };
        let ignored: Vec<String> = prim
            .attributes()
            .filter_map(|(semantic, _)| match semantic {
                Semantic::Positions
                | Semantic::Normals
                | Semantic::TexCoords(0)
                | Semantic::Joints(_)
                | Semantic::Weights(_) => None,
                other => Some(other.to_string()),
            })
            .collect();
        if !ignored.is_empty() {
            self.note(
                &format!("{base}/attributes"),
                format!("attributes not imported: {}", ignored.join(", ")),
            );
        }

        let indices = match prim.indices() {
            Some(acc) => {
                let at = format!("{base}/indices");
                let indices = self.read_indices(&acc, &at)?;
                if let Some(k) = indices.iter().position(|&i| i as usize >= n) {
                    return Err(self.err(
                        at,
                        format!("index {k} is {}, but there are {n} vertices", indices[k]),
                    ));
                }
                indices
            }
            None => (0..n as u32).collect(),
        };
        let triangles = match mode {
            Mode::TriangleStrip => strip_triangles(&indices),
            Mode::TriangleFan => fan_triangles(&indices),
            _ => {
                let rest = indices.len() % 3;
                if rest != 0 {
                    self.repaired(
                        base,
                        format!(
                            "{} indices is not a multiple of 3; last {rest} ignored",
                            indices.len()
                        ),
                    );
                }
                indices
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect()
            }
        };

        let names = target_names(mesh);
        let mut morph_targets = Vec::new();
        for (t, target) in prim.morph_targets().enumerate() {
            let position_deltas = match target.positions() {
                Some(acc) => {
                    let at = format!("{base}/targets/{t}/POSITION");
                    let d = self.read_vec3(&acc, &at)?;
                    count_check(self, &at, d.len())?;
                    d
                }
                None => vec![Vec3::ZERO; n],
            };
            let normal_deltas = match target.normals() {
                Some(acc) => {
                    let at = format!("{base}/targets/{t}/NORMAL");
                    let d = self.read_vec3(&acc, &at)?;
                    count_check(self, &at, d.len())?;
                    Some(d)
                }
                None => None,
            };
            morph_targets.push(MorphTarget {
                name: names.get(t).cloned().unwrap_or_default(),
                position_deltas,
                normal_deltas,
            });
        }
        if !names.is_empty() && names.len() != morph_targets.len() {
            self.note(
                &format!("/meshes/{}/extras/targetNames", mesh.index()),
                format!(
                    "{} target names for {} morph targets",
                    names.len(),
                    morph_targets.len()
                ),
            );
        }

        Ok(Some(Mesh {
            name,
            positions,
            normals,
            uvs,
            triangles,
            source_vertex: (0..n as u32).collect(),
            morph_targets,
            morph_weights: Vec::new(),
            attached_to: None,
        }))
    }

    /// Default morph weights (node `weights` override mesh `weights`, glTF 2.0 §3.7.2.2).
    fn default_weights(
        &mut self,
        weights: Option<&[f32]>,
        targets: usize,
        at: &str,
    ) -> Result<Vec<f32>, ImportError> {
        let Some(weights) = weights else {
            return Ok(Vec::new());
        };
        if let Some(k) = weights.iter().position(|w| !w.is_finite()) {
            return Err(self.err(format!("{at}/{k}"), "weight is not finite"));
        }
        if weights.len() == targets {
            return Ok(weights.to_vec());
        }
        self.repaired(
            at,
            format!(
                "{} default weights for {targets} morph targets; {}",
                weights.len(),
                if weights.len() > targets {
                    "extra weights dropped"
                } else {
                    "missing weights set to 0"
                }
            ),
        );
        let mut out = weights.to_vec();
        out.resize(targets, 0.0);
        Ok(out)
    }

    // --- skins --------------------------------------------------------------------------

    fn skin_data(
        &mut self,
        skin: &::gltf::Skin<'a>,
        node_joint: &[Option<JointIndex>],
    ) -> Result<SkinData, ImportError> {
        let at = format!("/skins/{}", skin.index());
        let mut joints = Vec::new();
        for (k, node) in skin.joints().enumerate() {
            match node_joint.get(node.index()).copied().flatten() {
                Some(j) => joints.push(j),
                None => {
                    return Err(self.err(
                        format!("{at}/joints/{k}"),
                        format!(
                            "joint node {} is not part of the imported scene",
                            node.index()
                        ),
                    ))
                }
            }
        }
        let inv_bind = match skin.inverse_bind_matrices() {
            // glTF 2.0 §5.27.1: without inverseBindMatrices each is the identity.
            None => vec![Mat4::IDENTITY; joints.len()],
            Some(acc) => {
                let ibm_at = format!("{at}/inverseBindMatrices");
                let count = self.check(&acc, Dimensions::Mat4, FLOAT, &ibm_at)?;
                if count < joints.len() {
                    return Err(self.err(
                        ibm_at,
                        format!("{count} matrices for {} joints", joints.len()),
                    ));
                }
                let mut mats: Vec<Mat4> = if Self::zero_filled(&acc) {
                    vec![Mat4::ZERO; count]
                } else {
                    skin.reader(self.data())
                        .read_inverse_bind_matrices()
                        .ok_or_else(|| self.err(&ibm_at, "data unavailable"))?
                        .map(|m| Mat4::from_cols_array_2d(&m))
                        .collect()
                };
                if let Some(k) = mats.iter().position(|m| !m.is_finite()) {
                    return Err(self.err(ibm_at, format!("matrix {k} is not finite")));
                }
                if mats.len() > joints.len() {
                    self.repaired(
                        &ibm_at,
                        format!(
                            "{} matrices for {} joints; extra ones ignored",
                            mats.len(),
                            joints.len()
                        ),
                    );
                    mats.truncate(joints.len());
                }
                mats
            }
        };
        Ok(SkinData { joints, inv_bind })
    }

    /// Influences from every `JOINTS_n`/`WEIGHTS_n` set: zero weights dropped, repeated
    /// joints merged, rows rescaled to sum to 1 (a warning reports rows visibly off).
    fn influences(
        &mut self,
        prim: &::gltf::Primitive<'a>,
        base: &str,
        n: usize,
        palette_len: usize,
        skin_index: usize,
    ) -> Result<Influences, ImportError> {
        let mut sets = BTreeSet::new();
        for (semantic, _) in prim.attributes() {
            if let Semantic::Joints(s) | Semantic::Weights(s) = semantic {
                sets.insert(s);
            }
        }
        let mut rows: Vec<Vec<Influence>> = vec![Vec::new(); n];
        let mut merged = vec![false; n];
        for s in sets {
            let j_at = format!("{base}/attributes/JOINTS_{s}");
            let w_at = format!("{base}/attributes/WEIGHTS_{s}");
            let (Some(j_acc), Some(w_acc)) = (
                prim.get(&Semantic::Joints(s)),
                prim.get(&Semantic::Weights(s)),
            ) else {
                self.repaired(
                    &format!("{base}/attributes"),
                    format!("JOINTS_{s} and WEIGHTS_{s} must come in pairs; set {s} ignored"),
                );
                continue;
            };
            let joints = self.read_joints(&j_acc, &j_at)?;
            let weights = self.read_weights(&w_acc, &w_at)?;
            if joints.len() != n {
                return Err(self.err(
                    j_at,
                    format!("has {} elements for {n} vertices", joints.len()),
                ));
            }
            if weights.len() != n {
                return Err(self.err(
                    w_at,
                    format!("has {} elements for {n} vertices", weights.len()),
                ));
            }
            for (v, ((js, ws), row)) in joints.iter().zip(&weights).zip(&mut rows).enumerate() {
                for (k, (&j, &w)) in js.iter().zip(ws).enumerate() {
                    if !w.is_finite() || w < 0.0 {
                        return Err(self.err(
                            &w_at,
                            format!("vertex {v} weight {k} is {w}; weights must be >= 0"),
                        ));
                    }
                    if w == 0.0 {
                        continue;
                    }
                    if usize::from(j) >= palette_len {
                        return Err(self.err(
                            &j_at,
                            format!(
                                "vertex {v} influence {k} names joint {j}, but skin \
                                 {skin_index} has {palette_len} joints"
                            ),
                        ));
                    }
                    let joint = u32::from(j);
                    match row.iter_mut().find(|e| e.joint == joint) {
                        Some(e) => {
                            e.weight += w;
                            merged[v] = true;
                        }
                        None => row.push(Influence { joint, weight: w }),
                    }
                }
            }
        }
        let merged_count = merged.iter().filter(|&&m| m).count();
        if merged_count > 0 {
            self.repaired(
                &format!("{base}/attributes"),
                format!(
                    "{merged_count} vertices list the same joint more than once; weights merged"
                ),
            );
        }
        // glTF 2.0 §3.7.3.3: weights must sum to 1. Rows that do not are rescaled, so what
        // rigport evaluates is what every file it writes holds (both exporters normalize);
        // rows visibly off are reported.
        let mut off = 0usize;
        let mut worst = 0.0f32;
        for row in &mut rows {
            let sum: f32 = row.iter().map(|i| i.weight).sum();
            let dev = (sum - 1.0).abs();
            if dev > WEIGHT_SUM_TOLERANCE {
                off += 1;
                worst = worst.max(dev);
            }
            if dev > f32::EPSILON && sum > 0.0 {
                for i in row.iter_mut() {
                    i.weight /= sum;
                }
            }
        }
        if off > 0 {
            self.warnings.push(Warning::WeightsRenormalized {
                source: Location::json(self.path, format!("{base}/attributes/WEIGHTS_0"))
                    .to_string(),
                rows: off,
                max_row_sum_error: worst,
            });
        }
        Ok(Influences::from_rows(rows))
    }

    // --- animations ---------------------------------------------------------------------

    fn clips(
        &mut self,
        node_joint: &[Option<JointIndex>],
        node_meshes: &[Vec<MeshIndex>],
        meshes: &[Mesh],
    ) -> Result<Vec<Clip>, ImportError> {
        let mut clips = Vec::new();
        for anim in self.doc.animations() {
            let a = anim.index();
            let name = anim
                .name()
                .filter(|s| !s.is_empty())
                .map_or_else(|| format!("animation_{a}"), str::to_string);
            let mut tracks = Vec::new();
            for channel in anim.channels() {
                let ch_at = format!("/animations/{a}/channels/{}", channel.index());
                let sampler = channel.sampler();
                let s_at = format!("/animations/{a}/samplers/{}", sampler.index());
                // gltf-json 1.4 does not validate channel targets: check them before the
                // accessors that unwrap them.
                let json_target = self
                    .doc
                    .as_json()
                    .animations
                    .get(a)
                    .and_then(|anim| anim.channels.get(channel.index()))
                    .map(|ch| &ch.target);
                let Some(json_target) = json_target else {
                    return Err(self.err(ch_at, "channel not found"));
                };
                let node_count = self.doc.nodes().len();
                if json_target.node.value() >= node_count {
                    return Err(self.err(
                        format!("{ch_at}/target/node"),
                        format!(
                            "node {} does not exist ({node_count} nodes)",
                            json_target.node.value()
                        ),
                    ));
                }
                if !matches!(
                    json_target.path,
                    ::gltf::json::validation::Checked::Valid(_)
                ) {
                    self.note(
                        &format!("{ch_at}/target/path"),
                        "unknown target path; channel skipped".into(),
                    );
                    continue;
                }
                let target = channel.target();
                let node = target.node().index();
                let Some(joint) = node_joint.get(node).copied().flatten() else {
                    self.note(
                        &format!("{ch_at}/target/node"),
                        format!("node {node} is not in the imported scene; channel skipped"),
                    );
                    continue;
                };
                let interpolation = match sampler.interpolation() {
                    GltfInterpolation::Linear => Interpolation::Linear,
                    GltfInterpolation::Step => Interpolation::Step,
                    GltfInterpolation::CubicSpline => Interpolation::CubicSpline,
                };
                let per_key = if interpolation == Interpolation::CubicSpline {
                    3
                } else {
                    1
                };
                let times = self.read_times(&sampler.input(), &format!("{s_at}/input"))?;
                let keys = times.len();
                let out_at = format!("{s_at}/output");
                let output = sampler.output();
                let property = target.property();
                let (components, types) = match property {
                    Property::Translation | Property::Scale => (Dimensions::Vec3, FLOAT),
                    Property::Rotation => (Dimensions::Vec4, FLOAT_OR_NORM),
                    Property::MorphTargetWeights => (Dimensions::Scalar, FLOAT_OR_NORM),
                };
                let count = self.check(&output, components, types, &out_at)?;
                let zeros = count * components.multiplicity();
                let values: Vec<f32> = match channel.reader(self.data()).read_outputs() {
                    _ if Self::zero_filled(&output) => vec![0.0; zeros],
                    Some(ReadOutputs::Translations(it)) | Some(ReadOutputs::Scales(it)) => {
                        it.flatten().collect()
                    }
                    Some(ReadOutputs::Rotations(it)) => it.into_f32().flatten().collect(),
                    Some(ReadOutputs::MorphTargetWeights(it)) => it.into_f32().collect(),
                    None => return Err(self.err(out_at, "data unavailable")),
                };
                if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                    return Err(self.err(out_at, format!("value {k} is not finite")));
                }
                let track = |target, values| Track {
                    target,
                    interpolation,
                    times: times.clone(),
                    values,
                };
                if property == Property::MorphTargetWeights {
                    let Some(instanced) = node_meshes.get(node).filter(|m| !m.is_empty()) else {
                        self.note(
                            &ch_at,
                            format!(
                                "node {node} instances no triangle mesh; weights channel skipped"
                            ),
                        );
                        continue;
                    };
                    for &mi in instanced {
                        let targets = meshes.get(mi.get()).map_or(0, |m| m.morph_targets.len());
                        if targets == 0 {
                            self.note(
                                &ch_at,
                                format!(
                                    "mesh {mi} has no morph targets; weights channel skipped \
                                     for it"
                                ),
                            );
                            continue;
                        }
                        if count != keys * per_key * targets {
                            return Err(self.err(
                                out_at,
                                format!(
                                    "{count} weights for {keys} keys of a mesh with {targets} \
                                     morph targets ({interpolation:?})"
                                ),
                            ));
                        }
                        tracks.push(track(TrackTarget::MorphWeights(mi), values.clone()));
                    }
                    continue;
                }
                if count != keys * per_key {
                    return Err(self.err(
                        out_at,
                        format!(
                            "{count} outputs for {keys} keys ({interpolation:?} needs {})",
                            keys * per_key
                        ),
                    ));
                }
                let target = match property {
                    Property::Translation => TrackTarget::Translation(joint),
                    Property::Scale => TrackTarget::Scale(joint),
                    _ => TrackTarget::Rotation(joint),
                };
                let values = if property == Property::Rotation {
                    self.unit_rotations(values, interpolation, &out_at)?
                } else {
                    values
                };
                tracks.push(track(target, values));
            }
            clips.push(Clip { name, tracks });
        }
        Ok(clips)
    }

    /// Key times: seconds, finite, `>= 0`, strictly increasing (glTF 2.0 §3.11).
    fn read_times(&self, acc: &::gltf::Accessor<'a>, at: &str) -> Result<Vec<f32>, ImportError> {
        let times = self.read_scalars(acc, at)?;
        if let Some(k) = times.iter().position(|t| !(t.is_finite() && *t >= 0.0)) {
            return Err(self.err(
                at,
                format!("key {k} time {} is negative or not finite", times[k]),
            ));
        }
        if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(self.err(
                at,
                format!(
                    "key times must increase strictly: key {} at {} follows {}",
                    k + 1,
                    times[k + 1],
                    times[k]
                ),
            ));
        }
        Ok(times)
    }

    /// Normalizes LINEAR/STEP rotation keys (warning when one is off by more than the
    /// validator's tolerance); cubic-spline keys are kept with their tangents, only reported.
    fn unit_rotations(
        &mut self,
        mut values: Vec<f32>,
        interpolation: Interpolation,
        at: &str,
    ) -> Result<Vec<f32>, ImportError> {
        let cubic = interpolation == Interpolation::CubicSpline;
        let mut off = 0usize;
        let mut worst = 0.0f32;
        for (k, q) in values.chunks_exact_mut(4).enumerate() {
            if cubic && k % 3 != 1 {
                continue;
            }
            let len = q.iter().map(|c| c * c).sum::<f32>().sqrt();
            if len.is_nan() || len <= 1e-6 {
                return Err(self.err(
                    at,
                    format!("rotation {k} has length {len}; it must be a unit quaternion"),
                ));
            }
            if (len - 1.0).abs() > UNIT_QUAT_TOLERANCE {
                off += 1;
                worst = worst.max((len - 1.0).abs());
            }
            if !cubic {
                q.iter_mut().for_each(|c| *c /= len);
            }
        }
        if off > 0 {
            let message = format!(
                "{off} rotation keys are not unit quaternions (largest |length - 1| {worst:.6}); {}",
                if cubic { "kept (cubic spline)" } else { "normalized" }
            );
            if cubic {
                self.note(at, message);
            } else {
                self.repaired(at, message);
            }
        }
        Ok(values)
    }
}

/// Triangles of a strip: `{v_i, v_(i+1+i%2), v_(i+2-i%2)}` (glTF 2.0 §3.7.2.1), degenerate
/// ones (restart tricks) dropped.
fn strip_triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    indices
        .windows(3)
        .enumerate()
        .map(|(i, w)| {
            if i % 2 == 0 {
                [w[0], w[1], w[2]]
            } else {
                [w[0], w[2], w[1]]
            }
        })
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect()
}

/// Triangles of a fan: `{v_(i+1), v_(i+2), v_0}` (glTF 2.0 §3.7.2.1), degenerate ones
/// dropped.
fn fan_triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    let Some((&first, rest)) = indices.split_first() else {
        return Vec::new();
    };
    rest.windows(2)
        .map(|w| [w[0], w[1], first])
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect()
}

/// `mesh.extras.targetNames` (the de-facto convention for morph target names).
fn target_names(mesh: &::gltf::Mesh<'_>) -> Vec<String> {
    let Some(raw) = mesh.extras().as_ref() else {
        return Vec::new();
    };
    let Ok(value) = ::gltf::json::deserialize::from_str::<::gltf::json::Value>(raw.get()) else {
        return Vec::new();
    };
    value
        .get("targetNames")
        .and_then(|v| v.as_array())
        .map(|names| {
            names
                .iter()
                .map(|n| n.as_str().unwrap_or_default().to_string())
                .collect()
        })
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use ::gltf::json::Value;

    const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/gltf/");
    const CORPUS: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/corpus/5_gltf/"
    );

    fn fixture(name: &str) -> PathBuf {
        PathBuf::from(FIXTURES).join(name)
    }

    fn import_fixture(name: &str) -> Imported {
        match import(&fixture(name)) {
            Ok(imported) => imported,
            Err(e) => panic!("{name}: {e}"),
        }
    }

    /// Imports a fixture after editing its JSON.
    fn import_edited(name: &str, edit: impl FnOnce(&mut Value)) -> Result<Imported, ImportError> {
        let path = fixture(name);
        let mut json: Value =
            ::gltf::json::deserialize::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        edit(&mut json);
        import_slice(&::gltf::json::serialize::to_vec(&json).unwrap(), &path)
    }

    /// A GLB container around `json` and `bin`.
    fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
        let mut json = json.as_bytes().to_vec();
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let mut bin = bin.to_vec();
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::new();
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        out
    }

    fn floats(values: &[f32]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    /// One triangle whose positions are `positions` (9 floats), in a GLB.
    fn triangle_glb(positions: &[f32]) -> Vec<u8> {
        let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
            "nodes":[{"name":"T","mesh":0}],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
            "buffers":[{"byteLength":36}],
            "bufferViews":[{"buffer":0,"byteLength":36}],
            "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
                          "min":[0,0,0],"max":[1,1,0]}]}"#;
        glb(json, &floats(positions))
    }

    fn json_path(e: &ImportError) -> &str {
        e.location.json_path.as_deref().unwrap_or("")
    }

    fn names(asset: &Asset) -> Vec<&str> {
        asset
            .skeleton
            .joints()
            .iter()
            .map(|j| j.name.as_str())
            .collect()
    }

    fn has_warning(warnings: &[Warning], location_part: &str, message_part: &str) -> bool {
        warnings.iter().any(|w| match w {
            Warning::Note { location, message } | Warning::Repaired { location, message } => {
                location.contains(location_part) && message.contains(message_part)
            }
            other => {
                let text = other.to_string();
                text.contains(location_part) && text.contains(message_part)
            }
        })
    }

    fn assert_close(a: &[f32], b: &[f32]) {
        assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() < 1e-5, "{a:?} vs {b:?}: {x} != {y}");
        }
    }

    /// `model_rest(joint) * inv_bind` when it is the same matrix for every palette joint of
    /// every skin (the rest pose is the bind pose up to that transform of the mesh), else
    /// `None`.
    fn rest_times_inv_bind(asset: &Asset) -> Option<Mat4> {
        let model = asset.skeleton.model_rest_matrices();
        let mut all = asset.skins.iter().flat_map(|skin| {
            skin.joints
                .iter()
                .zip(&skin.inv_bind)
                .map(|(j, ib)| model[j.get()] * *ib)
        });
        let first = all.next()?;
        all.all(|m| m.abs_diff_eq(first, 1e-4)).then_some(first)
    }

    fn bind_pose_is_rest_pose(asset: &Asset) -> bool {
        rest_times_inv_bind(asset).is_some_and(|m| m.abs_diff_eq(Mat4::IDENTITY, 1e-4))
    }

    // --- fixtures -----------------------------------------------------------------------

    #[test]
    fn skin_basic_maps_nodes_mesh_skin_and_clips() {
        let Imported { asset, warnings } = import_fixture("skin_basic.gltf");
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(asset.name, "skin_basic");
        assert_eq!(asset.meters_per_unit, Some(1.0));
        // Nodes are stored child-before-parent (Spine = node 0); the skeleton is sorted.
        assert_eq!(
            names(&asset),
            ["Hips", "Spine"],
            "the skinned mesh node Body is no joint"
        );
        let parents: Vec<_> = asset.skeleton.parents().collect();
        assert_eq!(parents, [None, Some(JointIndex(0))]);
        assert_eq!(
            asset.skeleton.joint(JointIndex(1)).rest_local.translation,
            Vec3::Y
        );

        assert_eq!(asset.meshes.len(), 1);
        let mesh = &asset.meshes[0];
        assert_eq!(mesh.name, "Body");
        assert_eq!(mesh.vertex_count(), 6);
        assert_eq!(mesh.triangles, [[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]]);
        assert_eq!(mesh.source_vertex, [0, 1, 2, 3, 4, 5]);
        assert_eq!(mesh.normals.as_ref().unwrap()[0], Vec3::Z);
        // As stored in glTF: no V flip.
        assert_eq!(mesh.uvs.as_ref().unwrap()[0], Vec2::new(0.0, 1.0));
        assert_eq!(mesh.attached_to, None, "skinned meshes are in bind space");

        assert_eq!(asset.skins.len(), 1);
        let skin = &asset.skins[0];
        assert_eq!(skin.mesh, MeshIndex(0));
        assert_eq!(skin.joints, [JointIndex(0), JointIndex(1)]);
        assert!(bind_pose_is_rest_pose(&asset));
        let row = |v| {
            skin.influences
                .vertex(v)
                .iter()
                .map(|i| (i.joint, i.weight))
                .collect::<Vec<_>>()
        };
        assert_eq!(row(0), [(0, 1.0)]);
        assert_eq!(row(2), [(0, 0.5), (1, 0.5)]);
        assert_eq!(row(5), [(1, 1.0)]);

        assert_eq!(asset.clips.len(), 2);
        let bend = &asset.clips[0];
        assert_eq!(bend.name, "bend");
        assert_eq!(bend.tracks.len(), 3);
        let rot = &bend.tracks[0];
        assert_eq!(rot.target, TrackTarget::Rotation(JointIndex(1)));
        assert_eq!(rot.interpolation, Interpolation::Linear);
        assert_eq!(rot.times, [0.0, 1.0]);
        let s = 0.5f32.sqrt();
        assert_close(&rot.values, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, s, s]);
        let step = &bend.tracks[1];
        assert_eq!(step.target, TrackTarget::Translation(JointIndex(0)));
        assert_eq!(step.interpolation, Interpolation::Step);
        assert_eq!(step.times, [0.0, 0.5, 1.0]);
        assert_close(&step.values, &[0.0, 1.0, 0.0, 0.0, 1.5, 0.0, 0.0, 1.0, 0.0]);
        let cubic = &bend.tracks[2];
        assert_eq!(cubic.target, TrackTarget::Scale(JointIndex(1)));
        assert_eq!(cubic.interpolation, Interpolation::CubicSpline);
        assert_eq!(cubic.values.len(), 2 * 3 * 3, "[in, value, out] per key");
        assert_eq!(cubic.key_value(1), [1.0, 2.0, 1.0]);
        assert_eq!(asset.clips[1].name, "animation_1");
        assert_eq!(
            asset.clips[1].tracks[0].target,
            TrackTarget::Rotation(JointIndex(0))
        );
    }

    #[test]
    fn glb_imports_like_the_gltf() {
        let gltf = import_fixture("skin_basic.gltf");
        let glb = import_fixture("skin_basic.glb");
        assert_eq!(glb.asset, gltf.asset);
        assert!(glb.warnings.is_empty(), "{:?}", glb.warnings);
    }

    #[test]
    fn weights_from_all_sets_merged_and_renormalized() {
        let Imported { asset, warnings } = import_fixture("skin_weights.gltf");
        assert_eq!(
            names(&asset),
            ["A", "B", "C"],
            "the skinned mesh node is no joint"
        );
        let skin = &asset.skins[0];
        assert_eq!(skin.joints, [JointIndex(0), JointIndex(1), JointIndex(2)]);
        assert_eq!(
            skin.inv_bind,
            vec![Mat4::IDENTITY; 3],
            "identity when absent"
        );
        let rows: Vec<Vec<(u32, f32)>> = skin
            .influences
            .rows()
            .map(|r| r.iter().map(|i| (i.joint, i.weight)).collect())
            .collect();
        // Vertex 0: 0.5 on joint 0, 0.25 (set 0) + 51/255 (set 1, normalized u8) on joint 1,
        // a zero weight on joint 2 dropped; the row (sum 0.95) rescaled to sum 1.
        assert_eq!(rows[0].len(), 2);
        assert_eq!(rows[0][0].0, 0);
        assert!((rows[0][0].1 - 0.5 / 0.95).abs() < 1e-6, "{rows:?}");
        assert_eq!(rows[0][1].0, 1);
        assert!((rows[0][1].1 - 0.45 / 0.95).abs() < 1e-6, "{rows:?}");
        assert_eq!(rows[1], [(2, 1.0)]);
        // Vertex 2 names joint 0 twice in one set.
        assert_eq!(rows[2].len(), 1);
        assert!((rows[2][0].1 - 1.0).abs() < 1e-6);
        assert!(
            has_warning(
                &warnings,
                "/meshes/0/primitives/0/attributes",
                "2 vertices list the same joint"
            ),
            "{warnings:?}"
        );
        assert!(
            warnings.iter().any(|w| matches!(
                w,
                Warning::WeightsRenormalized { source, rows: 1, max_row_sum_error }
                    if source.contains("WEIGHTS_0") && (max_row_sum_error - 0.05).abs() < 1e-6
            )),
            "{warnings:?}"
        );
        assert_eq!(asset.meshes[0].triangles, [[0, 1, 2]], "implicit indices");
    }

    #[test]
    fn morph_targets_sparse_accessors_and_weight_tracks_per_primitive() {
        let Imported { asset, warnings } = import_fixture("morph_sparse.gltf");
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(asset.meshes.len(), 2);
        for (k, mesh) in asset.meshes.iter().enumerate() {
            assert_eq!(mesh.name, format!("Face_{k}"));
            assert_eq!(mesh.attached_to, Some(JointIndex(0)));
            assert_eq!(mesh.morph_weights, [0.25, 0.0]);
            let target_names: Vec<_> = mesh.morph_targets.iter().map(|t| t.name.as_str()).collect();
            assert_eq!(target_names, ["smile", "blink"]);
            assert_eq!(
                mesh.morph_targets[0].position_deltas[2],
                Vec3::new(0.0, 0.3, 0.0)
            );
            assert!(mesh.morph_targets[0].normal_deltas.is_some());
            // Sparse, no bufferView: zeros except vertex 2.
            assert_eq!(
                mesh.morph_targets[1].position_deltas,
                [Vec3::ZERO, Vec3::ZERO, Vec3::Z]
            );
            assert!(mesh.morph_targets[1].normal_deltas.is_none());
        }
        assert_eq!(asset.meshes[0].positions[0], Vec3::ZERO);
        // Sparse over a base view: vertex 0 replaced.
        assert_eq!(asset.meshes[1].positions, [-Vec3::Z, Vec3::X, Vec3::Y]);
        let clip = &asset.clips[0];
        assert_eq!(clip.name, "talk");
        let targets: Vec<_> = clip.tracks.iter().map(|t| t.target).collect();
        assert_eq!(
            targets,
            [
                TrackTarget::MorphWeights(MeshIndex(0)),
                TrackTarget::MorphWeights(MeshIndex(1))
            ]
        );
        for t in &clip.tracks {
            assert_eq!(t.times, [0.0, 2.0]);
            assert_eq!(t.values, [0.0, 1.0, 1.0, 0.5]);
            assert_eq!(t.components(), 2);
        }
    }

    #[test]
    fn strips_and_fans_become_triangles_lines_are_skipped() {
        let Imported { asset, warnings } = import_fixture("primitive_modes.gltf");
        assert_eq!(asset.meshes.len(), 2);
        assert_eq!(asset.meshes[0].name, "Modes_0");
        assert_eq!(asset.meshes[0].triangles, [[0, 1, 2], [1, 3, 2], [2, 3, 4]]);
        assert_eq!(asset.meshes[1].name, "Modes_1");
        assert_eq!(asset.meshes[1].triangles, [[1, 2, 0], [2, 3, 0], [3, 4, 0]]);
        assert!(
            has_warning(
                &warnings,
                "/meshes/0/primitives/2/mode",
                "Lines primitive skipped"
            ),
            "{warnings:?}"
        );
    }

    #[test]
    fn strip_and_fan_helpers() {
        assert_eq!(strip_triangles(&[0, 1]), Vec::<[u32; 3]>::new());
        // A restart by repeated indices makes degenerate triangles, which are dropped.
        assert_eq!(strip_triangles(&[0, 1, 2, 3]), [[0, 1, 2], [1, 3, 2]]);
        // A restart by repeated indices makes degenerate triangles, which are dropped; the
        // winding still alternates with the position in the strip.
        assert_eq!(
            strip_triangles(&[0, 1, 2, 2, 3, 4, 5]),
            [[0, 1, 2], [2, 4, 3], [3, 4, 5]]
        );
        assert_eq!(fan_triangles(&[]), Vec::<[u32; 3]>::new());
        assert_eq!(fan_triangles(&[7, 8, 9]), [[8, 9, 7]]);
    }

    #[test]
    fn node_matrices_decompose_and_shear_is_reported() {
        let Imported { asset, warnings } = import_fixture("node_matrix.gltf");
        assert_eq!(names(&asset), ["Rotated", "Sheared", "Quat"]);
        let rotated = asset.skeleton.joint(JointIndex(0)).rest_local;
        assert_eq!(rotated.translation, Vec3::new(1.0, 2.0, 3.0));
        let expect = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
        assert!(
            rotated.rotation.abs_diff_eq(expect, 1e-6),
            "{:?}",
            rotated.rotation
        );
        assert!(rotated.scale.abs_diff_eq(Vec3::ONE, 1e-6));
        assert!(!has_warning(&warnings, "/nodes/0/", ""), "{warnings:?}");
        assert!(
            has_warning(&warnings, "/nodes/1/matrix", "not a TRS"),
            "{warnings:?}"
        );
        let quat = asset.skeleton.joint(JointIndex(2)).rest_local.rotation;
        assert_eq!(quat, Quat::IDENTITY);
        assert!(
            has_warning(&warnings, "/nodes/2/rotation", "length 2; normalized"),
            "{warnings:?}"
        );
    }

    #[test]
    fn node_names_made_unique_and_non_empty() {
        let Imported { asset, warnings } = import_fixture("node_names.gltf");
        assert_eq!(
            names(&asset),
            ["node_0_1", "arm", "arm_2", "node_0", "node_4"]
        );
        assert!(
            has_warning(&warnings, "/nodes/2/name", r#"duplicate node name "arm""#),
            "{warnings:?}"
        );
        assert!(
            has_warning(&warnings, "/nodes/0/name", "taken"),
            "{warnings:?}"
        );
        assert!(
            has_warning(&warnings, "/nodes", "2 unnamed node(s)"),
            "{warnings:?}"
        );
    }

    #[test]
    fn external_bin_is_read_relative_to_the_file() {
        let Imported { asset, .. } = import_fixture("external_bin.gltf");
        assert_eq!(asset.meshes[0].positions, [Vec3::ZERO, Vec3::X, Vec3::Y]);
        assert_eq!(asset.meshes[0].attached_to, Some(JointIndex(0)));
    }

    #[test]
    fn missing_bin_names_the_file() {
        let e = import(&fixture("missing_bin.gltf")).unwrap_err();
        assert_eq!(json_path(&e), "/buffers/0/uri");
        let text = e.to_string();
        assert!(
            text.contains("missing.bin") && text.contains("cannot read"),
            "{text}"
        );
    }

    #[test]
    fn data_uris_need_no_file_system() {
        let bytes = std::fs::read(fixture("morph_sparse.gltf")).unwrap();
        let imported = import_slice(&bytes, Path::new("/nonexistent/dir/face.gltf")).unwrap();
        assert_eq!(imported.asset.name, "face");
        assert_eq!(imported.asset.meshes.len(), 2);
    }

    // --- errors -------------------------------------------------------------------------

    #[test]
    fn empty_input() {
        let e = import_slice(b"  \n", Path::new("e.gltf")).unwrap_err();
        assert!(matches!(e.problem, Problem::Empty), "{e}");
    }

    #[test]
    fn json_syntax_error_has_line_and_column() {
        let text = b"{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [ }\n}\n";
        let e = import_slice(text, Path::new("bad.gltf")).unwrap_err();
        assert_eq!(e.location.line, Some(3), "{e}");
        assert!(e.location.column.is_some(), "{e}");
        assert!(e.to_string().starts_with("bad.gltf:3:"), "{e}");
        let e = import_slice(b"{\"asset\": {", Path::new("cut.gltf")).unwrap_err();
        assert!(matches!(e.problem, Problem::Truncated(_)), "{e}");
    }

    #[test]
    fn schema_error_has_json_pointer() {
        let e = import_edited("skin_basic.gltf", |j| j["nodes"][1]["mesh"] = 7.into()).unwrap_err();
        assert_eq!(json_path(&e), "/nodes/1/mesh", "{e}");
        assert!(e.to_string().contains("index out of range"), "{e}");
        assert_eq!(
            json_pointer(r#"meshes[0].primitives[1].attributes["JOINTS_0"]"#),
            "/meshes/0/primitives/1/attributes/JOINTS_0"
        );
        let e = import_edited("skin_basic.gltf", |j| {
            j["extensionsRequired"] = vec!["KHR_draco_mesh_compression"].into();
            j["extensionsUsed"] = vec!["KHR_draco_mesh_compression"].into();
        })
        .unwrap_err();
        assert_eq!(json_path(&e), "/extensionsRequired/0", "{e}");
        assert!(
            e.to_string()
                .contains("required extension KHR_draco_mesh_compression is not supported"),
            "{e}"
        );
        let ok = import_edited("skin_basic.gltf", |j| {
            j["extensionsRequired"] = vec!["KHR_texture_transform"].into();
            j["extensionsUsed"] = vec!["KHR_texture_transform"].into();
        })
        .unwrap();
        assert!(has_warning(
            &ok.warnings,
            "/extensionsRequired/0",
            "only affects materials"
        ));
    }

    #[test]
    fn truncated_glb_is_reported_not_panicked() {
        let bytes = std::fs::read(fixture("skin_basic.glb")).unwrap();
        let e = import_slice(&bytes[..100], Path::new("cut.glb")).unwrap_err();
        assert!(matches!(e.problem, Problem::Truncated(_)), "{e}");
        assert_eq!(e.location.byte_offset, Some(8));
        assert!(e.to_string().contains("truncated"), "{e}");
        for len in 0..bytes.len() {
            if let Ok(i) = import_slice(&bytes[..len], Path::new("cut.glb")) {
                panic!("prefix of {len} bytes imported: {:?}", i.asset.name);
            }
        }
    }

    #[test]
    fn glb_header_and_chunk_errors_have_byte_offsets() {
        let good = std::fs::read(fixture("skin_basic.glb")).unwrap();
        let mut v1 = good.clone();
        v1[4] = 1;
        let e = import_slice(&v1, Path::new("v1.glb")).unwrap_err();
        assert_eq!(e.location.byte_offset, Some(4), "{e}");
        let mut bin_first = good.clone();
        bin_first[16..20].copy_from_slice(b"BIN\0");
        let e = import_slice(&bin_first, Path::new("b.glb")).unwrap_err();
        assert_eq!(e.location.byte_offset, Some(16), "{e}");
        let e = import_slice(b"glTF\x02\0\0\0", Path::new("h.glb")).unwrap_err();
        assert!(matches!(e.problem, Problem::Truncated(_)), "{e}");
    }

    #[test]
    fn glb_byte_flips_never_panic() {
        let good = std::fs::read(fixture("skin_basic.glb")).unwrap();
        for i in 0..good.len() {
            for value in [0x00, 0xff, b'9'] {
                let mut bytes = good.clone();
                bytes[i] = value;
                let _ = import_slice(&bytes, Path::new("flip.glb"));
            }
        }
    }

    #[test]
    fn joint_index_out_of_range_names_the_joints_attribute() {
        let e = import_edited("skin_weights.gltf", |j| {
            j["skins"][0]["joints"] = vec![1, 2].into()
        })
        .unwrap_err();
        assert_eq!(
            json_path(&e),
            "/meshes/0/primitives/0/attributes/JOINTS_0",
            "{e}"
        );
        assert!(
            e.to_string()
                .contains("names joint 2, but skin 0 has 2 joints"),
            "{e}"
        );
    }

    #[test]
    fn nan_position_is_an_error() {
        let e = import_slice(
            &triangle_glb(&[0.0, 0.0, 0.0, 1.0, f32::NAN, 0.0, 0.0, 1.0, 0.0]),
            Path::new("nan.glb"),
        )
        .unwrap_err();
        assert_eq!(json_path(&e), "/meshes/0/primitives/0/attributes/POSITION");
        assert!(e.to_string().contains("element 1 is not finite"), "{e}");
        let ok = import_slice(
            &triangle_glb(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
            Path::new("ok.glb"),
        )
        .unwrap();
        assert_eq!(ok.asset.meshes[0].positions.len(), 3);
    }

    #[test]
    fn accessor_without_buffer_view_is_zeros() {
        // glTF 2.0 §3.6.2.1; gltf-json 1.4 alone would reject it as missing bufferView.
        let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
            "nodes":[{"mesh":0}],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
            "accessors":[{"componentType":5126,"count":3,"type":"VEC3",
                          "min":[0,0,0],"max":[0,0,0]}]}"#;
        let ok = import_slice(json.as_bytes(), Path::new("zeros.gltf")).unwrap();
        assert_eq!(ok.asset.meshes[0].positions, [Vec3::ZERO; 3]);
        let huge = json.replace(r#""count":3"#, r#""count":100000000"#);
        let e = import_slice(huge.as_bytes(), Path::new("huge.gltf")).unwrap_err();
        assert!(e.to_string().contains("no bufferView"), "{e}");
    }

    #[test]
    fn accessor_data_out_of_range_is_an_error() {
        let e = import_edited("skin_basic.gltf", |j| {
            j["accessors"][0]["byteOffset"] = 4.into()
        })
        .unwrap_err();
        assert_eq!(
            json_path(&e),
            "/meshes/0/primitives/0/attributes/POSITION",
            "{e}"
        );
        assert!(e.to_string().contains("which holds 72 bytes"), "{e}");
        let e = import_edited("skin_basic.gltf", |j| {
            j["bufferViews"][4]["byteLength"] = 100_000.into()
        })
        .unwrap_err();
        assert_eq!(
            json_path(&e),
            "/meshes/0/primitives/0/attributes/JOINTS_0",
            "{e}"
        );
        assert!(e.to_string().contains("buffer view 4 spans"), "{e}");
        let e = import_edited("skin_basic.gltf", |j| j["accessors"][0]["count"] = 0.into())
            .unwrap_err();
        assert!(e.to_string().contains("count 0"), "{e}");
        let e = import_edited("skin_basic.gltf", |j| {
            j["accessors"][0]["type"] = "VEC2".into()
        })
        .unwrap_err();
        assert!(
            e.to_string()
                .contains("is VEC2 of FLOAT; expected VEC3 of FLOAT"),
            "{e}"
        );
        let e = import_edited("skin_basic.gltf", |j| {
            j["buffers"][0]["byteLength"] = 5000.into()
        })
        .unwrap_err();
        assert!(matches!(e.problem, Problem::Truncated(_)), "{e}");
        assert_eq!(json_path(&e), "/buffers/0");
    }

    #[test]
    fn node_hierarchy_errors_name_the_children_entry() {
        let doc = |nodes: &str| {
            format!(r#"{{"asset":{{"version":"2.0"}},"nodes":{nodes}}}"#).into_bytes()
        };
        let e = import_slice(
            &doc(r#"[{"children":[2]},{"children":[2]},{}]"#),
            Path::new("p.gltf"),
        )
        .unwrap_err();
        assert_eq!(json_path(&e), "/nodes/1/children/0", "{e}");
        assert!(e.to_string().contains("already a child of node 0"), "{e}");
        let e = import_slice(
            &doc(r#"[{"children":[1]},{"children":[0]}]"#),
            Path::new("c.gltf"),
        )
        .unwrap_err();
        assert!(e.to_string().contains("cycle"), "{e}");
        assert!(json_path(&e).ends_with("/children"), "{e}");
        let e = import_slice(&doc(r#"[{"children":[0]}]"#), Path::new("s.gltf")).unwrap_err();
        assert_eq!(json_path(&e), "/nodes/0/children/0", "{e}");
        // No scenes: every node, with a note.
        let ok = import_slice(
            &doc(r#"[{"children":[1]},{"name":"b"}]"#),
            Path::new("n.gltf"),
        )
        .unwrap();
        assert_eq!(names(&ok.asset), ["node_0", "b"]);
        assert!(has_warning(&ok.warnings, "/nodes", "no scenes"));
    }

    #[test]
    fn bad_key_times_are_errors() {
        let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
            "nodes":[{"name":"J"}],
            "animations":[{"samplers":[{"input":0,"output":1}],
                           "channels":[{"sampler":0,"target":{"node":0,"path":"translation"}}]}],
            "buffers":[{"byteLength":32}],
            "bufferViews":[{"buffer":0,"byteLength":8},{"buffer":0,"byteOffset":8,"byteLength":24}],
            "accessors":[{"bufferView":0,"componentType":5126,"count":2,"type":"SCALAR",
                          "min":[0],"max":[1]},
                         {"bufferView":1,"componentType":5126,"count":2,"type":"VEC3"}]}"#;
        let bin = |t0: f32, t1: f32| floats(&[t0, t1, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        let ok = import_slice(&glb(json, &bin(0.0, 1.0)), Path::new("t.glb")).unwrap();
        assert_eq!(ok.asset.clips[0].tracks[0].times, [0.0, 1.0]);
        let e = import_slice(&glb(json, &bin(1.0, 1.0)), Path::new("t.glb")).unwrap_err();
        assert_eq!(json_path(&e), "/animations/0/samplers/0/input", "{e}");
        assert!(e.to_string().contains("increase strictly"), "{e}");
        let e = import_slice(&glb(json, &bin(-1.0, 1.0)), Path::new("t.glb")).unwrap_err();
        assert!(e.to_string().contains("negative"), "{e}");
    }

    #[test]
    fn base64_and_percent_decoding() {
        assert_eq!(decode_base64("TWFu").unwrap(), b"Man");
        assert_eq!(decode_base64("TWE=").unwrap(), b"Ma");
        assert_eq!(decode_base64("TQ==").unwrap(), b"M");
        assert_eq!(decode_base64("").unwrap(), b"");
        assert!(decode_base64("T").is_none());
        assert!(decode_base64("TW!u").is_none());
        assert_eq!(percent_decode("a%20b%2").unwrap(), "a b%2");
        assert!(percent_decode("%ff").is_none());
    }

    // --- corpus -------------------------------------------------------------------------

    /// A corpus file, or `None` (with a message) when the corpus is absent; on CI a missing
    /// corpus is a failure.
    fn corpus(rel: &str) -> Option<PathBuf> {
        let path = PathBuf::from(CORPUS).join(rel);
        if path.exists() {
            return Some(path);
        }
        if std::env::var_os("CI").is_some() {
            panic!("corpus file {} is missing", path.display());
        }
        eprintln!("skipping: corpus file {} is absent", path.display());
        None
    }

    fn import_corpus(rel: &str) -> Option<Imported> {
        let path = corpus(rel)?;
        Some(import(&path).unwrap_or_else(|e| panic!("{e}")))
    }

    /// Every track of every clip has `keys` keys from `first` to `last` seconds.
    fn assert_keys(clip: &Clip, tracks: usize, keys: usize, first: f32, last: f32) {
        assert_eq!(clip.tracks.len(), tracks, "{}", clip.name);
        for t in &clip.tracks {
            assert_eq!(t.times.len(), keys, "{:?}", t.target);
            assert!((t.times[0] - first).abs() < 1e-4, "{:?}", t.times);
            assert!((t.times[keys - 1] - last).abs() < 1e-4, "{:?}", t.times);
        }
    }

    #[test]
    fn corpus_rigged_simple() {
        let Some(Imported { asset, warnings }) =
            import_corpus("khronos_samples__nobuyuki83_delfem2/RiggedSimple.glb")
        else {
            return;
        };
        assert_eq!(
            asset.skeleton.len(),
            4,
            "5 nodes less the skinned mesh node"
        );
        assert_eq!(asset.meshes.len(), 1);
        assert_eq!(asset.meshes[0].name, "Cylinder");
        assert_eq!(asset.meshes[0].vertex_count(), 96);
        assert_eq!(asset.meshes[0].triangles.len(), 564 / 3);
        assert_eq!(asset.skins[0].joints.len(), 2);
        // COLLADA2GLTF: rest * inverse bind is the root node's Z-up to Y-up matrix for
        // every joint (bind pose = rest pose seen through the root).
        let root = asset.skeleton.joint(JointIndex(0)).rest_local.to_mat4();
        assert!(rest_times_inv_bind(&asset).is_some_and(|m| m.abs_diff_eq(root, 1e-4)));
        assert!(root.abs_diff_eq(Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2), 1e-6));
        assert_eq!(asset.clips.len(), 1);
        assert_eq!(asset.clips[0].name, "animation_0");
        assert_keys(&asset.clips[0], 6, 3, 0.041_666, 2.083_333);
        // The skinned mesh node sits under the Z-up-to-Y-up root matrix.
        assert!(has_warning(
            &warnings,
            "/nodes/1",
            "skinned mesh node has a transform"
        ));
        assert!(has_warning(&warnings, "/nodes", "4 unnamed node(s)"));
    }

    #[test]
    fn corpus_rigged_figure() {
        let Some(Imported { asset, warnings }) =
            import_corpus("khronos_samples__nobuyuki83_delfem2/RiggedFigure.glb")
        else {
            return;
        };
        assert_eq!(
            asset.skeleton.len(),
            21,
            "22 nodes less the skinned mesh node"
        );
        assert_eq!(asset.meshes.len(), 1);
        assert_eq!(asset.meshes[0].name, "Proxy");
        assert_eq!(asset.meshes[0].vertex_count(), 370);
        assert_eq!(asset.meshes[0].triangles.len(), 768 / 3);
        assert_eq!(asset.skins[0].joints.len(), 19);
        // COLLADA2GLTF: rest * inverse bind is the root node's Z-up to Y-up matrix for
        // every joint (bind pose = rest pose seen through the root).
        let root = asset.skeleton.joint(JointIndex(0)).rest_local.to_mat4();
        assert!(rest_times_inv_bind(&asset).is_some_and(|m| m.abs_diff_eq(root, 1e-4)));
        assert!(root.abs_diff_eq(Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2), 1e-6));
        assert_eq!(asset.clips.len(), 1);
        assert_keys(&asset.clips[0], 57, 2, 0.0, 1.25);
        assert!(
            has_warning(&warnings, "WEIGHTS_0", "renormalized 31 weight rows"),
            "{warnings:?}"
        );
    }

    #[test]
    fn corpus_cesium_man() {
        let Some(Imported { asset, warnings }) =
            import_corpus("khronos_samples__nobuyuki83_delfem2/CesiumMan.glb")
        else {
            return;
        };
        assert_eq!(
            asset.skeleton.len(),
            21,
            "22 nodes less the skinned mesh node"
        );
        assert_eq!(asset.meshes.len(), 1);
        let mesh = &asset.meshes[0];
        assert_eq!(mesh.name, "Cesium_Man");
        assert_eq!(mesh.vertex_count(), 3273);
        assert_eq!(mesh.triangles.len(), 14016 / 3);
        assert!(mesh.uvs.is_some() && mesh.normals.is_some());
        assert_eq!(asset.skins[0].joints.len(), 19);
        assert!(asset.skins[0].influences.max_per_vertex() <= 4);
        // COLLADA2GLTF: rest * inverse bind is the root node's Z-up to Y-up matrix for
        // every joint (bind pose = rest pose seen through the root).
        let root = asset.skeleton.joint(JointIndex(0)).rest_local.to_mat4();
        assert!(rest_times_inv_bind(&asset).is_some_and(|m| m.abs_diff_eq(root, 1e-4)));
        assert!(root.abs_diff_eq(Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2), 1e-6));
        assert_eq!(asset.clips.len(), 1);
        assert_keys(&asset.clips[0], 57, 49, 0.0, 2.0);
        assert!(
            has_warning(&warnings, "WEIGHTS_0", "renormalized 210 weight rows"),
            "{warnings:?}"
        );
    }

    #[test]
    fn corpus_simple_skin() {
        let Some(Imported { asset, warnings }) =
            import_corpus("bevy_assets__bevyengine_bevy/SimpleSkin.gltf")
        else {
            return;
        };
        assert_eq!(asset.skeleton.len(), 3);
        // The skinned mesh node is the parent of the joints.
        let parents: Vec<_> = asset.skeleton.parents().collect();
        assert_eq!(parents, [None, Some(JointIndex(0)), Some(JointIndex(1))]);
        assert_eq!(asset.meshes[0].name, "mesh_0");
        assert_eq!(asset.meshes[0].vertex_count(), 10);
        assert_eq!(asset.meshes[0].triangles.len(), 8);
        assert_eq!(asset.skins[0].joints, [JointIndex(1), JointIndex(2)]);
        // The inverse binds place the mesh 0.5 to the -X of the rest pose.
        let offset = rest_times_inv_bind(&asset).unwrap();
        assert!(offset.abs_diff_eq(Mat4::from_translation(Vec3::new(-0.5, 0.0, 0.0)), 1e-6));
        assert_eq!(asset.clips.len(), 1);
        assert_keys(&asset.clips[0], 1, 12, 0.0, 5.5);
        // Keys are up to 2.3e-4 off unit length: normalized silently (within tolerance).
        for q in asset.clips[0].tracks[0].values.chunks_exact(4) {
            let len = q.iter().map(|c| c * c).sum::<f32>().sqrt();
            assert!((len - 1.0).abs() < 1e-6, "{q:?}");
        }
        assert!(
            has_warning(&warnings, "/scenes", "no default scene"),
            "{warnings:?}"
        );
    }

    #[test]
    fn corpus_blender_skinned_cylinder() {
        let Some(Imported { asset, warnings }) =
            import_corpus("blender_io_roundtrip__KhronosGroup/03_skinned_cylinder.gltf")
        else {
            return;
        };
        // Nodes are stored children first; the skeleton is parents first.
        assert_eq!(
            names(&asset),
            [
                "Root",
                "Cylinder",
                "Root.001",
                "Joint_One",
                "Joint_Two",
                "Joint_Three",
                "Joint_Four",
                "Camera"
            ]
        );
        assert_eq!(asset.meshes[0].name, "Cylinder");
        assert_eq!(asset.meshes[0].vertex_count(), 750);
        assert_eq!(asset.meshes[0].triangles.len(), 948 / 3);
        assert!(asset.meshes[0].uvs.is_some());
        let palette: Vec<&str> = asset.skins[0]
            .joints
            .iter()
            .map(|j| asset.skeleton.joint(*j).name.as_str())
            .collect();
        assert_eq!(
            palette,
            ["Joint_One", "Joint_Two", "Joint_Three", "Joint_Four"]
        );
        // The rest pose is bent (Joint_Three 30 degrees, Joint_Four 15 more about X), the
        // bind pose straight: rest * inverse bind is the identity for the first two only.
        let model = asset.skeleton.model_rest_matrices();
        let skin = &asset.skins[0];
        let offsets: Vec<bool> = skin
            .joints
            .iter()
            .zip(&skin.inv_bind)
            .map(|(j, ib)| (model[j.get()] * *ib).abs_diff_eq(Mat4::IDENTITY, 1e-4))
            .collect();
        assert_eq!(offsets, [true, true, false, false]);
        assert_eq!(asset.clips.len(), 1);
        assert_eq!(asset.clips[0].name, "SkeletonAnimation_Root.001");
        assert_keys(&asset.clips[0], 12, 49, 0.0, 2.0);
        assert!(warnings.is_empty(), "{warnings:?}");
    }

    /// The Khronos validator's negative tests: each may import or fail, never panic.
    #[test]
    fn corpus_validator_negative_tests_never_panic() {
        let Some(dir) = corpus("validator_negative_tests__KhronosGroup") else {
            return;
        };
        let mut files = Vec::new();
        let mut stack = vec![dir];
        while let Some(d) = stack.pop() {
            for entry in std::fs::read_dir(&d).unwrap() {
                let p = entry.unwrap().path();
                if p.is_dir() {
                    stack.push(p);
                } else if p.extension().is_some_and(|e| e == "gltf" || e == "glb") {
                    files.push(p);
                }
            }
        }
        files.sort();
        assert!(!files.is_empty());
        for file in &files {
            let result = std::panic::catch_unwind(|| import(file));
            match result {
                Ok(Ok(i)) => eprintln!("ok   {}: {} warnings", file.display(), i.warnings.len()),
                Ok(Err(e)) => eprintln!("err  {e}"),
                Err(_) => panic!("{} panicked", file.display()),
            }
        }
    }
}
