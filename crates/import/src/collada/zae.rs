//! `.zae` packages: a zip archive whose `manifest.xml` names the root `.dae` in
//! `<dae_root>` (else the archive's only `.dae`), and the files (textures) the document
//! names, found relative to the root `.dae` inside the archive or beside the package.

use std::io::{Cursor, Read};
use std::path::{Path, PathBuf};

use crate::{ImportError, Location};

/// Whether `bytes` start like a zip archive: a local file header, or the end record of an
/// empty archive.
pub(super) fn is_zip(bytes: &[u8]) -> bool {
    bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06")
}

/// The most a member may inflate to (a bound against zip bombs).
const MAX_MEMBER_BYTES: u64 = 1 << 30;

/// Where the files a document names are read from.
pub(super) struct Files<'b> {
    /// The folder of the file (or of the package).
    pub(super) folder: PathBuf,
    /// The package's bytes and the root `.dae`'s folder inside it.
    pub(super) package: Option<(&'b [u8], String)>,
}

impl Files<'_> {
    /// The bytes of `relative` (a path as the document writes it): inside the package
    /// first, then on disk.
    pub(super) fn read(&self, relative: &str) -> Option<Vec<u8>> {
        if let Some((bytes, root)) = &self.package {
            let mut archive = zip::ZipArchive::new(Cursor::new(*bytes)).ok()?;
            let inside = normalize(&format!("{root}{relative}"));
            let name = Path::new(relative)
                .file_name()?
                .to_string_lossy()
                .into_owned();
            let found = archive
                .file_names()
                .find(|n| normalize(n) == inside)
                .or_else(|| {
                    archive
                        .file_names()
                        .find(|n| n.ends_with(&format!("/{name}")) || *n == name)
                })
                .map(str::to_string);
            if let Some(member) = found {
                if let Ok(b) = read_member(&mut archive, &member) {
                    return Some(b);
                }
            }
        }
        candidates(&self.folder, relative)
            .iter()
            .find_map(|p| std::fs::read(p).ok())
    }
}

/// `a/./b/../c` as `a/c`.
fn normalize(path: &str) -> String {
    let mut parts: Vec<&str> = Vec::new();
    for p in path.split('/') {
        match p {
            "" | "." => {}
            ".." => {
                parts.pop();
            }
            p => parts.push(p),
        }
    }
    parts.join("/")
}

fn read_member(
    archive: &mut zip::ZipArchive<Cursor<&[u8]>>,
    name: &str,
) -> Result<Vec<u8>, String> {
    let file = archive.by_name(name).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    file.take(MAX_MEMBER_BYTES)
        .read_to_end(&mut out)
        .map_err(|e| e.to_string())?;
    Ok(out)
}

/// The root `.dae` of a package: its member name and bytes.
///
/// # Errors
/// Not a readable zip archive; no `.dae` (or several and no manifest naming one); a
/// manifest naming a member that is not there.
pub(super) fn root(bytes: &[u8], path: &Path) -> Result<(String, Vec<u8>), ImportError> {
    let at = || Location::file(path);
    let mut archive = zip::ZipArchive::new(Cursor::new(bytes)).map_err(|e| {
        ImportError::invalid(at(), format!("not a readable .zae (zip) package: {e}"))
    })?;
    let manifest = archive
        .file_names()
        .find(|n| n.eq_ignore_ascii_case("manifest.xml"))
        .map(str::to_string);
    let named = match manifest {
        Some(m) => {
            let text = read_member(&mut archive, &m).map_err(|e| {
                ImportError::invalid(at(), format!("cannot read {m} in the package: {e}"))
            })?;
            let text = String::from_utf8_lossy(&text).into_owned();
            roxmltree::Document::parse(&text).ok().and_then(|d| {
                d.descendants()
                    .find(|n| n.tag_name().name() == "dae_root")
                    .and_then(|n| n.text())
                    .map(|t| normalize(t.trim()))
            })
        }
        None => None,
    };
    let daes: Vec<String> = archive
        .file_names()
        .filter(|n| n.to_ascii_lowercase().ends_with(".dae"))
        .map(str::to_string)
        .collect();
    let member = match named {
        Some(name) => archive
            .file_names()
            .find(|n| normalize(n) == name)
            .map(str::to_string)
            .ok_or_else(|| {
                ImportError::invalid(
                    at(),
                    format!("manifest.xml names the root document {name:?}, which the package does not hold"),
                )
            })?,
        None => match daes.as_slice() {
            [one] => one.clone(),
            [] => {
                return Err(ImportError::invalid(
                    at(),
                    "the .zae package holds no .dae document",
                ))
            }
            several => {
                return Err(ImportError::invalid(
                    at(),
                    format!(
                        "the .zae package holds {} .dae documents ({}) and no manifest.xml naming the root one",
                        several.len(),
                        several.join(", ")
                    ),
                ))
            }
        },
    };
    let dae = read_member(&mut archive, &member).map_err(|e| {
        ImportError::invalid(at(), format!("cannot read {member} in the package: {e}"))
    })?;
    Ok((member, dae))
}

/// Where a texture path is looked for: beside the file (absolute paths as they are, then
/// by file name), or among the members of its `.zae`.
fn candidates(folder: &Path, relative: &str) -> Vec<PathBuf> {
    let p = PathBuf::from(relative);
    let mut out = vec![if p.is_absolute() {
        p.clone()
    } else {
        folder.join(&p)
    }];
    if let Some(name) = p.file_name() {
        out.push(folder.join(name));
    }
    out
}
