//! USD packages (`.usdz`) read and written, and the choice of reader for a layer's bytes.
//!
//! A `.usdz` is a zip archive whose members are stored uncompressed (and 64-byte aligned,
//! which a reader need not rely on); its first member is the root layer, `.usda` or
//! `.usdc` (`UsdZipFileFormat`, the usdz specification). Other members (textures, more
//! layers) are not read: references into them are not resolved, like every other arc.
//! [`write_package`] writes a package: the root layer first, every member stored and
//! 64-byte aligned.

use std::io::Read;
use std::path::{Path, PathBuf};

use super::crate_file;
use super::layer::Layer;
use super::parse;
use crate::error::{utf8, Location, PackageProblem, Problem, UsdError};

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
            return Err(UsdError::new(
                Location::file(&inner),
                PackageProblem::Nested.into(),
            ));
        }
        read_layer(&data, &inner)
    } else {
        parse::parse(utf8(bytes, path)?, path)
    }
}

/// A `.usdz` package held in memory, whose members are read by name.
pub struct Package<'a> {
    bytes: &'a [u8],
    /// The root layer's folder in the archive (`""` at the top), which relative asset
    /// paths start from.
    root_dir: String,
    /// Member names, in archive order.
    names: Vec<String>,
}

impl<'a> Package<'a> {
    /// The package in `bytes`, or `None` when they are not a zip archive (a `.usda` or
    /// `.usdc` layer).
    ///
    /// # Errors
    /// An archive that cannot be read, is empty or does not start with a layer.
    pub fn open(bytes: &'a [u8], path: &Path) -> Result<Option<Self>, UsdError> {
        if !bytes.starts_with(ZIP_MAGIC) {
            return Ok(None);
        }
        let archive = zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(|e| {
            UsdError::new(Location::file(path), PackageProblem::Unreadable(e).into())
        })?;
        let names: Vec<String> = archive.file_names().map(str::to_string).collect();
        // `file_names` is in no set order: the root is the first member by index.
        let (root, _) = root_layer(bytes, path)?;
        let root_dir = match root.rfind('/') {
            Some(k) => root[..=k].to_string(),
            None => String::new(),
        };
        Ok(Some(Self {
            bytes,
            root_dir,
            names,
        }))
    }

    /// The member an asset path of the root layer names (relative to the root layer's
    /// folder; `./` and `..` segments resolved), if the package holds it: its name and
    /// bytes. `None` for a path outside the package, an absolute path, or a member that
    /// cannot be read.
    pub fn member(&self, asset_path: &str) -> Option<(String, Vec<u8>)> {
        if asset_path.starts_with('/') || asset_path.contains(['\\', ':']) {
            return None;
        }
        let joined = format!("{}{asset_path}", self.root_dir);
        let mut parts: Vec<&str> = Vec::new();
        for part in joined.split('/') {
            match part {
                "" | "." => {}
                ".." => {
                    parts.pop()?;
                }
                p => parts.push(p),
            }
        }
        let name = parts.join("/");
        if !self.names.contains(&name) {
            return None;
        }
        let mut archive = zip::ZipArchive::new(std::io::Cursor::new(self.bytes)).ok()?;
        let mut file = archive.by_name(&name).ok()?;
        let mut data = Vec::with_capacity((file.size() as usize).min(self.bytes.len()));
        file.read_to_end(&mut data).ok()?;
        Some((name, data))
    }
}

/// The name and bytes of a package's first member.
fn root_layer(bytes: &[u8], path: &Path) -> Result<(String, Vec<u8>), UsdError> {
    let zip_error = |e: zip::result::ZipError| {
        UsdError::new(Location::file(path), PackageProblem::Unreadable(e).into())
    };
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(zip_error)?;
    if archive.is_empty() {
        return Err(UsdError::new(
            Location::file(path),
            PackageProblem::Empty.into(),
        ));
    }
    let mut member = archive.by_index(0).map_err(zip_error)?;
    let name = member.name().to_string();
    let ext = Path::new(&name)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if !matches!(ext.as_deref(), Some("usd" | "usda" | "usdc")) {
        return Err(UsdError::new(
            Location::file(path),
            PackageProblem::FirstNotLayer(name).into(),
        ));
    }
    let offset = member.data_start();
    // The size comes from the archive's directory: never trust it for a reservation.
    let mut data = Vec::with_capacity((member.size() as usize).min(bytes.len()));
    member.read_to_end(&mut data).map_err(|error| {
        let name = name.clone();
        UsdError::new(
            Location::byte(path, offset),
            PackageProblem::Member { name, error }.into(),
        )
    })?;
    Ok((name, data))
}

/// Alignment of every member's data in a package (the usdz specification: 64 bytes).
pub const ALIGNMENT: usize = 64;

/// Writes a `.usdz` package: `root` (name and bytes) first, then `files` (relative names,
/// as the root layer's asset paths name them), each stored uncompressed with its data at a
/// multiple of [`ALIGNMENT`] bytes (a padding extra field in the local header, as
/// `UsdZipFileWriter` writes), no time stamps (the bytes depend on the inputs only).
///
/// # Errors
/// A member name that is empty, absolute, contains `..` or a backslash, or is given
/// twice; a member or package over 4 GiB (zip64 is not written), naming `path`.
pub fn write_package(
    root: (&str, &[u8]),
    files: &[(String, Vec<u8>)],
    path: &Path,
) -> Result<Vec<u8>, UsdError> {
    let members =
        std::iter::once(root).chain(files.iter().map(|(n, b)| (n.as_str(), b.as_slice())));
    let mut out = Vec::new();
    let mut central = Vec::new();
    let mut names: Vec<&str> = Vec::new();
    let refuse = |p: PackageProblem| UsdError::new(Location::file(path), p.into());
    for (name, data) in members {
        if name.is_empty()
            || name.starts_with('/')
            || name.contains('\\')
            || name.split('/').any(|part| part == ".." || part.is_empty())
        {
            return Err(refuse(PackageProblem::BadName(name.to_string())));
        }
        if names.contains(&name) {
            return Err(refuse(PackageProblem::Twice(name.to_string())));
        }
        names.push(name);
        let size = u32::try_from(data.len())
            .map_err(|_| refuse(PackageProblem::Over4Gib(Some(name.to_string()))))?;
        let offset =
            u32::try_from(out.len()).map_err(|_| refuse(PackageProblem::Over4Gib(None)))?;
        let name_len = u16::try_from(name.len())
            .map_err(|_| refuse(PackageProblem::NameTooLong(name.to_string())))?;
        // Padding so that the data starts at a multiple of the alignment; an extra field
        // needs 4 bytes of header.
        let unpadded = out.len() + 30 + name.len();
        let mut pad = (ALIGNMENT - unpadded % ALIGNMENT) % ALIGNMENT;
        if pad > 0 && pad < 4 {
            pad += ALIGNMENT;
        }
        let crc = crc32(data);
        let header = |sig: u32, out: &mut Vec<u8>, central: bool| {
            out.extend_from_slice(&sig.to_le_bytes());
            if central {
                out.extend_from_slice(&20_u16.to_le_bytes()); // made by: 2.0
            }
            out.extend_from_slice(&10_u16.to_le_bytes()); // needed: 1.0 (stored)
            out.extend_from_slice(&0_u16.to_le_bytes()); // flags
            out.extend_from_slice(&0_u16.to_le_bytes()); // stored
            out.extend_from_slice(&0_u16.to_le_bytes()); // time 00:00
            out.extend_from_slice(&0x21_u16.to_le_bytes()); // date 1980-01-01
            out.extend_from_slice(&crc.to_le_bytes());
            out.extend_from_slice(&size.to_le_bytes());
            out.extend_from_slice(&size.to_le_bytes());
            out.extend_from_slice(&name_len.to_le_bytes());
        };
        header(0x0403_4b50, &mut out, false);
        out.extend_from_slice(&(pad as u16).to_le_bytes());
        out.extend_from_slice(name.as_bytes());
        if pad > 0 {
            // `UsdZipFileWriter`'s padding field id, then zeros.
            out.extend_from_slice(&0x1986_u16.to_le_bytes());
            out.extend_from_slice(&((pad - 4) as u16).to_le_bytes());
            out.resize(out.len() + pad - 4, 0);
        }
        out.extend_from_slice(data);
        header(0x0201_4b50, &mut central, true);
        central.extend_from_slice(&0_u16.to_le_bytes()); // extra
        central.extend_from_slice(&0_u16.to_le_bytes()); // comment
        central.extend_from_slice(&0_u16.to_le_bytes()); // disk
        central.extend_from_slice(&0_u16.to_le_bytes()); // internal attributes
        central.extend_from_slice(&0_u32.to_le_bytes()); // external attributes
        central.extend_from_slice(&offset.to_le_bytes());
        central.extend_from_slice(name.as_bytes());
    }
    let count = u16::try_from(names.len()).map_err(|_| {
        let too_many = Problem::TooMany {
            what: "files",
            count: None,
        };
        UsdError::new(Location::file(path), too_many)
    })?;
    let cd_offset = u32::try_from(out.len()).map_err(|_| refuse(PackageProblem::Over4Gib(None)))?;
    let cd_size = central.len() as u32;
    out.extend_from_slice(&central);
    out.extend_from_slice(&0x0605_4b50_u32.to_le_bytes());
    out.extend_from_slice(&[0; 4]); // disk numbers
    out.extend_from_slice(&count.to_le_bytes());
    out.extend_from_slice(&count.to_le_bytes());
    out.extend_from_slice(&cd_size.to_le_bytes());
    out.extend_from_slice(&cd_offset.to_le_bytes());
    out.extend_from_slice(&0_u16.to_le_bytes()); // comment
    Ok(out)
}

/// CRC-32 (IEEE, reflected, as zip uses).
fn crc32(data: &[u8]) -> u32 {
    let mut table = [0_u32; 256];
    for (i, slot) in table.iter_mut().enumerate() {
        let mut c = i as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
        *slot = c;
    }
    let mut crc = !0_u32;
    for &b in data {
        crc = table[((crc ^ u32::from(b)) & 0xff) as usize] ^ (crc >> 8);
    }
    !crc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_of_a_known_string() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn packages_are_aligned_stored_and_read_back() {
        let root = b"#usda 1.0\ndef Xform \"A\"\n{\n}\n";
        let files = vec![
            ("a_tex.png".to_string(), vec![1_u8; 100]),
            ("b.jpg".to_string(), vec![2_u8; 3]),
        ];
        let bytes = write_package(("x.usda", root), &files, Path::new("x.usdz")).unwrap();
        let mut archive = zip::ZipArchive::new(std::io::Cursor::new(&bytes)).unwrap();
        assert_eq!(archive.len(), 3);
        for i in 0..archive.len() {
            let mut member = archive.by_index(i).unwrap();
            assert_eq!(member.compression(), zip::CompressionMethod::Stored);
            assert_eq!(
                member.data_start() % ALIGNMENT as u64,
                0,
                "{}",
                member.name()
            );
            let mut data = Vec::new();
            member.read_to_end(&mut data).unwrap();
            let want: &[u8] = match i {
                0 => root,
                k => &files[k - 1].1,
            };
            assert_eq!(data, want);
        }
        let layer = read_layer(&bytes, Path::new("x.usdz")).unwrap();
        assert_eq!(layer.root.children[0].name, "A");
        for bad in ["", "/a.png", "../a.png", "a\\b.png", "x.usda"] {
            let files = vec![(bad.to_string(), vec![0_u8])];
            assert!(write_package(("x.usda", root), &files, Path::new("x.usdz")).is_err());
        }
    }
}
