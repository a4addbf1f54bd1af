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
    ufbx::load_memory(bytes, options(ufbx::InheritModeHandling::Compensate))
        .map_err(|e| error(&e, bytes, path))
}

/// [`load`]'s options, with `inherit` for the inherit types.
fn options(inherit: ufbx::InheritModeHandling) -> ufbx::LoadOpts<'static> {
    ufbx::LoadOpts {
        target_axes: ufbx::CoordinateAxes::right_handed_y_up(),
        space_conversion: ufbx::SpaceConversion::ModifyGeometry,
        geometry_transform_handling: ufbx::GeometryTransformHandling::ModifyGeometry,
        inherit_mode_handling: inherit,
        generate_missing_normals: true,
        load_external_files: false,
        ignore_missing_external_files: true,
        file_format: ufbx::FileFormat::Fbx,
        ..Default::default()
    }
}

/// Where ufbx's scale helpers put nodes away from the file's definition: the node that
/// moved most, how far, and the size of the scene's nodes (the diagonal of their origins'
/// box at rest), in the file's units; `None` when `scene` has no scale helper.
///
/// ufbx compensates inherit types exactly for uniform scale only; for a non-uniform or
/// animated parent scale it adds a scale helper node, which drops the child's scaling
/// pivot and rotation offset. The file is read again with the inherit types preserved,
/// where ufbx evaluates each node's world transform as the file defines it, and the nodes'
/// origins are compared by name (names used once in both readings): at rest, and at the
/// start, middle and end of each animation stack.
pub(super) fn scale_helper_drift(bytes: &[u8], scene: &ufbx::Scene) -> Option<(String, f64, f64)> {
    use rigport_model::glam::DVec3;
    use std::collections::HashMap;
    if !scene.nodes.iter().any(|n| n.is_scale_helper) {
        return None;
    }
    let exact = ufbx::load_memory(bytes, options(ufbx::InheritModeHandling::Preserve)).ok()?;
    let origins = |scene: &ufbx::Scene| {
        let mut by_name: HashMap<String, Option<DVec3>> = HashMap::new();
        for n in scene.nodes.iter() {
            if n.is_root || n.is_scale_helper || n.is_geometry_transform_helper {
                continue;
            }
            let at = super::skeleton::mat(&n.node_to_world).w_axis.truncate();
            by_name
                .entry(n.element.name.to_string())
                .and_modify(|seen| *seen = None)
                .or_insert(Some(at));
        }
        by_name
    };
    let mut worst = (String::new(), 0.0);
    let mut compare = |ours: &ufbx::Scene, theirs: &ufbx::Scene| {
        let (ours, theirs) = (origins(ours), origins(theirs));
        let mut names: Vec<&String> = theirs.keys().collect();
        names.sort();
        for name in names {
            if let (Some(at), Some(Some(ours))) = (&theirs[name], ours.get(name)) {
                let d = ours.distance(*at);
                if d > worst.1 * (1.0 + 1e-9) {
                    worst = (name.clone(), d);
                }
            }
        }
    };
    compare(scene, &exact);
    for (stack, exact_stack) in scene.anim_stacks.iter().zip(exact.anim_stacks.iter()) {
        let (begin, end) = (stack.time_begin, stack.time_end);
        for t in [begin, 0.5 * (begin + end), end] {
            let opts = || ufbx::EvaluateOpts::default();
            let (Ok(ours), Ok(theirs)) = (
                ufbx::evaluate_scene(scene, &stack.anim, t, opts()),
                ufbx::evaluate_scene(&exact, &exact_stack.anim, t, opts()),
            ) else {
                continue;
            };
            compare(&ours, &theirs);
        }
    }
    let rest = origins(&exact);
    let (lo, hi) = (rest.values().flatten()).fold((DVec3::MAX, DVec3::MIN), |(lo, hi), p| {
        (lo.min(*p), hi.max(*p))
    });
    Some((worst.0, worst.1, (hi - lo).length().max(f64::MIN_POSITIVE)))
}

/// A ufbx error as an [`ImportError`], located where the file shows the problem.
///
/// ufbx reports what failed but not where (its error stack is compiled out), so the
/// location is found here: for binary FBX the top-level node records are walked, and the
/// first that runs past the end of the file is the truncation (its byte offset); an
/// unsupported version is at byte 23, where the version is stored. For ASCII FBX the
/// braces are counted, and a file that ends inside a block is truncated at its last line.
/// Anything else is at the file.
pub(super) fn error(e: &ufbx::Error, bytes: &[u8], path: &Path) -> ImportError {
    let mut message = e.description.to_string();
    let info = e.info();
    if !info.is_empty() {
        message.push_str(": ");
        message.push_str(info);
    }
    if bytes.starts_with(BINARY_MAGIC) {
        if matches!(e.type_, ufbx::ErrorType::UnsupportedVersion) {
            return ImportError::invalid(
                Location::byte(path, VERSION_OFFSET as u64),
                format!("unsupported FBX version {info}"),
            );
        }
        if let Some((offset, what)) = binary_truncation(bytes) {
            return ImportError::new(Location::byte(path, offset), Problem::Truncated(what));
        }
    } else if let Some((line, what)) = ascii_truncation(bytes) {
        return ImportError::new(Location::line(path, line), Problem::Truncated(what));
    }
    ImportError::invalid(
        Location::file(path),
        format!("not a readable FBX file: {message}"),
    )
}

/// Where a binary FBX file stores its version (after the magic, a 0x1A and a 0x00).
const VERSION_OFFSET: usize = 23;

/// The first top-level node record of a binary FBX file that does not fit in it: its byte
/// offset and what is cut (`None` when every record fits up to the null record).
fn binary_truncation(bytes: &[u8]) -> Option<(u64, String)> {
    let len = bytes.len();
    let u32_at = |at: usize| -> Option<u64> {
        let b = bytes.get(at..at + 4)?;
        Some(u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
    };
    let u64_at = |at: usize| -> Option<u64> {
        let b = bytes.get(at..at + 8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Some(u64::from_le_bytes(a))
    };
    let Some(version) = u32_at(VERSION_OFFSET) else {
        return Some((len as u64, "the file ends inside its header".to_string()));
    };
    // FBX 7.5 widened the record offsets to 64 bits.
    let wide = version >= 7500;
    let header = if wide { 25 } else { 13 };
    let mut at = VERSION_OFFSET + 4;
    loop {
        if at + header > len {
            return Some((
                at as u64,
                format!("the file ({len} bytes) ends inside the node record starting here"),
            ));
        }
        let end = if wide { u64_at(at)? } else { u32_at(at)? };
        if end == 0 {
            return None;
        }
        let name_len = usize::from(*bytes.get(at + header - 1)?);
        let name = bytes
            .get(at + header..(at + header + name_len).min(len))
            .map(|n| String::from_utf8_lossy(n).into_owned())
            .unwrap_or_default();
        if end > len as u64 {
            return Some((
                at as u64,
                format!(
                    "the node record {name:?} starting here ends at byte {end}, past the end \
                     of the file ({len} bytes)"
                ),
            ));
        }
        if end <= at as u64 {
            return None;
        }
        at = end as usize;
    }
}

/// The last line of an ASCII FBX file that ends inside a `{ }` block, with the line that
/// opened the innermost open block (`None` when the braces balance).
fn ascii_truncation(bytes: &[u8]) -> Option<(usize, String)> {
    let mut line = 1;
    let mut open: Vec<usize> = Vec::new();
    let mut in_string = false;
    let mut in_comment = false;
    for &b in bytes {
        match b {
            b'\n' => {
                line += 1;
                in_comment = false;
                in_string = false;
            }
            _ if in_comment => {}
            b'"' => in_string = !in_string,
            _ if in_string => {}
            b';' => in_comment = true,
            b'{' => open.push(line),
            b'}' => {
                open.pop();
            }
            _ => {}
        }
    }
    let last = if bytes.last() == Some(&b'\n') {
        line - 1
    } else {
        line
    };
    let innermost = *open.last()?;
    Some((
        last.max(1),
        format!(
            "the file ends inside {} open block{} (the innermost opened on line {innermost})",
            open.len(),
            if open.len() == 1 { "" } else { "s" }
        ),
    ))
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
