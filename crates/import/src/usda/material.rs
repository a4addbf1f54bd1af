//! UsdPreviewSurface material networks and `material:binding` (text layers).
//!
//! Every `Material` prim whose `outputs:surface` connects to a `UsdPreviewSurface` shader
//! becomes a model [`Material`], in stage order:
//!
//! | UsdPreviewSurface | model |
//! |---|---|
//! | `inputs:diffuseColor` value, `inputs:opacity` value | `base_color_factor` |
//! | `inputs:diffuseColor.connect` to a `UsdUVTexture` | `base_color_texture` (its `inputs:file` read beside the layer, `inputs:scale` as the factor, wrap modes, UV set from the `UsdPrimvarReader_float2` `varname`: `st` 0, `stN` N) |
//! | `inputs:metallic`, `inputs:roughness` | `metallic_factor`, `roughness_factor` (USD's defaults 0 and 0.5 when unauthored) |
//! | `inputs:emissiveColor` | `emissive_factor` |
//! | `inputs:opacityThreshold` > 0 | `alpha_mode = Mask`, `alpha_cutoff` |
//! | `inputs:normal.connect` to a `UsdUVTexture` | `normal_texture` |
//!
//! A Mesh's `rel material:binding` picks its material. Only absolute connection paths are
//! followed; texture files are read beside the layer's file (not from inside a `.usdz`).

use std::collections::HashMap;

use rigport_model::{
    AlphaMode, Image, ImageIndex, Material, MaterialIndex, Sampler, TextureRef, Wrap,
};

use super::importer::Importer;
use super::layer::Value;
use super::stage::Prim;
use super::values::{number, token, tuple};

/// The materials of a stage and where meshes find them.
#[derive(Default)]
pub(super) struct Materials {
    pub(super) materials: Vec<Material>,
    pub(super) images: Vec<Image>,
    /// Material prim path -> its index.
    by_path: HashMap<String, MaterialIndex>,
}

impl Materials {
    /// The material bound to `prim` (a Mesh) by `rel material:binding`.
    pub(super) fn bound(&self, prim: &Prim<'_>) -> Option<MaterialIndex> {
        let target = prim.prop("material:binding")?.targets?.first()?;
        self.by_path.get(target.as_str()).copied()
    }
}

/// Splits `</A/B.outputs:rgb>` into the prim path and the property name.
fn split_connection(path: &str) -> Option<(&str, &str)> {
    let slash = path.rfind('/')?;
    let dot = path[slash..].find('.')? + slash;
    Some((&path[..dot], &path[dot + 1..]))
}

impl<'l> Importer<'l, '_> {
    /// Reads every Material prim with a UsdPreviewSurface surface.
    pub(super) fn materials(&mut self) -> Materials {
        let mut out = Materials::default();
        let mut image_paths: Vec<std::path::PathBuf> = Vec::new();
        for i in 0..self.stage.prims.len() {
            let Some(prim) = self.stage.prims.get(i) else {
                continue;
            };
            if prim.type_name != Some("Material") || !prim.is_scene_prim() {
                continue;
            }
            let Some((surface, _)) = prim
                .prop("outputs:surface")
                .and_then(|p| p.connect)
                .and_then(|c| c.first())
                .and_then(|c| split_connection(c))
            else {
                continue;
            };
            let Some(shader) = self.stage.get(surface) else {
                continue;
            };
            if shader_id(shader) != Some("UsdPreviewSurface") {
                continue;
            }
            let mut material = Material {
                name: prim.name.to_string(),
                // USD's UsdPreviewSurface fallbacks.
                base_color_factor: [0.18, 0.18, 0.18, 1.0],
                metallic_factor: 0.0,
                roughness_factor: 0.5,
                ..Material::default()
            };
            let get = |name: &str| shader.prop(name).and_then(|p| p.default);
            if let Some([r, g, b]) = get("inputs:diffuseColor").and_then(tuple::<3>) {
                material.base_color_factor = [r as f32, g as f32, b as f32, 1.0];
            }
            if let Some(a) = get("inputs:opacity").and_then(number) {
                material.base_color_factor[3] = a as f32;
            }
            if let Some(m) = get("inputs:metallic").and_then(number) {
                material.metallic_factor = m as f32;
            }
            if let Some(r) = get("inputs:roughness").and_then(number) {
                material.roughness_factor = r as f32;
            }
            if let Some([r, g, b]) = get("inputs:emissiveColor").and_then(tuple::<3>) {
                material.emissive_factor = [r as f32, g as f32, b as f32];
            }
            if let Some(t) = get("inputs:opacityThreshold").and_then(number) {
                if t > 0.0 {
                    material.alpha_mode = AlphaMode::Mask;
                    material.alpha_cutoff = t as f32;
                }
            }
            let connected = |name: &str| {
                shader
                    .prop(name)
                    .and_then(|p| p.connect)
                    .and_then(|c| c.first())
                    .and_then(|c| split_connection(c))
                    .map(|(p, _)| p)
            };
            if let Some(tex) = connected("inputs:diffuseColor").and_then(|p| self.stage.get(p)) {
                if let Some((texture, scale)) = self.texture(tex, &mut out.images, &mut image_paths)
                {
                    material.base_color_texture = Some(texture);
                    material.base_color_factor = scale.unwrap_or([1.0; 4]);
                }
            }
            if let Some(tex) = connected("inputs:normal").and_then(|p| self.stage.get(p)) {
                if let Some((texture, _)) = self.texture(tex, &mut out.images, &mut image_paths) {
                    material.normal_texture = Some(texture);
                }
            }
            out.by_path
                .insert(prim.path.clone(), MaterialIndex(out.materials.len() as u32));
            out.materials.push(material);
        }
        out
    }

    /// A `UsdUVTexture` shader as a texture reference (loading its file) and its
    /// `inputs:scale`; `None` (with a warning) when the file cannot be read.
    fn texture(
        &self,
        shader: &Prim<'l>,
        images: &mut Vec<Image>,
        image_paths: &mut Vec<std::path::PathBuf>,
    ) -> Option<(TextureRef, Option<[f32; 4]>)> {
        if shader_id(shader) != Some("UsdUVTexture") {
            return None;
        }
        let get = |name: &str| shader.prop(name).and_then(|p| p.default);
        let Some(Value::Asset(file, _)) = get("inputs:file") else {
            return None;
        };
        let relative = file.strip_prefix("./").unwrap_or(file);
        let path = self
            .path
            .parent()
            .unwrap_or(std::path::Path::new(""))
            .join(relative);
        let image = match image_paths.iter().position(|p| *p == path) {
            Some(k) => ImageIndex(k as u32),
            None => {
                let bytes = std::fs::read(&path).ok()?;
                let mime_type = Image::sniff_mime_type(&bytes)
                    .unwrap_or("application/octet-stream")
                    .to_string();
                images.push(Image {
                    name: path
                        .file_name()
                        .map(|n| n.to_string_lossy().into_owned())
                        .unwrap_or_default(),
                    mime_type,
                    bytes,
                });
                image_paths.push(path);
                ImageIndex(images.len() as u32 - 1)
            }
        };
        let scale = get("inputs:scale")
            .and_then(tuple::<4>)
            .map(|s| s.map(|v| v as f32));
        let wrap = |name: &str| match get(name).and_then(token) {
            Some("clamp") => Wrap::ClampToEdge,
            Some("mirror") => Wrap::MirroredRepeat,
            _ => Wrap::Repeat,
        };
        let tex_coord = shader
            .prop("inputs:st")
            .and_then(|p| p.connect)
            .and_then(|c| c.first())
            .and_then(|c| split_connection(c))
            .and_then(|(p, _)| self.stage.get(p))
            .and_then(|reader| reader.prop("inputs:varname").and_then(|p| p.default))
            .and_then(token)
            .map_or(0, |name| {
                name.strip_prefix("st")
                    .and_then(|k| k.parse::<u32>().ok())
                    .unwrap_or(0)
            });
        Some((
            TextureRef {
                image,
                tex_coord,
                sampler: Sampler {
                    wrap_s: wrap("inputs:wrapS"),
                    wrap_t: wrap("inputs:wrapT"),
                    ..Sampler::default()
                },
            },
            scale,
        ))
    }
}

/// A shader's `info:id`.
fn shader_id<'a>(shader: &'a Prim<'_>) -> Option<&'a str> {
    if shader.type_name != Some("Shader") {
        return None;
    }
    shader
        .prop("info:id")
        .and_then(|p| p.default)
        .and_then(token)
}
