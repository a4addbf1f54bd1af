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
use super::text::{put, quoted, Usda};

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

/// Writes the `Materials` scope; `files[k]` is the relative path of image `k`.
pub(crate) fn write_materials(
    doc: &mut Usda,
    asset: &Asset,
    root_path: &str,
    prims: &[String],
    files: &[String],
) {
    if asset.materials.is_empty() {
        return;
    }
    doc.open(&format!("def Scope \"{MATERIALS}\""));
    for (k, (material, prim)) in asset.materials.iter().zip(prims).enumerate() {
        if k > 0 {
            doc.blank();
        }
        write_material(
            doc,
            material,
            &format!("{root_path}/{MATERIALS}/{prim}"),
            prim,
            files,
        );
    }
    doc.close();
    doc.blank();
}

fn write_material(doc: &mut Usda, m: &Material, path: &str, prim: &str, files: &[String]) {
    let header = format!("def Material \"{prim}\"");
    if !m.name.is_empty() && m.name != prim {
        doc.open_meta(&header);
        let line = doc.start();
        line.push_str("displayName = ");
        quoted(line, &m.name);
        doc.end();
        doc.close_meta();
        doc.open_body();
    } else {
        doc.open(&header);
    }
    doc.line(&format!(
        "token outputs:surface.connect = <{path}/PreviewSurface.outputs:surface>"
    ));
    doc.blank();
    doc.open("def Shader \"PreviewSurface\"");
    doc.line("uniform token info:id = \"UsdPreviewSurface\"");
    let [r, g, b, a] = m.base_color_factor;
    let base_file = m
        .base_color_texture
        .as_ref()
        .and_then(|t| files.get(t.image.get()).map(|f| (t, f)));
    if base_file.is_some() {
        doc.line(&format!(
            "color3f inputs:diffuseColor.connect = <{path}/BaseColorTexture.outputs:rgb>"
        ));
        doc.line(&format!(
            "float inputs:opacity.connect = <{path}/BaseColorTexture.outputs:a>"
        ));
    } else {
        color3(doc, "color3f inputs:diffuseColor", [r, g, b]);
        float(doc, "float inputs:opacity", a);
    }
    color3(doc, "color3f inputs:emissiveColor", m.emissive_factor);
    float(doc, "float inputs:metallic", m.metallic_factor);
    let normal_file = m
        .normal_texture
        .as_ref()
        .and_then(|t| files.get(t.image.get()).map(|f| (t, f)));
    if normal_file.is_some() {
        doc.line(&format!(
            "normal3f inputs:normal.connect = <{path}/NormalTexture.outputs:rgb>"
        ));
    }
    if m.alpha_mode == rigport_model::AlphaMode::Mask {
        float(doc, "float inputs:opacityThreshold", m.alpha_cutoff);
    }
    float(doc, "float inputs:roughness", m.roughness_factor);
    doc.line("int inputs:useSpecularWorkflow = 0");
    doc.line("token outputs:surface");
    doc.close();
    let mut readers: Vec<u32> = Vec::new();
    if let Some((t, file)) = base_file {
        doc.blank();
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
        doc.blank();
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
        doc.blank();
        doc.open(&format!("def Shader \"{}Reader\"", st_name(k)));
        doc.line("uniform token info:id = \"UsdPrimvarReader_float2\"");
        let line = doc.start();
        line.push_str("string inputs:varname = ");
        quoted(line, &st_name(k));
        doc.end();
        doc.line("float2 outputs:result");
        doc.close();
    }
    doc.close();
}

#[allow(
    clippy::too_many_arguments,
    reason = "one shader's fields, written in one place"
)]
fn write_texture(
    doc: &mut Usda,
    path: &str,
    prim: &str,
    t: &TextureRef,
    file: &str,
    scale: [f32; 4],
    bias: Option<[f32; 4]>,
    color_space: &str,
) {
    doc.open(&format!("def Shader \"{prim}\""));
    doc.line("uniform token info:id = \"UsdUVTexture\"");
    if let Some(bias) = bias {
        float4(doc, "float4 inputs:bias", bias);
    }
    doc.line(&format!("asset inputs:file = @./{file}@"));
    float4(doc, "float4 inputs:scale", scale);
    let line = doc.start();
    line.push_str("token inputs:sourceColorSpace = ");
    quoted(line, color_space);
    doc.end();
    doc.line(&format!(
        "float2 inputs:st.connect = <{path}/{}Reader.outputs:result>",
        st_name(t.tex_coord)
    ));
    doc.line(&format!(
        "token inputs:wrapS = \"{}\"",
        wrap_token(t.sampler.wrap_s)
    ));
    doc.line(&format!(
        "token inputs:wrapT = \"{}\"",
        wrap_token(t.sampler.wrap_t)
    ));
    doc.line("float outputs:a");
    doc.line("float3 outputs:rgb");
    doc.close();
}

fn float(doc: &mut Usda, decl: &str, v: f32) {
    let line = doc.start();
    line.push_str(decl);
    line.push_str(" = ");
    put(line, v);
    doc.end();
}

fn color3(doc: &mut Usda, decl: &str, c: [f32; 3]) {
    let line = doc.start();
    line.push_str(decl);
    line.push_str(" = ");
    super::text::tuple(line, &c);
    doc.end();
}

fn float4(doc: &mut Usda, decl: &str, c: [f32; 4]) {
    let line = doc.start();
    line.push_str(decl);
    line.push_str(" = ");
    super::text::tuple(line, &c);
    doc.end();
}
