//! The binary encodings of a USD export. The stage is built as `.usda` text (`stage`);
//! for a `.usdc` that text is parsed into a layer by `rigport-usd` and written as a crate
//! file, and a `.usdz` is a package holding that crate file as its root layer, followed by
//! the textures the materials name (their asset paths are relative file names, which
//! resolve inside the package). The layer is the same in every encoding: usd-core reads
//! the `.usdc` to the same specs, fields and values as the `.usda`.

use std::path::Path;

use crate::{ExportError, ImageFile};

/// The `.usda` text as a crate file; `path` names the output in errors.
///
/// # Errors
/// [`ExportError::Usd`] if the text cannot be parsed or encoded (a bug of the writer:
/// the text is rigport's own).
pub(crate) fn crate_file(text: &str, path: &Path) -> Result<Vec<u8>, ExportError> {
    let layer = rigport_usd::parse::parse(text, path)?;
    Ok(rigport_usd::crate_write::write(&layer, path)?)
}

/// A package: `<stem>.usdc` (the text as a crate file) first, then `images` under their
/// file names.
///
/// # Errors
/// As [`crate_file`], and a texture name the package cannot hold.
pub(crate) fn package(
    text: &str,
    images: &[ImageFile],
    stem: &str,
    path: &Path,
) -> Result<Vec<u8>, ExportError> {
    let root = crate_file(text, path)?;
    let root_name = format!("{stem}.usdc");
    let files: Vec<(String, Vec<u8>)> = images
        .iter()
        .map(|i| (i.uri.clone(), i.bytes.clone()))
        .collect();
    Ok(rigport_usd::usdz::write_package(
        (&root_name, &root),
        &files,
        path,
    )?)
}
