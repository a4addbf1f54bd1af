//! The parsed files as one asset: parents-first skeleton, mesh, skin with inverse bind
//! matrices, influences remapped to skeleton joints and output vertices.

use std::path::Path;

use glam::{DAffine3, DMat4, DVec3, Mat4};
use rigport_model::conventions::EulerOrder;
use rigport_model::{
    parents_first_order, Asset, Influence, Influences, Joint, JointIndex, Mesh, MeshIndex,
    Skeleton, SkinBinding,
};

use crate::problem::Mismatch;
use crate::{ImportError, Location, Problem};

use super::rest::rest_local_transform;
use super::types::RestTransforms;
use super::weights::{rows_from_ends, sort_row};

/// What [`assemble`] builds.
pub(super) struct Assembled {
    pub(super) asset: Asset,
    /// Skeleton joint -> file joint.
    pub(super) order: Vec<usize>,
    /// File joint -> skeleton joint.
    pub(super) new_index: Vec<u32>,
}

/// Builds the asset from parsed files. `weights` rows are per OBJ `v` line with file joint
/// indices; `rest_path` is where assembly errors point (they come from rest values).
pub(super) fn assemble(
    name: &str,
    mesh: Mesh,
    parents: &[Option<usize>],
    rest: &RestTransforms,
    weights: Option<Influences>,
    rest_path: &Path,
) -> Result<Assembled, ImportError> {
    let here = || Location::file(rest_path);
    let joint_count = parents.len();
    let order = parents_first_order(parents)
        .map_err(|problems| ImportError::new(here(), Problem::Skeleton(problems)))?;
    let mut new_index = vec![0_u32; joint_count];
    for (k, &f) in order.iter().enumerate() {
        if let Some(slot) = new_index.get_mut(f) {
            *slot = k as u32;
        }
    }
    let joints: Vec<Joint> = order
        .iter()
        .map(|&f| {
            let get = |v: &[DVec3]| v.get(f).copied().unwrap_or(DVec3::ZERO);
            Joint {
                name: format!("joint_{f}"),
                parent: parents
                    .get(f)
                    .copied()
                    .flatten()
                    .and_then(|p| new_index.get(p))
                    .map(|&p| JointIndex(p)),
                rest_local: rest_local_transform(
                    get(&rest.translations),
                    get(&rest.joint_orients_deg),
                    get(&rest.rest_angles_deg),
                    rest.rotate_orders
                        .get(f)
                        .copied()
                        .unwrap_or(EulerOrder::Xyz),
                ),
            }
        })
        .collect();
    let skeleton =
        Skeleton::new(joints).map_err(|p| ImportError::new(here(), Problem::Skeleton(p)))?;

    let mut skins = Vec::new();
    if let Some(weights) = weights {
        // parse_weights made one row per `v` line, which is what source_vertex names.
        if mesh.source_vertex_count() > weights.vertex_count() {
            return Err(ImportError::at(
                here(),
                Mismatch::WeightRows {
                    rows: weights.vertex_count(),
                    vertices: mesh.source_vertex_count(),
                },
            ));
        }
        skins.push(SkinBinding {
            mesh: MeshIndex(0),
            joints: (0..skeleton.len() as u32).map(JointIndex).collect(),
            inv_bind: inverse_bind_matrices(&skeleton),
            influences: remap_influences(&weights, &new_index, &mesh.source_vertex),
            method: Default::default(),
        });
    }
    let asset = Asset {
        name: name.to_string(),
        skeleton,
        meshes: vec![mesh],
        skins,
        clips: Vec::new(),
        meters_per_unit: None,
        frame: Default::default(),
        ik_handles: Vec::new(),
        ..Default::default()
    };
    crate::check_asset(&asset, here)?;
    Ok(Assembled {
        asset,
        order,
        new_index,
    })
}

/// The inverse of each joint's model-space rest matrix, from the stored (`f32`) rest
/// transforms evaluated and inverted in `f64`, so that `model_rest · inv_bind` is the
/// identity up to one `f32` rounding of `inv_bind`. Affine inverses keep the last row
/// exactly `(0, 0, 0, 1)`.
fn inverse_bind_matrices(skeleton: &Skeleton) -> Vec<Mat4> {
    let mut model: Vec<DAffine3> = Vec::with_capacity(skeleton.len());
    for joint in skeleton.joints() {
        let t = &joint.rest_local;
        let local = DAffine3::from_scale_rotation_translation(
            t.scale.as_dvec3(),
            t.rotation.as_dquat(),
            t.translation.as_dvec3(),
        );
        let parent = joint.parent.and_then(|p| model.get(p.get()));
        model.push(parent.map_or(local, |p| *p * local));
    }
    model
        .iter()
        .map(|m| DMat4::from(m.inverse()).as_mat4())
        .collect()
}

/// Rows keyed by file joint and OBJ `v` line -> rows keyed by skeleton joint and output
/// vertex (`source_vertex[v]` is output vertex `v`'s `v` line), re-sorted.
fn remap_influences(weights: &Influences, new_index: &[u32], source_vertex: &[u32]) -> Influences {
    let mut entries: Vec<Influence> = Vec::with_capacity(weights.entries().len());
    let mut ends = Vec::with_capacity(weights.vertex_count());
    for row in weights.rows() {
        let start = entries.len();
        entries.extend(row.iter().map(|inf| Influence {
            joint: new_index.get(inf.joint as usize).copied().unwrap_or(0),
            weight: inf.weight,
        }));
        sort_row(entries.get_mut(start..).unwrap_or_default());
        ends.push(entries.len());
    }
    let by_source = rows_from_ends(&entries, &ends);
    let identity = source_vertex.len() == by_source.vertex_count()
        && source_vertex
            .iter()
            .enumerate()
            .all(|(i, &s)| s as usize == i);
    if identity {
        by_source
    } else {
        // The caller checked that every source vertex has a row.
        by_source.remap_vertices(source_vertex)
    }
}
