//! `<controller>`s: `<skin>` and `<morph>`, possibly chained (a skin whose `source` is a
//! morph controller), resolved down to their `<geometry>`.
//!
//! | COLLADA | model |
//! |---|---|
//! | `<bind_shape_matrix>` | applied to the mesh's points (bind-time model space = `BSM · p`) |
//! | `<joints>` `JOINT` names (`Name_array`: `sid`s looked up below the `<skeleton>` roots, then anywhere; `IDREF_array`: `id`s) | the [`SkinBinding`]'s palette |
//! | `<joints>` `INV_BIND_MATRIX` | [`SkinBinding::inv_bind`] (row-major in the file) |
//! | `<vertex_weights>` `<vcount>`/`<v>` with the `JOINT`/`WEIGHT` offsets | every influence of each `<vertices>` vertex; joint `-1` (the bind shape itself) is left out |
//! | `<morph method="NORMALIZED">` targets | morph targets, deltas `target - base` |
//! | `<morph method="RELATIVE">` targets | morph targets, the targets' points as deltas |
//! | `MORPH_WEIGHT` | default morph weights |
//!
//! [`SkinBinding`]: rigport_model::SkinBinding
//! [`SkinBinding::inv_bind`]: rigport_model::SkinBinding::inv_bind

use rigport_model::glam::{DMat4, DVec3, Mat4};
use rigport_model::Influence;

use super::geometry;
use super::scene::Scene;
use super::xml::{child, children, Doc, Node};
use crate::{ImportError, Problem};

/// What an `<instance_geometry>` or `<instance_controller>` draws.
pub(super) struct Resolved<'a, 'i> {
    /// The `<geometry>` at the end of the chain.
    pub(super) geometry: Node<'a, 'i>,
    pub(super) skin: Option<Skin>,
    pub(super) morph: Option<Morph<'a, 'i>>,
}

/// A skin: palette (scene nodes), inverse binds, bind shape matrix and weights per
/// `<vertices>` vertex (palette index, weight).
pub(super) struct Skin {
    pub(super) joints: Vec<usize>,
    pub(super) inv_bind: Vec<Mat4>,
    pub(super) bind_shape: DMat4,
    pub(super) weights: Vec<Vec<Influence>>,
    /// How many influences named joint `-1` (the bind shape itself) with a weight, left out.
    pub(super) on_bind_shape: usize,
}

/// A morph: per target its name and deltas per `<vertices>` vertex, and default weights.
pub(super) struct Morph<'a, 'i> {
    /// The `<controller>` (animations name its weights).
    pub(super) controller: Node<'a, 'i>,
    pub(super) targets: Vec<(String, Vec<DVec3>)>,
    pub(super) weights: Vec<f32>,
}

/// Resolves an instance's `url` (a geometry or a controller) down to its geometry.
///
/// # Errors
/// A missing id, a chain that loops or is not skin -> morph -> geometry, bad skin or morph
/// data.
pub(super) fn resolve<'a, 'i>(
    doc: &Doc<'a, 'i>,
    scene: &Scene,
    instance: Node<'a, 'i>,
) -> Result<Resolved<'a, 'i>, ImportError> {
    let mut target = doc.link(instance, "url", "geometry or controller")?;
    let mut out_skin = None;
    let mut out_morph = None;
    let mut skin_node = None;
    for _ in 0..3 {
        if target.tag_name().name() == "geometry" {
            if let Some(skin) = skin_node {
                out_skin = Some(read_skin(doc, scene, instance, skin, target)?);
            }
            return Ok(Resolved {
                geometry: target,
                skin: out_skin,
                morph: out_morph,
            });
        }
        if target.tag_name().name() != "controller" {
            return Err(doc.invalid(target, "is neither a <geometry> nor a <controller>"));
        }
        if let Some(skin) =
            child(target, "skin").filter(|_| skin_node.is_none() && out_morph.is_none())
        {
            skin_node = Some(skin);
            target = doc.link(skin, "source", "geometry or controller")?;
        } else if let Some(morph) = child(target, "morph").filter(|_| out_morph.is_none()) {
            let base = doc.link(morph, "source", "geometry")?;
            out_morph = Some(read_morph(doc, target, morph, base)?);
            target = base;
        } else {
            return Err(doc.invalid(target, "is not a skin over a morph over a geometry"));
        }
    }
    Err(doc.invalid(instance, "its controllers do not end at a <geometry>"))
}

/// The `<source>` an `<input semantic>` among `inputs` names.
fn input<'a, 'i>(
    doc: &Doc<'a, 'i>,
    parent: Node<'a, 'i>,
    semantic: &str,
) -> Result<Option<(Node<'a, 'i>, usize)>, ImportError> {
    let Some(i) = children(parent, "input").find(|i| i.attribute("semantic") == Some(semantic))
    else {
        return Ok(None);
    };
    let offset = i
        .attribute("offset")
        .and_then(|o| o.trim().parse().ok())
        .unwrap_or(0);
    Ok(Some((doc.link(i, "source", "source")?, offset)))
}

fn read_skin(
    doc: &Doc,
    scene: &Scene,
    instance: Node,
    skin: Node,
    geometry: Node,
) -> Result<Skin, ImportError> {
    let bind_shape = match child(skin, "bind_shape_matrix") {
        Some(m) => {
            let v = doc.floats(m)?;
            let v: [f64; 16] = v
                .as_slice()
                .try_into()
                .map_err(|_| ImportError::count(doc.at(m), "values", v.len(), 16))?;
            super::xml::row_major(&v)
        }
        None => DMat4::IDENTITY,
    };
    let joints_el = child(skin, "joints").ok_or_else(|| doc.invalid(skin, "has no <joints>"))?;
    let (names_node, _) = input(doc, joints_el, "JOINT")?
        .ok_or_else(|| doc.invalid(joints_el, "has no JOINT input"))?;
    let (ibm_node, _) = input(doc, joints_el, "INV_BIND_MATRIX")?
        .ok_or_else(|| doc.invalid(joints_el, "has no INV_BIND_MATRIX input"))?;
    let names = doc.source(names_node)?;
    if names.count == 0 {
        return Err(doc.error(
            joints_el,
            Problem::Invalid("the skin names no joints: its skeleton is empty".into()),
        ));
    }
    let ibm = doc.source(ibm_node)?;
    if ibm.count != names.count || ibm.stride < 16 {
        return Err(ImportError::count(
            doc.at(ibm_node),
            "inverse bind matrices",
            ibm.count,
            names.count,
        ));
    }
    // The `<skeleton>` roots the joint sids are looked up below.
    let roots: Vec<usize> = children(instance, "skeleton")
        .filter_map(|s| scene.by_id(s.text()?.trim().trim_start_matches('#')))
        .collect();
    let by_id = names_node
        .descendants()
        .any(|n| n.tag_name().name() == "IDREF_array");
    let mut joints = Vec::with_capacity(names.count);
    for k in 0..names.count {
        let name = names.name(k).unwrap_or("");
        let node = if by_id {
            scene.by_id(name)
        } else {
            scene
                .find_joint(name, &roots)
                .or_else(|| scene.find_joint(name, &[]))
        };
        let node = node.ok_or_else(|| {
            doc.error(
                names_node,
                Problem::UnknownName {
                    what: "joint",
                    name: name.to_string(),
                    within: "the visual scene".into(),
                },
            )
        })?;
        joints.push(node);
    }
    let inv_bind = (0..ibm.count).map(|k| ibm.mat4(k).as_mat4()).collect();
    let vertex_count = child(geometry, "mesh")
        .map(|m| geometry::positions(doc, m).map(|p| p.len()))
        .transpose()?
        .unwrap_or(0);
    let (weights, on_bind_shape) = read_weights(doc, skin, joints.len(), vertex_count)?;
    Ok(Skin {
        joints,
        inv_bind,
        bind_shape,
        weights,
        on_bind_shape,
    })
}

/// `<vertex_weights>`: per vertex, its (palette index, weight) pairs with weight > 0, and
/// how many weighted influences on joint `-1` were left out.
fn read_weights(
    doc: &Doc,
    skin: Node,
    joint_count: usize,
    vertex_count: usize,
) -> Result<(Vec<Vec<Influence>>, usize), ImportError> {
    let vw = child(skin, "vertex_weights")
        .ok_or_else(|| doc.invalid(skin, "has no <vertex_weights>"))?;
    let (_, joint_offset) =
        input(doc, vw, "JOINT")?.ok_or_else(|| doc.invalid(vw, "has no JOINT input"))?;
    let (weight_node, weight_offset) =
        input(doc, vw, "WEIGHT")?.ok_or_else(|| doc.invalid(vw, "has no WEIGHT input"))?;
    let weights = doc.source(weight_node)?;
    let stride = children(vw, "input")
        .filter_map(|i| i.attribute("offset")?.trim().parse::<usize>().ok())
        .max()
        .map_or(1, |m| m + 1);
    let vcount_node = child(vw, "vcount");
    let vcount: Vec<i64> = match vcount_node {
        Some(n) => doc.ints(n)?,
        None => Vec::new(),
    };
    if vcount.len() != vertex_count {
        return Err(ImportError::count(
            doc.at(vcount_node.unwrap_or(vw)),
            "vertex weight counts",
            vcount.len(),
            format!("{vertex_count} (the geometry's vertices)"),
        ));
    }
    let v_node = child(vw, "v");
    let v = match v_node {
        Some(n) => doc.ints(n)?,
        None => Vec::new(),
    };
    let pairs: i64 = vcount.iter().map(|&n| n.max(0)).sum();
    if usize::try_from(pairs)
        .ok()
        .and_then(|p| p.checked_mul(stride))
        != Some(v.len())
    {
        return Err(ImportError::count(
            doc.at(v_node.unwrap_or(vw)),
            "values",
            v.len(),
            format!("{pairs} influences x {stride} inputs"),
        ));
    }
    let mut at = 0;
    let mut on_bind_shape = 0;
    let mut out = Vec::with_capacity(vertex_count);
    for &n in &vcount {
        let mut row = Vec::new();
        for _ in 0..n.max(0) {
            let joint = v[at * stride + joint_offset];
            let w = v[at * stride + weight_offset];
            at += 1;
            // Joint -1 is the bind shape itself: the vertex keeps that share unskinned,
            // which a joint palette cannot say; it is left out (and the row renormalized
            // on output).
            if joint == -1 {
                let weighted = usize::try_from(w)
                    .ok()
                    .filter(|&i| i < weights.count)
                    .is_some_and(|i| weights.float(i, 0) > 0.0);
                on_bind_shape += usize::from(weighted);
                continue;
            }
            let oob = |what, plural, index: i64, count| {
                doc.error(
                    v_node.unwrap_or(vw),
                    Problem::IndexOutOfRange {
                        what,
                        plural,
                        index,
                        count,
                    },
                )
            };
            let j = usize::try_from(joint)
                .ok()
                .filter(|&j| j < joint_count)
                .ok_or_else(|| oob("joint", "joints", joint, joint_count))?;
            let wi = usize::try_from(w)
                .ok()
                .filter(|&i| i < weights.count)
                .ok_or_else(|| oob("weight", "weights", w, weights.count))?;
            let weight = weights.float(wi, 0) as f32;
            if weight > 0.0 {
                row.push(Influence {
                    joint: j as u32,
                    weight,
                });
            }
        }
        out.push(row);
    }
    Ok((out, on_bind_shape))
}

fn read_morph<'a, 'i>(
    doc: &Doc<'a, 'i>,
    controller: Node<'a, 'i>,
    morph: Node<'a, 'i>,
    base: Node<'a, 'i>,
) -> Result<Morph<'a, 'i>, ImportError> {
    let relative = morph.attribute("method") == Some("RELATIVE");
    let base_mesh = child(base, "mesh").ok_or_else(|| doc.invalid(base, "has no <mesh>"))?;
    let base_points = geometry::positions(doc, base_mesh)?;
    let targets_el =
        child(morph, "targets").ok_or_else(|| doc.invalid(morph, "has no <targets>"))?;
    let (target_node, _) = input(doc, targets_el, "MORPH_TARGET")?
        .ok_or_else(|| doc.invalid(targets_el, "has no MORPH_TARGET input"))?;
    let (weight_node, _) = input(doc, targets_el, "MORPH_WEIGHT")?
        .ok_or_else(|| doc.invalid(targets_el, "has no MORPH_WEIGHT input"))?;
    let names = doc.source(target_node)?;
    let weights = doc.source(weight_node)?;
    if weights.count != names.count {
        return Err(ImportError::count(
            doc.at(weight_node),
            "morph weights",
            weights.count,
            names.count,
        ));
    }
    let mut targets = Vec::with_capacity(names.count);
    for k in 0..names.count {
        let id = names.name(k).unwrap_or("");
        let geometry = doc.by_id(id).ok_or_else(|| {
            doc.error(
                target_node,
                Problem::UnknownName {
                    what: "morph target geometry",
                    name: id.to_string(),
                    within: "the document".into(),
                },
            )
        })?;
        let mesh = child(geometry, "mesh").ok_or_else(|| doc.invalid(geometry, "has no <mesh>"))?;
        let points = geometry::positions(doc, mesh)?;
        if points.len() != base_points.len() {
            return Err(ImportError::count(
                doc.at(geometry),
                "vertices",
                points.len(),
                format!("{} (the morph's base geometry)", base_points.len()),
            ));
        }
        let deltas = points
            .iter()
            .zip(&base_points)
            .map(|(p, b)| if relative { *p } else { *p - *b })
            .collect();
        let name = geometry
            .attribute("name")
            .filter(|n| !n.is_empty())
            .unwrap_or(id)
            .to_string();
        targets.push((name, deltas));
    }
    Ok(Morph {
        controller,
        targets,
        weights: (0..weights.count)
            .map(|k| weights.float(k, 0) as f32)
            .collect(),
    })
}
