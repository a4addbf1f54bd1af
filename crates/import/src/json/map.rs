//! `MAP.json`: which source joint drives which target joint when retargeting.
//!
//! ```json
//! {"joints": {"Hips": ["root", "bone_4"], "LeftUpLeg": "bone_5", "LeftLeg": "bone_6"},
//!  "pelvis": {"source": "Hips", "target": "bone_4"}}
//! ```
//! `joints` maps each source joint name to one target joint name or a list of them; a
//! target joint may be driven by one source joint only. The hierarchy must agree: when
//! source joint `A` is above `B`, `B`'s targets may not be above `A`'s (the two
//! hierarchies joined by the map would hold a cycle). `pelvis` (optional) names the joints
//! whose positions stand for the hips; by default the mapped source joint nearest its root
//! and its first target.

use std::collections::BTreeMap;
use std::path::Path;

use rigport_model::{JointIndex, Skeleton};
use serde::Deserialize;

use super::{from_value, token, JsonError, JsonProblem};

/// One or several target names.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum Targets {
    One(String),
    Many(Vec<String>),
}

/// The pelvis pair.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Pelvis {
    source: String,
    target: String,
}

/// The file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    joints: BTreeMap<String, serde_json::Value>,
    pelvis: Option<Pelvis>,
}

/// A joint map read from a file, resolved against both skeletons.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct JointMapFile {
    /// `(source joint, target joint)` pairs, in the file's order (source names sorted).
    pub pairs: Vec<(JointIndex, JointIndex)>,
    /// `(source, target)` pelvis joints, when the file names them.
    pub pelvis: Option<(JointIndex, JointIndex)>,
}

/// Whether `a` is a proper ancestor of `b`.
fn above(skeleton: &Skeleton, a: JointIndex, b: JointIndex) -> bool {
    let mut cur = skeleton.joint(b).parent;
    while let Some(p) = cur {
        if p == a {
            return true;
        }
        cur = skeleton.joint(p).parent;
    }
    false
}

/// Reads a joint map from `source` onto `target`.
///
/// # Errors
/// Unreadable file, JSON syntax (line and column), a structure that is not the format's,
/// and with the JSON path: no pairs, a joint either skeleton lacks, a target joint given
/// twice, a pair that reverses the hierarchy of another (a cycle).
///
/// ```
/// # use rigport_model::{Joint, JointIndex, Skeleton, Transform};
/// let chain = |names: [&str; 2]| {
///     Skeleton::new(vec![
///         Joint { name: names[0].into(), parent: None, rest_local: Transform::IDENTITY },
///         Joint { name: names[1].into(), parent: Some(JointIndex(0)), rest_local: Transform::IDENTITY },
///     ])
///     .expect("a chain")
/// };
/// let (source, target) = (chain(["Hips", "Spine"]), chain(["root", "bone_1"]));
/// let dir = std::env::temp_dir().join(format!("rigport-map-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let path = dir.join("map.json");
/// std::fs::write(&path, r#"{"joints": {"Hips": "bone_1", "Spine": "root"}}"#)?;
/// let err = rigport_import::json::map::read(&path, &source, &target).unwrap_err();
/// assert!(err.to_string().contains("at /joints/Spine: "), "{err}");
/// std::fs::write(&path, r#"{"joints": {"Hips": "root", "Spine": "bone_1"}}"#)?;
/// let map = rigport_import::json::map::read(&path, &source, &target)?;
/// assert_eq!(map.pairs, [(JointIndex(0), JointIndex(0)), (JointIndex(1), JointIndex(1))]);
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read(path: &Path, source: &Skeleton, target: &Skeleton) -> Result<JointMapFile, JsonError> {
    let file: File = super::read(path)?;
    let err = |at: String, problem| JsonError::at(path, at, problem);
    if file.joints.is_empty() {
        return Err(err("/joints".into(), JsonProblem::Empty("joints")));
    }
    let unknown = |side: &'static str, name: &str| JsonProblem::MapUnknownJoint {
        side,
        name: name.to_string(),
    };
    let mut pairs: Vec<(JointIndex, JointIndex)> = Vec::new();
    // Per target joint: the source name that drives it.
    let mut driven: BTreeMap<JointIndex, String> = BTreeMap::new();
    for (name, value) in file.joints {
        let at = format!("/joints/{}", token(&name));
        let targets: Targets = from_value(value, path, &at)?;
        let Some(s) = source.find(&name) else {
            return Err(err(at, unknown("source", &name)));
        };
        let (names, many) = match targets {
            Targets::One(t) => (vec![t], false),
            Targets::Many(ts) if ts.is_empty() => {
                return Err(err(at, JsonProblem::Empty("target joints")))
            }
            Targets::Many(ts) => (ts, true),
        };
        for (i, t_name) in names.iter().enumerate() {
            let at = if many {
                format!("{at}/{i}")
            } else {
                at.clone()
            };
            let Some(t) = target.find(t_name) else {
                return Err(err(at, unknown("target", t_name)));
            };
            if let Some(first) = driven.get(&t) {
                return Err(err(
                    at,
                    JsonProblem::MappedTwice {
                        target: t_name.clone(),
                        first: first.clone(),
                    },
                ));
            }
            for &(s2, t2) in &pairs {
                let reversed = (above(source, s2, s) && above(target, t, t2))
                    || (above(source, s, s2) && above(target, t2, t));
                if reversed {
                    return Err(err(
                        at,
                        JsonProblem::MapCycle {
                            pair: [name.clone(), t_name.clone()],
                            other: [source.joint(s2).name.clone(), target.joint(t2).name.clone()],
                        },
                    ));
                }
            }
            driven.insert(t, name.clone());
            pairs.push((s, t));
        }
    }
    let pelvis = match file.pelvis {
        None => None,
        Some(p) => {
            let s = source
                .find(&p.source)
                .ok_or_else(|| err("/pelvis/source".into(), unknown("source", &p.source)))?;
            let t = target
                .find(&p.target)
                .ok_or_else(|| err("/pelvis/target".into(), unknown("target", &p.target)))?;
            Some((s, t))
        }
    };
    Ok(JointMapFile { pairs, pelvis })
}
