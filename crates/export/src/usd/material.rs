//! Materials as UsdPreviewSurface networks (USD's "UsdPreviewSurface Specification").
//!
//! Each model [`Material`] becomes `def Material "<name>"` in a `Materials` scope under the
//! root prim, its surface output connected to a `UsdPreviewSurface` shader:
//!
//! | model | UsdPreviewSurface |
//! |---|---|
//! | `base_color_factor` RGB / alpha | `inputs:diffuseColor` / `inputs:opacity` (or the texture's `inputs:scale`) |
//! | `base_color_texture` | a `UsdUVTexture` (`inputs:file` beside the `.usda`, `inputs:st` from a `UsdPrimvarReader_float2` reading `st`, `st1`, ...; `inputs:scale` = the factor; `sourceColorSpace` `sRGB`) connected to `diffuseColor` (`outputs:rgb`) and `opacity` (`outputs:a`) |
//! | `metallic_factor`, `roughness_factor` | `inputs:metallic`, `inputs:roughness` |
//! | `emissive_factor` | `inputs:emissiveColor` |
//! | `alpha_mode = Mask`, `alpha_cutoff` | `inputs:opacityThreshold` |
//! | `normal_texture` | a `UsdUVTexture` (`raw`, scale 2 bias -1) connected to `inputs:normal` |
//!
//! Meshes bind theirs with `rel material:binding` (MaterialBindingAPI). Prim names are made
//! valid and unique as other prims' are; the original name goes to `displayName`.

use rigport_model::{Asset, Material, TextureRef, Wrap};

use super::names::Namespace;
use super::values::zeroed;
use rigport_usd::layer::Specifier;
use rigport_usd::sink::{AttrDecl, Data, Field, LayerSink};

/// Name of the Scope holding the Material prims.
pub(crate) const MATERIALS: &str = "Materials";

/// The prim name of each material (valid, unique in the scope).
pub(crate) fn material_prims(asset: &Asset) -> Vec<String> {
    let mut ns = Namespace::default();
    asset
        .materials
        .iter()
        .map(|m| ns.claim(&m.name, "material").0)
        .collect()
}

/// The UV primvar name of set `k`: `st`, `st1`, `st2`, ...
pub(crate) fn st_name(k: u32) -> String {
    if k == 0 {
        "st".to_string()
    } else {
        format!("st{k}")
    }
}

fn wrap_token(w: Wrap) -> &'static str {
    match w {
        Wrap::Repeat => "repeat",
        Wrap::ClampToEdge => "clamp",
        Wrap::MirroredRepeat => "mirror",
    }
}

/// Describes the `Materials` scope; `files[k]` is the relative path of image `k`.
pub(crate) fn write_materials(
    doc: &mut dyn LayerSink,
    asset: &Asset,
    root_path: &str,
    prims: &[String],
    files: &[String],
) {
    if asset.materials.is_empty() {
        return;
    }
    doc.begin_prim(Specifier::Def, Some("Scope"), MATERIALS, &[]);
    for (k, (material, prim)) in asset.materials.iter().zip(prims).enumerate() {
        if k > 0 {
            doc.blank_line();
        }
        write_material(
            doc,
            material,
            &format!("{root_path}/{MATERIALS}/{prim}"),
            prim,
            files,
        );
    }
    doc.end_prim();
    doc.blank_line();
}

/// A `def Shader` prim with its `info:id`.
fn begin_shader(doc: &mut dyn LayerSink, prim: &str, id: &str) {
    doc.begin_prim(Specifier::Def, Some("Shader"), prim, &[]);
    doc.attribute(
        AttrDecl::uniform("token", "info:id"),
        Some(Data::Str(id)),
        &[],
    );
}

fn write_material(doc: &mut dyn LayerSink, m: &Material, path: &str, prim: &str, files: &[String]) {
    let meta = if !m.name.is_empty() && m.name != prim {
        vec![Field::new("displayName", m.name.as_str().into())]
    } else {
        Vec::new()
    };
    doc.begin_prim(Specifier::Def, Some("Material"), prim, &meta);
    doc.connection(
        AttrDecl::new("token", "outputs:surface"),
        &format!("{path}/PreviewSurface.outputs:surface"),
    );
    doc.blank_line();
    begin_shader(doc, "PreviewSurface", "UsdPreviewSurface");
    let [r, g, b, a] = m.base_color_factor;
    let base_file = m
        .base_color_texture
        .as_ref()
        .and_then(|t| files.get(t.image.get()).map(|f| (t, f)));
    if base_file.is_some() {
        doc.connection(
            AttrDecl::new("color3f", "inputs:diffuseColor"),
            &format!("{path}/BaseColorTexture.outputs:rgb"),
        );
        doc.connection(
            AttrDecl::new("float", "inputs:opacity"),
            &format!("{path}/BaseColorTexture.outputs:a"),
        );
    } else {
        color3(doc, "inputs:diffuseColor", [r, g, b]);
        float(doc, "inputs:opacity", a);
    }
    color3(doc, "inputs:emissiveColor", m.emissive_factor);
    float(doc, "inputs:metallic", m.metallic_factor);
    let normal_file = m
        .normal_texture
        .as_ref()
        .and_then(|t| files.get(t.image.get()).map(|f| (t, f)));
    if normal_file.is_some() {
        doc.connection(
            AttrDecl::new("normal3f", "inputs:normal"),
            &format!("{path}/NormalTexture.outputs:rgb"),
        );
    }
    if m.alpha_mode == rigport_model::AlphaMode::Mask {
        float(doc, "inputs:opacityThreshold", m.alpha_cutoff);
    }
    float(doc, "inputs:roughness", m.roughness_factor);
    doc.attribute(
        AttrDecl::new("int", "inputs:useSpecularWorkflow"),
        Some(Data::Int(0)),
        &[],
    );
    doc.attribute(AttrDecl::new("token", "outputs:surface"), None, &[]);
    doc.end_prim();
    let mut readers: Vec<u32> = Vec::new();
    if let Some((t, file)) = base_file {
        doc.blank_line();
        write_texture(
            doc,
            path,
            "BaseColorTexture",
            t,
            file,
            [r, g, b, a],
            None,
            "sRGB",
        );
        readers.push(t.tex_coord);
    }
    if let Some((t, file)) = normal_file {
        doc.blank_line();
        let s = m.normal_scale;
        write_texture(
            doc,
            path,
            "NormalTexture",
            t,
            file,
            [2.0 * s, 2.0 * s, 2.0, 1.0],
            Some([-s, -s, -1.0, 0.0]),
            "raw",
        );
        readers.push(t.tex_coord);
    }
    readers.sort_unstable();
    readers.dedup();
    for k in readers {
        doc.blank_line();
        begin_shader(
            doc,
            &format!("{}Reader", st_name(k)),
            "UsdPrimvarReader_float2",
        );
        doc.attribute(
            AttrDecl::new("string", "inputs:varname"),
            Some(Data::Str(&st_name(k))),
            &[],
        );
        doc.attribute(AttrDecl::new("float2", "outputs:result"), None, &[]);
        doc.end_prim();
    }
    doc.end_prim();
}

#[allow(
    clippy::too_many_arguments,
    reason = "one shader's fields, written in one place"
)]
fn write_texture(
    doc: &mut dyn LayerSink,
    path: &str,
    prim: &str,
    t: &TextureRef,
    file: &str,
    scale: [f32; 4],
    bias: Option<[f32; 4]>,
    color_space: &str,
) {
    begin_shader(doc, prim, "UsdUVTexture");
    if let Some(bias) = bias {
        float4(doc, "inputs:bias", bias);
    }
    doc.attribute(
        AttrDecl::new("asset", "inputs:file"),
        Some(Data::Asset(&format!("./{file}"))),
        &[],
    );
    float4(doc, "inputs:scale", scale);
    doc.attribute(
        AttrDecl::new("token", "inputs:sourceColorSpace"),
        Some(Data::Str(color_space)),
        &[],
    );
    doc.connection(
        AttrDecl::new("float2", "inputs:st"),
        &format!("{path}/{}Reader.outputs:result", st_name(t.tex_coord)),
    );
    doc.attribute(
        AttrDecl::new("token", "inputs:wrapS"),
        Some(Data::Str(wrap_token(t.sampler.wrap_s))),
        &[],
    );
    doc.attribute(
        AttrDecl::new("token", "inputs:wrapT"),
        Some(Data::Str(wrap_token(t.sampler.wrap_t))),
        &[],
    );
    doc.attribute(AttrDecl::new("float", "outputs:a"), None, &[]);
    doc.attribute(AttrDecl::new("float3", "outputs:rgb"), None, &[]);
    doc.end_prim();
}

/// `float name = v`, the value as it is (a `-0` stays `-0`).
fn float(doc: &mut dyn LayerSink, name: &str, v: f32) {
    doc.attribute(AttrDecl::new("float", name), Some(Data::Float(v)), &[]);
}

fn color3(doc: &mut dyn LayerSink, name: &str, c: [f32; 3]) {
    doc.attribute(
        AttrDecl::new("color3f", name),
        Some(Data::Float3(zeroed(c))),
        &[],
    );
}

fn float4(doc: &mut dyn LayerSink, name: &str, c: [f32; 4]) {
    doc.attribute(
        AttrDecl::new("float4", name),
        Some(Data::Float4(zeroed(c))),
        &[],
    );
}
