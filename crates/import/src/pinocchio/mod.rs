//! Pinocchio rigs (Baran & Popović, "Automatic Rigging and Animation of 3D Characters",
//! 2007): an OBJ mesh, `skeleton.out` and `attachment.out`.
//!
//! # The files (see FORMATS.md, Pinocchio)
//! - `skeleton.out`: one line `index x y z parent` per joint, joints numbered 0, 1, 2, ...
//!   in file order, the root (joint 0) with parent `-1`; positions in the mesh's own
//!   coordinates and unit.
//! - `attachment.out`: one row per OBJ `v` line, in `v` order. Pinocchio writes one weight
//!   per **bone**, `J - 1` columns for `J` joints, column `k` being the bone that ends at
//!   joint `k + 1`; some derived tools write `J` columns, a root column first. Both are
//!   accepted and a [`Warning::Note`] says which was seen. Weights are rounded to 4
//!   decimals, so every row is renormalized.
//!
//! # The skeleton rigport builds
//! Pinocchio's deformer rotates each bone about its **head** (the parent joint's position)
//! and sibling bones sharing a head move independently, so a faithful glTF/USD skin needs
//! one skin joint per bone, not one per Pinocchio joint:
//! - `root` at Pinocchio joint 0's position;
//! - for each Pinocchio joint `k >= 1`, `bone_<k>` with its origin at the bone's head,
//!   `position[parent(k)]`, and skeleton parent `bone_<parent(k)>` (or `root` when
//!   `parent(k)` is joint 0).
//!
//! Rest rotations are identity (Pinocchio has none) and scales 1; a joint's rest
//! translation is its origin minus its parent's origin, so bones hanging off the root sit
//! at the root with zero local translation. Joints are stored parents-first. The positions
//! of the leaf joints (bone tails) carry no weight and are not part of this skeleton.
//!
//! The skin's palette is every joint in skeleton order (palette index == joint index), with
//! inverse bind matrices that are pure translations by `-origin`.

mod files;

use std::path::Path;

use glam::{Mat4, Vec3};
use rigport_model::conventions::WEIGHT_EPSILON;
use rigport_model::{
    Asset, Influence, Influences, Joint, JointIndex, Mesh, MeshIndex, Skeleton, SkinBinding,
    Transform, Warning,
};

use crate::problem::{Hierarchy, Mismatch, Missing, Rule};
use crate::{obj, read_file, utf8, ImportError, Imported, Location, Problem};
use files::check_topology;
pub use files::{parse_attachment, parse_skeleton, read_skeleton, Attachment, PinocchioSkeleton};

/// Imports a Pinocchio rig: the OBJ mesh, `skeleton.out` and `attachment.out`.
///
/// The asset is named after the mesh file's stem; it holds the skeleton described in the
/// module docs, the mesh (via [`obj::parse`]) and one skin binding. Warnings come in
/// order: mesh, attachment (layout, renormalization), then assembly (a skeleton lying far
/// outside the mesh).
///
/// # Errors
/// A file cannot be read or is not UTF-8 text, or [`obj::parse`], [`parse_skeleton`],
/// [`parse_attachment`] or [`assemble`] fails.
pub fn import(mesh: &Path, skeleton: &Path, attachment: &Path) -> Result<Imported, ImportError> {
    let mesh_bytes = read_file(mesh)?;
    // The OBJ and the weights are independent text files of similar size: parse them on
    // two threads. The weights need the vertex count, which a cheap line count gives up
    // front on the other thread (checked against the parsed mesh below).
    let read_rig = || -> Result<_, ImportError> {
        let expected_vertices = obj::count_vertex_lines(&mesh_bytes);
        let skeleton_bytes = read_file(skeleton)?;
        let (pino, repaired) = read_skeleton(utf8(&skeleton_bytes, skeleton)?, skeleton)?;
        let attachment_bytes = read_file(attachment)?;
        let parsed = parse_attachment(
            utf8(&attachment_bytes, attachment)?,
            attachment,
            pino.positions.len(),
            expected_vertices,
        );
        // The per-vertex influences need only the skeleton and the weights: build them
        // here too. Any problem is left for `assemble_from` to report, in file order.
        let influences = match (&parsed, check_topology(&pino.parents)) {
            (Ok((weights, _)), Ok(order)) => source_influences(
                weights.rows(),
                weights.root_weights.as_deref(),
                &skeleton_indices(&order),
                pino.positions.len().saturating_sub(1),
                &|| Location::file(attachment),
            )
            .ok(),
            _ => None,
        };
        Ok((
            pino,
            repaired,
            attachment_bytes,
            parsed,
            influences,
            expected_vertices,
        ))
    };
    let (mesh_result, rig_result) =
        crate::join(|| obj::parse_with_materials(&mesh_bytes, mesh), read_rig);
    // Errors in file order: the mesh first.
    let (mesh_data, mut warnings, materials_used) = mesh_result?;
    let (pino, repaired, attachment_bytes, parsed, mut influences, expected_vertices) = rig_result?;
    warnings.extend(repaired);
    let vertex_count = mesh_data.source_vertex_count();
    let (weights, attachment_warnings) = if vertex_count == expected_vertices {
        parsed?
    } else {
        influences = None;
        // The line count and the parser disagree (unusual syntax): parse again with the
        // parser's count, so errors name the right rows.
        parse_attachment(
            utf8(&attachment_bytes, attachment)?,
            attachment,
            pino.positions.len(),
            vertex_count,
        )?
    };
    warnings.extend(attachment_warnings);
    let name = mesh_data.name.clone();
    let imported = assemble_from(
        &name,
        &skeleton.display().to_string(),
        mesh_data,
        &pino,
        None,
        weights.rows(),
        weights.root_weights.as_deref(),
        influences,
    )?;
    warnings.extend(imported.warnings);
    let mut asset = imported.asset;
    // The OBJ's `.mtl` materials; one skinned mesh keeps one material.
    obj::apply_materials(&mut asset, mesh, &materials_used, false, &mut warnings);
    Ok(Imported { asset, warnings })
}

/// Imports a Pinocchio mesh and skeleton that come without an `attachment.out`: `weigh`
/// computes the weights (one row of `J - 1` bone weights per OBJ `v`, column `k` for the
/// bone ending at joint `k + 1`, as the file would hold them) from the mesh (its
/// [`Mesh::source_vertex`] maps its vertices to rows) and the skeleton, with any warnings;
/// the rig is then built as [`import`] builds it.
///
/// # Errors
/// As [`import`] for the mesh and skeleton; as `weigh`.
pub fn import_weighing(
    mesh: &Path,
    skeleton: &Path,
    weigh: impl FnOnce(&Mesh, &PinocchioSkeleton) -> Result<(Vec<Vec<f32>>, Vec<Warning>), ImportError>,
) -> Result<Imported, ImportError> {
    let mesh_bytes = read_file(mesh)?;
    let (mesh_data, mut warnings, materials_used) = obj::parse_with_materials(&mesh_bytes, mesh)?;
    let skeleton_bytes = read_file(skeleton)?;
    let (pino, repaired) = read_skeleton(utf8(&skeleton_bytes, skeleton)?, skeleton)?;
    warnings.extend(repaired);
    let (rows, weigh_warnings) = weigh(&mesh_data, &pino)?;
    warnings.extend(weigh_warnings);
    let name = mesh_data.name.clone();
    let imported = assemble_from(
        &name,
        &skeleton.display().to_string(),
        mesh_data,
        &pino,
        None,
        rows.iter().map(Vec::as_slice),
        None,
        None,
    )?;
    warnings.extend(imported.warnings);
    let mut asset = imported.asset;
    obj::apply_materials(&mut asset, mesh, &materials_used, false, &mut warnings);
    Ok(Imported { asset, warnings })
}

/// Builds the asset from already-parsed or generated Pinocchio data; [`import`] and the
/// built-in demo rig use it.
///
/// - `name`: the asset's name (the mesh keeps its own); also the location in errors and
///   warnings.
/// - `mesh`: the mesh in the skeleton's coordinates; its [`Mesh::source_vertex`] maps
///   output vertices to weight rows.
/// - `skeleton`: Pinocchio joints (root = joint 0, any parent/child order).
/// - `bone_names`: `None` for `root`, `bone_<k>`; else `J` names indexed by Pinocchio joint:
///   `names[0]` for the root joint, `names[k]` for the bone ending at joint `k`. Must be
///   non-empty and unique.
/// - `rows`: one row per source vertex (`mesh.source_vertex_count()` rows), `J - 1` weights
///   each, column `k` for the bone ending at joint `k + 1`.
/// - `root_weights`: an optional root weight per row (the `J`-column layout's first
///   column), bound to the root joint.
///
/// Each row's weights (with its root weight) are normalized to sum 1 here without a
/// warning, weights below [`WEIGHT_EPSILON`] dropped, the rest sorted by descending weight
/// (ties by joint index). A [`Warning::Note`] is returned when some skeleton joint lies
/// outside the mesh's bounding box by more than half its diagonal (a unit or axis mismatch
/// is likely).
///
/// # Errors
/// At `name` (no line): a skeleton that is not one tree rooted at joint 0 or has fewer than
/// 2 joints, position/parent counts that differ, a non-finite position, a wrong number of
/// names or rows or row weights, an empty or duplicate name, a negative, non-finite or
/// all-zero row, an asset that fails [`Asset::validate`].
pub fn assemble(
    name: &str,
    mesh: Mesh,
    skeleton: &PinocchioSkeleton,
    bone_names: Option<&[String]>,
    rows: &[Vec<f32>],
    root_weights: Option<&[f32]>,
) -> Result<Imported, ImportError> {
    let rows = rows.iter().map(Vec::as_slice);
    assemble_from(
        name,
        name,
        mesh,
        skeleton,
        bone_names,
        rows,
        root_weights,
        None,
    )
}

/// [`assemble`] with the weights of an [`Attachment`] (as [`parse_attachment`] returns
/// them).
///
/// # Errors
/// As [`assemble`]; also when `weights.bones` is not the skeleton's joint count minus 1.
pub fn assemble_attachment(
    name: &str,
    mesh: Mesh,
    skeleton: &PinocchioSkeleton,
    bone_names: Option<&[String]>,
    weights: &Attachment,
) -> Result<Imported, ImportError> {
    let bones = skeleton.positions.len().saturating_sub(1);
    if weights.bones != bones || weights.weights.len() % bones.max(1) != 0 {
        return Err(ImportError::at(
            Location::file(Path::new(name)),
            Mismatch::RowLength {
                weights: weights.weights.len(),
                row_len: weights.bones,
                bones,
            },
        ));
    }
    let root = weights.root_weights.as_deref();
    assemble_from(
        name,
        name,
        mesh,
        skeleton,
        bone_names,
        weights.rows(),
        root,
        None,
    )
}

/// Each weight row's influences on the skeleton joints (`new_index[k]` is Pinocchio joint
/// `k`'s skeleton index): zero weights dropped, renormalized, largest first (ties by joint).
///
/// # Errors
/// At `here()`: a row of the wrong length, a negative or non-finite weight, a row with no
/// weight.
fn source_influences<'a>(
    rows: impl ExactSizeIterator<Item = &'a [f32]>,
    root_weights: Option<&[f32]>,
    new_index: &[u32],
    bones: usize,
    here: &dyn Fn() -> Location,
) -> Result<Influences, ImportError> {
    // Built flat (one allocation) rather than one Vec per row.
    let mut entries: Vec<Influence> = Vec::with_capacity(rows.len() * 4);
    let mut ends: Vec<usize> = Vec::with_capacity(rows.len());
    for (v, row) in rows.enumerate() {
        if row.len() != bones {
            return Err(ImportError::at(
                here(),
                Mismatch::RowWeights {
                    row: v,
                    weights: row.len(),
                    bones,
                },
            ));
        }
        let start = entries.len();
        let root = root_weights.and_then(|r| r.get(v)).copied();
        let columns = root
            .map(|w| (0_usize, w))
            .into_iter()
            .chain(row.iter().enumerate().map(|(c, &w)| (c + 1, w)));
        let mut sum = 0.0_f64;
        for (k, w) in columns {
            if !w.is_finite() || w < 0.0 {
                return Err(ImportError::at(here(), Rule::Weight { row: v, weight: w }));
            }
            if w >= WEIGHT_EPSILON {
                sum += f64::from(w);
                entries.push(Influence {
                    joint: new_index.get(k).copied().unwrap_or(0),
                    weight: w,
                });
            }
        }
        if sum <= 0.0 {
            return Err(ImportError::at(here(), Missing::RowWeight(v)));
        }
        let kept = entries.get_mut(start..).unwrap_or_default();
        for inf in kept.iter_mut() {
            inf.weight = (f64::from(inf.weight) / sum) as f32;
        }
        kept.sort_by(|a, b| b.weight.total_cmp(&a.weight).then(a.joint.cmp(&b.joint)));
        ends.push(entries.len());
    }
    Ok(Influences::from_rows(ends.iter().scan(0, |start, &end| {
        let row = entries.get(*start..end).unwrap_or_default().iter().copied();
        *start = end;
        Some(row)
    })))
}

/// Skeleton index of each Pinocchio joint, for a topology [`check_topology`] accepted.
fn skeleton_indices(order: &[usize]) -> Vec<u32> {
    let mut new_index = vec![0_u32; order.len()];
    for (i, &k) in order.iter().enumerate() {
        if let Some(slot) = new_index.get_mut(k) {
            *slot = i as u32;
        }
    }
    new_index
}

/// [`assemble`], with `skeleton_source` as the location of the bounding-box note and the
/// rows from any source (nested vectors or an [`Attachment`]'s flat storage).
#[allow(
    clippy::too_many_arguments,
    reason = "private: the two public entry points fill in different subsets"
)]
fn assemble_from<'a>(
    name: &str,
    skeleton_source: &str,
    mesh: Mesh,
    skeleton: &PinocchioSkeleton,
    bone_names: Option<&[String]>,
    rows: impl ExactSizeIterator<Item = &'a [f32]>,
    root_weights: Option<&[f32]>,
    precomputed: Option<Influences>,
) -> Result<Imported, ImportError> {
    let here = || Location::file(Path::new(name));
    let joint_count = skeleton.positions.len();
    if skeleton.parents.len() != joint_count {
        return Err(ImportError::at(
            here(),
            Mismatch::Parents {
                positions: joint_count,
                parents: skeleton.parents.len(),
            },
        ));
    }
    if let Some(j) = skeleton.positions.iter().position(|p| !p.is_finite()) {
        return Err(ImportError::at(here(), Rule::NonFinitePosition(j)));
    }
    let order = check_topology(&skeleton.parents).map_err(|(joint, problem)| {
        let problem = match (joint, problem) {
            (Some(joint), Problem::Hierarchy(problem)) => Hierarchy::OfJoint {
                joint,
                problem: Box::new(problem),
            }
            .into(),
            (_, p) => p,
        };
        ImportError::new(here(), problem)
    })?;
    let bones = joint_count - 1;

    // Weight rows: one per source vertex.
    let row_count = rows.len();
    let source_count = mesh.source_vertex_count();
    if row_count != source_count {
        return Err(ImportError::at(
            here(),
            Mismatch::WeightRows {
                rows: row_count,
                vertices: source_count,
            },
        ));
    }
    if let Some(root) = root_weights {
        if root.len() != row_count {
            return Err(ImportError::at(
                here(),
                Mismatch::For {
                    found: root.len(),
                    what: "root weights",
                    expected: row_count,
                    per: "weight rows",
                },
            ));
        }
    }

    // Skeleton: output joint i is Pinocchio joint order[i].
    let new_index = skeleton_indices(&order);
    let parent_of = |k: usize| skeleton.parents.get(k).copied().flatten();
    let position = |k: usize| skeleton.positions.get(k).copied().unwrap_or(Vec3::ZERO);
    // A bone's origin is its head: its Pinocchio parent's position; the root's is its own.
    let origin = |k: usize| parent_of(k).map_or_else(|| position(k), position);
    if let Some(names) = bone_names {
        if names.len() != joint_count {
            return Err(ImportError::at(
                here(),
                Mismatch::For {
                    found: names.len(),
                    what: "bone names",
                    expected: joint_count,
                    per: "Pinocchio joints (one per joint, the root's first)",
                },
            ));
        }
    }
    let joints: Vec<Joint> = order
        .iter()
        .map(|&k| {
            let name = match bone_names.and_then(|n| n.get(k)) {
                Some(n) => n.clone(),
                None if k == 0 => "root".to_string(),
                None => format!("bone_{k}"),
            };
            let parent = parent_of(k);
            let local = origin(k) - parent.map_or(Vec3::ZERO, origin);
            Joint {
                name,
                parent: parent
                    .and_then(|p| new_index.get(p))
                    .map(|&p| JointIndex(p)),
                rest_local: Transform::from_translation(local),
            }
        })
        .collect();
    let skeleton_out =
        Skeleton::new(joints).map_err(|p| ImportError::new(here(), Problem::Skeleton(p)))?;
    // Pure translations: the inverse is exact (last row exactly 0 0 0 1).
    let inv_bind: Vec<Mat4> = skeleton_out
        .model_rest_matrices()
        .iter()
        .map(|m| Mat4::from_translation(-m.w_axis.truncate()))
        .collect();

    // Influences per source vertex (possibly built already, beside the OBJ parse), then
    // per output vertex.
    let by_source = match precomputed {
        Some(done) => done,
        None => source_influences(rows, root_weights, &new_index, bones, &here)?,
    };
    let identity = mesh.source_vertex.len() == row_count
        && mesh
            .source_vertex
            .iter()
            .enumerate()
            .all(|(i, &s)| s as usize == i);
    // source_vertex entries are < row_count since row_count == max + 1.
    let influences = if identity {
        by_source
    } else {
        by_source.remap_vertices(&mesh.source_vertex)
    };

    let mut warnings = Vec::new();
    if let Some(note) = bounds_note(&mesh, skeleton, skeleton_source) {
        warnings.push(note);
    }
    let palette = (0..skeleton_out.len() as u32).map(JointIndex).collect();
    let asset = Asset {
        frame: Default::default(),
        name: name.to_string(),
        skeleton: skeleton_out,
        meshes: vec![mesh],
        skins: vec![SkinBinding {
            method: Default::default(),
            mesh: MeshIndex(0),
            joints: palette,
            inv_bind,
            influences,
        }],
        clips: Vec::new(),
        meters_per_unit: None,
        ik_handles: Vec::new(),
        ..Default::default()
    };
    crate::check_asset(&asset, here)?;
    warnings.extend(crate::weights_fit::check(&asset, name));
    Ok(Imported { asset, warnings })
}

/// A note when some joint lies outside the mesh's bounding box by more than half the box's
/// diagonal: the skeleton and the mesh then probably disagree on unit or axes.
fn bounds_note(mesh: &Mesh, skeleton: &PinocchioSkeleton, location: &str) -> Option<Warning> {
    let (lo, hi) = mesh.bounds()?;
    let diagonal = (hi - lo).length();
    let outside = |p: Vec3| (lo - p).max(Vec3::ZERO) + (p - hi).max(Vec3::ZERO);
    let mut far = 0;
    let mut worst = (0, 0.0_f32);
    for (j, &p) in skeleton.positions.iter().enumerate() {
        let d = outside(p).length();
        if d > 0.5 * diagonal {
            far += 1;
            if d > worst.1 {
                worst = (j, d);
            }
        }
    }
    (far > 0).then(|| Warning::Note {
        location: location.to_string(),
        message: format!(
            "{far} of {} skeleton joints lie outside the mesh's bounding box by more than half its diagonal ({diagonal:.3}); joint {} is {:.3} away: the skeleton and the mesh probably use different units or axes",
            skeleton.positions.len(),
            worst.0,
            worst.1
        ),
    })
}

#[cfg(test)]
mod tests;
