//! Loading with ufbx: the options that put the scene in rigport's conventions, and ufbx's
//! errors as [`ImportError`]s.

use std::path::Path;

use crate::{ImportError, Location, Problem};

/// The first bytes of a binary FBX file (`Kaydara FBX Binary  \0`).
pub const BINARY_MAGIC: &[u8] = b"Kaydara FBX Binary";

/// The first bytes of an ASCII FBX file (after white space): its header comment.
pub const ASCII_MAGIC: &[u8] = b"; FBX";

/// Whether `head` (a file's first bytes) starts like a binary or ASCII FBX file; a UTF-8
/// byte-order mark and leading white space are skipped for ASCII.
pub fn is_fbx(head: &[u8]) -> bool {
    if head.starts_with(BINARY_MAGIC) {
        return true;
    }
    let text = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
    let start = text
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(text.len());
    text[start..].starts_with(ASCII_MAGIC)
}

/// Parses `bytes` with ufbx.
///
/// The options: axes converted to right-handed +Y up by modifying geometry, transforms
/// and keys (a signed permutation of axes, exact in floating point; no extra root
/// transform for the model to carry), units left as the file states them (the model keeps
/// source units and says what they are); geometric transforms baked into the geometry
/// (helper nodes where a mesh is instanced); inherit types (segment scale compensate)
/// compensated in the local transforms, with helper nodes where that is not exact;
/// missing normals generated; external files not opened by ufbx (textures are read by
/// `material.rs`, which warns when one is missing).
///
/// # Errors
/// What ufbx reports, located as [`error`] says.
pub(super) fn load(bytes: &[u8], path: &Path) -> Result<ufbx::SceneRoot, ImportError> {
    let opts = ufbx::LoadOpts {
        target_axes: ufbx::CoordinateAxes::right_handed_y_up(),
        space_conversion: ufbx::SpaceConversion::ModifyGeometry,
        geometry_transform_handling: ufbx::GeometryTransformHandling::ModifyGeometry,
        inherit_mode_handling: ufbx::InheritModeHandling::Compensate,
        generate_missing_normals: true,
        load_external_files: false,
        ignore_missing_external_files: true,
        file_format: ufbx::FileFormat::Fbx,
        ..Default::default()
    };
    ufbx::load_memory(bytes, opts).map_err(|e| error(&e, bytes, path))
}

/// A ufbx error as an [`ImportError`]. ufbx does not report where in the file it failed;
/// a truncated file fails at its end, so that is its location: the byte offset (the
/// file's length) for binary FBX, the last line for ASCII. Other errors are at the file.
pub(super) fn error(e: &ufbx::Error, bytes: &[u8], path: &Path) -> ImportError {
    let binary = bytes.starts_with(BINARY_MAGIC);
    let mut message = e.description.to_string();
    let info = e.info();
    if !info.is_empty() {
        message.push_str(": ");
        message.push_str(info);
    }
    match e.type_ {
        ufbx::ErrorType::TruncatedFile => {
            let location = if binary {
                Location::byte(path, bytes.len() as u64)
            } else {
                let lines = bytes.iter().filter(|&&b| b == b'\n').count();
                let last = if bytes.last() == Some(&b'\n') {
                    lines
                } else {
                    lines + 1
                };
                Location::line(path, last.max(1))
            };
            ImportError::new(location, Problem::Truncated(message))
        }
        ufbx::ErrorType::EmptyFile => ImportError::new(Location::file(path), Problem::Empty),
        _ => ImportError::invalid(Location::file(path), format!("not a readable FBX file: {message}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tells_fbx_by_its_first_bytes() {
        assert!(is_fbx(b"Kaydara FBX Binary  \0\x1a\0"));
        assert!(is_fbx(b"; FBX 7.3.0 project file"));
        assert!(is_fbx(b"\xEF\xBB\xBF\r\n; FBX 6.1.0 project file"));
        assert!(!is_fbx(b"glTF"));
        assert!(!is_fbx(b"; not fbx"));
        assert!(!is_fbx(b""));
    }
}
