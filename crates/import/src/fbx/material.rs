//! Materials: each FBX material (in ufbx's `scene.materials` order, so its typed id is its
//! [`MaterialIndex`](rigport_model::MaterialIndex)) as a glTF metallic-roughness core.
//!
//! ufbx maps both the classic FBX surfaces (Lambert, Phong) and the PBR ones (3ds Max
//! Physical, Maya Standard Surface, Stingray PBS) onto one set of `pbr` maps; each map is
//! a value and maybe a texture:
//!
//! | FBX (ufbx's maps) | model |
//! |---|---|
//! | `base_color` x `base_factor` (`DiffuseColor` x `DiffuseFactor`) | `base_color_factor`, with its texture `base_color_texture` |
//! | `opacity` (PBR surfaces, Blender's), else `1 - TransparencyFactor x TransparentColor` (averaged; FBX's default colour is black) | the base colour's alpha, and [`AlphaMode::Blend`] when under 1 or textured by the base colour's own texture |
//! | `emission_color` x `emission_factor` | `emissive_factor` (clamped to 1 with a warning), with its texture `emissive_texture` |
//! | `normal_map` (`NormalMap`) | `normal_texture` |
//! | `ambient_occlusion` | `occlusion_texture` |
//! | `metalness`, `roughness` of a PBR material (`features.pbr`; glossiness turned into roughness) | `metallic_factor`, `roughness_factor` |
//! | a Lambert or Phong surface | metallic 0, roughness 1 |
//!
//! Every loss is a [`Warning::Incomplete`] (W004) naming the material: a texture that cannot
//! be found, a texture on any other property (specular, bump, displacement, an opacity or
//! metalness/roughness map that is not the base colour's: glTF packs metalness and
//! roughness into one image, which rigport does not repaint), and a texture on another UV
//! set than the first.

use std::path::{Path, PathBuf};

use rigport_model::{AlphaMode, Image, ImageIndex, Material, Sampler, TextureRef, Warning, Wrap};

use super::incomplete;

/// The materials and the images they use.
#[derive(Default)]
pub(super) struct Materials {
    pub(super) materials: Vec<Material>,
    pub(super) images: Vec<Image>,
}

/// Images loaded so far, by texture typed id (a texture used twice is stored once).
struct Loader<'a> {
    path: &'a Path,
    loaded: Vec<(u32, Option<ImageIndex>)>,
    images: Vec<Image>,
}

impl Loader<'_> {
    /// The image of `texture` (loaded once; `None` with a warning when unreadable).
    fn image(
        &mut self,
        texture: &ufbx::Texture,
        warnings: &mut Vec<Warning>,
    ) -> Option<ImageIndex> {
        let id = texture.element.typed_id;
        if let Some((_, image)) = self.loaded.iter().find(|(t, _)| *t == id) {
            return *image;
        }
        let image = load_texture(texture, self.path, &mut self.images, warnings);
        self.loaded.push((id, image));
        image
    }

    /// `map`'s texture as a reference on the first UV set.
    fn texture(
        &mut self,
        material: &str,
        map: &ufbx::MaterialMap,
        warnings: &mut Vec<Warning>,
    ) -> Option<TextureRef> {
        let texture = map.texture.as_ref()?;
        if !texture.uv_set.is_empty() && !is_first_uv_set(&texture.uv_set) {
            warnings.push(incomplete(
                self.path,
                material,
                format!(
                    "the texture {:?} reads the UV set {:?}; it is kept on the first UV set",
                    texture.element.name.to_string(),
                    texture.uv_set.to_string()
                ),
            ));
        }
        let image = self.image(texture, warnings)?;
        Some(TextureRef {
            image,
            tex_coord: 0,
            sampler: Sampler {
                wrap_s: wrap(texture.wrap_u),
                wrap_t: wrap(texture.wrap_v),
                ..Sampler::default()
            },
        })
    }
}

/// Whether an FBX UV set name is the first set's (`map1` in Maya, `UVChannel_1` in 3ds
/// Max, `UVMap` in Blender, or unnamed).
fn is_first_uv_set(name: &str) -> bool {
    matches!(
        name,
        "map1" | "UVChannel_1" | "UVMap" | "UVSet0" | "DiffuseUV"
    )
}

/// Every material of the scene (see the module table).
pub(super) fn build(scene: &ufbx::Scene, path: &Path, warnings: &mut Vec<Warning>) -> Materials {
    let mut loader = Loader {
        path,
        loaded: Vec::new(),
        images: Vec::new(),
    };
    let mut materials = Vec::new();
    for material in scene.materials.iter() {
        materials.push(convert(material, &mut loader, warnings));
    }
    Materials {
        materials,
        images: loader.images,
    }
}

/// One material (see the module table).
fn convert(
    material: &ufbx::Material,
    loader: &mut Loader<'_>,
    warnings: &mut Vec<Warning>,
) -> Material {
    let pbr = &material.pbr;
    let name = material.element.name.to_string();
    let scalar =
        |m: &ufbx::MaterialMap, default: f64| if m.has_value { m.value_vec4.x } else { default };
    let color = pbr.base_color.value_vec4;
    let factor = scalar(&pbr.base_factor, 1.0);
    let channel = |c: f64| (c * factor).clamp(0.0, 1.0) as f32;
    let opacity = if pbr.opacity.has_value {
        pbr.opacity.value_vec4.x
    } else {
        // FBX's classic surfaces: 1 - TransparencyFactor x TransparentColor (averaged; the
        // colour defaults to black, so Maya's opaque `TransparencyFactor: 1` stays opaque).
        let fbx = &material.fbx;
        let c = fbx.transparency_color.value_vec4;
        let color = if fbx.transparency_color.has_value {
            (c.x + c.y + c.z) / 3.0
        } else {
            0.0
        };
        1.0 - scalar(&fbx.transparency_factor, 0.0) * color
    }
    .clamp(0.0, 1.0) as f32;
    let mut m = Material {
        name: name.clone(),
        base_color_factor: [
            channel(color.x),
            channel(color.y),
            channel(color.z),
            opacity,
        ],
        metallic_factor: 0.0,
        roughness_factor: 1.0,
        ..Material::default()
    };
    m.base_color_texture = loader.texture(&name, &pbr.base_color, warnings);
    let base_id = pbr.base_color.texture.as_ref().map(|t| t.element.typed_id);
    let mut used: Vec<u32> = base_id.into_iter().collect();
    if opacity < 1.0 {
        m.alpha_mode = AlphaMode::Blend;
    }
    if let Some(t) = pbr.opacity.texture.as_ref() {
        if Some(t.element.typed_id) == base_id {
            m.alpha_mode = AlphaMode::Blend;
        }
    }
    // Emission.
    let e = pbr.emission_color.value_vec4;
    let strength = scalar(&pbr.emission_factor, 1.0);
    let emitted = [e.x * strength, e.y * strength, e.z * strength];
    if material.features.emission.enabled || emitted.iter().any(|&c| c > 0.0) {
        if emitted.iter().any(|&c| c > 1.0) {
            warnings.push(incomplete(
                loader.path,
                &name,
                format!("emission {emitted:?} is brighter than glTF's emissive factor holds (1); it is clamped"),
            ));
        }
        m.emissive_factor = emitted.map(|c| c.clamp(0.0, 1.0) as f32);
    }
    for (map, slot) in [
        (&pbr.emission_color, &mut m.emissive_texture),
        (&pbr.normal_map, &mut m.normal_texture),
        (&pbr.ambient_occlusion, &mut m.occlusion_texture),
    ] {
        if let Some(t) = map.texture.as_ref() {
            used.push(t.element.typed_id);
            *slot = loader.texture(&name, map, warnings);
        }
    }
    if m.emissive_texture.is_some() && m.emissive_factor == [0.0; 3] {
        m.emissive_factor = [1.0; 3];
    }
    if material.features.pbr.enabled {
        m.metallic_factor = scalar(&pbr.metalness, 0.0).clamp(0.0, 1.0) as f32;
        let rough = scalar(&pbr.roughness, 1.0);
        let rough = if material.features.roughness_as_glossiness.enabled {
            1.0 - rough
        } else {
            rough
        };
        m.roughness_factor = rough.clamp(0.0, 1.0) as f32;
    }
    // Every texture on a property the model cannot hold.
    let mut lost: Vec<String> = Vec::new();
    for t in material.textures.iter() {
        let id = t.texture.element.typed_id;
        if used.contains(&id) {
            continue;
        }
        let prop = t.material_prop.to_string();
        // The base colour's texture again on the opacity (its alpha) is kept.
        if Some(id) == base_id {
            continue;
        }
        if !lost.contains(&prop) {
            lost.push(prop);
        }
    }
    if !lost.is_empty() {
        warnings.push(incomplete(
            loader.path,
            &name,
            format!(
                "textures on {} are not kept (glTF's metallic-roughness material has no such input)",
                lost.join(", ")
            ),
        ));
    }
    m
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
