//! COLLADA importer (`.dae`, and `.zae` packages), to a rig [`Asset`].
//!
//! Read with [roxmltree](https://docs.rs/roxmltree) and mapped here. `dae-parser` (0.11)
//! was weighed first: it represents skins, morphs and animation clips, but it parses
//! through minidom, which keeps no text positions, so its errors cannot name a line, and
//! they are strings without the element; roxmltree gives every element's byte range
//! (line and column for every error) and parses a 2 MB document in milliseconds.
//!
//! | COLLADA | model |
//! |---|---|
//! | `<asset><unit meter>` | [`Asset::meters_per_unit`] (1 when absent, COLLADA's default); numbers kept in the file's unit |
//! | `<asset><up_axis>` | `Z_UP`: [`SceneFrame::up_axis`] Z, data kept (as the USD importer does); `X_UP`: +Y up with [`SceneFrame::model_to_scene`] the turn taking +X up to +Y (`x, y, z` -> `-y, x, z`); `Y_UP`: the default |
//! | the `<visual_scene>`'s nodes | joints: see `skeleton.rs`; transform elements composed as `transform.rs` says |
//! | `<instance_geometry>` | one [`Mesh`] per material symbol (`geometry.rs`), placed in the space of its node's nearest joint ([`Mesh::attached_to`]), else in model space |
//! | `<instance_controller>` | the same, skinned (bind-time model space, [`SkinBinding`]) and/or with morph targets (`controller.rs`) |
//! | `<bind_material>` | the mesh's [`Material`] (`material.rs`) |
//! | `<library_animations>`, `<library_animation_clips>` | [`Clip`]s (`anim.rs`, `clips.rs`) |
//!
//! Errors name the file, the line and column and the element (`a.dae:12:5: element
//! <skin>: ...`); inside a `.zae` the file is `package.zae/member.dae`.
//!
//! [`Mesh`]: rigport_model::Mesh
//! [`Mesh::attached_to`]: rigport_model::Mesh::attached_to
//! [`Material`]: rigport_model::Material
//! [`Clip`]: rigport_model::Clip
//! [`SkinBinding`]: rigport_model::SkinBinding
//! [`SceneFrame::up_axis`]: rigport_model::SceneFrame::up_axis
//! [`SceneFrame::model_to_scene`]: rigport_model::SceneFrame::model_to_scene

mod anim;
mod assemble;
mod clips;
mod controller;
#[cfg(test)]
mod error_tests;
mod geometry;
mod material;
mod scene;
mod skeleton;
#[cfg(test)]
mod tests;
mod transform;
mod xml;
mod zae;

use std::path::Path;

use rigport_model::Asset;

use crate::{read_file, utf8, ImportError, Imported, Location, Problem};

/// Imports a COLLADA document (`.dae`) or package (`.zae`, told by its zip signature);
/// images are read relative to it (or from inside the package).
///
/// # Errors
/// The file cannot be read; bad XML or a truncated file (at its line and column); a
/// missing referenced id, counts that do not fit, indices out of range, a cyclic
/// hierarchy, a skin without joints (at the element); a package without a `.dae`.
pub fn import(path: &Path) -> Result<Imported, ImportError> {
    let bytes = read_file(path)?;
    import_slice(&bytes, path)
}

/// Imports COLLADA from bytes (a document, or a `.zae` package when they start with the
/// zip signature); `path` names the input in errors and warnings, and images are looked
/// up beside it.
///
/// # Errors
/// As [`import`].
pub fn import_slice(bytes: &[u8], path: &Path) -> Result<Imported, ImportError> {
    let folder = path.parent().unwrap_or(Path::new("")).to_path_buf();
    if zae::is_zip(bytes) {
        let (member, dae) = zae::root(bytes, path)?;
        let root = match member.rfind('/') {
            Some(i) => member[..=i].to_string(),
            None => String::new(),
        };
        let files = zae::Files {
            folder,
            package: Some((bytes, root)),
        };
        return document(&dae, &path.join(&member), path, &files);
    }
    let files = zae::Files {
        folder,
        package: None,
    };
    document(bytes, path, path, &files)
}

/// Imports the document `bytes`, named `shown` in errors; the asset is named after `file`.
fn document(
    bytes: &[u8],
    shown: &Path,
    file: &Path,
    files: &zae::Files,
) -> Result<Imported, ImportError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(ImportError::new(Location::file(shown), Problem::Empty));
    }
    let text = utf8(bytes, shown)?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let parsed = xml::parse(text, shown)?;
    let doc = xml::Doc::new(&parsed, shown);
    let root = doc.root();
    if root.tag_name().name() != "COLLADA" {
        return Err(doc.invalid(
            root,
            format!(
                "the root element is <{}>, not <COLLADA>",
                root.tag_name().name()
            ),
        ));
    }
    let name = file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (asset, warnings) = assemble::run(&doc, files, &name)?;
    crate::check_asset(&asset, || Location::file(shown))?;
    Ok(Imported { asset, warnings })
}

/// Whether `head` (a file's first bytes) is a COLLADA document: after a byte-order mark,
/// white space, the XML declaration, comments and a DOCTYPE, the root element is
/// `<COLLADA`.
pub fn is_collada(head: &[u8]) -> bool {
    let mut rest = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
    loop {
        let start = rest
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(rest.len());
        rest = &rest[start..];
        let skip_to = |rest: &[u8], end: &[u8]| {
            rest.windows(end.len())
                .position(|w| w == end)
                .map(|i| i + end.len())
        };
        let next = if rest.starts_with(b"<?") {
            skip_to(rest, b"?>")
        } else if rest.starts_with(b"<!--") {
            skip_to(rest, b"-->")
        } else if rest.starts_with(b"<!") {
            skip_to(rest, b">")
        } else {
            return rest.starts_with(b"<COLLADA")
                && rest
                    .get(8)
                    .is_none_or(|b| b.is_ascii_whitespace() || matches!(b, b'>' | b'/'));
        };
        match next {
            Some(n) => rest = &rest[n..],
            None => return false,
        }
    }
}

/// The unit and scene frame `<asset>` states.
///
/// # Errors
/// A `meter` that is not a positive number, an unknown `<up_axis>`.
fn asset_frame(doc: &xml::Doc) -> Result<(f64, rigport_model::SceneFrame), ImportError> {
    use rigport_model::glam::{DMat4, DVec4};
    use rigport_model::{SceneFrame, UpAxis};
    let asset = xml::child(doc.root(), "asset");
    let mut meters = 1.0;
    if let Some(unit) = asset.and_then(|a| xml::child(a, "unit")) {
        if let Some(m) = unit.attribute("meter") {
            meters = m
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|m| m.is_finite() && *m > 0.0)
                .ok_or_else(|| {
                    doc.invalid(unit, format!("meter {m:?} is not a positive number"))
                })?;
        }
    }
    let mut frame = SceneFrame::default();
    if let Some(up) = asset.and_then(|a| xml::child(a, "up_axis")) {
        match up.text().unwrap_or("").trim() {
            "Y_UP" | "" => {}
            "Z_UP" => frame.up_axis = UpAxis::Z,
            "X_UP" => {
                frame.model_to_scene = DMat4::from_cols(DVec4::Y, -DVec4::X, DVec4::Z, DVec4::W);
            }
            other => {
                return Err(doc.invalid(up, format!("up axis {other:?} is not X_UP, Y_UP or Z_UP")))
            }
        }
    }
    Ok((meters, frame))
}

/// An empty asset named `name` with the unit and frame of `doc`.
fn empty_asset(doc: &xml::Doc, name: &str) -> Result<Asset, ImportError> {
    let (meters, frame) = asset_frame(doc)?;
    Ok(Asset {
        name: name.to_string(),
        meters_per_unit: Some(meters),
        frame,
        ..Asset::default()
    })
}
