//! The binary encodings of a USD export. The stage is described once (`stage`) to a
//! `rigport-usd` sink: for `.usda` the printer, for `.usdc` and `.usdz` the layer builder,
//! whose typed layer (numbers as numbers, never text parsed back) is written as a crate
//! file here; a `.usdz` is a package holding that crate file as its root layer, followed
//! by the textures the materials name (their asset paths are relative file names, which
//! resolve inside the package). The layer is the same in every encoding: usd-core reads
//! the `.usdc` to the same specs, fields and values as the `.usda`.

use std::path::Path;

use rigport_usd::Layer;

use crate::{ExportError, ImageFile};

/// The layer as a crate file; `path` names the output in errors.
///
/// # Errors
/// [`ExportError::Usd`] if the layer cannot be encoded (a bug of the writer: the layer is
/// rigport's own).
pub(crate) fn crate_file(layer: &Layer, path: &Path) -> Result<Vec<u8>, ExportError> {
    Ok(rigport_usd::crate_write::write(layer, path)?)
}

/// A package: `<stem>.usdc` (the layer as a crate file) first, then `images` under their
/// file names.
///
/// # Errors
/// As [`crate_file`], and a texture name the package cannot hold.
pub(crate) fn package(
    layer: &Layer,
    images: &[ImageFile],
    stem: &str,
    path: &Path,
) -> Result<Vec<u8>, ExportError> {
    let root = crate_file(layer, path)?;
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
