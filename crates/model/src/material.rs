//! What a mesh looks like: metallic-roughness materials, their textures and the images
//! those read.
//!
//! The model follows glTF 2.0's core material (§3.9, "Materials"), the common ground of the
//! formats rigport reads and writes: USD's `UsdPreviewSurface` maps onto it, and OBJ `.mtl`
//! files are converted to it by the importer. Factors are linear; colours are in the
//! texture's own space (sRGB for base colour and emissive textures, linear for the others),
//! as in glTF. Defaults are glTF's.
//!
//! Images are kept as the source's encoded bytes (PNG, JPEG, ...) with their MIME type,
//! never decoded here, so a conversion copies them bit for bit.

use std::fmt;

/// Index of a [`Material`] in [`Asset::materials`](crate::Asset::materials).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MaterialIndex(pub u32);

impl MaterialIndex {
    /// The index as `usize`.
    pub fn get(self) -> usize {
        self.0 as usize
    }
}

impl fmt::Display for MaterialIndex {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "material {}", self.0)
    }
}

/// Index of an [`Image`] in [`Asset::images`](crate::Asset::images).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ImageIndex(pub u32);

impl ImageIndex {
    /// The index as `usize`.
    pub fn get(self) -> usize {
        self.0 as usize
    }
}

impl fmt::Display for ImageIndex {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "image {}", self.0)
    }
}

/// An encoded image file, as the source had it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Image {
    /// The source's name for it: the file name it was read from (`skin.png`), else the
    /// name the source gave it; may be empty. Exporters derive output file names from it.
    pub name: String,
    /// MIME type of `bytes`: `image/png`, `image/jpeg`, ... (sniffed from the bytes when the
    /// source did not say).
    pub mime_type: String,
    /// The encoded file.
    pub bytes: Vec<u8>,
}

impl Image {
    /// The MIME type that `bytes` start like: `image/png`, `image/jpeg`, `image/webp`,
    /// `image/gif`, `image/bmp`, or `None`.
    pub fn sniff_mime_type(bytes: &[u8]) -> Option<&'static str> {
        if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
            Some("image/png")
        } else if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
            Some("image/jpeg")
        } else if bytes.len() >= 12 && &bytes[..4] == b"RIFF" && &bytes[8..12] == b"WEBP" {
            Some("image/webp")
        } else if bytes.starts_with(b"GIF8") {
            Some("image/gif")
        } else if bytes.starts_with(b"BM") {
            Some("image/bmp")
        } else {
            None
        }
    }

    /// The usual file extension for [`Image::mime_type`] (`png`, `jpg`, ...; `bin` when
    /// unknown).
    pub fn extension(&self) -> &'static str {
        match self.mime_type.as_str() {
            "image/png" => "png",
            "image/jpeg" => "jpg",
            "image/webp" => "webp",
            "image/gif" => "gif",
            "image/bmp" => "bmp",
            "image/ktx2" => "ktx2",
            _ => "bin",
        }
    }
}

/// Magnification filter (glTF `sampler.magFilter`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MagFilter {
    /// Nearest texel.
    Nearest,
    /// Bilinear.
    Linear,
}

/// Minification filter (glTF `sampler.minFilter`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MinFilter {
    /// Nearest texel, no mipmaps.
    Nearest,
    /// Bilinear, no mipmaps.
    Linear,
    /// Nearest texel of the nearest mipmap.
    NearestMipmapNearest,
    /// Bilinear in the nearest mipmap.
    LinearMipmapNearest,
    /// Nearest texel, blended between mipmaps.
    NearestMipmapLinear,
    /// Trilinear.
    LinearMipmapLinear,
}

/// Texture wrap mode along one axis (glTF `sampler.wrapS` / `wrapT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// Tile (the glTF default).
    #[default]
    Repeat,
    /// Clamp to the edge texel.
    ClampToEdge,
    /// Tile, mirroring every other copy.
    MirroredRepeat,
}

/// How a texture is sampled. `None` filters leave the choice to the viewer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Sampler {
    /// Magnification filter.
    pub mag_filter: Option<MagFilter>,
    /// Minification filter.
    pub min_filter: Option<MinFilter>,
    /// Wrap along u.
    pub wrap_s: Wrap,
    /// Wrap along v.
    pub wrap_t: Wrap,
}

/// One use of an image by a material.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TextureRef {
    /// The image.
    pub image: ImageIndex,
    /// The UV set it is read with: 0 is [`Mesh::uvs`](crate::Mesh::uvs), `k >= 1` is
    /// [`Mesh::extra_uvs`](crate::Mesh::extra_uvs)`[k - 1]` (glTF `TEXCOORD_k`).
    pub tex_coord: u32,
    /// How it is sampled.
    pub sampler: Sampler,
}

/// How alpha is used (glTF `material.alphaMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum AlphaMode {
    /// Alpha ignored (the default).
    #[default]
    Opaque,
    /// Alpha below [`Material::alpha_cutoff`] is fully transparent, else opaque.
    Mask,
    /// Alpha blended.
    Blend,
}

/// A metallic-roughness material (glTF 2.0 §3.9.2). Every texture's value is multiplied by
/// its factor.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name (may be empty).
    pub name: String,
    /// Linear RGBA multiplier of the base colour; default `[1, 1, 1, 1]`.
    pub base_color_factor: [f32; 4],
    /// Base colour texture (sRGB RGB, linear alpha).
    pub base_color_texture: Option<TextureRef>,
    /// Metalness, `0..=1`; default 1.
    pub metallic_factor: f32,
    /// Perceptual roughness, `0..=1`; default 1.
    pub roughness_factor: f32,
    /// Roughness in G, metalness in B (linear).
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Tangent-space normal map.
    pub normal_texture: Option<TextureRef>,
    /// Scale of the normal map's X and Y; default 1.
    pub normal_scale: f32,
    /// Ambient occlusion in R (linear).
    pub occlusion_texture: Option<TextureRef>,
    /// Occlusion strength, `0..=1`; default 1.
    pub occlusion_strength: f32,
    /// Linear RGB emitted light; default black.
    pub emissive_factor: [f32; 3],
    /// Emissive texture (sRGB).
    pub emissive_texture: Option<TextureRef>,
    /// Alpha mode; default opaque.
    pub alpha_mode: AlphaMode,
    /// Cutoff for [`AlphaMode::Mask`]; default 0.5.
    pub alpha_cutoff: f32,
    /// Whether back faces are shown too; default `false`.
    pub double_sided: bool,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: String::new(),
            base_color_factor: [1.0; 4],
            base_color_texture: None,
            metallic_factor: 1.0,
            roughness_factor: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            emissive_factor: [0.0; 3],
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: 0.5,
            double_sided: false,
        }
    }
}

impl Material {
    /// Every texture with its role (`baseColor`, `metallicRoughness`, `normal`,
    /// `occlusion`, `emissive`), in that order.
    pub fn textures(&self) -> impl Iterator<Item = (&'static str, &TextureRef)> {
        [
            ("baseColor", &self.base_color_texture),
            ("metallicRoughness", &self.metallic_roughness_texture),
            ("normal", &self.normal_texture),
            ("occlusion", &self.occlusion_texture),
            ("emissive", &self.emissive_texture),
        ]
        .into_iter()
        .filter_map(|(role, t)| t.as_ref().map(|t| (role, t)))
    }

    /// Every factor as floats, in a fixed order (base colour RGBA, metallic, roughness,
    /// normal scale, occlusion strength, emissive RGB, alpha cutoff): handy to check that
    /// a conversion kept them.
    pub fn factors(&self) -> [f32; 12] {
        let [r, g, b, a] = self.base_color_factor;
        let [er, eg, eb] = self.emissive_factor;
        [
            r,
            g,
            b,
            a,
            self.metallic_factor,
            self.roughness_factor,
            self.normal_scale,
            self.occlusion_strength,
            er,
            eg,
            eb,
            self.alpha_cutoff,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sniffs_common_formats() {
        assert_eq!(
            Image::sniff_mime_type(b"\x89PNG\r\n\x1a\n...."),
            Some("image/png")
        );
        assert_eq!(
            Image::sniff_mime_type(&[0xFF, 0xD8, 0xFF, 0xE0]),
            Some("image/jpeg")
        );
        assert_eq!(Image::sniff_mime_type(b"hello"), None);
        let jpg = Image {
            mime_type: "image/jpeg".into(),
            ..Default::default()
        };
        assert_eq!(jpg.extension(), "jpg");
    }

    #[test]
    fn defaults_are_gltf_defaults() {
        let m = Material::default();
        assert_eq!(m.base_color_factor, [1.0; 4]);
        assert_eq!((m.metallic_factor, m.roughness_factor), (1.0, 1.0));
        assert_eq!(m.alpha_cutoff, 0.5);
        assert_eq!(m.textures().count(), 0);
    }
}
