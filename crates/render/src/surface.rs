//! What each mesh looks like in a picture: its material's base colour (factor times the
//! base colour texture sampled with the mesh's UVs), or one of [`MESH_COLORS`] for a mesh
//! without material.
//!
//! Textures are decoded once per render (PNG with the `png` crate, JPEG with `zune-jpeg`;
//! other formats are drawn with the factor alone) and sampled nearest-texel with the
//! material's wrap modes. UVs are interpolated linearly in screen space (exact for the
//! default orthographic camera; a close approximation under perspective). Colours are
//! combined in linear light: the factor is linear, the texture sRGB (glTF 2.0 §3.9.2).

use std::io::Cursor;

use rigport_model::{Asset, Image, Material, Wrap};

use crate::Rgba;

/// Base colours of meshes, mesh `i` uses entry `i % 4`.
pub const MESH_COLORS: [Rgba; 4] = [
    [222, 196, 164, 255],
    [150, 182, 222, 255],
    [170, 210, 160, 255],
    [220, 164, 182, 255],
];

/// A decoded texture: `width * height` RGBA8 texels, row by row from the top.
pub(crate) struct Texture {
    width: usize,
    height: usize,
    texels: Vec<Rgba>,
}

impl Texture {
    /// Decodes `image`; `None` for formats or files that cannot be decoded.
    pub(crate) fn decode(image: &Image) -> Option<Self> {
        match Image::sniff_mime_type(&image.bytes)? {
            "image/png" => decode_png(&image.bytes),
            "image/jpeg" => decode_jpeg(&image.bytes),
            _ => None,
        }
    }

    /// The texel at glTF UV `(u, v)` (origin top-left), wrapped per axis.
    fn sample(&self, u: f32, v: f32, wrap: (Wrap, Wrap)) -> Rgba {
        let x = wrap_index(u, self.width, wrap.0);
        let y = wrap_index(v, self.height, wrap.1);
        self.texels
            .get(y * self.width + x)
            .copied()
            .unwrap_or([255; 4])
    }
}

/// Texel index along an axis of `n` texels for coordinate `t`.
fn wrap_index(t: f32, n: usize, wrap: Wrap) -> usize {
    if n == 0 || !t.is_finite() {
        return 0;
    }
    let nf = n as f32;
    let f = match wrap {
        Wrap::ClampToEdge => t.clamp(0.0, 1.0),
        Wrap::Repeat => t.rem_euclid(1.0),
        Wrap::MirroredRepeat => {
            let m = t.rem_euclid(2.0);
            if m > 1.0 {
                2.0 - m
            } else {
                m
            }
        }
    };
    ((f * nf) as usize).min(n - 1)
}

fn decode_png(bytes: &[u8]) -> Option<Texture> {
    let mut decoder = png::Decoder::new(Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().ok()?;
    let mut buf = vec![0; reader.output_buffer_size()?];
    let info = reader.next_frame(&mut buf).ok()?;
    let (w, h) = (info.width as usize, info.height as usize);
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return None,
    };
    let mut texels = Vec::with_capacity(w * h);
    for row in buf.chunks(info.line_size).take(h) {
        for px in row.chunks_exact(channels).take(w) {
            texels.push(match *px {
                [g] => [g, g, g, 255],
                [g, a] => [g, g, g, a],
                [r, g, b] => [r, g, b, 255],
                [r, g, b, a] => [r, g, b, a],
                _ => [255; 4],
            });
        }
    }
    (texels.len() == w * h).then_some(Texture {
        width: w,
        height: h,
        texels,
    })
}

fn decode_jpeg(bytes: &[u8]) -> Option<Texture> {
    use zune_core::bytestream::ZCursor;
    use zune_core::colorspace::ColorSpace;
    use zune_core::options::DecoderOptions;
    let options = DecoderOptions::default().jpeg_set_out_colorspace(ColorSpace::RGBA);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), options);
    let data = decoder.decode().ok()?;
    let (w, h) = decoder.dimensions()?;
    let texels: Vec<Rgba> = data
        .chunks_exact(4)
        .map(|p| [p[0], p[1], p[2], p[3]])
        .collect();
    (texels.len() == w * h).then_some(Texture {
        width: w,
        height: h,
        texels,
    })
}

/// sRGB-encoded `u8` to linear, by the sRGB transfer function (IEC 61966-2-1).
fn to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear to sRGB-encoded `u8`.
fn to_srgb(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// How one mesh is coloured.
pub(crate) enum Look<'a> {
    /// A flat colour, shaded by [`crate::shade`] (the palette colours, or a material
    /// factor without texture).
    Flat(Rgba),
    /// A material factor times a texture sampled with these UVs.
    Textured {
        /// Linear RGB factor.
        factor: [f32; 3],
        texture: &'a Texture,
        uvs: &'a [rigport_model::glam::Vec2],
        wrap: (Wrap, Wrap),
        /// sRGB-to-linear table for the texture's channels.
        linear: &'a [f32; 256],
    },
}

/// The decoded textures of an asset and the linear table, shared by every frame.
pub(crate) struct Surfaces {
    textures: Vec<Option<Texture>>,
    linear: [f32; 256],
}

impl Surfaces {
    /// Decodes the images the asset's base colour textures use.
    pub(crate) fn new(asset: &Asset) -> Self {
        let used = |k: usize| {
            asset
                .materials
                .iter()
                .any(|m| m.base_color_texture.is_some_and(|t| t.image.get() == k))
        };
        let textures = asset
            .images
            .iter()
            .enumerate()
            .map(|(k, image)| used(k).then(|| Texture::decode(image)).flatten())
            .collect();
        let mut linear = [0.0; 256];
        for (c, slot) in linear.iter_mut().enumerate() {
            *slot = to_linear(c as u8);
        }
        Self { textures, linear }
    }

    /// The look of mesh `mi`.
    pub(crate) fn look<'a>(&'a self, asset: &'a Asset, mi: usize) -> Look<'a> {
        let Some(mesh) = asset.meshes.get(mi) else {
            return Look::Flat(MESH_COLORS[0]);
        };
        let Some(material) = mesh.material.and_then(|m| asset.materials.get(m.get())) else {
            return Look::Flat(MESH_COLORS[mi % MESH_COLORS.len()]);
        };
        let [r, g, b, _] = material.base_color_factor;
        if let Some((texture, uvs, wrap)) = self.texture_of(mesh, material) {
            return Look::Textured {
                factor: [r, g, b],
                texture,
                uvs,
                wrap,
                linear: &self.linear,
            };
        }
        Look::Flat([to_srgb(r), to_srgb(g), to_srgb(b), 255])
    }

    fn texture_of<'a>(
        &'a self,
        mesh: &'a rigport_model::Mesh,
        material: &Material,
    ) -> Option<(&'a Texture, &'a [rigport_model::glam::Vec2], (Wrap, Wrap))> {
        let t = material.base_color_texture?;
        let texture = self.textures.get(t.image.get())?.as_ref()?;
        let uvs = match t.tex_coord {
            0 => mesh.uvs.as_deref()?,
            k => mesh.extra_uvs.get(k as usize - 1)?.as_slice(),
        };
        Some((texture, uvs, (t.sampler.wrap_s, t.sampler.wrap_t)))
    }
}

impl Look<'_> {
    /// The lit colour at barycentric weights `w` of triangle `tri`, `k` the light factor.
    pub(crate) fn color(&self, tri: [u32; 3], w: [f32; 3], k: f32) -> Rgba {
        match self {
            Look::Flat(c) => {
                let s = |v: u8| (f32::from(v) * k).round().clamp(0.0, 255.0) as u8;
                [s(c[0]), s(c[1]), s(c[2]), 255]
            }
            Look::Textured {
                factor,
                texture,
                uvs,
                wrap,
                linear,
            } => {
                let uv = |i: u32| uvs.get(i as usize).copied().unwrap_or_default();
                let p = uv(tri[0]) * w[0] + uv(tri[1]) * w[1] + uv(tri[2]) * w[2];
                let t = texture.sample(p.x, p.y, *wrap);
                let c = |ch: usize| to_srgb(factor[ch] * linear[usize::from(t[ch])] * k);
                [c(0), c(1), c(2), 255]
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_modes() {
        assert_eq!(wrap_index(0.0, 4, Wrap::Repeat), 0);
        assert_eq!(wrap_index(1.25, 4, Wrap::Repeat), 1);
        assert_eq!(wrap_index(-0.25, 4, Wrap::Repeat), 3);
        assert_eq!(wrap_index(1.5, 4, Wrap::ClampToEdge), 3);
        assert_eq!(wrap_index(1.25, 4, Wrap::MirroredRepeat), 3);
    }

    #[test]
    fn srgb_round_trips() {
        for c in [0_u8, 1, 10, 128, 200, 255] {
            assert_eq!(to_srgb(to_linear(c)), c);
        }
    }
}
