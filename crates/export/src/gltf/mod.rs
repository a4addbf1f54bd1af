//! glTF 2.0 output: `.glb` (one binary file) or `.gltf` + `.bin`.
//!
//! What the document holds (node `i` is skeleton joint `i`):
//! - one node per joint, named after it, with its rest TRS (identity components omitted)
//!   and children from the parent links; skeleton roots are scene roots;
//! - an extra identity root node named `rigport_root` above all skeleton roots, only when a
//!   skin's joints have no common ancestor (glTF requires one; validator
//!   `SKIN_NO_COMMON_ROOT`);
//! - one mesh per model [`Mesh`](rigport_model::Mesh), one `TRIANGLES` primitive each, with
//!   `POSITION` (min/max), unit `NORMAL` (given or computed), `JOINTS_n` /
//!   `WEIGHTS_n` for skinned meshes, and morph targets (`POSITION` with min/max, `NORMAL`),
//!   target names in `mesh.extras.targetNames`;
//! - one node per mesh: at the scene root without transform for a skinned mesh (named
//!   after [`Mesh::node_name`](rigport_model::Mesh::node_name) when set), else a child of
//!   the joint it is attached to (or a scene root); except that an unskinned mesh whose
//!   `node_name` is its joint's name goes onto that joint's node itself (when it is the
//!   only such mesh), as it was in the source;
//! - every material, in order, with the textures, samplers and images it uses
//!   (`material.rs`): images in the binary buffer for `.glb`, files beside a `.gltf`;
//! - `TEXCOORD_0..n` from [`Mesh::uvs`](rigport_model::Mesh::uvs) and
//!   [`Mesh::extra_uvs`](rigport_model::Mesh::extra_uvs);
//! - one skin per binding, `skeleton` = the palette's nearest common ancestor;
//! - one animation per clip, one sampler per track.
//!
//! glTF is +Y up and in metres (spec, "Coordinate System and Units"). An asset whose
//! [`SceneFrame`](rigport_model::SceneFrame) is Z-up, placed by a transform above its
//! skeleton, or whose [`meters_per_unit`](rigport_model::Asset::meters_per_unit) is stated
//! and not 1 is converted by **transforming the data** (joint rest and animation
//! translations, root joints, inverse bind matrices, mesh points, normals and morph deltas;
//! see `frame.rs`), not by a corrective root node, so a skinned mesh's node stays at the
//! scene root without transform. A CMU ASF (`:units length 0.45`) comes out in metres, a
//! Blender USD (Z-up, `metersPerUnit = 0.01`, `scale 100`) Y-up in metres; sources that
//! state no unit (OBJ, Pinocchio, BVH, CSCI 520) keep their numbers.
//!
//! Everything binary lives in one buffer; output bytes depend only on the input (no hash
//! order, no time stamps).

mod animation;
mod buffer;
pub(crate) mod document;
mod frame;
pub(crate) mod material;
pub(crate) mod meshopt;
#[cfg(test)]
mod tests;
pub(crate) mod weights;

use std::path::{Path, PathBuf};

use gltf_json as json;
use json::validation::USize64;
use rigport_model::{Asset, Compression, Warning};

use crate::ExportError;
use rigport_atomic::TempFile;

/// Options for the glTF exporters.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfOptions {
    /// Most joint influences kept per vertex, `1..=8`. Up to 4 fit in `JOINTS_0` /
    /// `WEIGHTS_0`; 5 to 8 add `JOINTS_1` / `WEIGHTS_1` (written only when some vertex
    /// actually uses a fifth influence). Many viewers read only the first set, which always
    /// holds each vertex's 4 largest weights. Default 4.
    pub max_influences: usize,
    /// Write compactly, as a key reducer measured it: LINEAR and STEP rotation outputs as
    /// 16-bit normalized integers (`SHORT`, `normalized: true`; core glTF 2.0 §3.11), each
    /// key rounded by [`rigport_model::quantize::rotation_to_i16`], half the bytes of
    /// floats; and a skin's weights as normalized bytes when every weight is exactly
    /// `k / 255` (a bone mesh's 0 and 1: lossless, a quarter of the bytes). Default `false`.
    pub compact: bool,
    /// Skinned meshes without morph targets written with `KHR_mesh_quantization`
    /// (declared required): positions as 16-bit integers on the mesh's
    /// [`rigport_model::quantize::PositionGrid`] (folded into the skin's inverse bind
    /// matrices; a vertex moves by at most the grid's `max_error` times the skinning
    /// matrices' scale), normals as 8-bit normalized components. Default `false`.
    pub quantize_mesh: bool,
    /// With `quantize_mesh`: the most the grid may move a vertex, in the asset's unit (the
    /// coarsest [`rigport_model::quantize::PositionGrid::within`] it; 0: the finest grid,
    /// 65,534 steps along the longest side). A coarser grid leaves less for
    /// `EXT_meshopt_compression` to store. Default 0.
    pub position_error: f32,
    /// Compression beyond core glTF: with [`Compression::Meshopt`], animation data is
    /// written through `EXT_meshopt_compression` (declared required): with
    /// `compact`, rotations through its `QUATERNION` filter and translations and
    /// scales through its `EXPONENTIAL` filter ([`crate::meshopt_rotation_as_written`],
    /// [`crate::meshopt_vector_as_written`] say what a reader gets), else exact floats.
    /// Default none.
    pub compression: Compression,
    /// With `compact`: per clip (in the asset's order), per track, the bits of that LINEAR
    /// or STEP rotation track's components, as the key reducer measured them: with
    /// [`Compression::Meshopt`] the `QUATERNION` filter's bits (4 to 16,
    /// [`crate::meshopt_rotations_as_written_bits`]); without, any value under 16 writes
    /// 8-bit normalized components (`BYTE`, [`rigport_model::quantize::rotation_as_i8`]).
    /// 0, or a clip or track past the end: 16. Default empty (16 everywhere).
    pub rotation_bits: Vec<Vec<u8>>,
    /// With [`Compression::Meshopt`] and `compact`: the `EXPONENTIAL` filter's mantissa
    /// bits for translation and scale keys, 16 ([`crate::meshopt_vector_as_written_16`])
    /// or, for any other value, 20 ([`crate::meshopt_vector_as_written`]). Default 0.
    pub vector_bits: u8,
}

impl Default for GltfOptions {
    fn default() -> Self {
        Self {
            max_influences: 4,
            compact: false,
            quantize_mesh: false,
            position_error: 0.0,
            compression: Compression::None,
            rotation_bits: Vec::new(),
            vector_bits: 0,
        }
    }
}

/// A binary glTF (`.glb`) file in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct Exported {
    /// The complete `.glb` file: 12-byte header, JSON chunk (space-padded to 4 bytes), then
    /// a BIN chunk (zero-padded) when the asset has any binary data.
    pub glb: Vec<u8>,
    /// Lossy or repairing steps taken (dropped influences, repaired vertices, dropped
    /// tracks...), in the order they happened.
    pub warnings: Vec<Warning>,
}

/// A JSON glTF (`.gltf`) file and its binary buffer, in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportedSplit {
    /// The `.gltf` JSON, UTF-8, pretty-printed (stable field order).
    pub json: Vec<u8>,
    /// The buffer the JSON refers to by the `bin_uri` given (a multiple of 4 bytes long).
    /// Empty when the asset has no binary data; the JSON then declares no buffer.
    pub bin: Vec<u8>,
    /// The image files the JSON refers to, to be written beside it (images no material
    /// uses are not written).
    pub images: Vec<ImageFile>,
    /// As [`Exported::warnings`].
    pub warnings: Vec<Warning>,
}

/// An image file that a `.gltf` refers to by a relative URI.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageFile {
    /// The URI as written in the JSON: `<bin_uri stem>_<name>.<ext>` (see [`to_gltf`]).
    pub uri: String,
    /// The encoded image, as in the asset.
    pub bytes: Vec<u8>,
}

/// Length of a quaternion `[x, y, z, w]`, in `f64`.
///
/// Quaternion arithmetic here is scalar `f64`, not glam's `Vec4` (SIMD on some targets,
/// with a different summation order), so the output bytes are the same on every platform.
pub(crate) fn quat_length(q: [f32; 4]) -> f64 {
    q.iter()
        .map(|&c| f64::from(c) * f64::from(c))
        .sum::<f64>()
        .sqrt()
}

/// `q / |q|`, computed in `f64` (see [`quat_length`]); `q` must not be degenerate.
pub(crate) fn unit_quat(q: [f32; 4]) -> [f32; 4] {
    let len = quat_length(q);
    q.map(|c| (f64::from(c) / len) as f32)
}

/// The dot product of two quaternions, in `f64`.
pub(crate) fn quat_dot(a: [f32; 4], b: [f32; 4]) -> f64 {
    a.iter()
        .zip(&b)
        .map(|(&x, &y)| f64::from(x) * f64::from(y))
        .sum()
}

/// GLB header magic `glTF` (glTF 2.0 §4, "GLB File Format Specification").
const GLB_MAGIC: u32 = 0x4654_6C67;
/// GLB container version.
const GLB_VERSION: u32 = 2;
/// Chunk type `JSON`.
const CHUNK_JSON: u32 = 0x4E4F_534A;
/// Chunk type `BIN\0`.
const CHUNK_BIN: u32 = 0x004E_4942;

/// Exports `asset` as one binary glTF (`.glb`) file in memory.
///
/// The asset is checked first ([`Asset::validate`] plus the exporter's own rules); nothing
/// is built unless it passes.
///
/// # Errors
/// [`ExportError::MaxInfluences`], [`ExportError::Invalid`] listing every problem,
/// [`ExportError::TooLarge`] when the data exceeds GLB's 32-bit lengths,
/// [`ExportError::Json`] if serialization fails.
pub fn to_glb(asset: &Asset, opts: &GltfOptions) -> Result<Exported, ExportError> {
    let mut built = document::build(asset, opts, &material::ImagePlacement::Embedded)?;
    if !built.bin.is_empty() {
        built.root.buffers.push(buffer_entry(built.bin.len(), None));
    }
    let json = finish_json(built.root, built.compressed.as_ref(), false, opts.compact)?;
    let glb = glb_container(json, &built.bin)?;
    Ok(Exported {
        glb,
        warnings: built.warnings,
    })
}

/// Exports `asset` as a JSON glTF document and its binary buffer, in memory.
///
/// `bin_uri` is written verbatim as the buffer's `uri`: a relative URI reference, already
/// percent-encoded (e.g. `"walk.bin"`, `"my%20rig.bin"`). [`write_gltf`] encodes file names
/// itself. Images are referred to by URIs beside it: `<stem>_<image name>.<ext>` with
/// `<stem>` the `bin_uri` without `.bin` and the image name reduced to `[A-Za-z0-9_-]`
/// (`walk_skin.png`); their bytes are in [`ExportedSplit::images`].
///
/// # Errors
/// As [`to_glb`], except that there is no size limit.
pub fn to_gltf(
    asset: &Asset,
    opts: &GltfOptions,
    bin_uri: &str,
) -> Result<ExportedSplit, ExportError> {
    let stem = bin_uri.strip_suffix(".bin").unwrap_or(bin_uri);
    let uris = crate::labels::image_file_names(stem, asset);
    let placement = material::ImagePlacement::Uris(&uris);
    let mut built = document::build(asset, opts, &placement)?;
    if !built.bin.is_empty() {
        built
            .root
            .buffers
            .push(buffer_entry(built.bin.len(), Some(bin_uri.to_owned())));
    }
    let mut json = finish_json(built.root, built.compressed.as_ref(), true, opts.compact)?;
    json.push(b'\n');
    let images = asset
        .images
        .iter()
        .zip(uris)
        .enumerate()
        .filter(|(k, _)| crate::labels::image_used(asset, *k))
        .map(|(_, (image, uri))| ImageFile {
            uri,
            bytes: image.bytes.clone(),
        })
        .collect();
    Ok(ExportedSplit {
        json,
        bin: built.bin,
        images,
        warnings: built.warnings,
    })
}

/// Exports `asset` to `path`: a `.glb` file, or a `.gltf` file plus `<stem>.bin` beside it
/// (chosen by the extension, case-insensitive). Same as [`prepare_gltf`] followed by
/// [`PreparedGltf::write`].
///
/// # Errors
/// Those of [`prepare_gltf`] and [`PreparedGltf::write`]. On error no output or temporary
/// file is left (see [`PreparedGltf::write`] for the one exception).
pub fn write_gltf(
    asset: &Asset,
    path: &Path,
    opts: &GltfOptions,
) -> Result<Vec<Warning>, ExportError> {
    let prepared = prepare_gltf(asset, path, opts)?;
    prepared.write()?;
    Ok(prepared.warnings)
}

/// An export to a file, built in memory and not yet written, so that the caller can look at
/// the warnings (and, say, refuse to write under `--deny-warnings`) before any file changes.
#[derive(Clone, Debug, PartialEq)]
pub struct PreparedGltf {
    path: PathBuf,
    files: Files,
    warnings: Vec<Warning>,
}

/// The bytes of a prepared export.
#[derive(Clone, Debug, PartialEq)]
enum Files {
    /// One `.glb`.
    Glb(Vec<u8>),
    /// `.gltf` JSON and, unless empty, the `.bin` to write at `bin_path`.
    Split {
        json: Vec<u8>,
        bin: Vec<u8>,
        bin_path: PathBuf,
        /// Image files to write beside the `.gltf`: path and bytes.
        images: Vec<(PathBuf, Vec<u8>)>,
    },
}

/// Builds the export of `asset` to `path` in memory: `.glb`, or `.gltf` whose buffer is
/// `<stem>.bin` beside it (the URI percent-encoded), chosen by the extension
/// (case-insensitive). Nothing is written until [`PreparedGltf::write`].
///
/// # Errors
/// [`ExportError::UnsupportedExtension`] for any other extension (checked before any work),
/// and the errors of [`to_glb`] / [`to_gltf`].
pub fn prepare_gltf(
    asset: &Asset,
    path: &Path,
    opts: &GltfOptions,
) -> Result<PreparedGltf, ExportError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let (files, warnings) = match ext.as_deref() {
        Some("glb") => {
            let out = to_glb(asset, opts)?;
            (Files::Glb(out.glb), out.warnings)
        }
        Some("gltf") => {
            check_not_symlink(path)?;
            let bin_path = path.with_extension("bin");
            let bin_name = bin_path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let out = to_gltf(asset, opts, &percent_encode(&bin_name))?;
            let stem = bin_name.strip_suffix(".bin").unwrap_or(&bin_name);
            let names = crate::labels::image_file_names(stem, asset);
            let images = names
                .into_iter()
                .enumerate()
                .filter(|(k, _)| crate::labels::image_used(asset, *k))
                .map(|(_, name)| path.with_file_name(name))
                .zip(out.images.into_iter().map(|i| i.bytes))
                .collect();
            let files = Files::Split {
                json: out.json,
                bin: out.bin,
                bin_path,
                images,
            };
            (files, out.warnings)
        }
        _ => {
            return Err(ExportError::UnsupportedExtension {
                path: PathBuf::from(path),
            })
        }
    };
    Ok(PreparedGltf {
        path: path.to_path_buf(),
        files,
        warnings,
    })
}

impl PreparedGltf {
    /// The bytes [`PreparedGltf::write`] writes, over every file.
    pub fn byte_len(&self) -> u64 {
        match &self.files {
            Files::Glb(glb) => glb.len() as u64,
            Files::Split {
                json, bin, images, ..
            } => {
                (json.len() + bin.len() + images.iter().map(|(_, b)| b.len()).sum::<usize>()) as u64
            }
        }
    }

    /// Lossy or repairing steps taken, as [`Exported::warnings`].
    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    /// The main output file (`.glb` or `.gltf`).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes the files atomically: each goes to a temporary file in the same directory,
    /// then is renamed over its target (only regular files are replaced; a `.glb` that is
    /// a symbolic link is followed and its target replaced, see [`crate::write_atomic`]; a
    /// `.gltf` that is one is refused, as by [`prepare_gltf`], and a `.bin` that is one is
    /// followed). For `.gltf`
    /// both temporary files are written first, then the `.bin` is renamed, then the
    /// `.gltf`, so a reader that finds the new `.gltf` finds its buffer, and a `.gltf`
    /// never names a missing `.bin`. No `.bin` is written when the asset has no binary data.
    ///
    /// # Errors
    /// [`ExportError::Io`] naming the file that could not be written. No output or
    /// temporary file is left then. If the final `.gltf` rename fails after the `.bin`
    /// rename succeeded, the previous `.bin` is put back (kept meanwhile as a hard link;
    /// where the file system cannot link, the new `.bin` stays when a `.gltf` was there,
    /// so that `.gltf` still finds a buffer, and is removed otherwise).
    pub fn write(&self) -> Result<(), ExportError> {
        let io_err = |path: &Path| {
            let path = path.to_path_buf();
            move |source| ExportError::Io { path, source }
        };
        let path = self.path.as_path();
        match &self.files {
            Files::Glb(glb) => crate::write_atomic(path, glb).map_err(io_err(path)),
            Files::Split {
                json,
                bin,
                bin_path,
                images,
            } => {
                check_not_symlink(path)?;
                let target = rigport_atomic::check_output(path).map_err(io_err(path))?;
                // Images first (each atomically), so the new `.gltf` never names a missing
                // image; a failure later leaves them in place.
                for (image_path, bytes) in images {
                    crate::write_atomic(image_path, bytes).map_err(io_err(image_path))?;
                }
                let bin_target = if bin.is_empty() {
                    None
                } else {
                    Some(rigport_atomic::check_output(bin_path).map_err(io_err(bin_path))?)
                };
                let json_tmp = TempFile::create_beside(&target, json).map_err(io_err(path))?;
                let Some(bin_target) = bin_target else {
                    return json_tmp.persist(&target).map_err(io_err(path));
                };
                let bin_tmp =
                    TempFile::create_beside(&bin_target, bin).map_err(io_err(bin_path))?;
                let backup = TempFile::backup_of(&bin_target);
                let had_gltf = target.is_file();
                bin_tmp.persist(&bin_target).map_err(io_err(bin_path))?;
                if let Err(e) = json_tmp.persist(&target) {
                    // Best effort: the error to report is the rename's.
                    match backup {
                        Some(old) => {
                            let _ = old.persist(&bin_target);
                        }
                        None if !had_gltf => {
                            let _ = std::fs::remove_file(&bin_target);
                        }
                        None => {}
                    }
                    return Err(io_err(path)(e));
                }
                Ok(())
            }
        }
    }
}

/// Refuses a `.gltf` output that is a symbolic link. Its buffer URI is relative, and
/// readers resolve it against the folder of the path they were given: a `.bin` beside the
/// link's target is missed by readers that open the link, one beside the link by readers
/// that open the target. `.glb` and `.usda` outputs follow links ([`crate::write_atomic`]).
fn check_not_symlink(path: &Path) -> Result<(), ExportError> {
    let is_link = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink());
    if is_link {
        return Err(ExportError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "it is a symbolic link, and a .gltf finds its .bin relative to its own folder; write to the link's target or to a .glb",
            ),
        });
    }
    Ok(())
}

/// The one buffer entry.
fn buffer_entry(len: usize, uri: Option<String>) -> json::Buffer {
    json::Buffer {
        byte_length: USize64::from(len),
        name: None,
        uri,
        extensions: None,
        extras: None,
    }
}

/// The document's JSON; with compressed views, the fallback buffer (buffer 1, no data),
/// each view's `EXT_meshopt_compression` object, and the extension declared used and
/// required (Khronos `EXT_meshopt_compression`: a reader without it cannot read the data).
/// With `omit_linear` (compact exports), samplers leave out `"interpolation": "LINEAR"`,
/// the default (glTF 2.0 §5.10): 25 bytes per sampler.
fn finish_json(
    mut root: json::Root,
    compressed: Option<&meshopt::Compressed>,
    pretty: bool,
    omit_linear: bool,
) -> Result<Vec<u8>, ExportError> {
    let compressed = compressed.filter(|c| !c.views.is_empty());
    if compressed.is_none() && !omit_linear {
        return Ok(if pretty {
            root.to_vec_pretty()?
        } else {
            root.to_vec()?
        });
    }
    let name = "EXT_meshopt_compression".to_owned();
    let mut fallback = None;
    if let Some(compressed) = compressed {
        root.extensions_used.push(name.clone());
        root.extensions_required.push(name.clone());
        root.buffers
            .push(buffer_entry(compressed.fallback_len, None));
        fallback = Some(root.buffers.len() - 1);
    }
    // Through the serialized text, not `to_value`: `f32` fields keep their shortest form
    // (`to_value` widens them to `f64` digits).
    let mut value: serde_json::Value = serde_json::from_slice(&root.to_vec()?)?;
    if let (Some(compressed), Some(fallback)) = (compressed, fallback) {
        if let Some(buffer) = value.pointer_mut(&format!("/buffers/{fallback}")) {
            buffer["extensions"] = serde_json::json!({ name.clone(): { "fallback": true } });
        }
        for view in &compressed.views {
            if let Some(v) = value.pointer_mut(&format!("/bufferViews/{}", view.view)) {
                v["extensions"] = serde_json::json!({ name.clone(): view.extension });
            }
        }
    }
    if omit_linear {
        let animations = value.get_mut("animations").and_then(|a| a.as_array_mut());
        for animation in animations.into_iter().flatten() {
            let samplers = animation.get_mut("samplers").and_then(|s| s.as_array_mut());
            for sampler in samplers
                .into_iter()
                .flatten()
                .filter_map(|s| s.as_object_mut())
            {
                if sampler.get("interpolation").is_some_and(|i| i == "LINEAR") {
                    sampler.remove("interpolation");
                }
            }
        }
    }
    Ok(if pretty {
        serde_json::to_vec_pretty(&value)?
    } else {
        let mut out = Vec::new();
        serde::Serialize::serialize(
            &value,
            &mut serde_json::Serializer::with_formatter(&mut out, WholeNumbers),
        )?;
        out
    })
}

/// serde_json's compact text with whole numbers written as integers (`0` for `0.0`, `-1`
/// for `-1.0`; the same JSON numbers): a compact file's rest translations are often whole,
/// 2 bytes each (185 bytes of the Bandai dash's nodes).
struct WholeNumbers;

impl serde_json::ser::Formatter for WholeNumbers {
    fn write_f64<W: ?Sized + std::io::Write>(
        &mut self,
        writer: &mut W,
        value: f64,
    ) -> std::io::Result<()> {
        // Below 2^53 a whole f64 is an exact i64.
        if value.fract() == 0.0 && value.abs() < 9.0e15 {
            write!(writer, "{}", value as i64)
        } else {
            serde_json::ser::CompactFormatter.write_f64(writer, value)
        }
    }
}

/// Wraps JSON and binary data in a GLB container (glTF 2.0 §4).
fn glb_container(mut json: Vec<u8>, bin: &[u8]) -> Result<Vec<u8>, ExportError> {
    // Chunks start and end on 4-byte boundaries: JSON padded with spaces, BIN with zeros.
    let pad = json.len().wrapping_neg() % 4;
    json.resize(json.len() + pad, b' ');
    let bin_padded = bin.len() + bin.len().wrapping_neg() % 4;
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin_padded };
    let total = 12 + 8 + json.len() + bin_chunk;
    let too_large = || ExportError::TooLarge {
        bytes: total as u64,
    };
    let total32 = u32::try_from(total).map_err(|_| too_large())?;

    let mut out = Vec::with_capacity(total);
    for word in [GLB_MAGIC, GLB_VERSION, total32] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    // Lengths fit: each is smaller than `total`.
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&CHUNK_JSON.to_le_bytes());
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin_padded as u32).to_le_bytes());
        out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        out.extend_from_slice(bin);
        out.resize(total, 0);
    }
    Ok(out)
}

/// Percent-encodes a file name for use as a relative URI reference (RFC 3986): unreserved
/// characters and a few safe sub-delimiters stay, everything else (space, `%`, `#`, `?`,
/// `:`, non-ASCII bytes of the UTF-8 encoding) is escaped. `:` is escaped so the name is never
/// read as a scheme.
fn percent_encode(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for byte in name.bytes() {
        let keep = byte.is_ascii_alphanumeric() || b"-._~!$&'()*+,;=@".contains(&byte);
        if keep {
            out.push(char::from(byte));
        } else {
            out.push_str(&format!("%{byte:02X}"));
        }
    }
    out
}
