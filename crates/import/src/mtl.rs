//! Wavefront `.mtl` material libraries, converted to metallic-roughness materials the way
//! obj2gltf does by default (its `convertTraditionalToMetallicRoughness` and
//! `createMetallicRoughnessMaterial`, CesiumGS/obj2gltf `lib/loadMtl.js`).
//!
//! | MTL | default | model ([`Material`]) |
//! |---|---|---|
//! | `Kd r g b` | 0.5 0.5 0.5 | `base_color_factor` RGB; 1 1 1 when `map_Kd` is given |
//! | `d a` / `Tr t` | 1 | `base_color_factor` alpha = `a` or `1 - t` (0 is read as 1, as obj2gltf does: it is usually an export error); below 1 gives `alpha_mode = Blend` and `double_sided` |
//! | `Ks r g b`, `Ns s` | 0 0 0, 0 | `metallic_factor` = 0; `roughness_factor` = clamp(1 - `s`/1000, 0, 1), times (1 - L) when the luminance L = 0.2125 r + 0.7154 g + 0.0721 b of `Ks` is below 0.1 |
//! | `Ke r g b` | 0 0 0 | `emissive_factor`; 1 1 1 when `map_Ke` is given |
//! | `map_Kd file` | - | `base_color_texture` (UV set 0) |
//! | `map_Bump file` / `bump file` | - | `normal_texture` (UV set 0) |
//! | `map_Ke file` | - | `emissive_texture` (UV set 0) |
//!
//! Texture file names are read relative to the `.mtl`'s folder (backslashes as `/`; when
//! options such as `-bm 1` precede the name, the last word is the name, as obj2gltf
//! assumes); a file that is not found there is looked for by its base name in that folder,
//! then skipped with a W004 warning, as is a material no library defines. Textures on other
//! inputs (`map_Ka`, `map_Ks`, `map_d`, `disp`, `refl`, ...) are W004 warnings too; other
//! statements (`Ka`, `illum`, ...) are ignored.

use std::path::{Path, PathBuf};

use crate::text::{Lines, Number};
use rigport_model::{AlphaMode, Image, ImageIndex, Material, TextureRef, Warning};

/// A material as the `.mtl` states it, before conversion.
#[derive(Clone, Debug, PartialEq)]
pub struct MtlMaterial {
    /// `newmtl` name.
    pub name: String,
    /// `Kd`.
    pub diffuse: [f32; 3],
    /// `Ks`.
    pub specular: [f32; 3],
    /// `Ke`.
    pub emissive: [f32; 3],
    /// `Ns`.
    pub shininess: f32,
    /// `d`, or `1 - Tr`.
    pub alpha: f32,
    /// `map_Kd` file name as written.
    pub map_kd: Option<String>,
    /// `map_Bump` / `bump` file name as written.
    pub map_bump: Option<String>,
    /// `map_Ke` file name as written.
    pub map_ke: Option<String>,
}

impl MtlMaterial {
    /// A material with obj2gltf's defaults (grey `Kd`, no specular, opaque).
    pub fn default_named(name: &str) -> Self {
        Self::new(name)
    }

    fn new(name: &str) -> Self {
        Self {
            name: name.to_string(),
            diffuse: [0.5; 3],
            specular: [0.0; 3],
            emissive: [0.0; 3],
            shininess: 0.0,
            alpha: 1.0,
            map_kd: None,
            map_bump: None,
            map_ke: None,
        }
    }
}

/// Parses `.mtl` text. Lenient like the readers it feeds: a malformed number line is
/// skipped with a warning naming `path:line`.
pub fn parse(text: &str, path: &Path, warnings: &mut Vec<Warning>) -> Vec<MtlMaterial> {
    let mut out: Vec<MtlMaterial> = Vec::new();
    for (line_no, line) in Lines::new(text) {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (keyword, rest) = line
            .split_once(|c: char| c.is_ascii_whitespace())
            .unwrap_or((line, ""));
        let rest = rest.trim();
        if keyword == "newmtl" {
            out.push(MtlMaterial::new(rest));
            continue;
        }
        let Some(m) = out.last_mut() else {
            continue;
        };
        let numbers: Option<Vec<f32>> = rest
            .split_ascii_whitespace()
            .map(|t| f32::read(t).ok())
            .collect();
        let mut bad = false;
        let mut rgb = |slot: &mut [f32; 3]| match numbers.as_deref() {
            Some([r, g, b, ..]) => *slot = [*r, *g, *b],
            Some([v]) => *slot = [*v; 3],
            _ => bad = true,
        };
        match keyword.to_ascii_lowercase().as_str() {
            "kd" => rgb(&mut m.diffuse),
            "ks" => rgb(&mut m.specular),
            "ke" => rgb(&mut m.emissive),
            "ns" | "d" | "tr" => match numbers.as_deref() {
                Some([v, ..]) => match keyword.to_ascii_lowercase().as_str() {
                    "ns" => m.shininess = *v,
                    "d" => m.alpha = correct_alpha(*v),
                    _ => m.alpha = correct_alpha(1.0 - v),
                },
                _ => bad = true,
            },
            "map_kd" => m.map_kd = Some(texture_name(rest)),
            "map_bump" | "bump" => m.map_bump = Some(texture_name(rest)),
            "map_ke" => m.map_ke = Some(texture_name(rest)),
            // Textures the material cannot hold: a loss, with a code.
            k if k.starts_with("map_") || matches!(k, "disp" | "decal" | "refl" | "norm") => {
                warnings.push(Warning::Incomplete {
                    location: format!("{}:{line_no}", path.display()),
                    message: format!(
                        "material {:?}: the texture `{keyword}` {:?} is not kept (glTF's \
                         metallic-roughness material has no such input)",
                        m.name,
                        texture_name(rest)
                    ),
                });
            }
            _ => {}
        }
        if bad {
            warnings.push(Warning::Note {
                location: format!("{}:{line_no}", path.display()),
                message: format!("`{keyword}` needs numbers, found {rest:?}; line ignored"),
            });
        }
    }
    out
}

/// obj2gltf's `correctAlpha`: an alpha of 0 is read as 1 (usually an exporter's error).
fn correct_alpha(alpha: f32) -> f32 {
    if alpha == 0.0 {
        1.0
    } else {
        alpha
    }
}

/// The file name of a `map_*` statement: the last word when options precede it.
fn texture_name(rest: &str) -> String {
    let name = if rest.starts_with('-') {
        rest.split_ascii_whitespace().last().unwrap_or(rest)
    } else {
        rest
    };
    name.replace('\\', "/")
}

/// Luminance as obj2gltf computes it.
fn luminance([r, g, b]: [f32; 3]) -> f32 {
    r * 0.2125 + g * 0.7154 + b * 0.0721
}

/// Converts one material (see the module docs); `image` loads a texture file and returns
/// its index in the asset's images, or `None` when it cannot be read.
pub fn convert(m: &MtlMaterial, mut image: impl FnMut(&str) -> Option<ImageIndex>) -> Material {
    let mut roughness = (1.0 - m.shininess / 1000.0).clamp(0.0, 1.0);
    let intensity = luminance(m.specular);
    if intensity < 0.1 {
        roughness *= 1.0 - intensity;
    }
    let texture = |image: ImageIndex| TextureRef {
        image,
        tex_coord: 0,
        sampler: Default::default(),
    };
    let base_color_texture = m.map_kd.as_deref().and_then(&mut image).map(texture);
    let normal_texture = m.map_bump.as_deref().and_then(&mut image).map(texture);
    let emissive_texture = m.map_ke.as_deref().and_then(&mut image).map(texture);
    let [r, g, b] = if base_color_texture.is_some() {
        [1.0; 3]
    } else {
        m.diffuse
    };
    let transparent = m.alpha < 1.0;
    Material {
        name: m.name.clone(),
        base_color_factor: [r, g, b, m.alpha],
        base_color_texture,
        metallic_factor: 0.0,
        roughness_factor: roughness,
        normal_texture,
        emissive_factor: if emissive_texture.is_some() {
            [1.0; 3]
        } else {
            m.emissive
        },
        emissive_texture,
        alpha_mode: if transparent {
            AlphaMode::Blend
        } else {
            AlphaMode::Opaque
        },
        double_sided: transparent,
        ..Material::default()
    }
}

/// Loads the materials named `used` (in that order) from the `.mtl` files `libraries`
/// (names as written after `mtllib`, relative to `obj_path`'s folder), with their texture
/// images, and how many of `used` were found. A missing library, material or texture is a
/// note, and the material is then obj2gltf's default (grey) or lacks that texture.
pub fn load(
    obj_path: &Path,
    libraries: &[String],
    used: &[String],
    warnings: &mut Vec<Warning>,
) -> (Vec<Material>, Vec<Image>, usize) {
    let folder = obj_path.parent().unwrap_or(Path::new(""));
    let mut known: Vec<(MtlMaterial, PathBuf)> = Vec::new();
    for lib in libraries {
        let lib_path = folder.join(lib.replace('\\', "/"));
        match std::fs::read(&lib_path) {
            Ok(bytes) => {
                let text = String::from_utf8_lossy(&bytes);
                let mtl_folder = lib_path.parent().unwrap_or(Path::new("")).to_path_buf();
                for m in parse(&text, &lib_path, warnings) {
                    known.push((m, mtl_folder.clone()));
                }
            }
            Err(e) => warnings.push(Warning::Incomplete {
                location: obj_path.display().to_string(),
                message: format!(
                    "material library {} cannot be read ({e}); its materials are left out",
                    lib_path.display()
                ),
            }),
        }
    }
    let mut images: Vec<Image> = Vec::new();
    let mut image_paths: Vec<PathBuf> = Vec::new();
    let mut materials = Vec::new();
    let mut found = 0;
    for name in used {
        let Some((m, mtl_folder)) = known.iter().find(|(m, _)| m.name == *name) else {
            if !known.is_empty() {
                warnings.push(Warning::Incomplete {
                    location: obj_path.display().to_string(),
                    message: format!("material {name:?} is in no material library; it is grey"),
                });
            }
            materials.push(convert(&MtlMaterial::new(name), |_| None));
            continue;
        };
        found += 1;
        let load_image = |file: &str| -> Option<ImageIndex> {
            let direct = mtl_folder.join(file);
            let base = Path::new(file).file_name().map(|b| mtl_folder.join(b));
            let candidates = std::iter::once(direct).chain(base);
            for candidate in candidates {
                if let Some(k) = image_paths.iter().position(|p| *p == candidate) {
                    return Some(ImageIndex(k as u32));
                }
                if let Ok(bytes) = std::fs::read(&candidate) {
                    let mime_type = Image::sniff_mime_type(&bytes)
                        .unwrap_or("application/octet-stream")
                        .to_string();
                    let name = candidate
                        .file_name()
                        .map(|n| n.to_string_lossy().into_owned())
                        .unwrap_or_default();
                    images.push(Image {
                        name,
                        mime_type,
                        bytes,
                    });
                    image_paths.push(candidate);
                    return Some(ImageIndex(images.len() as u32 - 1));
                }
            }
            warnings.push(Warning::Incomplete {
                location: obj_path.display().to_string(),
                message: format!(
                    "texture {file:?} of material {name:?} not found in {}; skipped",
                    mtl_folder.display()
                ),
            });
            None
        };
        materials.push(convert(m, load_image));
    }
    (materials, images, found)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn converts_like_obj2gltf() {
        let text = "newmtl skin\nKd 0.8 0.6 0.4\nKs 0.5 0.5 0.5\nNs 250\nd 0.5\n\
                    newmtl plain\nKs 0 0 0\nNs 900\nmap_Kd -bm 1 tex\\skin.png\n";
        let mut w = Vec::new();
        let parsed = parse(text, Path::new("a.mtl"), &mut w);
        assert!(w.is_empty());
        assert_eq!(parsed.len(), 2);
        assert_eq!(parsed[1].map_kd.as_deref(), Some("tex/skin.png"));
        let skin = convert(&parsed[0], |_| None);
        assert_eq!(skin.base_color_factor, [0.8, 0.6, 0.4, 0.5]);
        assert_eq!(skin.metallic_factor, 0.0);
        assert!((skin.roughness_factor - 0.75).abs() < 1e-6);
        assert_eq!(skin.alpha_mode, AlphaMode::Blend);
        assert!(skin.double_sided);
        let plain = convert(&parsed[1], |_| Some(ImageIndex(3)));
        assert_eq!(plain.base_color_factor, [1.0; 4]);
        assert_eq!(
            plain.base_color_texture.map(|t| t.image),
            Some(ImageIndex(3))
        );
        // Ks luminance 0 < 0.1: roughness * (1 - 0) stays 0.1.
        assert!((plain.roughness_factor - 0.1).abs() < 1e-6);
        // Defaults: Kd 0.5 grey.
        let grey = convert(&MtlMaterial::new("x"), |_| None);
        assert_eq!(grey.base_color_factor, [0.5, 0.5, 0.5, 1.0]);
        assert_eq!(grey.roughness_factor, 1.0);
    }

    #[test]
    fn textures_it_cannot_hold_are_coded_losses_at_their_line() {
        let text =
            "newmtl skin\nmap_Kd skin.png\nmap_Ks spec.png\nmap_d -clamp on mask.png\nKa 1 1 1\n";
        let mut w = Vec::new();
        parse(text, Path::new("a.mtl"), &mut w);
        let shown: Vec<String> = w.iter().map(|w| format!("{}: {w}", w.code())).collect();
        assert_eq!(shown.len(), 2, "{shown:?}");
        assert!(
            shown[0]
                .starts_with("W004: a.mtl:3: material \"skin\": the texture `map_Ks` \"spec.png\""),
            "{shown:?}"
        );
        assert!(
            shown[1].starts_with("W004: a.mtl:4:") && shown[1].contains("\"mask.png\""),
            "{shown:?}"
        );
    }
}
