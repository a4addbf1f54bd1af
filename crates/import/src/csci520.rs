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

use std::path::Path;

use glam::{DAffine3, DMat4, DQuat, DVec3, Mat4, Vec3};
use rigport_model::conventions::EulerOrder;
use rigport_model::{
    parents_first_order, Asset, Influence, Influences, Joint, JointIndex, Mesh, MeshIndex,
    Skeleton, SkeletonProblem, SkinBinding, Transform, Warning,
};

use crate::{exact_fields, obj, read_file, utf8, ImportError, Imported, Location, Problem};

/// A row of weights whose sum differs from 1 by more than this is renormalized with a
/// [`Warning::WeightsRenormalized`]. The corpus rows sum to 1 within 2e-12 (13-digit
/// decimals); hand-edited files with 4-decimal weights stay within 1e-4.
pub const ROW_SUM_TOLERANCE: f64 = 1e-4;

/// `IKJointIDs` lists (after expanding ranges) longer than this are rejected, so a typo
/// such as `0:4000000000` cannot exhaust memory. Real rigs have tens of joints.
pub const MAX_LIST_LEN: usize = 1 << 16;

/// A CSCI 520 rig: the asset plus what the model has no field for.
///
/// Every per-joint vector has one entry per skeleton joint, in skeleton (parents-first)
/// order; [`Csci520Rig::file_index`] maps a skeleton joint to its index in the files.
#[derive(Clone, Debug)]
pub struct Csci520Rig {
    /// The asset (skeleton, mesh, and a skin unless the weights are absent) and the
    /// warnings of the import.
    pub imported: Imported,
    /// The `IKJointIDs` joints, in the config's order, as skeleton indices; empty when the
    /// config has no `IKJointIDs`. A handle's initial target is its joint's model-space
    /// rest position.
    pub ik_handles: Vec<JointIndex>,
    /// Each joint's rotate order (the order of its rest angles; joint orients are always
    /// `xyz`).
    pub rotate_orders: Vec<EulerOrder>,
    /// Each joint's rest Euler angles in degrees, `[x, y, z]` whatever the order: the
    /// angles the IK unknowns start from.
    pub rest_angles_deg: Vec<DVec3>,
    /// Each joint's `jointOrient` angles in degrees, `[x, y, z]`, applied in `xyz` order.
    pub joint_orients_deg: Vec<DVec3>,
    /// For each skeleton joint, its index in `jointHierarchy.txt`, the rest transforms,
    /// the weights and `IKJointIDs` (the `<i>` of its name `joint_<i>`).
    pub file_index: Vec<usize>,
}

/// A value of a `skin.config` option and the 1-based line it is on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConfigEntry<T> {
    /// The value (for file names: the trimmed line, relative to the config's folder).
    pub value: T,
    /// The 1-based line of the value in the config.
    pub line: usize,
}

/// The options of a `skin.config`, as read by [`parse_config`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SkinConfig {
    /// `*meshFilename`: the OBJ.
    pub mesh_filename: Option<ConfigEntry<String>>,
    /// `*jointHierarchyFilename`.
    pub joint_hierarchy_filename: Option<ConfigEntry<String>>,
    /// `*jointRestTransformsFilename`.
    pub joint_rest_transforms_filename: Option<ConfigEntry<String>>,
    /// `*jointWeightsFilename`.
    pub joint_weights_filename: Option<ConfigEntry<String>>,
    /// `*IKJointIDs`, ranges expanded, in the listed order (file joint numbering; not yet
    /// checked against the joint count).
    pub ik_joint_ids: Option<ConfigEntry<Vec<usize>>>,
    /// Every other option, in file order: its name as written and its value.
    pub other: Vec<(String, ConfigEntry<String>)>,
}

/// The contents of `jointRestTransforms.txt`, one entry per joint in file order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RestTransforms {
    /// Offset from the parent joint in the parent's frame (the root's: in model space),
    /// in the files' length unit.
    pub translations: Vec<DVec3>,
    /// Rest Euler angles in degrees, `[x, y, z]`, applied in `rotate_orders` order.
    pub rest_angles_deg: Vec<DVec3>,
    /// `jointOrient` angles in degrees, `[x, y, z]`, applied in `xyz` order.
    pub joint_orients_deg: Vec<DVec3>,
    /// Rotate order of each joint's rest angles (`xyz` for all when the file has none).
    pub rotate_orders: Vec<EulerOrder>,
    /// Whether the file has the rotate-order section.
    pub rotate_orders_given: bool,
}

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
/// [`Asset::validate`] (only for values too large for `f32`, at the rest transforms).
pub fn import(config: &Path) -> Result<Csci520Rig, ImportError> {
    let config_bytes = read_file(config)?;
    let (cfg, mut warnings) = parse_config(utf8(&config_bytes, config)?, config)?;
    let dir = config.parent().unwrap_or(Path::new(""));
    let required = |entry: &Option<ConfigEntry<String>>, option: &str| {
        entry.clone().ok_or_else(|| {
            ImportError::invalid(
                Location::file(config),
                format!("the required option *{option} is missing"),
            )
        })
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
                message: "no *jointWeightsFilename option: the rig has no skin weights; imported the skeleton and an unskinned mesh".into(),
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
                            "*jointWeightsFilename names {:?}, which does not exist: the rig has no skin weights; imported the skeleton and an unskinned mesh",
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
                let message = format!(
                    "*IKJointIDs: joint {id} does not exist: {} has {joint_count} joints (0..={})",
                    hierarchy_path.display(),
                    joint_count.saturating_sub(1)
                );
                return Err(ImportError::invalid(
                    Location::line(config, ik_line.unwrap_or(0)),
                    message,
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

/// Parses a `skin.config`.
///
/// Lines are trimmed first (CRLF, indentation); blank lines and lines starting with `#`
/// are skipped everywhere, also between an option and its value. An option's value is the
/// whole trimmed line. Returns the options and a [`Warning::Note`] per unknown option.
///
/// # Errors
/// At the offending line: a line that is neither an option, a comment nor a value
/// following an option; `*` without a name, or with something after the name (the value
/// goes on the next line); an option given twice; an option without a value (followed by
/// another option or the end of the file, at the option's line); an `IKJointIDs` value
/// that is not a `ListIO` list of non-negative integers (see [`parse_joint_list`]).
pub fn parse_config(text: &str, path: &Path) -> Result<(SkinConfig, Vec<Warning>), ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut cfg = SkinConfig::default();
    let mut warnings = Vec::new();
    // The option waiting for its value: name as written, line.
    let mut pending: Option<(&str, usize)> = None;
    // Lower-case names seen, with their lines.
    let mut seen: Vec<(String, usize)> = Vec::new();
    for (i, raw) in text.split('\n').enumerate() {
        let line_no = i + 1;
        let line = raw.trim_ascii();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let at = || Location::line(path, line_no);
        if let Some(name) = line.strip_prefix('*') {
            if let Some((previous, previous_line)) = pending {
                return Err(ImportError::invalid(
                    Location::line(path, previous_line),
                    format!("*{previous} has no value: the next line that is not blank or a comment (line {line_no}) starts another option"),
                ));
            }
            let name = name.trim_ascii();
            if name.is_empty() {
                return Err(ImportError::syntax(at(), "an option name after `*`", line));
            }
            if name.bytes().any(|b| b.is_ascii_whitespace()) {
                return Err(ImportError::syntax(
                    at(),
                    "an option name alone on its line (the value goes on the next line)",
                    line,
                ));
            }
            let lower = name.to_ascii_lowercase();
            if let Some((_, first)) = seen.iter().find(|(n, _)| *n == lower) {
                return Err(ImportError::invalid(
                    at(),
                    format!("*{name} is given twice (first on line {first})"),
                ));
            }
            seen.push((lower, line_no));
            pending = Some((name, line_no));
            continue;
        }
        let Some((name, option_line)) = pending.take() else {
            return Err(ImportError::syntax(
                at(),
                "an `*option` line, a `#` comment or a blank line",
                line,
            ));
        };
        let entry = ConfigEntry {
            value: line.to_string(),
            line: line_no,
        };
        match name.to_ascii_lowercase().as_str() {
            "meshfilename" => cfg.mesh_filename = Some(entry),
            "jointhierarchyfilename" => cfg.joint_hierarchy_filename = Some(entry),
            "jointresttransformsfilename" => cfg.joint_rest_transforms_filename = Some(entry),
            "jointweightsfilename" => cfg.joint_weights_filename = Some(entry),
            "ikjointids" => {
                let ids = parse_joint_list(line).map_err(|message| {
                    ImportError::invalid(at(), format!("*IKJointIDs: {message}"))
                })?;
                cfg.ik_joint_ids = Some(ConfigEntry {
                    value: ids,
                    line: line_no,
                });
            }
            // Cosmetic options of the course's driver: kept, nothing to say.
            "alllightsintensity" | "screenshotbasename" => {
                cfg.other.push((name.to_string(), entry));
            }
            _ => {
                warnings.push(Warning::Note {
                    location: format!("{}:{option_line}", path.display()),
                    message: format!("unknown option *{name} ignored"),
                });
                cfg.other.push((name.to_string(), entry));
            }
        }
    }
    if let Some((name, line)) = pending {
        return Err(ImportError::invalid(
            Location::line(path, line),
            format!("*{name} has no value: the file ends"),
        ));
    }
    Ok((cfg, warnings))
}

/// Parses an integer list in Vega `ListIO` syntax: non-negative integers separated by
/// commas and/or white space, `a:b` (blanks allowed around `:`) meaning `a, a+1, ..., b`.
/// Empty entries (`1,,2`, a trailing comma as `ListIO` writes) are allowed; an empty text
/// gives an empty list.
///
/// # Errors
/// A message (without location) for: a character other than digits, `,`, `:` and white
/// space; a negative or too large number; a `:` without a number on either side; a range
/// that runs backwards (`5:3`); more than [`MAX_LIST_LEN`] values.
pub fn parse_joint_list(text: &str) -> Result<Vec<usize>, String> {
    #[derive(Clone, Copy)]
    enum Token {
        Number(usize),
        Comma,
        Colon,
    }
    let mut tokens = Vec::new();
    let bytes = text.as_bytes();
    let mut i = 0;
    while let Some(&b) = bytes.get(i) {
        match b {
            b',' => tokens.push(Token::Comma),
            b':' => tokens.push(Token::Colon),
            b if b.is_ascii_whitespace() => {}
            b'0'..=b'9' | b'-' | b'+' => {
                let start = i;
                i += 1;
                while bytes.get(i).is_some_and(u8::is_ascii_digit) {
                    i += 1;
                }
                let token = text.get(start..i).unwrap_or_default();
                let value: i64 = token
                    .parse()
                    .map_err(|_| format!("{token:?} is not a joint index"))?;
                let value = usize::try_from(value).map_err(|_| {
                    format!("joint index {value} is negative (indices are 0-based)")
                })?;
                tokens.push(Token::Number(value));
                continue;
            }
            _ => {
                let rest: String = text.get(i..).unwrap_or_default().chars().take(20).collect();
                return Err(format!(
                    "expected a joint index, `,` or `:`, found {rest:?}"
                ));
            }
        }
        i += 1;
    }
    let mut out: Vec<usize> = Vec::new();
    let mut tokens = tokens.into_iter().peekable();
    while let Some(token) = tokens.next() {
        match token {
            Token::Comma => {}
            Token::Colon => return Err("a `:` range needs a number before it".into()),
            Token::Number(a) => {
                let b = if matches!(tokens.peek(), Some(Token::Colon)) {
                    tokens.next();
                    match tokens.next() {
                        Some(Token::Number(b)) if b >= a => b,
                        Some(Token::Number(b)) => {
                            return Err(format!("the range {a}:{b} runs backwards"))
                        }
                        _ => return Err(format!("the range {a}: needs a number after `:`")),
                    }
                } else {
                    a
                };
                if b - a >= MAX_LIST_LEN.saturating_sub(out.len()) {
                    return Err(format!("more than {MAX_LIST_LEN} joint indices"));
                }
                out.extend(a..=b);
            }
        }
    }
    Ok(out)
}

/// Parses `jointHierarchy.txt`: entry `i` is joint `i`'s parent, `-1` for the root.
///
/// Entries are integers separated by white space and/or commas, on any number of lines;
/// blank lines and `#` comment lines are skipped. Returns one parent per joint in file
/// numbering (not necessarily parents-first), already checked to form one tree.
///
/// # Errors
/// At the line of the offending entry: a token that is not an integer; a parent below -1
/// or not a joint; a joint that is its own parent; a parent cycle (at the line of the
/// cycle's smallest joint); a second root. A file without entries is [`Problem::Empty`].
pub fn parse_hierarchy(text: &str, path: &Path) -> Result<Vec<Option<usize>>, ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut parents: Vec<Option<usize>> = Vec::new();
    let mut lines: Vec<usize> = Vec::new();
    for (i, raw) in text.split('\n').enumerate() {
        let line = raw.trim_ascii();
        if line.starts_with('#') {
            continue;
        }
        let at = || Location::line(path, i + 1);
        for token in line
            .split(|c: char| c.is_ascii_whitespace() || c == ',')
            .filter(|t| !t.is_empty())
        {
            let joint = parents.len();
            let value: i64 = token.parse().map_err(|_| {
                ImportError::syntax(at(), "a parent index (-1 for the root)", token)
            })?;
            let parent = match value {
                -1 => None,
                p => Some(usize::try_from(p).map_err(|_| {
                    ImportError::invalid(
                        at(),
                        format!("joint {joint} has parent {p}: the root's parent is -1, every other is a joint index"),
                    )
                })?),
            };
            parents.push(parent);
            lines.push(i + 1);
        }
    }
    let count = parents.len();
    if count == 0 {
        return Err(ImportError::new(Location::file(path), Problem::Empty));
    }
    if u32::try_from(count).is_err() {
        return Err(ImportError::invalid(
            Location::file(path),
            format!("{count} joints is more than rigport's joint indices hold"),
        ));
    }
    let line_of = |joint: usize| match lines.get(joint) {
        Some(&line) => Location::line(path, line),
        None => Location::file(path),
    };
    for (joint, parent) in parents.iter().enumerate() {
        match *parent {
            Some(p) if p >= count => {
                return Err(ImportError::invalid(
                    line_of(joint),
                    format!(
                        "joint {joint} has parent {p}, but there are only {count} joints (0..={})",
                        count - 1
                    ),
                ))
            }
            Some(p) if p == joint => {
                return Err(ImportError::invalid(
                    line_of(joint),
                    format!("joint {joint} is its own parent"),
                ))
            }
            _ => {}
        }
    }
    parents_first_order(&parents).map_err(|problems| {
        let joint = problems.iter().find_map(|p| match p {
            SkeletonProblem::Cycle { joints } => joints.iter().min().copied(),
            _ => None,
        });
        let location = joint.map_or_else(|| Location::file(path), line_of);
        ImportError::new(location, Problem::Skeleton(problems))
    })?;
    let mut roots = parents
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_none())
        .map(|(j, _)| j);
    match (roots.next(), roots.next()) {
        (Some(_), None) => Ok(parents),
        (Some(first), Some(second)) => Err(ImportError::invalid(
            line_of(second),
            format!("joint {second} is a second root (parent -1) besides joint {first}: the rig must have exactly one root"),
        )),
        // A finite parent array without a root has a cycle, reported above.
        (None, _) => Err(ImportError::invalid(
            Location::file(path),
            "no joint has parent -1: the rig has no root",
        )),
    }
}

/// The three number sections of `jointRestTransforms.txt`, for messages.
const SECTIONS: [&str; 3] = ["translation", "rest angle", "joint orient"];

/// Parses `jointRestTransforms.txt` for `joint_count` joints.
///
/// The file is read as a stream, as the course's loader does: `9 · joint_count` numbers
/// separated by any white space (translations, rest angles, joint orients, `[x, y, z]` per
/// joint), then, if anything but white space follows, `joint_count` rotate orders, each the
/// next three characters after white space (so `xyzzxy` is two orders), case-insensitive.
///
/// # Errors
/// At the line of the offending token: a number that does not parse or is not finite, a
/// translation too large for `f32`, a rotate order other than `xyz yzx zxy xzy yxz zyx`,
/// anything after the last rotate order. Fewer numbers than needed, or fewer rotate orders
/// than joints, is [`Problem::Truncated`] at the last line holding data; an empty file is
/// [`Problem::Empty`].
pub fn parse_rest_transforms(
    text: &str,
    path: &Path,
    joint_count: usize,
) -> Result<RestTransforms, ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut cursor = Cursor::new(text);
    let per_section = joint_count.saturating_mul(3);
    let total = joint_count.saturating_mul(9);
    let mut values: Vec<f64> = Vec::with_capacity(total.min(1 << 20));
    let mut last_line = 0;
    while values.len() < total {
        let Some((token, line)) = cursor.token() else {
            if last_line == 0 {
                return Err(ImportError::new(Location::file(path), Problem::Empty));
            }
            return Err(ImportError::new(
                Location::line(path, last_line),
                Problem::Truncated(format!(
                    "{} numbers for {joint_count} joints, expected {total}: {per_section} translations, {per_section} rest angles and {per_section} joint orients",
                    values.len()
                )),
            ));
        };
        last_line = line;
        let k = values.len();
        let section = SECTIONS
            .get(k / per_section.max(1))
            .copied()
            .unwrap_or("value");
        let joint = (k % per_section.max(1)) / 3;
        let at = || Location::line(path, line);
        let value: f64 = token.parse().map_err(|_| {
            ImportError::syntax(
                at(),
                format!("a number ({section} of joint {joint})"),
                token,
            )
        })?;
        if !value.is_finite() {
            return Err(ImportError::invalid(
                at(),
                format!("{section} {token} of joint {joint} is not finite"),
            ));
        }
        if k < per_section && !(value as f32).is_finite() {
            return Err(ImportError::invalid(
                at(),
                format!("translation {token} of joint {joint} is too large for f32"),
            ));
        }
        values.push(value);
    }
    let triples = |section: usize| -> Vec<DVec3> {
        values
            .get(section * per_section..(section + 1) * per_section)
            .unwrap_or_default()
            .chunks_exact(3)
            .map(DVec3::from_slice)
            .collect()
    };
    let mut rest = RestTransforms {
        translations: triples(0),
        rest_angles_deg: triples(1),
        joint_orients_deg: triples(2),
        rotate_orders: vec![EulerOrder::Xyz; joint_count],
        rotate_orders_given: false,
    };
    cursor.skip_white_space();
    if cursor.at_end() {
        return Ok(rest);
    }
    rest.rotate_orders_given = true;
    for (joint, slot) in rest.rotate_orders.iter_mut().enumerate() {
        let Some((token, line)) = cursor.three_chars() else {
            return Err(ImportError::new(
                Location::line(path, last_line),
                Problem::Truncated(format!(
                    "rotate orders for {joint} of {joint_count} joints: give one per joint or none"
                )),
            ));
        };
        last_line = line;
        *slot = EulerOrder::parse(token).ok_or_else(|| {
            ImportError::syntax(
                Location::line(path, line),
                format!("a rotate order (xyz, yzx, zxy, xzy, yxz or zyx) for joint {joint}"),
                token,
            )
        })?;
    }
    if let Some((token, line)) = cursor.token() {
        return Err(ImportError::syntax(
            Location::line(path, line),
            format!("the end of the file after {joint_count} rotate orders"),
            token,
        ));
    }
    Ok(rest)
}

/// A position in a text that counts lines, for the stream-read rest transforms.
struct Cursor<'a> {
    text: &'a str,
    pos: usize,
    /// 1-based line of `pos`.
    line: usize,
}

impl<'a> Cursor<'a> {
    fn new(text: &'a str) -> Self {
        Self {
            text,
            pos: 0,
            line: 1,
        }
    }

    fn at_end(&self) -> bool {
        self.pos >= self.text.len()
    }

    fn skip_white_space(&mut self) {
        while let Some(&b) = self.text.as_bytes().get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    /// The next white-space-delimited token and its line.
    fn token(&mut self) -> Option<(&'a str, usize)> {
        self.skip_white_space();
        let start = self.pos;
        let bytes = self.text.as_bytes();
        while bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        // Both ends are at an ASCII byte or the end: char boundaries.
        let token = self.text.get(start..self.pos)?;
        (!token.is_empty()).then_some((token, self.line))
    }

    /// The next three characters after white space (fewer at the end of the text) and the
    /// line they start on; `None` at the end.
    fn three_chars(&mut self) -> Option<(&'a str, usize)> {
        self.skip_white_space();
        let line = self.line;
        let rest = self.text.get(self.pos..)?;
        if rest.is_empty() {
            return None;
        }
        let len = rest.char_indices().nth(3).map_or(rest.len(), |(i, _)| i);
        let chars = rest.get(..len)?;
        self.line += chars.bytes().filter(|&b| b == b'\n').count();
        self.pos += len;
        Some((chars, line))
    }
}

/// Parses `jointWeights.txt` for a mesh of `vertex_count` OBJ `v` lines and
/// `joint_count` joints.
///
/// Returns one influence row per OBJ `v` line, whose [`Influence::joint`] is the joint's
/// index **in the files** (not yet the skeleton's), sorted by descending weight (ties by
/// joint). Blank lines are skipped; CRLF, trailing spaces and a missing final newline are
/// fine. Entries with weight 0 are dropped (they have no effect). Warnings, in order:
/// a [`Warning::Note`] when duplicate `(vertex, joint)` entries were summed; one
/// [`Warning::WeightsRenormalized`] when rows whose sum differs from 1 by more than
/// [`ROW_SUM_TOLERANCE`] were rescaled to 1 (other rows are kept as written); a
/// [`Warning::Note`] counting the vertices without any entry, which are kept with no
/// influence.
///
/// # Errors
/// At the offending line: a header count that is not an integer, a row count other than
/// `vertex_count` or a column count other than `joint_count`, anything after `rows cols`
/// on the header's line; an entry line without exactly 3 fields, an index that is not an
/// integer or is out of range, a weight that does not parse or is NaN, infinite or
/// negative; a row whose sum overflows (at its first entry). A file without the two
/// header counts is [`Problem::Empty`] or [`Problem::Truncated`].
pub fn parse_weights(
    text: &str,
    path: &Path,
    vertex_count: usize,
    joint_count: usize,
) -> Result<(Influences, Vec<Warning>), ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_ascii()))
        .filter(|(_, l)| !l.is_empty());

    // Header: `rows cols` on one line or two.
    let mut header: Vec<(usize, &str)> = Vec::with_capacity(2);
    while header.len() < 2 {
        let Some((line_no, line)) = lines.next() else {
            return Err(match header.first() {
                None => ImportError::new(Location::file(path), Problem::Empty),
                Some(&(line, _)) => ImportError::new(
                    Location::line(path, line),
                    Problem::Truncated("the header `rows cols` has no column count".into()),
                ),
            });
        };
        for token in line.split_ascii_whitespace() {
            if header.len() == 2 {
                return Err(ImportError::syntax(
                    Location::line(path, line_no),
                    "the end of the header line (`rows cols`; entries start on the next line)",
                    token,
                ));
            }
            header.push((line_no, token));
        }
    }
    let header_count = |index: usize, what: &str, expected: usize, source: &str| {
        let (line, token) = header.get(index).copied().unwrap_or((0, ""));
        let at = || Location::line(path, line);
        let value: i64 = token
            .parse()
            .map_err(|_| ImportError::syntax(at(), format!("the {what} count"), token))?;
        if usize::try_from(value).ok() != Some(expected) {
            return Err(ImportError::invalid(
                at(),
                format!("the header declares {value} {what}s, but {source} {expected}"),
            ));
        }
        Ok(())
    };
    header_count(0, "row", vertex_count, "the mesh has (OBJ `v` lines)")?;
    header_count(1, "column", joint_count, "the hierarchy has joints:")?;

    // Entries: (vertex, joint, weight, line).
    let mut entries: Vec<(u32, u32, f64, usize)> =
        Vec::with_capacity(vertex_count.saturating_mul(4));
    for (line_no, line) in lines {
        let at = || Location::line(path, line_no);
        let Some([vertex, joint, weight]) = exact_fields::<3>(line) else {
            return Err(ImportError::syntax(
                at(),
                "an entry `vertex joint weight`",
                line,
            ));
        };
        let index = |token: &str, what: &str, count: usize| -> Result<u32, ImportError> {
            let value: i64 = token
                .parse()
                .map_err(|_| ImportError::syntax(at(), format!("a {what} index"), token))?;
            match usize::try_from(value) {
                Ok(v) if v < count => Ok(v as u32),
                _ => Err(ImportError::invalid(
                    at(),
                    format!(
                        "{what} index {value} is out of range: there are {count} {what}s (0..={})",
                        count.saturating_sub(1)
                    ),
                )),
            }
        };
        let vertex = index(vertex, "vertex", vertex_count)?;
        let joint = index(joint, "joint", joint_count)?;
        let value: f64 = weight
            .parse()
            .map_err(|_| ImportError::syntax(at(), "a weight", weight))?;
        if !value.is_finite() {
            return Err(ImportError::invalid(
                at(),
                format!("weight {weight} is not finite"),
            ));
        }
        if value < 0.0 {
            return Err(ImportError::invalid(
                at(),
                format!("weight {weight} is negative"),
            ));
        }
        if value > 0.0 {
            entries.push((vertex, joint, value, line_no));
        }
    }

    // Sum duplicates: sort by (vertex, joint), stable so the first line stays first.
    entries.sort_by_key(|&(v, j, _, _)| (v, j));
    let mut merged: Vec<(u32, u32, f64, usize)> = Vec::with_capacity(entries.len());
    let mut duplicates = 0_usize;
    let mut first_duplicate_line = usize::MAX;
    for entry in entries {
        match merged.last_mut() {
            Some(last) if last.0 == entry.0 && last.1 == entry.1 => {
                last.2 += entry.2;
                duplicates += 1;
                first_duplicate_line = first_duplicate_line.min(entry.3);
            }
            _ => merged.push(entry),
        }
    }

    // Rows, in vertex order.
    let mut influences: Vec<Influence> = Vec::with_capacity(merged.len());
    let mut ends: Vec<usize> = Vec::with_capacity(vertex_count);
    let mut rescaled = 0_usize;
    let mut max_error = 0.0_f64;
    let mut empty = 0_usize;
    let mut first_empty = None;
    let mut pos = 0;
    for v in 0..vertex_count {
        let start = influences.len();
        let begin = pos;
        // `merged` is sorted by vertex and every vertex is below vertex_count.
        while merged.get(pos).is_some_and(|e| e.0 as usize == v) {
            pos += 1;
        }
        let row = merged.get(begin..pos).unwrap_or_default();
        let sum: f64 = row.iter().map(|e| e.2).sum();
        let first_line = row.first().map_or(0, |e| e.3);
        if row.is_empty() {
            empty += 1;
            first_empty.get_or_insert(v);
            ends.push(start);
            continue;
        }
        if !sum.is_finite() {
            return Err(ImportError::invalid(
                Location::line(path, first_line),
                format!("the weights of vertex {v} sum to more than f64 holds"),
            ));
        }
        let error = (sum - 1.0).abs();
        let scale = if error > ROW_SUM_TOLERANCE {
            rescaled += 1;
            max_error = max_error.max(error);
            1.0 / sum
        } else {
            1.0
        };
        for &(_, joint, w, _) in row {
            let weight = (w * scale) as f32;
            // A weight below f32's range has no effect, as a written 0 has none.
            if weight > 0.0 {
                influences.push(Influence { joint, weight });
            }
        }
        sort_row(influences.get_mut(start..).unwrap_or_default());
        ends.push(influences.len());
    }

    let mut warnings = Vec::new();
    let source = path.display().to_string();
    if duplicates > 0 {
        warnings.push(Warning::Note {
            location: format!("{source}:{first_duplicate_line}"),
            message: format!(
                "{duplicates} duplicate (vertex, joint) entries were added to the first entry of their pair"
            ),
        });
    }
    if rescaled > 0 {
        warnings.push(Warning::WeightsRenormalized {
            source: source.clone(),
            rows: rescaled,
            max_row_sum_error: max_error as f32,
        });
    }
    if let Some(first) = first_empty {
        warnings.push(Warning::Note {
            location: source,
            message: format!(
                "{empty} of {vertex_count} vertices (the first is vertex {first}) have no weight entry: they are bound to no joint"
            ),
        });
    }
    Ok((rows_from_ends(&influences, &ends), warnings))
}

/// Sorts one vertex's influences by descending weight, ties by joint index.
fn sort_row(row: &mut [Influence]) {
    row.sort_by(|a, b| b.weight.total_cmp(&a.weight).then(a.joint.cmp(&b.joint)));
}

/// [`Influences`] from flat entries and each row's end offset.
fn rows_from_ends(entries: &[Influence], ends: &[usize]) -> Influences {
    Influences::from_rows(ends.iter().scan(0, |start, &end| {
        let row = entries.get(*start..end).unwrap_or_default().iter().copied();
        *start = end;
        Some(row)
    }))
}

/// The rotation `R_xyz(joint_orient) · R_order(angles)` of the assignment's
/// `local = T · R_xyz(jointOrient) · R_order(angles)`, angles in degrees `[x, y, z]`
/// (column vectors: the orient is applied after, i.e. outside, the rest angles).
pub fn local_rotation(joint_orient_deg: DVec3, angles_deg: DVec3, order: EulerOrder) -> DQuat {
    euler_rotation(EulerOrder::Xyz, joint_orient_deg) * euler_rotation(order, angles_deg)
}

/// The rotation of Euler angles in degrees `[x, y, z]` applied in `order` (the first
/// letter first: `xyz` is `Rz · Ry · Rx`), in `f64`.
pub fn euler_rotation(order: EulerOrder, angles_deg: DVec3) -> DQuat {
    order.as_str().bytes().fold(DQuat::IDENTITY, |q, axis| {
        let elementary = match axis {
            b'x' => DQuat::from_rotation_x(angles_deg.x.to_radians()),
            b'y' => DQuat::from_rotation_y(angles_deg.y.to_radians()),
            _ => DQuat::from_rotation_z(angles_deg.z.to_radians()),
        };
        // A later letter is applied later: it multiplies from the left.
        elementary * q
    })
}

/// A joint's local rest transform `T(translation) · R_xyz(joint_orient) · R_order(angles)`
/// (translation in the files' unit, angles in degrees), computed in `f64` and rounded to
/// `f32` once: translation, unit rotation with `w >= 0`, scale 1.
pub fn rest_local_transform(
    translation: DVec3,
    joint_orient_deg: DVec3,
    angles_deg: DVec3,
    order: EulerOrder,
) -> Transform {
    let mut q = local_rotation(joint_orient_deg, angles_deg, order).normalize();
    if q.w < 0.0 {
        q = -q;
    }
    Transform {
        translation: translation.as_vec3(),
        rotation: q.as_quat(),
        scale: Vec3::ONE,
    }
}

/// What [`assemble`] builds.
struct Assembled {
    asset: Asset,
    /// Skeleton joint -> file joint.
    order: Vec<usize>,
    /// File joint -> skeleton joint.
    new_index: Vec<u32>,
}

/// Builds the asset from parsed files. `weights` rows are per OBJ `v` line with file joint
/// indices; `rest_path` is where assembly errors point (they come from rest values).
fn assemble(
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
            return Err(ImportError::invalid(
                here(),
                format!(
                    "{} weight rows for a mesh of {} source vertices",
                    weights.vertex_count(),
                    mesh.source_vertex_count()
                ),
            ));
        }
        skins.push(SkinBinding {
            method: Default::default(),
            mesh: MeshIndex(0),
            joints: (0..skeleton.len() as u32).map(JointIndex).collect(),
            inv_bind: inverse_bind_matrices(&skeleton),
            influences: remap_influences(&weights, &new_index, &mesh.source_vertex),
        });
    }
    let asset = Asset {
        frame: Default::default(),
        name: name.to_string(),
        skeleton,
        meshes: vec![mesh],
        skins,
        clips: Vec::new(),
        meters_per_unit: None,
        ik_handles: Vec::new(),
    };
    if let Err(errors) = asset.validate() {
        let text: Vec<String> = errors.iter().map(ToString::to_string).collect();
        return Err(ImportError::invalid(here(), text.join("; ")));
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/csci520");
    const CORPUS: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/corpus/2_csci520_ik_skinning"
    );

    /// Model-space rest matrices evaluated in `f64` from the stored `f32` rest transforms.
    fn model_f64(skeleton: &Skeleton) -> Vec<DMat4> {
        let mut out: Vec<DMat4> = Vec::with_capacity(skeleton.len());
        for joint in skeleton.joints() {
            let t = &joint.rest_local;
            let local = DMat4::from_scale_rotation_translation(
                t.scale.as_dvec3(),
                t.rotation.as_dquat(),
                t.translation.as_dvec3(),
            );
            let m = match joint.parent {
                Some(p) => out[p.get()] * local,
                None => local,
            };
            out.push(m);
        }
        out
    }

    /// (largest |skin matrix - identity| entry, largest |LBS(p) - p| coordinate), skin
    /// matrix = model rest (f64 from the stored transforms) · inverse bind, LBS in f64.
    fn bind_pose_errors(asset: &Asset) -> (f64, f64) {
        let skin = &asset.skins[0];
        let model = model_f64(&asset.skeleton);
        let skin_matrices: Vec<DMat4> = skin
            .joints
            .iter()
            .zip(&skin.inv_bind)
            .map(|(j, inv)| model[j.get()] * inv.as_dmat4())
            .collect();
        let matrix_error = skin_matrices
            .iter()
            .map(|s| {
                (*s - DMat4::IDENTITY)
                    .to_cols_array()
                    .iter()
                    .fold(0.0_f64, |a, b| a.max(b.abs()))
            })
            .fold(0.0, f64::max);
        let mesh = &asset.meshes[0];
        let mut position_error = 0.0_f64;
        for (v, p) in mesh.positions.iter().enumerate() {
            let p = p.as_dvec3();
            let mut q = DVec3::ZERO;
            for inf in skin.influences.vertex(v) {
                q += f64::from(inf.weight) * skin_matrices[inf.joint as usize].transform_point3(p);
            }
            position_error = position_error.max((q - p).abs().max_element());
        }
        (matrix_error, position_error)
    }

    /// Asserts that every skin matrix is the identity and LBS reproduces every position,
    /// both within 1e-6, evaluating the stored `f32` data in `f64`. The residue is the
    /// `f32` rounding of the inverse bind matrices: half an ulp of their translations
    /// (4.8e-7 for the corpus hand, whose joints lie up to 11 units from the origin).
    fn assert_bind_pose(asset: &Asset, what: &str) {
        let (matrix, position) = bind_pose_errors(asset);
        assert!(
            matrix < 1e-6,
            "{what}: skin matrix differs from identity by {matrix:e}"
        );
        assert!(
            position < 1e-6,
            "{what}: bind pose moves a vertex by {position:e}"
        );
    }

    fn err<T: std::fmt::Debug>(result: Result<T, ImportError>) -> String {
        result.expect_err("should fail").to_string()
    }

    fn config(text: &str) -> Result<(SkinConfig, Vec<Warning>), ImportError> {
        parse_config(text, Path::new("skin.config"))
    }

    fn hierarchy(text: &str) -> Result<Vec<Option<usize>>, ImportError> {
        parse_hierarchy(text, Path::new("h.txt"))
    }

    fn rest(text: &str, joints: usize) -> Result<RestTransforms, ImportError> {
        parse_rest_transforms(text, Path::new("r.txt"), joints)
    }

    fn weights(text: &str, v: usize, j: usize) -> Result<(Influences, Vec<Warning>), ImportError> {
        parse_weights(text, Path::new("w.txt"), v, j)
    }

    fn inf(joint: u32, weight: f32) -> Influence {
        Influence { joint, weight }
    }

    #[test]
    fn config_with_comments_case_and_unknown_options() {
        let text = "\u{feff}# header comment\r\n\r\n*MESHFILENAME\r\n  # comment between option and value\r\n\r\nmy mesh.obj  \r\n*jointHierarchyFilename\nh.txt\n*jointRestTransformsFilename\nr.txt\n*allLightsIntensity\n0.5\n*ikJointIds\n15, 19, 4, 8\n#18, 15, 4, 8\n*frobnicate\n42\n";
        let (cfg, warnings) = config(text).unwrap();
        let entry = |value: &str, line| {
            Some(ConfigEntry {
                value: value.to_string(),
                line,
            })
        };
        assert_eq!(cfg.mesh_filename, entry("my mesh.obj", 6));
        assert_eq!(cfg.joint_hierarchy_filename, entry("h.txt", 8));
        assert_eq!(cfg.joint_rest_transforms_filename, entry("r.txt", 10));
        assert_eq!(cfg.joint_weights_filename, None);
        assert_eq!(
            cfg.ik_joint_ids,
            Some(ConfigEntry {
                value: vec![15, 19, 4, 8],
                line: 14
            })
        );
        let other: Vec<(&str, &str, usize)> = cfg
            .other
            .iter()
            .map(|(n, e)| (n.as_str(), e.value.as_str(), e.line))
            .collect();
        assert_eq!(
            other,
            [("allLightsIntensity", "0.5", 12), ("frobnicate", "42", 17)]
        );
        assert_eq!(
            warnings,
            [Warning::Note {
                location: "skin.config:16".into(),
                message: "unknown option *frobnicate ignored".into()
            }]
        );
    }

    #[test]
    fn config_errors_name_the_line() {
        assert_eq!(
            err(config("*meshFilename\n\n# c\n*jointHierarchyFilename\nh.txt\n")),
            "skin.config:1: *meshFilename has no value: the next line that is not blank or a comment (line 4) starts another option"
        );
        assert_eq!(
            err(config("*meshFilename\na.obj\n*IKJointIDs\n# none\n")),
            "skin.config:3: *IKJointIDs has no value: the file ends"
        );
        assert_eq!(
            err(config("*meshFilename\na.obj\n*MeshFileName\nb.obj\n")),
            "skin.config:3: *MeshFileName is given twice (first on line 1)"
        );
        assert_eq!(
            err(config("*meshFilename\na.obj\nb.obj\n")),
            "skin.config:3: expected an `*option` line, a `#` comment or a blank line, found \"b.obj\""
        );
        assert_eq!(
            err(config("*meshFilename a.obj\n")),
            "skin.config:1: expected an option name alone on its line (the value goes on the next line), found \"*meshFilename a.obj\""
        );
        assert_eq!(
            err(config("\n*\nx\n")),
            "skin.config:2: expected an option name after `*`, found \"*\""
        );
        assert_eq!(
            err(config("*IKJointIDs\n\n1, 2; 3\n")),
            "skin.config:3: *IKJointIDs: expected a joint index, `,` or `:`, found \"; 3\""
        );
    }

    #[test]
    fn joint_lists_follow_listio() {
        assert_eq!(parse_joint_list("15, 19, 4, 8"), Ok(vec![15, 19, 4, 8]));
        assert_eq!(
            parse_joint_list("6 10,14 ,22\t18"),
            Ok(vec![6, 10, 14, 22, 18])
        );
        assert_eq!(
            parse_joint_list("0:3, 7 9 : 10"),
            Ok(vec![0, 1, 2, 3, 7, 9, 10])
        );
        assert_eq!(parse_joint_list("5:5,"), Ok(vec![5]));
        assert_eq!(parse_joint_list("1,,2,"), Ok(vec![1, 2]));
        assert_eq!(parse_joint_list("  "), Ok(vec![]));
        assert_eq!(
            parse_joint_list("3:1"),
            Err("the range 3:1 runs backwards".into())
        );
        assert_eq!(
            parse_joint_list(":2"),
            Err("a `:` range needs a number before it".into())
        );
        assert_eq!(
            parse_joint_list("2:, 3"),
            Err("the range 2: needs a number after `:`".into())
        );
        assert_eq!(
            parse_joint_list("1, -1"),
            Err("joint index -1 is negative (indices are 0-based)".into())
        );
        assert_eq!(
            parse_joint_list("1 x"),
            Err("expected a joint index, `,` or `:`, found \"x\"".into())
        );
        assert_eq!(
            parse_joint_list("0:4000000000"),
            Err(format!("more than {MAX_LIST_LEN} joint indices"))
        );
        assert!(parse_joint_list("99999999999999999999").is_err());
    }

    #[test]
    fn hierarchy_parses_any_order_and_checks_the_tree() {
        assert_eq!(
            hierarchy("1 3 -1 2").unwrap(),
            [Some(1), Some(3), None, Some(2)]
        );
        assert_eq!(
            hierarchy("# c\n-1, 0,\n0\n").unwrap(),
            [None, Some(0), Some(0)]
        );
        assert_eq!(err(hierarchy(" \n")), "h.txt: the file is empty");
        assert_eq!(
            err(hierarchy("-1\n0 x\n")),
            "h.txt:2: expected a parent index (-1 for the root), found \"x\""
        );
        assert_eq!(
            err(hierarchy("-1\n0\n-2\n")),
            "h.txt:3: joint 2 has parent -2: the root's parent is -1, every other is a joint index"
        );
        assert_eq!(
            err(hierarchy("-1 0\n5\n")),
            "h.txt:2: joint 2 has parent 5, but there are only 3 joints (0..=2)"
        );
        assert_eq!(
            err(hierarchy("-1\n1\n")),
            "h.txt:2: joint 1 is its own parent"
        );
        // Joints 1 -> 2 -> 3 -> 1 loop; joint 1 is on line 2.
        assert_eq!(
            err(hierarchy("-1\n2\n3\n1\n")),
            "h.txt:2: invalid skeleton: joints [3, 2, 1] form a parent cycle"
        );
        assert_eq!(
            err(hierarchy("-1 0\n-1\n")),
            "h.txt:2: joint 2 is a second root (parent -1) besides joint 0: the rig must have exactly one root"
        );
    }

    #[test]
    fn rest_transforms_are_a_stream() {
        // 2 joints: 6 translations, 6 angles, 6 orients, broken over lines at random,
        // then orders written without spaces and in upper case.
        let text = "1 2 3 4\n5 6 10 20 30 40 50 60\n\n0.5 0 0\n0 0 -0.5e1\n  ZXYxyz";
        let r = rest(text, 2).unwrap();
        assert_eq!(
            r.translations,
            [DVec3::new(1.0, 2.0, 3.0), DVec3::new(4.0, 5.0, 6.0)]
        );
        assert_eq!(
            r.rest_angles_deg,
            [DVec3::new(10.0, 20.0, 30.0), DVec3::new(40.0, 50.0, 60.0)]
        );
        assert_eq!(
            r.joint_orients_deg,
            [DVec3::new(0.5, 0.0, 0.0), DVec3::new(0.0, 0.0, -5.0)]
        );
        assert_eq!(r.rotate_orders, [EulerOrder::Zxy, EulerOrder::Xyz]);
        assert!(r.rotate_orders_given);
        let plain = rest("0 0 0\n0 0 0\n0 0 0\n\n", 1).unwrap();
        assert_eq!(plain.rotate_orders, [EulerOrder::Xyz]);
        assert!(!plain.rotate_orders_given);
    }

    #[test]
    fn rest_transform_errors_name_the_line_and_token() {
        let numbers = "0 0 0 0 0 0\n0 0 0 0 0 0\n0 0 0 0 0 0\n";
        assert_eq!(
            err(rest(&format!("{numbers}xyz abc\n"), 2)),
            "r.txt:4: expected a rotate order (xyz, yzx, zxy, xzy, yxz or zyx) for joint 1, found \"abc\""
        );
        assert_eq!(
            err(rest(&format!("{numbers}xyz\n"), 2)),
            "r.txt:4: truncated: rotate orders for 1 of 2 joints: give one per joint or none"
        );
        assert_eq!(
            err(rest(&format!("{numbers}xyz xyz\n0\n"), 2)),
            "r.txt:5: expected the end of the file after 2 rotate orders, found \"0\""
        );
        assert_eq!(
            err(rest("0 0 0 0 0 0\n0 0 0 0 0 0\n", 2)),
            "r.txt:2: truncated: 12 numbers for 2 joints, expected 18: 6 translations, 6 rest angles and 6 joint orients"
        );
        // The orders line where the joint orients should be.
        assert_eq!(
            err(rest("0 0 0 0 0 0\n0 0 0 0 0 0\nxyz xyz\n", 2)),
            "r.txt:3: expected a number (joint orient of joint 0), found \"xyz\""
        );
        assert_eq!(
            err(rest("0 0 0 0 0 0\n0 0 0 0 0 1,5\n", 2)),
            "r.txt:2: expected a number (rest angle of joint 1), found \"1,5\""
        );
        assert_eq!(
            err(rest("0 0 0\nNaN 0 0\n0 0 0\n", 1)),
            "r.txt:2: rest angle NaN of joint 0 is not finite"
        );
        assert_eq!(
            err(rest("0 1e39 0\n0 0 0\n0 0 0\n", 1)),
            "r.txt:1: translation 1e39 of joint 0 is too large for f32"
        );
        assert_eq!(err(rest("\n\n", 1)), "r.txt: the file is empty");
    }

    /// Row-major 4×4 matrices written out by hand, the reference for the formula.
    type M4 = [[f64; 4]; 4];

    fn mul(a: &M4, b: &M4) -> M4 {
        let mut out = [[0.0; 4]; 4];
        for (r, row) in out.iter_mut().enumerate() {
            for (c, value) in row.iter_mut().enumerate() {
                *value = (0..4).map(|k| a[r][k] * b[k][c]).sum();
            }
        }
        out
    }

    fn rx(deg: f64) -> M4 {
        let (s, c) = deg.to_radians().sin_cos();
        [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, c, -s, 0.0],
            [0.0, s, c, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]
    }

    fn ry(deg: f64) -> M4 {
        let (s, c) = deg.to_radians().sin_cos();
        [
            [c, 0.0, s, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [-s, 0.0, c, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]
    }

    fn rz(deg: f64) -> M4 {
        let (s, c) = deg.to_radians().sin_cos();
        [
            [c, -s, 0.0, 0.0],
            [s, c, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]
    }

    fn translate(t: [f64; 3]) -> M4 {
        [
            [1.0, 0.0, 0.0, t[0]],
            [0.0, 1.0, 0.0, t[1]],
            [0.0, 0.0, 1.0, t[2]],
            [0.0, 0.0, 0.0, 1.0],
        ]
    }

    /// The table of csci520_format.md, section 4.
    fn euler_matrix(order: EulerOrder, a: [f64; 3]) -> M4 {
        let (x, y, z) = (rx(a[0]), ry(a[1]), rz(a[2]));
        match order {
            EulerOrder::Xyz => mul(&mul(&z, &y), &x),
            EulerOrder::Yzx => mul(&mul(&x, &z), &y),
            EulerOrder::Zxy => mul(&mul(&y, &x), &z),
            EulerOrder::Xzy => mul(&mul(&y, &z), &x),
            EulerOrder::Yxz => mul(&mul(&z, &x), &y),
            EulerOrder::Zyx => mul(&mul(&x, &y), &z),
        }
    }

    /// local = T(translate) · R_xyz(jointOrient) · R_order(angles).
    fn naive_local(t: [f64; 3], orient: [f64; 3], angles: [f64; 3], order: EulerOrder) -> M4 {
        mul(
            &mul(&translate(t), &euler_matrix(EulerOrder::Xyz, orient)),
            &euler_matrix(order, angles),
        )
    }

    fn assert_matrix_close(got: Mat4, expected: &M4, tolerance: f64, what: &str) {
        let got = got.as_dmat4();
        for (r, row) in expected.iter().enumerate() {
            for (c, &e) in row.iter().enumerate() {
                let g = got.col(c)[r];
                assert!(
                    (g - e).abs() < tolerance,
                    "{what}: [{r}][{c}] is {g}, expected {e} (difference {:e})\n{got}\nvs {expected:?}",
                    (g - e).abs()
                );
            }
        }
    }

    #[test]
    fn local_transform_matches_the_matrix_product() {
        let t = [0.3, -1.25, 2.0];
        let orient = [5.0, -10.0, 20.0];
        let angles = [30.0, 45.0, 15.0];
        for order in EulerOrder::ALL {
            let got = rest_local_transform(t.into(), orient.into(), angles.into(), order);
            assert_eq!(got.scale, Vec3::ONE);
            assert!(got.rotation.w >= 0.0);
            // f32 storage: 1e-6 relative is a few ulps of these magnitudes.
            assert_matrix_close(
                got.to_mat4(),
                &naive_local(t, orient, angles, order),
                1e-6,
                order.as_str(),
            );
        }
        // Orders matter: the same angles in another order give another rotation.
        let a = euler_rotation(EulerOrder::Xyz, DVec3::from(angles));
        let b = euler_rotation(EulerOrder::Zxy, DVec3::from(angles));
        assert!(a.angle_between(b) > 0.1);
    }

    #[test]
    fn weights_header_on_one_line_or_two() {
        let two = "3\n2\n0 0 1.0\n1 0 0.25\n1 1 0.75\n2 1 1.0";
        let one = "3 2\r\n0 0 1.0\r\n\r\n1 1 0.75  \r\n1 0 0.25\r\n2 1 1.0\r\n";
        let (a, wa) = weights(two, 3, 2).unwrap();
        let (b, wb) = weights(one, 3, 2).unwrap();
        assert_eq!(a, b);
        assert!(wa.is_empty() && wb.is_empty(), "{wa:?} {wb:?}");
        assert_eq!(a.vertex(1), [inf(1, 0.75), inf(0, 0.25)]);
    }

    #[test]
    fn weights_repairs_are_reported() {
        // Vertex 0: duplicate entries summed (0.25 + 0.25) and zero weight dropped;
        // vertex 1: sums to 2 (renormalized); vertex 2: no entry; vertex 3: off by 5e-5
        // (kept as written).
        let text = "4 3\n0 0 0.25\n0 1 0.5\n0 0 0.25\n0 2 0\n1 2 1.5\n1 0 0.5\n3 1 0.99995\n";
        let (influences, warnings) = weights(text, 4, 3).unwrap();
        assert_eq!(influences.vertex(0), [inf(0, 0.5), inf(1, 0.5)]);
        assert_eq!(influences.vertex(1), [inf(2, 0.75), inf(0, 0.25)]);
        assert_eq!(influences.vertex(2), []);
        assert_eq!(influences.vertex(3), [inf(1, 0.99995)]);
        assert_eq!(
            warnings,
            [
                Warning::Note {
                    location: "w.txt:4".into(),
                    message: "1 duplicate (vertex, joint) entries were added to the first entry of their pair".into()
                },
                Warning::WeightsRenormalized {
                    source: "w.txt".into(),
                    rows: 1,
                    max_row_sum_error: 1.0
                },
                Warning::Note {
                    location: "w.txt".into(),
                    message: "1 of 4 vertices (the first is vertex 2) have no weight entry: they are bound to no joint".into()
                },
            ]
        );
    }

    #[test]
    fn weight_errors_name_the_line() {
        assert_eq!(
            err(weights("5\n2\n0 0 1\n", 4, 2)),
            "w.txt:1: the header declares 5 rows, but the mesh has (OBJ `v` lines) 4"
        );
        assert_eq!(
            err(weights("4\n3\n0 0 1\n", 4, 2)),
            "w.txt:2: the header declares 3 columns, but the hierarchy has joints: 2"
        );
        assert_eq!(
            err(weights("4 2 0 0 1\n", 4, 2)),
            "w.txt:1: expected the end of the header line (`rows cols`; entries start on the next line), found \"0\""
        );
        assert_eq!(
            err(weights("four 2\n", 4, 2)),
            "w.txt:1: expected the row count, found \"four\""
        );
        assert_eq!(
            err(weights("4\n", 4, 2)),
            "w.txt:1: truncated: the header `rows cols` has no column count"
        );
        assert_eq!(err(weights("", 4, 2)), "w.txt: the file is empty");
        assert_eq!(
            err(weights("4 2\n0 0 1\n\n4 1 1\n", 4, 2)),
            "w.txt:4: vertex index 4 is out of range: there are 4 vertexs (0..=3)"
        );
        assert_eq!(
            err(weights("4 2\n0 -1 1\n", 4, 2)),
            "w.txt:2: joint index -1 is out of range: there are 2 joints (0..=1)"
        );
        assert_eq!(
            err(weights("4 2\n0 0 1\n1 1\n", 4, 2)),
            "w.txt:3: expected an entry `vertex joint weight`, found \"1 1\""
        );
        assert_eq!(
            err(weights("4 2\n0 0.5 1\n", 4, 2)),
            "w.txt:2: expected a joint index, found \"0.5\""
        );
        assert_eq!(
            err(weights("4 2\n0 0 -0.5\n", 4, 2)),
            "w.txt:2: weight -0.5 is negative"
        );
        assert_eq!(
            err(weights("4 2\n0 0 nan\n", 4, 2)),
            "w.txt:2: weight nan is not finite"
        );
        assert_eq!(
            err(weights("4 2\n0 0 1e308\n0 1 1e308\n", 4, 2)),
            "w.txt:2: the weights of vertex 0 sum to more than f64 holds"
        );
    }

    /// The chain fixture's files, in file numbering (see fixtures/README.md).
    const CHAIN_PARENTS: [Option<usize>; 4] = [Some(1), Some(3), None, Some(2)];
    const CHAIN_T: [[f64; 3]; 4] = [
        [0.0, 0.5, 0.0],
        [0.0, 0.75, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    const CHAIN_ANGLES: [[f64; 3]; 4] = [
        [0.0; 3],
        [0.0, 0.0, -20.0],
        [0.0, 15.0, 0.0],
        [30.0, 45.0, 15.0],
    ];
    const CHAIN_ORIENT: [[f64; 3]; 4] = [[0.0; 3], [10.0, 0.0, 0.0], [0.0; 3], [5.0, -10.0, 20.0]];
    const CHAIN_ORDER: [EulerOrder; 4] = [
        EulerOrder::Xyz,
        EulerOrder::Xyz,
        EulerOrder::Xyz,
        EulerOrder::Zxy,
    ];

    /// Recursive FK over the file numbering: global(i) = global(parent) · local(i).
    fn naive_global(f: usize) -> M4 {
        let local = naive_local(CHAIN_T[f], CHAIN_ORIENT[f], CHAIN_ANGLES[f], CHAIN_ORDER[f]);
        match CHAIN_PARENTS[f] {
            Some(p) => mul(&naive_global(p), &local),
            None => local,
        }
    }

    #[test]
    fn chain_fixture_is_sorted_parents_first_and_remapped() {
        let rig = import_folder(&Path::new(FIXTURES).join("chain")).unwrap();
        assert!(
            rig.imported.warnings.is_empty(),
            "{:?}",
            rig.imported.warnings
        );
        let asset = &rig.imported.asset;
        assert_eq!(asset.name, "chain");
        let sk = &asset.skeleton;
        let names: Vec<&str> = sk.joints().iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names, ["joint_2", "joint_3", "joint_1", "joint_0"]);
        assert_eq!(rig.file_index, [2, 3, 1, 0]);
        let parents: Vec<Option<u32>> = sk.parents().map(|p| p.map(|j| j.0)).collect();
        assert_eq!(parents, [None, Some(0), Some(1), Some(2)]);
        // Handles 0, 3 in the files are skeleton joints 3, 1.
        assert_eq!(rig.ik_handles, [JointIndex(3), JointIndex(1)]);
        assert_eq!(
            rig.rotate_orders,
            [
                EulerOrder::Xyz,
                EulerOrder::Zxy,
                EulerOrder::Xyz,
                EulerOrder::Xyz
            ]
        );
        assert_eq!(rig.rest_angles_deg[1], DVec3::new(30.0, 45.0, 15.0));
        assert_eq!(rig.joint_orients_deg[2], DVec3::new(10.0, 0.0, 0.0));
        // Model-space rest matrices against recursive FK over the file numbering.
        for (k, m) in sk.model_rest_matrices().into_iter().enumerate() {
            assert_matrix_close(m, &naive_global(rig.file_index[k]), 1e-5, names[k]);
        }
        // Influences: per output vertex (8 `v` lines + 2 UV-seam copies of v 5 and 6),
        // joints in skeleton numbering, largest first.
        let mesh = &asset.meshes[0];
        assert_eq!(mesh.vertex_count(), 10);
        assert_eq!(mesh.source_vertex_count(), 8);
        let skin = &asset.skins[0];
        assert_eq!(skin.joints, (0..4).map(JointIndex).collect::<Vec<_>>());
        let inf_of = |v: usize| skin.influences.vertex(v).to_vec();
        assert_eq!(inf_of(0), [inf(0, 1.0)]);
        assert_eq!(inf_of(2), [inf(1, 0.75), inf(0, 0.25)]);
        assert_eq!(inf_of(4), [inf(1, 0.5), inf(2, 0.5)]);
        assert_eq!(inf_of(6), [inf(3, 0.6), inf(2, 0.4)]);
        for (v, &s) in mesh.source_vertex.iter().enumerate() {
            assert_eq!(inf_of(v), inf_of(s as usize), "output vertex {v}");
        }
        assert_eq!(mesh.source_vertex[8..], [4, 5]);
        assert_bind_pose(asset, "chain");
    }

    #[test]
    fn absent_or_unnamed_weights_give_an_unskinned_rig() {
        let dir = Path::new(FIXTURES).join("variants");
        let absent = import(&dir.join("absent_weights.config")).unwrap();
        assert!(absent.imported.asset.skins.is_empty());
        assert_eq!(absent.imported.asset.skeleton.len(), 4);
        assert_eq!(absent.imported.warnings.len(), 1);
        let text = absent.imported.warnings[0].to_string();
        assert!(
            text.ends_with("absent_weights.config:9: *jointWeightsFilename names \"absent_jointWeights.txt\", which does not exist: the rig has no skin weights; imported the skeleton and an unskinned mesh"),
            "{text}"
        );
        let unnamed = import(&dir.join("no_weights_option.config")).unwrap();
        assert!(unnamed.imported.asset.skins.is_empty());
        let text = unnamed.imported.warnings[0].to_string();
        assert!(
            text.ends_with("no_weights_option.config: no *jointWeightsFilename option: the rig has no skin weights; imported the skeleton and an unskinned mesh"),
            "{text}"
        );
        assert_eq!(unnamed.ik_handles, [JointIndex(3)]);
    }

    #[test]
    fn import_errors_name_the_config_line() {
        let dir = Path::new(FIXTURES).join("variants");
        let text = err(import(&dir.join("missing_rest.config")));
        assert!(
            text.contains("missing_rest.config:8: *jointRestTransformsFilename names \"missing_jointRestTransforms.txt\", which cannot be read ("),
            "{text}"
        );
        let text = err(import(&dir.join("handle_out_of_range.config")));
        assert!(
            text.contains("handle_out_of_range.config:11: *IKJointIDs: joint 4 does not exist: ")
                && text.ends_with("jointHierarchy.txt has 4 joints (0..=3)"),
            "{text}"
        );
        let text = err(import(&dir.join("no_such.config")));
        assert!(text.contains("no_such.config: cannot read: "), "{text}");
    }

    /// (folder, J, V, largest influence count (`None`: no weights), IK handles in file
    /// numbering).
    type CorpusRig = (&'static str, usize, usize, Option<usize>, &'static [usize]);

    #[test]
    fn corpus_rigs_import() {
        if !Path::new(CORPUS).is_dir() {
            assert!(
                std::env::var_os("CI").is_none(),
                "corpus missing at {CORPUS}"
            );
            println!("skipped: no corpus at {CORPUS}");
            return;
        }
        // As csci520_format.md states them.
        let rigs: [CorpusRig; 4] = [
            ("tydia/armadillo", 22, 5002, Some(5), &[15, 19, 4, 8]),
            ("tydia/hand", 23, 2673, Some(7), &[6, 10, 14, 22, 18]),
            ("tydia/dragon", 28, 38615, None, &[3, 7, 9, 11, 12, 23, 27]),
            ("shreyabhaumik/star", 12, 12, Some(4), &[4, 6, 9, 11]),
        ];
        for (dir, joints, vertices, max_influences, handles) in rigs {
            let config = Path::new(CORPUS).join(dir).join("skin.config");
            let start = std::time::Instant::now();
            let rig = import(&config).unwrap_or_else(|e| panic!("{e}"));
            println!("{dir}: {:?}", start.elapsed());
            for w in &rig.imported.warnings {
                println!("  warning: {w}");
            }
            let asset = &rig.imported.asset;
            assert!(asset.validate().is_ok());
            assert_eq!(asset.skeleton.len(), joints, "{dir}");
            assert_eq!(asset.meshes[0].source_vertex_count(), vertices, "{dir}");
            let file_handles: Vec<usize> = rig
                .ik_handles
                .iter()
                .map(|h| rig.file_index[h.get()])
                .collect();
            assert_eq!(file_handles, handles, "{dir}");
            assert_eq!(rig.rotate_orders.len(), joints);
            // The staged hierarchies are already parents-first: the order is kept.
            assert_eq!(rig.file_index, (0..joints).collect::<Vec<_>>(), "{dir}");
            match max_influences {
                Some(max) => {
                    assert!(rig.imported.warnings.is_empty(), "{dir}");
                    let skin = &asset.skins[0];
                    assert_eq!(skin.influences.max_per_vertex(), max, "{dir}");
                    for row in skin.influences.rows() {
                        assert!(!row.is_empty(), "{dir}");
                        assert!(row.windows(2).all(|w| w[0].weight >= w[1].weight));
                    }
                    assert_bind_pose(asset, dir);
                }
                None => {
                    assert!(asset.skins.is_empty(), "{dir}");
                    // The dragon's OBJ mixes `f a b c` with `f a/t ...` faces (a note
                    // from the OBJ reader), then the missing weights.
                    let texts: Vec<String> = rig
                        .imported
                        .warnings
                        .iter()
                        .map(ToString::to_string)
                        .collect();
                    assert_eq!(texts.len(), 2, "{texts:?}");
                    assert!(
                        texts[0].ends_with("dragon.obj: some face corners have no texture coordinate; they get (0, 0)"),
                        "{texts:?}"
                    );
                    assert!(
                        texts[1].ends_with("skin.config:11: *jointWeightsFilename names \"jointWeights.txt\", which does not exist: the rig has no skin weights; imported the skeleton and an unskinned mesh"),
                        "{texts:?}"
                    );
                }
            }
        }
        // Armadillo: 4 joints use zxy (file joints 2, 6, 14, 18), the rest xyz; the others
        // are all xyz.
        let armadillo = import_folder(&Path::new(CORPUS).join("tydia/armadillo")).unwrap();
        let zxy: Vec<usize> = (0..22)
            .filter(|&k| armadillo.rotate_orders[k] == EulerOrder::Zxy)
            .map(|k| armadillo.file_index[k])
            .collect();
        assert_eq!(zxy, [2, 6, 14, 18]);
        assert!(armadillo
            .rotate_orders
            .iter()
            .all(|o| matches!(o, EulerOrder::Xyz | EulerOrder::Zxy)));
    }

    proptest::proptest! {
        #[test]
        fn parsers_never_panic_on_random_text(
            text in "(\\*|#|-?[0-9]{1,3}|[ ,:.eE]|xyz|ZxY|nan|inf|\r?\n|[a-z]|é|\u{3000}|\u{feff}){0,200}",
            vertices in 0_usize..6,
            joints in 0_usize..5,
        ) {
            let path = Path::new("r.txt");
            let _ = parse_config(&text, path);
            let _ = parse_joint_list(&text);
            if let Ok(parents) = parse_hierarchy(&text, path) {
                proptest::prop_assert!(parents_first_order(&parents).is_ok());
            }
            if let Ok(r) = parse_rest_transforms(&text, path, joints) {
                proptest::prop_assert_eq!(r.translations.len(), joints);
                proptest::prop_assert_eq!(r.rotate_orders.len(), joints);
            }
            if let Ok((influences, _)) = parse_weights(&text, path, vertices, joints) {
                proptest::prop_assert_eq!(influences.vertex_count(), vertices);
                proptest::prop_assert!(influences
                    .entries()
                    .iter()
                    .all(|i| (i.joint as usize) < joints && i.weight > 0.0));
            }
        }
    }
}
