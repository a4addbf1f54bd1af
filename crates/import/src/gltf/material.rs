//! Materials, textures, samplers and images (glTF 2.0 §3.8, §3.9) to the model's
//! [`Material`]s and [`Image`]s.
//!
//! Every material and every image of the file is imported, in file order, so indices are
//! kept. Images come from a buffer view (GLB), a `data:` URI or a file beside the glTF; the
//! bytes are kept as they are. A texture becomes a [`TextureRef`] (its image, sampler and
//! `texCoord`); glTF textures themselves are not kept, since they are only (image, sampler)
//! pairs. Extensions (`KHR_texture_transform`, `KHR_materials_*`) are not imported.

use ::gltf::texture as gtex;
use rigport_model::{
    AlphaMode, Image, ImageIndex, MagFilter, Material, MinFilter, Sampler, TextureRef, Wrap,
};

use crate::ImportError;

use super::container::{percent_decode, read_uri};
use super::importer::Importer;

impl<'a> Importer<'a> {
    /// Every image of the document, in order.
    pub(super) fn images(&mut self) -> Result<Vec<Image>, ImportError> {
        let mut out = Vec::new();
        for image in self.doc.images() {
            let at = format!("/images/{}", image.index());
            let mut name = image.name().unwrap_or_default().to_string();
            let (bytes, declared) = match image.source() {
                ::gltf::image::Source::View { view, mime_type } => {
                    let buffer = self.buffers.get(view.buffer().index());
                    let range = view.offset()..view.offset().saturating_add(view.length());
                    let Some(bytes) = buffer.and_then(|b| b.get(range)) else {
                        return Err(self.err(
                            format!("{at}/bufferView"),
                            "buffer view lies outside its buffer",
                        ));
                    };
                    (bytes.to_vec(), Some(mime_type.to_string()))
                }
                ::gltf::image::Source::Uri { uri, mime_type } => {
                    let bytes = read_uri(uri, self.path, &format!("{at}/uri"), "image")?;
                    if name.is_empty() && !uri.starts_with("data:") {
                        let file = uri.rsplit('/').next().unwrap_or(uri);
                        name = percent_decode(file).unwrap_or_else(|| file.to_string());
                    }
                    let declared = mime_type.map(str::to_string).or_else(|| {
                        // data:image/png;base64,...
                        uri.strip_prefix("data:")
                            .and_then(|r| r.split([';', ',']).next())
                            .filter(|m| m.starts_with("image/"))
                            .map(str::to_string)
                    });
                    (bytes, declared)
                }
            };
            let sniffed = Image::sniff_mime_type(&bytes);
            let mime_type = match (declared, sniffed) {
                (Some(d), Some(s)) if d != s => {
                    self.repaired(
                        &at,
                        format!("declared {d:?} but the bytes are {s:?}; using {s:?}"),
                    );
                    s.to_string()
                }
                (Some(d), _) => d,
                (None, Some(s)) => s.to_string(),
                (None, None) => {
                    self.note(&at, "image format not recognised".into());
                    "application/octet-stream".to_string()
                }
            };
            out.push(Image {
                name,
                mime_type,
                bytes,
            });
        }
        Ok(out)
    }

    /// Every material of the document, in order.
    pub(super) fn materials(&mut self) -> Vec<Material> {
        let mut out = Vec::new();
        for material in self.doc.materials() {
            if material.index().is_none() {
                continue;
            }
            let pbr = material.pbr_metallic_roughness();
            let normal = material.normal_texture();
            let occlusion = material.occlusion_texture();
            out.push(Material {
                name: material.name().unwrap_or_default().to_string(),
                base_color_factor: pbr.base_color_factor(),
                base_color_texture: pbr.base_color_texture().map(|t| texture_ref(&t)),
                metallic_factor: pbr.metallic_factor(),
                roughness_factor: pbr.roughness_factor(),
                metallic_roughness_texture: pbr
                    .metallic_roughness_texture()
                    .map(|t| texture_ref(&t)),
                normal_scale: normal.as_ref().map_or(1.0, |n| n.scale()),
                normal_texture: normal.as_ref().map(|n| TextureRef {
                    image: ImageIndex(n.texture().source().index() as u32),
                    tex_coord: n.tex_coord(),
                    sampler: sampler(&n.texture().sampler()),
                }),
                occlusion_strength: occlusion.as_ref().map_or(1.0, |o| o.strength()),
                occlusion_texture: occlusion.as_ref().map(|o| TextureRef {
                    image: ImageIndex(o.texture().source().index() as u32),
                    tex_coord: o.tex_coord(),
                    sampler: sampler(&o.texture().sampler()),
                }),
                emissive_factor: material.emissive_factor(),
                emissive_texture: material.emissive_texture().map(|t| texture_ref(&t)),
                alpha_mode: match material.alpha_mode() {
                    ::gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                    ::gltf::material::AlphaMode::Mask => AlphaMode::Mask,
                    ::gltf::material::AlphaMode::Blend => AlphaMode::Blend,
                },
                alpha_cutoff: material.alpha_cutoff().unwrap_or(0.5),
                double_sided: material.double_sided(),
            });
        }
        out
    }
}

/// A `textureInfo` as a [`TextureRef`].
fn texture_ref(info: &::gltf::texture::Info<'_>) -> TextureRef {
    let texture = info.texture();
    TextureRef {
        image: ImageIndex(texture.source().index() as u32),
        tex_coord: info.tex_coord(),
        sampler: sampler(&texture.sampler()),
    }
}

/// A glTF sampler as the model's.
fn sampler(s: &gtex::Sampler<'_>) -> Sampler {
    let wrap = |w: gtex::WrappingMode| match w {
        gtex::WrappingMode::Repeat => Wrap::Repeat,
        gtex::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        gtex::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
    };
    Sampler {
        mag_filter: s.mag_filter().map(|f| match f {
            gtex::MagFilter::Nearest => MagFilter::Nearest,
            gtex::MagFilter::Linear => MagFilter::Linear,
        }),
        min_filter: s.min_filter().map(|f| match f {
            gtex::MinFilter::Nearest => MinFilter::Nearest,
            gtex::MinFilter::Linear => MinFilter::Linear,
            gtex::MinFilter::NearestMipmapNearest => MinFilter::NearestMipmapNearest,
            gtex::MinFilter::LinearMipmapNearest => MinFilter::LinearMipmapNearest,
            gtex::MinFilter::NearestMipmapLinear => MinFilter::NearestMipmapLinear,
            gtex::MinFilter::LinearMipmapLinear => MinFilter::LinearMipmapLinear,
        }),
        wrap_s: wrap(s.wrap_s()),
        wrap_t: wrap(s.wrap_t()),
    }
}
