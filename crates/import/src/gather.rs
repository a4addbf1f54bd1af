//! The assets of a folder tree: what `rigport batch` converts one by one and what
//! `rigport combine` gathers as clips. Each asset is its main file with the inputs it is
//! read from, found by [`crate::detect::detect`] (extension, and content for `.out`,
//! FBX and COLLADA files).
//!
//! ```
//! use rigport_import::gather::assets_in;
//!
//! let fixtures = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/bvh");
//! let assets = assets_in(&fixtures, None)?;
//! assert!(assets.iter().any(|(main, inputs)| main.ends_with("end_sites.bvh") && inputs.len() == 1));
//! # Ok::<(), rigport_import::detect::DetectError>(())
//! ```

use std::path::{Path, PathBuf};

use crate::detect::{detect, DetectError, Kind};

/// Collects `(main file, inputs)` per asset below `dir`, walking it in sorted order,
/// skipping hidden entries and files rigport does not read:
/// - each glTF, BVH, USD, FBX and COLLADA file;
/// - a CSCI 520 `.config` (the folder's `.obj` files are its meshes);
/// - an `.asf` with the `.amc` files beside it (all of them when it is the folder's only
///   `.asf`, else those of its subject number, CMU style: `07-walk.asf` takes
///   `07_05-walk.amc`);
/// - an `.obj`, with every `.out` file beside it (a Pinocchio rig) when it is the folder's
///   only `.obj`, or alone.
///
/// `exclude` (canonical) is a folder not to descend into.
///
/// # Errors
/// A folder that cannot be read ([`DetectError::Io`]).
pub fn assets_in(
    dir: &Path,
    exclude: Option<&Path>,
) -> Result<Vec<(PathBuf, Vec<PathBuf>)>, DetectError> {
    let mut found = Vec::new();
    walk(dir, exclude, &mut found)?;
    Ok(found)
}

/// The stem of `path` as text (empty without one).
fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default()
}

/// Whether the `.amc` at `amc` belongs to the subject of `asf` (CMU numbering: `07.asf`
/// or `07-walk.asf` takes `07_05.amc`, `07_05-walk.amc`).
pub fn same_subject(asf: &Path, amc: &Path) -> bool {
    let asf = stem(asf);
    let subject = asf.split(['-', '_']).next().unwrap_or_default();
    stem(amc)
        .strip_prefix(subject)
        .is_some_and(|rest| rest.is_empty() || rest.starts_with(['-', '_']))
}

fn walk(
    dir: &Path,
    exclude: Option<&Path>,
    found: &mut Vec<(PathBuf, Vec<PathBuf>)>,
) -> Result<(), DetectError> {
    let io = |source| DetectError::Io {
        path: dir.display().to_string(),
        folder: true,
        source,
    };
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()
        .map_err(io)?;
    entries.retain(|p| {
        !p.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('.'))
    });
    entries.sort();
    let mut dirs = Vec::new();
    let mut files: Vec<(PathBuf, Kind)> = Vec::new();
    for path in entries {
        match detect(&path) {
            Ok(Kind::Folder) => dirs.push(path),
            Ok(kind) => files.push((path, kind)),
            // Not an input rigport reads (.txt, .bin, .mtl, ...), or unreadable: skipped.
            Err(_) => {}
        }
    }
    let of = |k: &[Kind]| -> Vec<PathBuf> {
        files
            .iter()
            .filter(|(_, kind)| k.contains(kind))
            .map(|(p, _)| p.clone())
            .collect()
    };
    let has_config = !of(&[Kind::Csci520]).is_empty();
    let asfs = of(&[Kind::Asf]);
    let amcs = of(&[Kind::Amc]);
    let objs = of(&[Kind::Obj]);
    let outs = of(&[
        Kind::PinocchioSkeleton,
        Kind::PinocchioAttachment,
        Kind::PinocchioUnknown,
    ]);
    for (file, kind) in &files {
        let mut inputs = vec![file.clone()];
        match kind {
            Kind::Gltf | Kind::Bvh | Kind::Usda | Kind::Fbx | Kind::Collada | Kind::Csci520 => {}
            Kind::Asf => inputs.extend(
                amcs.iter()
                    .filter(|a| asfs.len() == 1 || same_subject(file, a))
                    .cloned(),
            ),
            // The meshes of a skin.config are read through it.
            Kind::Obj if !has_config => {
                if objs.len() == 1 {
                    inputs.extend(outs.iter().cloned());
                }
            }
            _ => continue,
        }
        found.push((file.clone(), inputs));
    }
    for sub in dirs {
        if exclude.is_some_and(|e| sub.canonicalize().is_ok_and(|s| s == e)) {
            continue;
        }
        walk(&sub, exclude, found)?;
    }
    Ok(())
}
