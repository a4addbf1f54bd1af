//! UsdPreviewSurface material networks and `material:binding` (text layers).
//!
//! Every `Material` prim whose `outputs:surface` connects to a `UsdPreviewSurface` shader
//! becomes a model [`Material`], in stage order:
//!
//! | UsdPreviewSurface | model |
//! |---|---|
//! | `inputs:diffuseColor` value, `inputs:opacity` value | `base_color_factor` |
//! | `inputs:diffuseColor.connect` to a `UsdUVTexture` | `base_color_texture` (its `inputs:file`, `inputs:scale` as the factor, wrap modes, UV set from the `UsdPrimvarReader_float2` `varname`: `st` 0, `stN` N) |
//! | `inputs:metallic`, `inputs:roughness` | `metallic_factor`, `roughness_factor` (USD's defaults 0 and 0.5 when unauthored) |
//! | `inputs:metallic.connect` to `outputs:b` and `inputs:roughness.connect` to `outputs:g` of one `UsdUVTexture` | `metallic_roughness_texture` (glTF's packing; factors 1) |
//! | `inputs:emissiveColor` | `emissive_factor` |
//! | `inputs:emissiveColor.connect` to a `UsdUVTexture` | `emissive_texture` (factor 1) |
//! | `inputs:occlusion.connect` to a `UsdUVTexture` | `occlusion_texture` |
//! | `inputs:opacityThreshold` > 0 | `alpha_mode = Mask`, `alpha_cutoff` |
//! | `inputs:normal.connect` to a `UsdUVTexture` | `normal_texture` |
//!
//! A Mesh's `rel material:binding` picks its material. Only absolute connection paths are
//! followed. A texture's file is the package's member when the layer came from a `.usdz`
//! (the asset path taken relative to the root layer's folder in the archive), else the
//! file beside the layer. A texture that cannot be read, and a connected input the model
//! cannot hold (metallic and roughness from different images or channels, opacity from a
//! texture, ...), are left out with a [`rigport_model::Warning::Incomplete`] naming the
//! shader input.

use std::collections::HashMap;

use rigport_model::{
    AlphaMode, Image, ImageIndex, Material, MaterialIndex, Sampler, TextureRef, Wrap,
};

use rigport_model::Warning;

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
        let mut warnings = Vec::new();
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
            // Each connected input: the texture shader and the output it reads.
            let connected = |name: &str| {
                shader
                    .prop(name)
                    .and_then(|p| p.connect)
                    .and_then(|c| c.first())
                    .and_then(|c| split_connection(c))
                    .and_then(|(p, output)| Some((self.stage.get(p)?, output)))
            };
            let mut lost: Vec<&str> = Vec::new();
            let mut take = |name: &'static str, lost: &mut Vec<&str>| {
                let (tex, _) = connected(name)?;
                let got = self.texture(tex, &mut out.images, &mut image_paths, &mut warnings);
                if got.is_none() && shader_id(tex) != Some("UsdUVTexture") {
                    lost.push(name);
                }
                got
            };
            if let Some((texture, scale)) = take("inputs:diffuseColor", &mut lost) {
                material.base_color_texture = Some(texture);
                material.base_color_factor = scale.unwrap_or([1.0; 4]);
            }
            if let Some((texture, _)) = take("inputs:normal", &mut lost) {
                material.normal_texture = Some(texture);
            }
            if let Some((texture, _)) = take("inputs:emissiveColor", &mut lost) {
                material.emissive_texture = Some(texture);
                material.emissive_factor = [1.0; 3];
            }
            if let Some((texture, _)) = take("inputs:occlusion", &mut lost) {
                material.occlusion_texture = Some(texture);
            }
            // glTF packs metallic in blue and roughness in green of one image.
            match (connected("inputs:metallic"), connected("inputs:roughness")) {
                (None, None) => {}
                (Some((m, m_out)), Some((r, r_out)))
                    if m.path == r.path && m_out.ends_with(":b") && r_out.ends_with(":g") =>
                {
                    if let Some((texture, _)) = take("inputs:metallic", &mut lost) {
                        material.metallic_roughness_texture = Some(texture);
                        material.metallic_factor = 1.0;
                        material.roughness_factor = 1.0;
                    }
                }
                (m, r) => {
                    lost.extend(m.map(|_| "inputs:metallic"));
                    lost.extend(r.map(|_| "inputs:roughness"));
                }
            }
            for input in [
                "inputs:opacity",
                "inputs:specularColor",
                "inputs:clearcoat",
                "inputs:displacement",
            ] {
                if connected(input).is_some() {
                    lost.push(input);
                }
            }
            if !lost.is_empty() {
                warnings.push(Warning::Incomplete {
                    location: self.location(&shader.path),
                    message: format!(
                        "{} {} connected to what a glTF material cannot hold (metallic and \
                         roughness from one texture's blue and green only): left out",
                        lost.join(", "),
                        if lost.len() == 1 { "is" } else { "are" }
                    ),
                });
            }
            out.by_path
                .insert(prim.path.clone(), MaterialIndex(out.materials.len() as u32));
            out.materials.push(material);
        }
        self.warnings.extend(warnings);
        out
    }

    /// A `UsdUVTexture` shader as a texture reference (loading its file) and its
    /// `inputs:scale`; `None` when the shader is not a `UsdUVTexture` with a file, or (with
    /// a warning in `warnings`) when the file cannot be read.
    fn texture(
        &self,
        shader: &Prim<'l>,
        images: &mut Vec<Image>,
        image_paths: &mut Vec<std::path::PathBuf>,
        warnings: &mut Vec<Warning>,
    ) -> Option<(TextureRef, Option<[f32; 4]>)> {
        if shader_id(shader) != Some("UsdUVTexture") {
            return None;
        }
        let get = |name: &str| shader.prop(name).and_then(|p| p.default);
        let Some(Value::Asset(file, _)) = get("inputs:file") else {
            return None;
        };
        let relative = file.strip_prefix("./").unwrap_or(file);
        // Inside the package first (a `.usdz`), then beside the layer's file.
        let in_package = self.package.as_ref().and_then(|p| p.member(relative));
        let path = match &in_package {
            Some((name, _)) => std::path::PathBuf::from(format!("{}[{name}]", self.path.display())),
            None => self
                .path
                .parent()
                .unwrap_or(std::path::Path::new(""))
                .join(relative),
        };
        let image = match image_paths.iter().position(|p| *p == path) {
            Some(k) => ImageIndex(k as u32),
            None => {
                let bytes = match in_package {
                    Some((_, bytes)) => bytes,
                    None => match std::fs::read(&path) {
                        Ok(bytes) => bytes,
                        Err(e) => {
                            warnings.push(Warning::Incomplete {
                                location: self.location(&shader.path),
                                message: format!(
                                    "the texture {file:?} cannot be read ({e}): the material \
                                     is imported without it"
                                ),
                            });
                            return None;
                        }
                    },
                };
                let mime_type = Image::sniff_mime_type(&bytes)
                    .unwrap_or("application/octet-stream")
                    .to_string();
                let name = std::path::Path::new(relative)
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                images.push(Image {
                    name,
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
