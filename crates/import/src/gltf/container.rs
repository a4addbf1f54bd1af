//! The container: GLB chunks (glTF 2.0 §4.4), the JSON document with its schema check, and
//! the buffers (the GLB `BIN` chunk, external files, `data:` URIs).

use std::borrow::Cow;

use super::ext_meshopt::Meshopt;
use std::path::{Path, PathBuf};

use ::gltf::Semantic;
use rigport_model::Warning;

use crate::problem::{Missing, Repeated, Rule, Schema, Uri};
use crate::{ImportError, Location, Problem};

fn le_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a GLB into its JSON chunk and optional BIN chunk (glTF 2.0 §4.4).
pub(super) fn split_glb<'b>(
    bytes: &'b [u8],
    path: &Path,
    warnings: &mut Vec<Warning>,
) -> Result<(&'b [u8], Option<&'b [u8]>), ImportError> {
    let truncated = |offset: usize, msg: String| {
        ImportError::new(Location::byte(path, offset as u64), Problem::Truncated(msg))
    };
    let refuse = |offset: usize, problem: Problem| {
        ImportError::new(Location::byte(path, offset as u64), problem)
    };
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
        return Err(refuse(4, Rule::GlbVersion(version).into()));
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
            b"JSON" => return Err(refuse(pos + 4, Repeated::Chunk("JSON").into())),
            _ if json.is_none() => {
                let kind = String::from_utf8_lossy(kind).into_owned();
                return Err(refuse(pos + 4, Rule::FirstChunk(kind).into()));
            }
            b"BIN\0" if bin.is_none() => bin = Some(data),
            b"BIN\0" => return Err(refuse(pos + 4, Repeated::Chunk("BIN").into())),
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
pub(super) fn json_pointer(gltf_path: &str) -> String {
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

/// The document, when its only fault for `gltf-json` is a scene without `nodes`: glTF 2.0
/// allows one (a scene's `nodes` is optional: an empty scene), the crate requires the field.
fn with_scene_nodes(json: &[u8]) -> Option<::gltf::json::Root> {
    let mut value: serde_json::Value = serde_json::from_slice(json).ok()?;
    for scene in value.get_mut("scenes")?.as_array_mut()? {
        let scene = scene.as_object_mut()?;
        scene
            .entry("nodes")
            .or_insert_with(|| serde_json::json!([]));
    }
    serde_json::from_value(value).ok()
}

/// Parses and validates the glTF JSON (what `gltf::Gltf::from_slice` does, plus a check
/// its validation needs first).
pub(super) fn parse_document(
    json: &[u8],
    path: &Path,
    is_glb: bool,
    warnings: &mut Vec<Warning>,
) -> Result<::gltf::Document, ImportError> {
    use ::gltf::json::validation::{Checked, Error as SchemaError, Validate};
    let parsed = ::gltf::json::deserialize::from_slice(json);
    let root: ::gltf::json::Root = parsed
        .or_else(|e| with_scene_nodes(json).ok_or(e))
        .map_err(|e| {
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
                return Err(ImportError::at(
                    Location::json(
                        path,
                        format!("/meshes/{m}/primitives/{p}/attributes/POSITION"),
                    ),
                    Rule::Schema {
                        first: Schema::IndexOutOfRange,
                        more: 0,
                    },
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
        if error == SchemaError::Unsupported
            && (value == Some("KHR_mesh_quantization") || value == Some("EXT_meshopt_compression"))
        {
            // Read: integer mesh attributes are decoded (`accessor.rs`), compressed views
            // decoded into their buffers (`ext_meshopt.rs`).
            continue;
        }
        if error == SchemaError::Unsupported && material_only {
            warnings.push(Warning::Incomplete {
                location: Location::json(path, json_pointer(at_path)).to_string(),
                message: format!(
                    "required extension {} only affects materials; not imported, the \
                     materials are read without it",
                    value.unwrap_or_default()
                ),
            });
        } else {
            kept.push((at, error));
        }
    }
    // Extensions a file uses without requiring them: rigport reads none of them but the
    // quantized accessors the reader decodes, so each is a loss, said once.
    let unread: Vec<&str> = root
        .extensions_used
        .iter()
        .map(String::as_str)
        .filter(|e| {
            *e != "KHR_mesh_quantization"
                && *e != "EXT_meshopt_compression"
                && !root.extensions_required.iter().any(|r| r == e)
        })
        .collect();
    if !unread.is_empty() {
        warnings.push(Warning::Incomplete {
            location: Location::json(path, "/extensionsUsed".to_string()).to_string(),
            message: format!(
                "extensions not imported (what they add to materials, lights or geometry is \
                 left out): {}",
                unread.join(", ")
            ),
        });
    }
    if let Some((first_path, first)) = kept.first() {
        let (at_path, value) = split_path_value(first_path.as_str());
        let first = match first {
            SchemaError::IndexOutOfBounds => Schema::IndexOutOfRange,
            SchemaError::Invalid => Schema::Invalid,
            SchemaError::Missing => Schema::Missing,
            SchemaError::Oversize => Schema::Oversize,
            SchemaError::Unsupported => Schema::Unsupported(value.unwrap_or_default().to_string()),
        };
        return Err(ImportError::at(
            Location::json(path, json_pointer(at_path)),
            Rule::Schema {
                first,
                more: kept.len() - 1,
            },
        ));
    }
    Ok(::gltf::Document::from_json_without_validation(root))
}

/// Decodes standard base64 (RFC 4648 §4), padding optional; `None` on any other byte.
pub(super) fn decode_base64(text: &str) -> Option<Vec<u8>> {
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
pub(super) fn percent_decode(uri: &str) -> Option<String> {
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

/// The bytes a buffer or image `uri` names: a base64 `data:` URI, or a file relative to
/// the glTF's folder. `what` (`buffer`, `image`) names it in errors.
pub(super) fn read_uri(
    uri: &str,
    path: &Path,
    at: &str,
    what: &'static str,
) -> Result<Vec<u8>, ImportError> {
    let err = |problem: Uri| ImportError::at(Location::json(path, at), problem);
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((meta, payload)) = rest.split_once(',') else {
            return Err(err(Uri::NoComma));
        };
        if !meta.ends_with(";base64") {
            return Err(err(Uri::NotBase64(meta.to_string())));
        }
        return decode_base64(payload).ok_or_else(|| err(Uri::InvalidBase64));
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
                    let uri = uri.to_string();
                    return Err(err(Uri::Scheme { what, uri }));
                }
            }
            uri
        }
    };
    let decoded = percent_decode(relative).ok_or_else(|| {
        let uri = uri.to_string();
        err(Uri::NotUtf8 { what, uri })
    })?;
    let base = path.parent().unwrap_or(Path::new(""));
    let file: PathBuf = base.join(decoded);
    std::fs::read(&file).map_err(|error| err(Uri::File { what, file, error }))
}

/// Largest `EXT_meshopt_compression` fallback buffer decoded (256 MiB, as for zero-filled
/// accessors: its size is not bounded by the file's bytes).
const MAX_FALLBACK_BYTES: usize = 1 << 28;

pub(super) fn load_buffers<'b>(
    doc: &::gltf::Document,
    mut blob: Option<&'b [u8]>,
    path: &Path,
    meshopt: &Meshopt,
) -> Result<Vec<Cow<'b, [u8]>>, ImportError> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let at = format!("/buffers/{}", buffer.index());
        if meshopt.is_fallback(buffer.index()) {
            // Filled by decoding (`ext_meshopt.rs`); its length is not bounded by the file's
            // bytes, so it is capped as zero-filled accessors are.
            if buffer.length() > MAX_FALLBACK_BYTES {
                return Err(ImportError::invalid(
                    Location::json(path, format!("{at}/byteLength")),
                    format!(
                        "a fallback buffer of {} bytes; rigport decodes at most {MAX_FALLBACK_BYTES}",
                        buffer.length()
                    ),
                ));
            }
            out.push(Cow::Owned(vec![0; buffer.length()]));
            continue;
        }
        let data: Cow<'b, [u8]> = match buffer.source() {
            ::gltf::buffer::Source::Bin => Cow::Borrowed(
                blob.take()
                    .ok_or_else(|| ImportError::at(Location::json(path, &at), Missing::BinChunk))?,
            ),
            ::gltf::buffer::Source::Uri(uri) => {
                Cow::Owned(read_uri(uri, path, &format!("{at}/uri"), "buffer")?)
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
