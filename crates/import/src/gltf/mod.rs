//! glTF 2.0 importer: `.gltf` (with `data:` or external buffers) and `.glb`, to a rig
//! [`Asset`].
//!
//! How glTF maps onto the model:
//!
//! | glTF | model |
//! |---|---|
//! | every node of the default scene (of all scenes when `scene` is unset, of the whole file when there are no scenes) | one [`Joint`] each, parents first; the name is the node's, made unique and non-empty |
//! | node `matrix` or TRS | [`Joint::rest_local`] |
//! | each triangle primitive of a node's mesh | one [`Mesh`] (`<mesh>` or `<mesh>_<primitive>`), positions as stored, every `TEXCOORD_n`, its material |
//! | the node holding a mesh | [`Mesh::node_name`] |
//! | materials, textures, samplers, images | [`Asset::materials`], [`Asset::images`] (see `material.rs`) |
//! | node with mesh and skin | a [`SkinBinding`]; the mesh is in bind space (glTF ignores the node's transform) |
//! | node with mesh and no skin | [`Mesh::attached_to`] = that node's joint, positions in node space |
//! | animation | one [`Clip`], one [`Track`] per channel (per primitive mesh for `weights`) |
//!
//! Lengths are metres (glTF 2.0 §3.4), so [`Asset::meters_per_unit`] is `Some(1.0)`.
//! Triangle strips and fans become triangle lists; points and lines are skipped with a
//! warning. Every accessor is range-checked before it is read, so no input makes this
//! module panic.
//!
//! [`Joint`]: rigport_model::Joint
//! [`Joint::rest_local`]: rigport_model::Joint::rest_local
//! [`Clip`]: rigport_model::Clip
//! [`Track`]: rigport_model::Track

mod accessor;
mod animation;
mod container;
mod ext_meshopt;
mod importer;
mod material;
mod mesh;
mod nodes;
mod skin;
#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::path::Path;

use ::gltf::Semantic;
use rigport_model::glam::Mat4;
use rigport_model::{Asset, Mesh, MeshIndex, SkinBinding};

use crate::{read_file, ImportError, Imported, Location, Problem};

use self::container::{load_buffers, parse_document, split_glb};
use self::ext_meshopt::Meshopt;
use self::importer::Importer;
use self::nodes::SceneNodes;
use self::skin::SkinData;

/// Imports a `.gltf` or `.glb` file; external buffers are read relative to its folder.
///
/// Returns the asset (valid by [`Asset::validate`]) and the warnings of every lossy or
/// repairing step (renamed nodes, sheared matrices, skipped primitives, weights that do not
/// sum to 1, ...).
///
/// # Errors
/// The file or one of its buffers cannot be read; a broken GLB container (with the byte
/// offset); JSON syntax (with line and column); a glTF schema violation or out-of-range
/// data (with the JSON path, e.g. `/meshes/0/primitives/0/attributes/JOINTS_0`).
pub fn import(path: &Path) -> Result<Imported, ImportError> {
    let bytes = read_file(path)?;
    import_slice(&bytes, path)
}

/// Imports glTF from bytes: a `.glb` if they start with the `glTF` magic, else JSON.
///
/// `path` names the input in errors and warnings, and relative buffer URIs are resolved
/// against its folder (`data:` URIs and the GLB `BIN` chunk need no file system).
///
/// # Errors
/// As [`import`].
pub fn import_slice(bytes: &[u8], path: &Path) -> Result<Imported, ImportError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(ImportError::new(Location::file(path), Problem::Empty));
    }
    let mut warnings = Vec::new();
    let is_glb = bytes.starts_with(b"glTF");
    let (json, blob) = if is_glb {
        split_glb(bytes, path, &mut warnings)?
    } else {
        (bytes, None)
    };
    let document = parse_document(json, path, is_glb, &mut warnings)?;
    let fault =
        |(at, message): ext_meshopt::Fault| ImportError::invalid(Location::json(path, at), message);
    let meshopt = if document
        .extensions_used()
        .any(|e| e == "EXT_meshopt_compression")
    {
        // The JSON parsed above: it is valid, only the extension's fields are read here.
        let value: serde_json::Value = serde_json::from_slice(json).unwrap_or_default();
        Meshopt::of(&value).map_err(fault)?
    } else {
        Meshopt::default()
    };
    let mut buffers = load_buffers(&document, blob, path, &meshopt)?;
    meshopt.decode(&mut buffers).map_err(fault)?;
    let mut importer = Importer {
        path,
        doc: &document,
        buffers: &buffers,
        warnings,
    };
    let asset = importer.run()?;
    Ok(Imported {
        asset,
        warnings: importer.warnings,
    })
}

impl<'a> Importer<'a> {
    fn run(&mut self) -> Result<Asset, ImportError> {
        let SceneNodes {
            skeleton,
            order,
            node_joint,
            mesh_only,
        } = self.skeleton()?;
        let model_rest = skeleton.model_rest_matrices();
        let nodes: Vec<::gltf::Node<'a>> = self.doc.nodes().collect();
        let mut meshes: Vec<Mesh> = Vec::new();
        let mut skins: Vec<SkinBinding> = Vec::new();
        let mut node_meshes: Vec<Vec<MeshIndex>> = vec![Vec::new(); nodes.len()];
        let mut geometry: HashMap<(usize, usize), Option<Mesh>> = HashMap::new();
        let mut skin_data: HashMap<usize, SkinData> = HashMap::new();

        // Every joint node, then the skinned-mesh nodes that are not joints.
        let mesh_nodes = order
            .iter()
            .map(|&i| (i, None))
            .chain(mesh_only.iter().map(|&(i, parent)| (i, Some(parent))));
        for (node_index, mesh_only_parent) in mesh_nodes {
            let Some(node) = nodes.get(node_index) else {
                continue;
            };
            // The node's model-space rest matrix; its joint, when it is one.
            let (node_model, joint) = match mesh_only_parent {
                None => {
                    let Some(joint) = node_joint.get(node_index).copied().flatten() else {
                        continue;
                    };
                    (model_rest.get(joint.get()).copied(), Some(joint))
                }
                Some(parent) => {
                    let parent_model = parent
                        .and_then(|p| model_rest.get(p.get()).copied())
                        .unwrap_or(Mat4::IDENTITY);
                    let local = Mat4::from_cols_array_2d(&node.transform().matrix());
                    (Some(parent_model * local), None)
                }
            };
            let Some(mesh) = node.mesh() else {
                if node.skin().is_some() {
                    self.note(
                        &format!("/nodes/{node_index}/skin"),
                        "node has a skin but no mesh; skin ignored".into(),
                    );
                }
                continue;
            };
            let skin = node.skin();
            if skin.is_some() {
                let moved = node_model.is_some_and(|m| !m.abs_diff_eq(Mat4::IDENTITY, 1e-6));
                if moved {
                    self.note(
                        &format!("/nodes/{node_index}"),
                        "skinned mesh node has a transform or a transformed ancestor; glTF \
                         ignores it for skinned meshes, and so does rigport"
                            .into(),
                    );
                }
            }
            let primitive_count = mesh.primitives().len();
            let mesh_name = mesh
                .name()
                .filter(|n| !n.is_empty())
                .map_or_else(|| format!("mesh_{}", mesh.index()), str::to_string);
            for prim in mesh.primitives() {
                let base = format!("/meshes/{}/primitives/{}", mesh.index(), prim.index());
                let key = (mesh.index(), prim.index());
                let built = match geometry.get(&key) {
                    Some(built) => built.clone(),
                    None => {
                        let name = if primitive_count > 1 {
                            format!("{mesh_name}_{}", prim.index())
                        } else {
                            mesh_name.clone()
                        };
                        let built = self.primitive(&mesh, &prim, &base, name)?;
                        geometry.insert(key, built.clone());
                        built
                    }
                };
                let Some(mut model_mesh) = built else {
                    continue;
                };
                model_mesh.node_name = match joint {
                    // The joint's name is the node's, made unique and non-empty.
                    Some(j) => skeleton.joint(j).name.clone(),
                    None => node.name().unwrap_or_default().to_string(),
                };
                let (weights, weights_at) = match node.weights() {
                    Some(w) => (Some(w), format!("/nodes/{node_index}/weights")),
                    None => (mesh.weights(), format!("/meshes/{}/weights", mesh.index())),
                };
                model_mesh.morph_weights =
                    self.default_weights(weights, model_mesh.morph_targets.len(), &weights_at)?;
                let mesh_index = MeshIndex(meshes.len() as u32);
                let has_joints = prim.get(&Semantic::Joints(0)).is_some();
                match (&skin, has_joints) {
                    (Some(skin), true) => {
                        let data = match skin_data.get(&skin.index()) {
                            Some(d) => d.clone(),
                            None => {
                                let d = self.skin_data(skin, &node_joint)?;
                                skin_data.insert(skin.index(), d.clone());
                                d
                            }
                        };
                        let influences = self.influences(
                            &prim,
                            &base,
                            model_mesh.vertex_count(),
                            data.joints.len(),
                            skin.index(),
                        )?;
                        skins.push(SkinBinding {
                            mesh: mesh_index,
                            joints: data.joints,
                            inv_bind: data.inv_bind,
                            influences,
                            method: Default::default(),
                        });
                    }
                    (Some(_), false) => {
                        self.note(
                            &base,
                            format!(
                                "node {node_index} has a skin but this primitive has no \
                                 JOINTS_0; imported unskinned, attached to the node"
                            ),
                        );
                        model_mesh.attached_to = joint;
                    }
                    (None, has_joints) => {
                        if has_joints {
                            self.note(
                                &base,
                                format!(
                                    "primitive has JOINTS_0 but node {node_index} has no skin; \
                                     imported unskinned, attached to the node"
                                ),
                            );
                        }
                        model_mesh.attached_to = joint;
                    }
                }
                meshes.push(model_mesh);
                if let Some(list) = node_meshes.get_mut(node_index) {
                    list.push(mesh_index);
                }
            }
        }

        let clips = self.clips(&node_joint, &node_meshes, &meshes)?;
        let images = self.images()?;
        let materials = self.materials();
        let name = self
            .path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let asset = Asset {
            name,
            skeleton,
            meshes,
            skins,
            clips,
            // glTF 2.0 §3.4: "The units for all linear distances are meters."
            meters_per_unit: Some(1.0),
            frame: Default::default(),
            ik_handles: Vec::new(),
            materials,
            images,
        };
        crate::check_asset(&asset, || Location::file(self.path))?;
        Ok(asset)
    }
}
