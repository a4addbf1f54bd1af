//! Automatic skin weights by bone heat (`rigport_deform::weights`):
//! - a Pinocchio mesh and skeleton without an `attachment.out` ([`auto_rig`]): one bone
//!   per Pinocchio joint after the root (from its parent's position to its own), the rig
//!   then built as the attachment would have built it;
//! - any other rig's meshes that have no skin ([`bind_unskinned`]: a CSCI 520 folder
//!   without weights, a mesh bound to a BVH or ASF skeleton by `skin`).

use std::path::Path;

use rigport_deform::weights::{Bone, HeatOptions, Repairs, bind, bone_heat};
use rigport_import::pinocchio::{PinocchioSkeleton, import_weighing};
use rigport_import::{ImportError, Imported, Location, Problem};
use rigport_model::{Mesh, MeshIndex, Warning};

use crate::PipelineError;
use crate::progress::Progress;

/// Meshes with more vertices than this show counted progress while they are weighted
/// (smaller ones take under a second).
const COUNTED: usize = 50_000;

/// Bone heat's progress for a mesh of `vertices`, as counted work of `progress` when the
/// mesh is large.
fn counter(progress: &dyn Progress, vertices: usize) -> impl Fn(usize, usize) + Sync + '_ {
    move |done, total| {
        if vertices > COUNTED {
            progress.count("computing weights by bone heat", done, total);
        }
    }
}

/// The rig of `mesh` and `skeleton` with weights by bone heat; the repairs, if any, as a
/// W003 warning, and a note saying the weights were computed.
///
/// # Errors
/// As the Pinocchio importer; a mesh without faces or a skeleton without bones.
pub(crate) fn auto_rig(
    mesh: &Path,
    skeleton: &Path,
    progress: &dyn Progress,
) -> Result<Imported, PipelineError> {
    Ok(auto_rig_rows(mesh, skeleton, progress)?.0)
}

/// [`auto_rig`], and the weights as an `attachment.out` holds them: one row of bone
/// weights per OBJ vertex.
///
/// # Errors
/// As [`auto_rig`].
pub(crate) fn auto_rig_rows(
    mesh: &Path,
    skeleton: &Path,
    progress: &dyn Progress,
) -> Result<(Imported, Vec<Vec<f32>>), PipelineError> {
    let mut kept = Vec::new();
    let imported = import_weighing(mesh, skeleton, |m, s| {
        let (rows, warnings) = weigh(m, s, mesh, progress)?;
        kept.clone_from(&rows);
        Ok((rows, warnings))
    })?;
    Ok((imported, kept))
}

/// Binds every mesh of `imported` that has no skin and follows no joint to its skeleton by
/// bone heat ([`bind`]): a note per mesh with what was computed, and the repairs as W003.
/// Returns how many meshes were bound.
///
/// # Errors
/// A mesh without faces, a skeleton without bones (named with `source`).
pub(crate) fn bind_unskinned(
    imported: &mut Imported,
    source: &str,
    progress: &dyn Progress,
) -> Result<usize, PipelineError> {
    let Imported { asset, warnings } = imported;
    let mut skins = Vec::new();
    for (m, mesh) in asset.meshes.iter().enumerate() {
        if mesh.attached_to.is_some() || asset.skins.iter().any(|s| s.mesh.get() == m) {
            continue;
        }
        let bound = bind(
            &asset.skeleton,
            mesh,
            MeshIndex(m as u32),
            &HeatOptions::default(),
            &counter(progress, mesh.positions.len()),
        )
        .map_err(|e| PipelineError::Invalid(format!("{source}: mesh {:?}: {e}", mesh.name)))?;
        warnings.extend(heat_warnings(
            (source.to_string(), format!("mesh {:?}", mesh.name)),
            format!("{source}: mesh {:?}", mesh.name),
            (mesh.positions.len(), bound.bones),
            &bound.repairs,
        ));
        skins.push(bound.binding);
    }
    let count = skins.len();
    asset.skins.extend(skins);
    asset.skins.sort_by_key(|s| s.mesh);
    Ok(count)
}

/// One row of bone weights per OBJ vertex (column `k`: the bone ending at joint `k + 1`).
fn weigh(
    mesh: &Mesh,
    skeleton: &PinocchioSkeleton,
    path: &Path,
    progress: &dyn Progress,
) -> Result<(Vec<Vec<f32>>, Vec<Warning>), ImportError> {
    let bones: Vec<Bone> = (1..skeleton.positions.len())
        .map(|k| Bone {
            head: skeleton.parents[k].map_or(skeleton.positions[k], |p| skeleton.positions[p]),
            tail: skeleton.positions[k],
        })
        .collect();
    let heat = bone_heat(
        &mesh.positions,
        &mesh.triangles,
        &bones,
        &HeatOptions::default(),
        &counter(progress, mesh.positions.len()),
    )
    .map_err(|e| ImportError::new(Location::file(path), Problem::Invalid(e.to_string())))?;
    let mut rows = vec![vec![0.0f32; bones.len()]; mesh.source_vertex_count()];
    for (v, row) in heat.rows.iter().enumerate() {
        let source = mesh.source_vertex.get(v).map_or(v, |&s| s as usize);
        if let Some(out) = rows.get_mut(source) {
            out.iter_mut().for_each(|w| *w = 0.0);
            for &(b, w) in row {
                out[b as usize] = w;
            }
        }
    }
    let at = path.display().to_string();
    let warnings = heat_warnings(
        (at.clone(), "no attachment".to_string()),
        at,
        (mesh.positions.len(), bones.len()),
        &heat.repairs,
    );
    Ok((rows, warnings))
}

/// What bone heat did, for the user: a note at `(location, subject)` with the vertices and
/// bones weighted and the vertices that see no bone (part of the method, Pinocchio's too),
/// and the other repairs, of a broken mesh, as a W003 warning at `repaired_at`.
fn heat_warnings(
    (location, subject): (String, String),
    repaired_at: String,
    (vertices, bones): (usize, usize),
    repairs: &Repairs,
) -> Vec<Warning> {
    let mut warnings = vec![Warning::Note {
        location,
        message: format!(
            "{subject}: skin weights computed by bone heat for {vertices} vertices and {bones} \
             bones ({} vertices see no bone and take their neighbours' weights)",
            repairs.unseen
        ),
    }];
    let repairs = Repairs {
        unseen: 0,
        ..*repairs
    };
    if repairs.any() {
        warnings.push(Warning::Repaired {
            location: repaired_at,
            message: repairs_text(&repairs),
        });
    }
    warnings
}

/// What bone heat repaired, as one sentence.
fn repairs_text(r: &Repairs) -> String {
    let parts: Vec<String> = [
        (r.welded, "coincident vertices welded"),
        (r.degenerate_faces, "faces without area skipped"),
        (r.non_manifold_edges, "non-manifold edges"),
        (
            r.by_distance,
            "vertices no heat reaches weighted by distance",
        ),
        (r.negative_edges, "negative cotangent weights clamped"),
    ]
    .iter()
    .filter(|(n, _)| *n > 0)
    .map(|(n, what)| format!("{n} {what}"))
    .collect();
    format!("automatic weights: {}", parts.join(", "))
}
