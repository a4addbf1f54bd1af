//! Materials: a `<material>`'s `<instance_effect>`, its `<profile_COMMON>` technique
//! (`<phong>`, `<blinn>`, `<lambert>` or `<constant>`) as a glTF metallic-roughness core.
//!
//! | COLLADA | model |
//! |---|---|
//! | `<diffuse><color>` (`<emission>` for `<constant>`) | `base_color_factor` (alpha 1) |
//! | `<diffuse><texture texture=... texcoord=...>`: a `sampler2D` `newparam` -> its `surface` `newparam` -> `<init_from>` image (or the image id itself, as some exporters write) | `base_color_texture`, on the UV set the instance binds `texcoord` to (`<bind_vertex_input>`) |
//! | `<image><init_from>` (1.4) or `<init_from><ref>` (1.5), a path relative to the file (or a member of the `.zae`), `file://` URLs and `%20` escapes decoded | the image's bytes |
//! | anything else | metallic 0, roughness 1 (a Lambert/Phong surface) |
//!
//! A texture whose file cannot be read is left out with a [`Warning::Incomplete`].

use std::collections::HashMap;
use std::path::Path;

use rigport_model::{Image, ImageIndex, Material, MaterialIndex, TextureRef, Warning};

use super::xml::{child, child_elements, children, Doc, Node};
use super::zae::Files;
use crate::ImportError;

/// The materials built so far, by `<material>` id.
#[derive(Default)]
pub(super) struct Materials {
    pub(super) materials: Vec<Material>,
    pub(super) images: Vec<Image>,
    by_id: HashMap<String, (MaterialIndex, Option<String>)>,
    image_by_id: HashMap<String, Option<ImageIndex>>,
}

impl Materials {
    /// The material `<material>` `node` maps to, and the `texcoord` semantic its texture
    /// reads (built on first use).
    ///
    /// # Errors
    /// An `<instance_effect>` naming no element.
    pub(super) fn get(
        &mut self,
        doc: &Doc,
        node: Node,
        files: &Files,
        warnings: &mut Vec<Warning>,
    ) -> Result<(MaterialIndex, Option<String>), ImportError> {
        let id = node.attribute("id").unwrap_or("").to_string();
        if let Some(found) = self.by_id.get(&id) {
            return Ok(found.clone());
        }
        let name = node
            .attribute("name")
            .or(node.attribute("id"))
            .unwrap_or("")
            .to_string();
        let mut m = Material {
            name,
            metallic_factor: 0.0,
            roughness_factor: 1.0,
            ..Material::default()
        };
        let mut texcoord = None;
        let effect = match child(node, "instance_effect") {
            Some(i) => Some(doc.link(i, "url", "effect")?),
            None => None,
        };
        let technique = effect
            .and_then(|e| child(e, "profile_COMMON"))
            .and_then(|p| child(p, "technique"));
        let shading = technique.and_then(|t| {
            child_elements(t).find(|s| {
                matches!(
                    s.tag_name().name(),
                    "phong" | "blinn" | "lambert" | "constant"
                )
            })
        });
        if let (Some(effect), Some(shading)) = (effect, shading) {
            let slot = if shading.tag_name().name() == "constant" {
                "emission"
            } else {
                "diffuse"
            };
            if let Some(diffuse) = child(shading, slot) {
                if let Some(color) = child(diffuse, "color") {
                    if let Ok(c) = doc.floats(color) {
                        if c.len() >= 3 {
                            let ch = |v: f64| v.clamp(0.0, 1.0) as f32;
                            m.base_color_factor = [ch(c[0]), ch(c[1]), ch(c[2]), 1.0];
                        }
                    }
                }
                if let Some(texture) = child(diffuse, "texture") {
                    texcoord = texture.attribute("texcoord").map(str::to_string);
                    let image = texture
                        .attribute("texture")
                        .and_then(|t| image_of(doc, effect, t));
                    if let Some(image) = image {
                        if let Some(index) = self.image(doc, image, files, warnings) {
                            m.base_color_factor = [1.0; 4];
                            m.base_color_texture = Some(TextureRef {
                                image: index,
                                tex_coord: 0,
                                sampler: Default::default(),
                            });
                        }
                    }
                }
            }
        }
        let index = MaterialIndex(self.materials.len() as u32);
        self.materials.push(m);
        self.by_id.insert(id, (index, texcoord.clone()));
        Ok((index, texcoord))
    }

    /// The image of `<image>` `node`, read once; `None` with a warning when unreadable.
    fn image(
        &mut self,
        doc: &Doc,
        node: Node,
        files: &Files,
        warnings: &mut Vec<Warning>,
    ) -> Option<ImageIndex> {
        let id = node.attribute("id").unwrap_or("").to_string();
        if let Some(found) = self.image_by_id.get(&id) {
            return *found;
        }
        let init = child(node, "init_from");
        let uri = init
            .and_then(|i| child(i, "ref").and_then(|r| r.text()).or(i.text()))
            .unwrap_or("")
            .trim()
            .to_string();
        let relative = decode_uri(&uri);
        let bytes = files.read(&relative);
        let found = match bytes {
            Some(bytes) => {
                let name = Path::new(&relative)
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_else(|| id.clone());
                let mime_type = Image::sniff_mime_type(&bytes)
                    .unwrap_or("application/octet-stream")
                    .to_string();
                self.images.push(Image {
                    name,
                    mime_type,
                    bytes,
                });
                Some(ImageIndex(self.images.len() as u32 - 1))
            }
            None => {
                warnings.push(Warning::Incomplete {
                    location: doc.at(node).to_string(),
                    message: format!(
                        "the texture {uri:?} is found neither beside the file nor in its \
                         package: the material is imported without it"
                    ),
                });
                None
            }
        };
        self.image_by_id.insert(id, found);
        found
    }
}

/// The `<image>` a `<texture texture="...">` names within `effect`: a `sampler2D`
/// `newparam` whose `<source>` is a `surface` `newparam` whose `<init_from>` is the
/// image id (1.4); a `sampler2D` with `<instance_image>` (1.5); else an image id.
fn image_of<'a, 'i>(doc: &Doc<'a, 'i>, effect: Node<'a, 'i>, sid: &str) -> Option<Node<'a, 'i>> {
    let newparam = |sid: &str| {
        effect
            .descendants()
            .find(|n| n.tag_name().name() == "newparam" && n.attribute("sid") == Some(sid))
    };
    if let Some(sampler) = newparam(sid).and_then(|p| child(p, "sampler2D")) {
        if let Some(url) = child(sampler, "instance_image").and_then(|i| i.attribute("url")) {
            return doc.by_id(url);
        }
        let surface_sid = child(sampler, "source")?.text()?.trim();
        let surface = newparam(surface_sid).and_then(|p| child(p, "surface"))?;
        let image_id = children(surface, "init_from").next()?.text()?.trim();
        return doc.by_id(image_id);
    }
    doc.by_id(sid).filter(|n| n.tag_name().name() == "image")
}

/// A COLLADA image URI as a path: `file://` dropped, `%XX` escapes decoded, `\` as `/`.
fn decode_uri(uri: &str) -> String {
    let uri = uri.strip_prefix("file://").unwrap_or(uri);
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
            if let Some(b) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(b);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).replace('\\', "/")
}
