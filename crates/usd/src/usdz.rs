//! USD packages (`.usdz`) and the choice of reader for a layer's bytes.
//!
//! A `.usdz` is a zip archive whose members are stored uncompressed (and 64-byte aligned,
//! which a reader need not rely on); its first member is the root layer, `.usda` or
//! `.usdc` (`UsdZipFileFormat`, the usdz specification). Other members (textures, more
//! layers) are not read: references into them are not resolved, like every other arc.

use std::io::Read;
use std::path::{Path, PathBuf};

use super::crate_file;
use super::parse::{self, Layer};
use crate::error::{utf8, Location, UsdError};

/// The first bytes of a zip archive (a local file header).
const ZIP_MAGIC: &[u8; 4] = b"PK\x03\x04";

/// Reads a layer from `.usda` text, a `.usdc` crate file or a `.usdz` package, chosen by
/// the bytes (`PXR-USDC`, `PK\x03\x04`, else text), not by the file name, so `.usd` files
/// of either encoding work.
///
/// # Errors
/// The reader's errors; for a package, those of its root layer name the member
/// (`pack.usdz[root.usdc]`).
pub fn read_layer(bytes: &[u8], path: &Path) -> Result<Layer, UsdError> {
    if bytes.starts_with(crate_file::MAGIC) {
        crate_file::read(bytes, path)
    } else if bytes.starts_with(ZIP_MAGIC) {
        let (member, data) = root_layer(bytes, path)?;
        let inner = PathBuf::from(format!("{}[{member}]", path.display()));
        if data.starts_with(ZIP_MAGIC) {
            return Err(UsdError::invalid(
                Location::file(&inner),
                "the root layer of a .usdz is itself a package",
            ));
        }
        read_layer(&data, &inner)
    } else {
        parse::parse(utf8(bytes, path)?, path)
    }
}

/// The name and bytes of a package's first member.
fn root_layer(bytes: &[u8], path: &Path) -> Result<(String, Vec<u8>), UsdError> {
    let zip_error = |e: zip::result::ZipError| {
        UsdError::invalid(Location::file(path), format!("not a readable .usdz: {e}"))
    };
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(zip_error)?;
    if archive.is_empty() {
        return Err(UsdError::invalid(
            Location::file(path),
            "the .usdz package is empty (it needs a root layer)",
        ));
    }
    let mut member = archive.by_index(0).map_err(zip_error)?;
    let name = member.name().to_string();
    let ext = Path::new(&name)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if !matches!(ext.as_deref(), Some("usd" | "usda" | "usdc")) {
        return Err(UsdError::invalid(
            Location::file(path),
            format!(
                "the first file of a .usdz must be its root layer (.usda/.usdc), found {name:?}"
            ),
        ));
    }
    let offset = member.data_start();
    // The size comes from the archive's directory: never trust it for a reservation.
    let mut data = Vec::with_capacity((member.size() as usize).min(bytes.len()));
    member.read_to_end(&mut data).map_err(|e| {
        UsdError::invalid(
            Location::byte(path, offset),
            format!("cannot read {name:?} from the package: {e}"),
        )
    })?;
    Ok((name, data))
}
