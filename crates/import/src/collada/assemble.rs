//! The document to an [`Asset`]: the scene, its animations, the skeleton they need, the
//! meshes of every geometry and controller instance, their materials, then the clips.

use std::collections::{HashMap, HashSet};

use rigport_model::glam::{DMat3, DMat4};
use rigport_model::{
    Asset, Influences, JointIndex, MeshIndex, MorphTarget, SkinBinding, SkinningMethod, Warning,
};

use super::anim::{self, Target};
use super::clips::{self, MorphUse};
use super::controller::{self, Resolved};
use super::geometry;
use super::material::Materials;
use super::scene::{self, Scene};
use super::skeleton::{self, Skel};
use super::xml::{child, child_elements, Doc, Node};
use super::zae::Files;
use crate::names::unique;
use crate::{ImportError, Problem};

/// Builds the asset of `doc` (named `name`), with the warnings of lossy steps.
///
/// # Errors
/// As [`super::import`].
pub(super) fn run(
    doc: &Doc,
    files: &Files,
    name: &str,
) -> Result<(Asset, Vec<Warning>), ImportError> {
    let mut asset = super::empty_asset(doc, name)?;
    let mut warnings = Vec::new();
    let scene = scene::read(doc)?;
    let channels = anim::read(doc, &scene, &mut warnings)?;
    let mut instances = Vec::new();
    for (n, node) in scene.nodes.iter().enumerate() {
        for i in child_elements(node.xml) {
            if matches!(
                i.tag_name().name(),
                "instance_geometry" | "instance_controller"
            ) {
                instances.push((n, i, controller::resolve(doc, &scene, i)?));
            }
        }
    }
    let mut used: Vec<usize> = channels
        .iter()
        .filter_map(|c| match c.target {
            Target::Transform { node, .. } => Some(node),
            Target::Morph { .. } => None,
        })
        .collect();
    for (.., r) in &instances {
        used.extend(r.skin.iter().flat_map(|s| s.joints.iter().copied()));
    }
    let skel = skeleton::build(&scene, &used, doc.path)?;
    if let Some((node, off)) = skel.sheared.first() {
        warnings.push(Warning::Incomplete {
            location: crate::Location::file(doc.path).to_string(),
            message: format!(
                "{} joint transforms have a shear (from <skew>, <lookat> or a <matrix>) that a \
                 joint's translation, rotation and scale cannot hold; it is left out (node {node:?}: \
                 {off:.1e} of the matrix)",
                skel.sheared.len()
            ),
        });
    }
    let mut materials = Materials::default();
    let mut morphs = Vec::new();
    let mut names = HashSet::new();
    let mut geometries: HashMap<Node, geometry::Geometry> = HashMap::new();
    for (n, instance, resolved) in &instances {
        let geo = match geometries.entry(resolved.geometry) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) => {
                let geo = geometry::read(doc, resolved.geometry)?;
                for (location, message) in &geo.lost {
                    warnings.push(Warning::Incomplete {
                        location: location.clone(),
                        message: message.clone(),
                    });
                }
                e.insert(geo)
            }
        };
        let (place, attached_to) = placement(&scene, &skel, *n, resolved);
        let linear = DMat3::from_mat4(place);
        let several = geo.parts.len() > 1;
        let base = ["name", "id"]
            .iter()
            .find_map(|a| resolved.geometry.attribute(*a).filter(|s| !s.is_empty()))
            .unwrap_or("mesh");
        for (k, part) in geo.parts.iter().enumerate() {
            let mut mesh = part.mesh(&place);
            let label = if several {
                format!("{base}_{k}")
            } else {
                base.to_string()
            };
            mesh.name = unique(&label, "mesh", &mut names);
            mesh.node_name = scene.nodes[*n].name().to_string();
            mesh.attached_to = attached_to;
            if let Some(material) = material_of(doc, *instance, part.symbol.as_deref())? {
                let (index, texcoord) = materials.get(doc, material, files, &mut warnings)?;
                mesh.material = Some(index);
                let set = texcoord.and_then(|t| uv_set_of(*instance, part.symbol.as_deref(), &t));
                let uv = set.and_then(|s| part.uv_sets.iter().position(|&u| u == s));
                if let Some(tex) = materials.materials[index.get()].base_color_texture.as_mut() {
                    tex.tex_coord = uv.unwrap_or(0) as u32;
                }
            }
            let index = MeshIndex(asset.meshes.len() as u32);
            if let Some(morph) = &resolved.morph {
                for (name, deltas) in &morph.targets {
                    mesh.morph_targets.push(MorphTarget {
                        name: name.clone(),
                        position_deltas: mesh
                            .source_vertex
                            .iter()
                            .map(|&v| {
                                let d = deltas.get(v as usize).copied().unwrap_or_default();
                                (linear * d).as_vec3()
                            })
                            .collect(),
                        normal_deltas: None,
                    });
                }
                mesh.morph_weights.clone_from(&morph.weights);
                if let Some(id) = morph.controller.attribute("id") {
                    morphs.push(MorphUse {
                        controller: id.to_string(),
                        mesh: index,
                        defaults: morph.weights.clone(),
                    });
                }
            }
            if let Some(skin) = resolved
                .skin
                .as_ref()
                .filter(|s| s.on_bind_shape > 0 && k == 0)
            {
                warnings.push(Warning::Incomplete {
                    location: doc.at(*instance).to_string(),
                    message: format!(
                        "{} influences on joint -1 (the bind shape itself, unmoved) are left out \
                         and their rows renormalized: those vertices follow their joints fully",
                        skin.on_bind_shape
                    ),
                });
            }
            if let Some(skin) = &resolved.skin {
                let joints = skin
                    .joints
                    .iter()
                    .map(|&j| skel.joint_of[j])
                    .collect::<Option<Vec<JointIndex>>>()
                    .ok_or_else(|| {
                        doc.error(
                            *instance,
                            Problem::Invalid("a skin joint is not in the skeleton".into()),
                        )
                    })?;
                let mut rows =
                    Influences::from_rows(skin.weights.iter().map(|r| r.iter().copied()));
                // As every importer: rows rescaled to sum to 1, as viewers and the writers
                // take them (rows left short by joint -1 are already reported above).
                let (off, max_row_sum_error) = rows.normalize(1e-3);
                if off > 0 && skin.on_bind_shape == 0 {
                    warnings.push(Warning::WeightsRenormalized {
                        source: doc.at(*instance).to_string(),
                        rows: off,
                        max_row_sum_error,
                    });
                }
                asset.skins.push(SkinBinding {
                    mesh: index,
                    joints,
                    inv_bind: skin.inv_bind.clone(),
                    influences: rows.remap_vertices(&mesh.source_vertex),
                    method: SkinningMethod::Lbs,
                });
            }
            asset.meshes.push(mesh);
        }
    }
    asset.clips = clips::build(doc, &scene, &channels, &skel, &morphs, name)?;
    asset.skeleton = skel.skeleton;
    asset.materials = materials.materials;
    asset.images = materials.images;
    Ok((asset, warnings))
}

/// Where an instance's points go: bind-time model space through the bind shape matrix for
/// a skin; else its node's matrix in the space of its nearest joint (attached to it), else
/// in model space.
fn placement(
    scene: &Scene,
    skel: &Skel,
    node: usize,
    resolved: &Resolved,
) -> (DMat4, Option<JointIndex>) {
    if let Some(skin) = &resolved.skin {
        return (skin.bind_shape, None);
    }
    let world = scene.nodes[node].world;
    match skel.nearest_joint(scene, node) {
        Some(j) => (skel.world[j.get()].inverse() * world, Some(j)),
        None => (world, None),
    }
}

/// The `<instance_material>` of an instance for `symbol`; for a primitive without a
/// `material` symbol, the instance's only one (exporters such as MakeHuman's bind one
/// material and leave the symbol off the primitive).
fn instance_material<'a, 'i>(instance: Node<'a, 'i>, symbol: Option<&str>) -> Option<Node<'a, 'i>> {
    let technique = child(instance, "bind_material").and_then(|b| child(b, "technique_common"))?;
    let mut all = child_elements(technique).filter(|m| m.tag_name().name() == "instance_material");
    match symbol {
        Some(symbol) => all.find(|m| m.attribute("symbol") == Some(symbol)),
        None => {
            let first = all.next()?;
            all.next().is_none().then_some(first)
        }
    }
}

/// The `<material>` an instance binds `symbol` to (`<instance_material symbol target>`),
/// else the material whose id is the symbol.
///
/// # Errors
/// An `<instance_material>` whose target is no element.
fn material_of<'a, 'i>(
    doc: &Doc<'a, 'i>,
    instance: Node<'a, 'i>,
    symbol: Option<&str>,
) -> Result<Option<Node<'a, 'i>>, ImportError> {
    Ok(match instance_material(instance, symbol) {
        Some(m) => Some(doc.link(m, "target", "material")?),
        None => symbol
            .and_then(|s| doc.by_id(s))
            .filter(|n| n.tag_name().name() == "material"),
    })
}

/// The `TEXCOORD` set an instance binds a texture's `texcoord` semantic to
/// (`<bind_vertex_input semantic input_set>`).
fn uv_set_of(instance: Node, symbol: Option<&str>, texcoord: &str) -> Option<u32> {
    child_elements(instance_material(instance, symbol)?)
        .find(|b| {
            b.tag_name().name() == "bind_vertex_input" && b.attribute("semantic") == Some(texcoord)
        })
        .and_then(|b| b.attribute("input_set")?.trim().parse().ok())
}
