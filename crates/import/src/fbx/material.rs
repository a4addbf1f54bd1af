//! Materials: each FBX material (in ufbx's `scene.materials` order, so its typed id is its
//! [`MaterialIndex`](rigport_model::MaterialIndex)) as a glTF metallic-roughness core.
//!
//! | FBX (ufbx's maps) | model |
//! |---|---|
//! | `DiffuseColor` x `DiffuseFactor` (ufbx `pbr.base_color` x `pbr.base_factor`) | `base_color_factor` (alpha 1) |
//! | the texture on the base colour: embedded content, else the file (absolute, relative to the FBX, or by name beside it) | `base_color_texture` (the first UV set, wrap modes) |
//! | anything else | metallic 0, roughness 1 (a Lambert/Phong surface) |
//!
//! A texture that cannot be found is left out with a [`Warning::Incomplete`].

use std::path::{Path, PathBuf};

use rigport_model::{Image, ImageIndex, Material, Sampler, TextureRef, Warning, Wrap};

use super::incomplete;

/// The materials and the images they use.
#[derive(Default)]
pub(super) struct Materials {
    pub(super) materials: Vec<Material>,
    pub(super) images: Vec<Image>,
}

/// Every material of the scene (see the module table).
pub(super) fn build(scene: &ufbx::Scene, path: &Path, warnings: &mut Vec<Warning>) -> Materials {
    let mut out = Materials::default();
    // Texture typed id -> image, so a texture used twice is stored once.
    let mut loaded: Vec<(u32, Option<ImageIndex>)> = Vec::new();
    for material in scene.materials.iter() {
        let pbr = &material.pbr;
        let color = pbr.base_color.value_vec4;
        let factor = if pbr.base_factor.has_value {
            pbr.base_factor.value_vec4.x
        } else {
            1.0
        };
        let channel = |c: f64| (c * factor).clamp(0.0, 1.0) as f32;
        let mut m = Material {
            name: material.element.name.to_string(),
            base_color_factor: [channel(color.x), channel(color.y), channel(color.z), 1.0],
            metallic_factor: 0.0,
            roughness_factor: 1.0,
            ..Material::default()
        };
        if let Some(texture) = pbr.base_color.texture.as_ref() {
            let id = texture.element.typed_id;
            let image = match loaded.iter().find(|(t, _)| *t == id) {
                Some((_, image)) => *image,
                None => {
                    let image = load_texture(texture, path, &mut out.images, warnings);
                    loaded.push((id, image));
                    image
                }
            };
            m.base_color_texture = image.map(|image| TextureRef {
                image,
                tex_coord: 0,
                sampler: Sampler {
                    wrap_s: wrap(texture.wrap_u),
                    wrap_t: wrap(texture.wrap_v),
                    ..Sampler::default()
                },
            });
        }
        out.materials.push(m);
    }
    out
}

fn wrap(mode: ufbx::WrapMode) -> Wrap {
    match mode {
        ufbx::WrapMode::Clamp => Wrap::ClampToEdge,
        ufbx::WrapMode::Repeat => Wrap::Repeat,
    }
}

/// The texture's image: its embedded bytes, else its file; `None` with a warning when
/// neither can be read.
fn load_texture(
    texture: &ufbx::Texture,
    path: &Path,
    images: &mut Vec<Image>,
    warnings: &mut Vec<Warning>,
) -> Option<ImageIndex> {
    let file_name = |s: &str| {
        Path::new(&s.replace('\\', "/"))
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
    };
    let (name, bytes) = if !texture.content.is_empty() {
        let name = file_name(&texture.relative_filename)
            .or_else(|| file_name(&texture.filename))
            .unwrap_or_else(|| texture.element.name.to_string());
        (name, texture.content.to_vec())
    } else {
        let folder = path.parent().unwrap_or(Path::new(""));
        let mut candidates: Vec<PathBuf> = Vec::new();
        for s in [
            &texture.absolute_filename,
            &texture.relative_filename,
            &texture.filename,
        ] {
            if !s.is_empty() {
                let p = PathBuf::from(s.replace('\\', "/"));
                candidates.push(if p.is_absolute() { p } else { folder.join(p) });
            }
        }
        if let Some(n) =
            file_name(&texture.filename).or_else(|| file_name(&texture.relative_filename))
        {
            candidates.push(folder.join(n));
        }
        let found = candidates
            .iter()
            .find_map(|p| std::fs::read(p).ok().map(|b| (p.clone(), b)));
        let Some((file, bytes)) = found else {
            let shown = if texture.relative_filename.is_empty() {
                texture.filename.to_string()
            } else {
                texture.relative_filename.to_string()
            };
            warnings.push(incomplete(
                path,
                &texture.element.name,
                format!(
                    "the texture {shown:?} is neither embedded nor found beside the file: the \
                     material is imported without it"
                ),
            ));
            return None;
        };
        let name = file
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        (name, bytes)
    };
    let mime_type = Image::sniff_mime_type(&bytes)
        .unwrap_or("application/octet-stream")
        .to_string();
    images.push(Image {
        name,
        mime_type,
        bytes,
    });
    Some(ImageIndex(images.len() as u32 - 1))
}
