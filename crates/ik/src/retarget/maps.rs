//! Joint maps: which source joint drives which target joint. [`auto_map`] pairs the body
//! roles both skeletons' structure shows ([`super::roles`]); built-in naming conventions
//! name the joints of each role for skeletons whose structure shows no body, and say how
//! far a skeleton's names agree with its structure.

use glam::Vec3;
use rigport_model::{Clip, JointIndex, Skeleton};

use super::roles::{find_body, Body};
use super::RetargetError;
use crate::naming::{find_bare, is_pinocchio_human};

/// One mapped joint: the target joint takes the source joint's world rotation (relative
/// to rest, see the module docs of [`super`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MapPair {
    /// The driving joint, in the source skeleton.
    pub source: JointIndex,
    /// The driven joint, in the target skeleton.
    pub target: JointIndex,
    /// The body role both joints play (`"LeftUpperArm"`), when the map came from
    /// conventions; `None` for name-for-name and file maps.
    pub role: Option<&'static str>,
}

/// A joint map between a source and a target skeleton.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct JointMap {
    /// The pairs, in target joint order. A target joint appears at most once; a source
    /// joint may drive several target joints.
    pub pairs: Vec<MapPair>,
    /// The source joint whose world position drives the target's hips (the pelvis), and
    /// the target joint at the target's pelvis.
    pub pelvis: (JointIndex, JointIndex),
    /// How the map was made (`"by name"`, `"cgspeed BVH -> Pinocchio human template"`,
    /// `"file"`).
    pub how: String,
}

pub use super::roles::ROLES;

pub use crate::naming::{
    Convention, BANDAI_NAMCO_BVH, CGSPEED_BVH, CMU_ASF, CONVENTIONS, MIXAMO, PINOCCHIO_HUMAN,
    RIGPORT_DEMO,
};

/// The joints of `skeleton` for each role of `convention` (roles whose joint is missing
/// are left out). For Pinocchio's template the sides are swapped when its `l` limbs lie
/// on the character's right in the rest pose (`up` is the model-space up direction).
pub fn resolve(
    skeleton: &Skeleton,
    convention: &Convention,
    up: Vec3,
) -> Vec<(&'static str, JointIndex)> {
    if convention.label == PINOCCHIO_HUMAN.label && !is_pinocchio_human(skeleton) {
        return Vec::new();
    }
    let mut found: Vec<(&'static str, JointIndex)> = convention
        .joints
        .iter()
        .filter_map(|&(role, name)| find_bare(skeleton, name).map(|j| (role, j)))
        .collect();
    if convention.label == PINOCCHIO_HUMAN.label {
        let rest = skeleton.model_rest_matrices();
        let at = |role: &str| {
            found
                .iter()
                .find(|(r, _)| *r == role)
                .and_then(|(_, j)| rest.get(j.get()))
                .map(|m| m.w_axis.truncate())
        };
        if let (Some(l), Some(r)) = (at("LeftUpperLeg"), at("RightUpperLeg")) {
            let forward = super::align::facing(&rest, &found, up);
            let right = forward.cross(up);
            if (l - r).dot(right) > 0.0 {
                for (role, _) in &mut found {
                    *role = mirror(role);
                }
            }
        }
    }
    found
}

/// The role of the other side (`LeftHand` <-> `RightHand`); other roles unchanged.
fn mirror(role: &'static str) -> &'static str {
    let other = if let Some(rest) = role.strip_prefix("Left") {
        format!("Right{rest}")
    } else if let Some(rest) = role.strip_prefix("Right") {
        format!("Left{rest}")
    } else {
        return role;
    };
    ROLES.iter().find(|r| **r == other).copied().unwrap_or(role)
}

/// The convention of `skeleton` that names the most of its joints (at least 5), with its
/// resolved joints.
fn best_convention(
    skeleton: &Skeleton,
    up: Vec3,
) -> Option<(&'static Convention, Vec<(&'static str, JointIndex)>)> {
    let mut best: Option<(&'static Convention, Vec<(&'static str, JointIndex)>)> = None;
    for c in &CONVENTIONS {
        let found = resolve(skeleton, c, up);
        if found.len() >= 5 && best.as_ref().is_none_or(|(_, b)| found.len() > b.len()) {
            best = Some((c, found));
        }
    }
    best
}

/// The map chosen for two skeletons: when at least 90% of the target's joints (and at
/// least two) have a source joint of the same name, joint for joint by name (a rig onto its
/// own skeleton, or two rigs of one convention); otherwise role for role between the bodies
/// both skeletons' structure shows ([`find_body`]; the source's read from `source_clip`'s
/// first frame when its rest pose does not stand); otherwise through the body roles of the
/// naming conventions ([`CONVENTIONS`]) that name the most joints of each skeleton.
/// `source_up`/`target_up` are the model-space up directions.
///
/// # Errors
/// [`RetargetError::NoMap`] when no way finds at least 5 roles in both skeletons.
pub fn auto_map(
    source: &Skeleton,
    target: &Skeleton,
    source_up: Vec3,
    target_up: Vec3,
    source_clip: Option<&Clip>,
) -> Result<JointMap, RetargetError> {
    let same: Vec<MapPair> = target
        .joints()
        .iter()
        .enumerate()
        .filter_map(|(t, j)| {
            source.find(&j.name).map(|s| MapPair {
                source: s,
                target: JointIndex(t as u32),
                role: None,
            })
        })
        .collect();
    if same.len() >= 2 && same.len() * 10 >= target.len() * 9 {
        let shallowest = same
            .iter()
            .min_by_key(|p| depth(source, p.source))
            .map(|p| (p.source, p.target));
        if let Some(pelvis) = shallowest {
            return Ok(JointMap {
                pairs: same,
                pelvis,
                how: "by name (same joint names)".into(),
            });
        }
    }
    if let (Some(bs), Some(bt)) = (
        find_body(source, source_up, source_clip),
        find_body(target, target_up, None),
    ) {
        let mut pairs: Vec<MapPair> = bt
            .roles
            .iter()
            .filter_map(|&(role, t)| {
                bs.joint(role).map(|s| MapPair {
                    source: s,
                    target: t,
                    role: Some(role),
                })
            })
            .collect();
        if pairs.len() >= 5 {
            pairs.sort_by_key(|p| p.target);
            return Ok(JointMap {
                pairs,
                pelvis: (bs.pelvis, bt.pelvis),
                how: format!(
                    "by body structure: source {} -> target {}",
                    evidence(source, &bs, source_up),
                    evidence(target, &bt, target_up)
                ),
            });
        }
    }
    let (Some((sc, sj)), Some((tc, tj))) = (
        best_convention(source, source_up),
        best_convention(target, target_up),
    ) else {
        return Err(RetargetError::NoMap);
    };
    let mut pairs: Vec<MapPair> = Vec::new();
    for &(role, t) in &tj {
        if let Some(&(_, s)) = sj.iter().find(|(r, _)| *r == role) {
            pairs.push(MapPair {
                source: s,
                target: t,
                role: Some(role),
            });
        }
    }
    pairs.sort_by_key(|p| p.target);
    let source_pelvis = find_bare(source, sc.pelvis);
    let target_pelvis = find_bare(target, tc.pelvis);
    let roles = pairs.iter().filter(|p| p.role.is_some()).count();
    match (source_pelvis, target_pelvis) {
        (Some(s), Some(t)) if roles >= 5 => Ok(JointMap {
            pairs,
            pelvis: (s, t),
            how: format!("by names: {} -> {}", sc.label, tc.label),
        }),
        _ => Err(RetargetError::NoMap),
    }
}

/// What a body was read from, for [`JointMap::how`]: the pose, how the sides were told,
/// and how far the best naming convention agrees (`"(rest pose, sides by geometry;
/// cgspeed BVH names agree on 23 of 23 roles)"`).
fn evidence(skeleton: &Skeleton, body: &Body, up: Vec3) -> String {
    let names = match best_convention(skeleton, up) {
        Some((c, found)) => {
            let agree = found
                .iter()
                .filter(|(r, j)| body.joint(r) == Some(*j))
                .count();
            format!(
                "{} names agree on {agree} of {} roles",
                c.label,
                body.roles.len()
            )
        }
        None => "no known names".to_string(),
    };
    format!("({}, sides by {}; {names})", body.pose, body.sides)
}

/// Number of ancestors of `j`.
pub(crate) fn depth(skeleton: &Skeleton, j: JointIndex) -> usize {
    let mut d = 0;
    let mut cur = skeleton.joint(j).parent;
    while let Some(p) = cur {
        d += 1;
        cur = skeleton.joint(p).parent;
    }
    d
}

/// The body roles of `skeleton`'s joints under the built-in convention that names the most
/// of them (empty when none names 5), for skeletons whose structure shows no body. `up` is
/// the model-space up direction.
pub fn roles_of(skeleton: &Skeleton, up: Vec3) -> Vec<(&'static str, JointIndex)> {
    best_convention(skeleton, up)
        .map(|b| b.1)
        .unwrap_or_default()
}

impl JointMap {
    /// A map from `(source, target)` pairs (a map file's): the pelvis is `pelvis`, or the
    /// mapped source joint nearest its root with its first target. `None` without pairs.
    pub fn from_pairs(
        source: &Skeleton,
        pairs: &[(JointIndex, JointIndex)],
        pelvis: Option<(JointIndex, JointIndex)>,
        how: &str,
    ) -> Option<Self> {
        let pelvis = pelvis.or_else(|| {
            pairs
                .iter()
                .filter(|(s, _)| s.get() < source.len())
                .min_by_key(|(s, _)| depth(source, *s))
                .copied()
        })?;
        let mut pairs: Vec<MapPair> = pairs
            .iter()
            .map(|&(source, target)| MapPair {
                source,
                target,
                role: None,
            })
            .collect();
        pairs.sort_by_key(|p| p.target);
        Some(Self {
            pairs,
            pelvis,
            how: how.to_string(),
        })
    }
}
