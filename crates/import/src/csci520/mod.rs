//! USC CSCI 520 "Inverse Kinematics with Skinning" folders: a `skin.config` naming an OBJ
//! mesh, `jointHierarchy.txt`, `jointRestTransforms.txt` and `jointWeights.txt`.
//!
//! # The files (see FORMATS.md and the corpus notes `csci520_format.md`)
//! - `skin.config` (Vega `ConfigFile`): a line `*optionName` (name case-insensitive), its
//!   value on the next line that is neither blank nor a `#` comment. Paths are relative to
//!   the config's folder. `meshFilename`, `jointHierarchyFilename` and
//!   `jointRestTransformsFilename` are required; `jointWeightsFilename` is optional (see
//!   [`import`] for a named file that is absent); `IKJointIDs` is an integer list in Vega
//!   `ListIO` syntax (commas and/or blanks, inclusive `a:b` ranges). The driver's cosmetic
//!   `allLightsIntensity` and `screenshotBaseName` are kept in [`SkinConfig::other`];
//!   unknown options too, with a [`Warning::Note`].
//! - `jointHierarchy.txt`: `J` integers, entry `i` the parent of joint `i`, `-1` for the one
//!   root; parents may come after their children.
//! - `jointRestTransforms.txt`: a stream of `3·J` translations, `3·J` rest Euler angles
//!   (degrees) and `3·J` joint orients (degrees, always `xyz`), then optionally `J` rotate
//!   orders, each read as the next 3 characters after white space (`xyz`, `ZXY`, ...;
//!   missing means `xyz`). Line breaks are conventional, not required.
//! - `jointWeights.txt`: `rows cols` (`V` and `J`, on one line or two), then one
//!   `vertex joint weight` triplet per line until the end of the file, indices 0-based,
//!   vertex `k` being the OBJ's `k`-th `v` line.
//!
//! # The asset rigport builds
//! - Skeleton: the file's joints sorted parents-first ([`parents_first_order`], which keeps
//!   the file order when it already is parents-first), named `joint_<i>` with `i` the
//!   joint's index **in the files**. [`Csci520Rig::file_index`] maps back.
//! - Rest transforms: the assignment's `local = T(translate) · R_xyz(jointOrient) ·
//!   R_order(angles)` (column vectors; `xyz` = `Rz·Ry·Rx`, see
//!   [`EulerOrder`]), computed in `f64` and stored as translation + rotation, scale 1
//!   ([`rest_local_transform`]). Lengths stay in the files' unit (the OBJ headers claim
//!   centimetres, a Maya boilerplate comment; [`Asset::meters_per_unit`] is left unset).
//! - Mesh: [`obj::parse`] of `meshFilename`; the asset is named after its file stem.
//! - Skin (when weights exist): the palette is every joint in skeleton order (palette index
//!   == joint index); the bind pose is the rest pose, as the course's skinning matrix
//!   `global(pose) · inverse(global(rest))` requires, so each inverse bind matrix is the
//!   inverse of the joint's model-space rest matrix, computed in `f64` from the stored
//!   (`f32`) rest transforms so that bind pose × inverse bind is the identity to `f32`
//!   rounding (evaluated in `f64`: within 5e-7 on the corpus, the rounding of inverse-bind
//!   translations up to 11 units; forward kinematics in `f32` arithmetic adds its own,
//!   2e-6 there). Influences are per output vertex (split OBJ vertices share their `v` line's
//!   row), sorted by descending weight (ties by joint index), with no limit on their count
//!   (the corpus has up to 7).
//! - IK handles, rotate orders, rest angles and joint orients, which the model has no field
//!   for, come beside the asset in [`Csci520Rig`].
//!
//! [`parents_first_order`]: rigport_model::parents_first_order
//! [`Asset::meters_per_unit`]: rigport_model::Asset::meters_per_unit

mod assemble;
mod config;
mod hierarchy;
mod rest;
#[cfg(test)]
mod tests;
mod types;
mod weights;

pub use self::config::{parse_config, parse_joint_list, MAX_LIST_LEN};

/// The end of the warning ([`Warning::Incomplete`]) for a rig whose weights file is not
/// named or does not exist, so that a caller who computes the weights can drop it.
pub const NO_WEIGHTS: &str =
    "the rig has no skin weights; imported the skeleton and an unskinned mesh";
pub use self::hierarchy::parse_hierarchy;
pub use self::rest::{euler_rotation, local_rotation, parse_rest_transforms, rest_local_transform};
pub use self::types::{ConfigEntry, Csci520Rig, RestTransforms, SkinConfig};
pub use self::weights::{parse_weights, ROW_SUM_TOLERANCE};

use std::path::Path;

use glam::DVec3;
use rigport_model::conventions::EulerOrder;
use rigport_model::{JointIndex, Warning};

use crate::problem::{Missing, Rule};
use crate::{obj, read_file, utf8, ImportError, Imported, Location};

use self::assemble::assemble;

/// Imports a CSCI 520 rig from its `skin.config` (paths in it are relative to its folder).
///
/// Returns a [`Csci520Rig`] rather than a bare [`Imported`] (which is its `imported`
/// field): the IK handles and the per-joint Euler data have no place in the model yet.
/// See the module docs for the asset built. Warnings come in order: config (unknown
/// options, no `IKJointIDs`), mesh, rest transforms (no rotate-order section), weights
/// (absent, duplicate entries, renormalized rows, vertices without weights), IK handles
/// (a joint listed twice: the repeats are dropped).
///
/// `jointWeightsFilename` is optional: when the option is missing, or names a file that
/// does not exist (the corpus dragon's config names a `jointWeights.txt` that was never
/// committed), the rig is imported with its skeleton and mesh but **no skin**, and a
/// [`Warning::Note`] says so. Any other unreadable file is an error.
///
/// # Errors
/// Every error names a file and, where one exists, a line: the config cannot be read or
/// is malformed (see [`parse_config`]); a required option is missing (at the config); a
/// named file cannot be read (at the config line naming it); [`obj::parse`],
/// [`parse_hierarchy`], [`parse_rest_transforms`] or [`parse_weights`] fails; an
/// `IKJointIDs` entry is not a joint (at its config line); the asset fails
/// [`Asset::validate`](rigport_model::Asset::validate) (only for values too large for `f32`, at the rest transforms).
pub fn import(config: &Path) -> Result<Csci520Rig, ImportError> {
    let config_bytes = read_file(config)?;
    let (cfg, mut warnings) = parse_config(utf8(&config_bytes, config)?, config)?;
    let dir = config.parent().unwrap_or(Path::new(""));
    let required = |entry: &Option<ConfigEntry<String>>, option: &'static str| {
        entry
            .clone()
            .ok_or_else(|| ImportError::at(Location::file(config), Missing::Option(option)))
    };
    let mesh_entry = required(&cfg.mesh_filename, "meshFilename")?;
    let hierarchy_entry = required(&cfg.joint_hierarchy_filename, "jointHierarchyFilename")?;
    let rest_entry = required(
        &cfg.joint_rest_transforms_filename,
        "jointRestTransformsFilename",
    )?;
    let location = |line: usize| format!("{}:{line}", config.display());

    // IK handles: checked against the joint count once the hierarchy is read.
    let (ik_ids, ik_line) = match &cfg.ik_joint_ids {
        Some(entry) => (entry.value.clone(), Some(entry.line)),
        None => {
            warnings.push(Warning::Note {
                location: config.display().to_string(),
                message: "no *IKJointIDs option: the rig has no IK handles".into(),
            });
            (Vec::new(), None)
        }
    };

    let mesh_path = dir.join(&mesh_entry.value);
    let mesh_bytes = read_named(config, "meshFilename", &mesh_entry, &mesh_path)?;
    let (mesh, mesh_warnings) = obj::parse(&mesh_bytes, &mesh_path)?;
    warnings.extend(mesh_warnings);

    let hierarchy_path = dir.join(&hierarchy_entry.value);
    let hierarchy_bytes = read_named(
        config,
        "jointHierarchyFilename",
        &hierarchy_entry,
        &hierarchy_path,
    )?;
    let parents = parse_hierarchy(utf8(&hierarchy_bytes, &hierarchy_path)?, &hierarchy_path)?;
    let joint_count = parents.len();

    let rest_path = dir.join(&rest_entry.value);
    let rest_bytes = read_named(
        config,
        "jointRestTransformsFilename",
        &rest_entry,
        &rest_path,
    )?;
    let rest = parse_rest_transforms(utf8(&rest_bytes, &rest_path)?, &rest_path, joint_count)?;
    if !rest.rotate_orders_given {
        warnings.push(Warning::Note {
            location: rest_path.display().to_string(),
            message: "no rotate-order section: every joint uses xyz".into(),
        });
    }

    let weights = match &cfg.joint_weights_filename {
        None => {
            warnings.push(Warning::Incomplete {
                location: config.display().to_string(),
                message: format!("no *jointWeightsFilename option: {NO_WEIGHTS}"),
            });
            None
        }
        Some(entry) => {
            let path = dir.join(&entry.value);
            match std::fs::read(&path) {
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                    warnings.push(Warning::Incomplete {
                        location: location(entry.line),
                        message: format!(
                            "*jointWeightsFilename names {:?}, which does not exist: {NO_WEIGHTS}",
                            entry.value
                        ),
                    });
                    None
                }
                Err(e) => return Err(unreadable(config, "jointWeightsFilename", entry, &path, &e)),
                Ok(bytes) => {
                    let (influences, weight_warnings) = parse_weights(
                        utf8(&bytes, &path)?,
                        &path,
                        mesh.source_vertex_count(),
                        joint_count,
                    )?;
                    warnings.extend(weight_warnings);
                    Some(influences)
                }
            }
        }
    };

    let mut seen = vec![false; joint_count];
    let mut handles_file = Vec::with_capacity(ik_ids.len());
    let mut duplicates = 0;
    for &id in &ik_ids {
        match seen.get_mut(id) {
            None => {
                return Err(ImportError::at(
                    Location::line(config, ik_line.unwrap_or(0)),
                    Rule::IkJoint {
                        joint: id,
                        hierarchy: hierarchy_path.to_path_buf(),
                        count: joint_count,
                    },
                ));
            }
            Some(true) => duplicates += 1,
            Some(slot) => {
                *slot = true;
                handles_file.push(id);
            }
        }
    }
    if duplicates > 0 {
        warnings.push(Warning::Repaired {
            location: location(ik_line.unwrap_or(0)),
            message: format!("*IKJointIDs lists {duplicates} joints twice; kept the first of each"),
        });
    }

    let name = mesh.name.clone();
    let assembled = assemble(&name, mesh, &parents, &rest, weights, &rest_path)?;
    let new_index = &assembled.new_index;
    let ik_handles: Vec<JointIndex> = handles_file
        .iter()
        .filter_map(|&f| new_index.get(f).map(|&k| JointIndex(k)))
        .collect();
    let mut asset = assembled.asset;
    asset.ik_handles = ik_handles.clone();
    warnings.extend(crate::weights_fit::check(
        &asset,
        &config.display().to_string(),
    ));
    let pick = |values: &[DVec3]| -> Vec<DVec3> {
        assembled
            .order
            .iter()
            .map(|&f| values.get(f).copied().unwrap_or(DVec3::ZERO))
            .collect()
    };
    Ok(Csci520Rig {
        rotate_orders: assembled
            .order
            .iter()
            .map(|&f| {
                rest.rotate_orders
                    .get(f)
                    .copied()
                    .unwrap_or(EulerOrder::Xyz)
            })
            .collect(),
        rest_angles_deg: pick(&rest.rest_angles_deg),
        joint_orients_deg: pick(&rest.joint_orients_deg),
        ik_handles,
        file_index: assembled.order,
        imported: Imported { asset, warnings },
    })
}

/// [`import`] of `dir/skin.config`.
///
/// # Errors
/// As [`import`].
pub fn import_folder(dir: &Path) -> Result<Csci520Rig, ImportError> {
    import(&dir.join("skin.config"))
}

/// Reads a file named by a config option; failure is an error at the config line.
fn read_named(
    config: &Path,
    option: &str,
    entry: &ConfigEntry<String>,
    path: &Path,
) -> Result<Vec<u8>, ImportError> {
    std::fs::read(path).map_err(|e| unreadable(config, option, entry, path, &e))
}

/// The error for a file named by a config option that cannot be read.
fn unreadable(
    config: &Path,
    option: &str,
    entry: &ConfigEntry<String>,
    path: &Path,
    error: &std::io::Error,
) -> ImportError {
    ImportError::invalid(
        Location::line(config, entry.line),
        format!(
            "*{option} names {:?}, which cannot be read ({}): {error}",
            entry.value,
            path.display()
        ),
    )
}
