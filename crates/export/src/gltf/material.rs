//! Materials, textures, samplers and images (glTF 2.0 §3.8, §3.9).
//!
//! Every material of the asset is written, in order, so material `k` of the model is
//! material `k` of the file. Images are written only when a material uses them (an unused
//! one would be the validator's `UNUSED_OBJECT`), in order; each is stored in the binary
//! buffer with its `mimeType` (`.glb`) or referred to by a relative URI naming a file
//! written beside the `.gltf`. One texture per distinct (image, sampler) pair, one sampler
//! per distinct non-default sampler.

use std::collections::BTreeMap;

use gltf_json as json;
use json::validation::Checked;
use json::Index;
use rigport_model::{
    AlphaMode, Asset, MagFilter, Material, MinFilter, Sampler, TextureRef, Warning, Wrap,
};

use super::buffer::Builder;

/// Where image bytes go.
pub(crate) enum ImagePlacement<'u> {
    /// In the binary buffer, one buffer view each (`.glb`).
    Embedded,
    /// At these relative URIs, one per asset image (`.gltf`); the caller writes the files.
    Uris(&'u [String]),
}

/// Writes every material (and the images, textures and samplers they use), so that glTF
/// material `k` is the model's material `k`.
pub(crate) fn write_materials(
    b: &mut Builder,
    asset: &Asset,
    placement: &ImagePlacement<'_>,
    warnings: &mut Vec<Warning>,
) {
    let mut used: Vec<bool> = vec![false; asset.images.len()];
    for m in &asset.materials {
        for (_, t) in m.textures() {
            if let Some(u) = used.get_mut(t.image.get()) {
                *u = true;
            }
        }
    }
    let unused = used.iter().filter(|u| !**u).count();
    if unused > 0 {
        warnings.push(Warning::Note {
            location: "images".into(),
            message: format!("{unused} image(s) no material uses were not written"),
        });
    }
    let mut image_index: Vec<Option<Index<json::Image>>> = vec![None; asset.images.len()];
    for (k, image) in asset.images.iter().enumerate() {
        if !used[k] {
            continue;
        }
        let name = (!image.name.is_empty()).then(|| image.name.clone());
        let mime_type = Some(json::image::MimeType(image.mime_type.clone()));
        let entry = match placement {
            ImagePlacement::Embedded => json::Image {
                buffer_view: Some(b.bytes_view(&image.bytes)),
                mime_type,
                name,
                uri: None,
                extensions: None,
                extras: None,
            },
            ImagePlacement::Uris(uris) => json::Image {
                buffer_view: None,
                mime_type,
                name,
                uri: uris.get(k).cloned(),
                extensions: None,
                extras: None,
            },
        };
        image_index[k] = Some(b.root.push(entry));
    }

    let mut samplers: BTreeMap<SamplerKey, Index<json::texture::Sampler>> = BTreeMap::new();
    let mut textures: BTreeMap<(u32, SamplerKey), Index<json::Texture>> = BTreeMap::new();
    let mut texture = |b: &mut Builder, t: &TextureRef| -> Option<Index<json::Texture>> {
        let source = image_index.get(t.image.get()).copied().flatten()?;
        let key = SamplerKey::of(&t.sampler);
        if let Some(&index) = textures.get(&(t.image.0, key)) {
            return Some(index);
        }
        let sampler = (t.sampler != Sampler::default()).then(|| {
            *samplers
                .entry(key)
                .or_insert_with(|| b.root.push(json_sampler(&t.sampler)))
        });
        let index = b.root.push(json::Texture {
            name: None,
            sampler,
            source,
            extensions: None,
            extras: None,
        });
        textures.insert((t.image.0, key), index);
        Some(index)
    };
    let mut info = |b: &mut Builder, t: &Option<TextureRef>| {
        let t = t.as_ref()?;
        Some(json::texture::Info {
            index: texture(b, t)?,
            tex_coord: t.tex_coord,
            extensions: None,
            extras: None,
        })
    };
    for m in &asset.materials {
        let base_color_texture = info(b, &m.base_color_texture);
        let metallic_roughness_texture = info(b, &m.metallic_roughness_texture);
        let normal_texture = info(b, &m.normal_texture).map(|i| json::material::NormalTexture {
            index: i.index,
            scale: m.normal_scale,
            tex_coord: i.tex_coord,
            extensions: None,
            extras: None,
        });
        let occlusion_texture =
            info(b, &m.occlusion_texture).map(|i| json::material::OcclusionTexture {
                index: i.index,
                strength: json::material::StrengthFactor(m.occlusion_strength),
                tex_coord: i.tex_coord,
                extensions: None,
                extras: None,
            });
        let emissive_texture = info(b, &m.emissive_texture);
        b.root.push(json_material(
            m,
            base_color_texture,
            metallic_roughness_texture,
            normal_texture,
            occlusion_texture,
            emissive_texture,
        ));
    }
}

/// The glTF material for `m`, given its written textures.
fn json_material(
    m: &Material,
    base_color_texture: Option<json::texture::Info>,
    metallic_roughness_texture: Option<json::texture::Info>,
    normal_texture: Option<json::material::NormalTexture>,
    occlusion_texture: Option<json::material::OcclusionTexture>,
    emissive_texture: Option<json::texture::Info>,
) -> json::Material {
    let alpha_mode = match m.alpha_mode {
        AlphaMode::Opaque => json::material::AlphaMode::Opaque,
        AlphaMode::Mask => json::material::AlphaMode::Mask,
        AlphaMode::Blend => json::material::AlphaMode::Blend,
    };
    json::Material {
        // Only meaningful in MASK mode (validator MATERIAL_ALPHA_CUTOFF_INVALID_MODE).
        alpha_cutoff: (m.alpha_mode == AlphaMode::Mask)
            .then_some(json::material::AlphaCutoff(m.alpha_cutoff)),
        alpha_mode: Checked::Valid(alpha_mode),
        double_sided: m.double_sided,
        name: (!m.name.is_empty()).then(|| m.name.clone()),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor(m.base_color_factor),
            base_color_texture,
            metallic_factor: json::material::StrengthFactor(m.metallic_factor),
            roughness_factor: json::material::StrengthFactor(m.roughness_factor),
            metallic_roughness_texture,
            extensions: None,
            extras: None,
        },
        normal_texture,
        occlusion_texture,
        emissive_texture,
        emissive_factor: json::material::EmissiveFactor(m.emissive_factor),
        extensions: None,
        extras: None,
    }
}

/// A sampler as an orderable key (glTF enumerant values).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct SamplerKey([u32; 4]);

impl SamplerKey {
    fn of(s: &Sampler) -> Self {
        let mag = s.mag_filter.map_or(0, |f| f as u32 + 1);
        let min = s.min_filter.map_or(0, |f| f as u32 + 1);
        Self([mag, min, s.wrap_s as u32, s.wrap_t as u32])
    }
}

/// The glTF sampler for `s`.
fn json_sampler(s: &Sampler) -> json::texture::Sampler {
    use json::texture as t;
    let wrap = |w: Wrap| {
        Checked::Valid(match w {
            Wrap::Repeat => t::WrappingMode::Repeat,
            Wrap::ClampToEdge => t::WrappingMode::ClampToEdge,
            Wrap::MirroredRepeat => t::WrappingMode::MirroredRepeat,
        })
    };
    t::Sampler {
        mag_filter: s.mag_filter.map(|f| {
            Checked::Valid(match f {
                MagFilter::Nearest => t::MagFilter::Nearest,
                MagFilter::Linear => t::MagFilter::Linear,
            })
        }),
        min_filter: s.min_filter.map(|f| {
            Checked::Valid(match f {
                MinFilter::Nearest => t::MinFilter::Nearest,
                MinFilter::Linear => t::MinFilter::Linear,
                MinFilter::NearestMipmapNearest => t::MinFilter::NearestMipmapNearest,
                MinFilter::LinearMipmapNearest => t::MinFilter::LinearMipmapNearest,
                MinFilter::NearestMipmapLinear => t::MinFilter::NearestMipmapLinear,
                MinFilter::LinearMipmapLinear => t::MinFilter::LinearMipmapLinear,
            })
        }),
        name: None,
        wrap_s: wrap(s.wrap_s),
        wrap_t: wrap(s.wrap_t),
        extensions: None,
        extras: None,
    }
}

/// The highest UV set `material` reads, plus one (0 when it has no texture).
pub(crate) fn uv_sets_needed(material: &Material) -> u32 {
    material
        .textures()
        .map(|(_, t)| t.tex_coord + 1)
        .max()
        .unwrap_or(0)
}
