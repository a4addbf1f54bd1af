//! `HANDLES.json`: IK handle tracks (`rigport ik`, `rigport render --handles`).
//!
//! ```json
//! {"fps": 30, "handles": [
//!   {"joint": "fingertip_l", "relative": true, "offset": [0.16, 0, 0], "weight": 1,
//!    "keys": [{"time": 0, "position": [0, 0, 0]}, {"time": 1, "position": [-0.35, 0.15, 0.35]}]}
//! ]}
//! ```
//!
//! Chain-aware fields (all optional; a file without them solves as before):
//! - per handle: `"root"` (the topmost joint the solve may rotate: an ancestor of `joint`),
//!   `"pin": true` (no keys: the effector stays where the input puts it at the first frame;
//!   with `"orient": true` its rotation too), `"solver": "two_bone"` (analytic; `joint` is the
//!   tip, its parent the mid joint, its grandparent the root, which `"root"` may only
//!   repeat), `"pole": [x, y, z]` (two-bone pole target, model space or relative like the
//!   keys; also allowed per key), `"twist_deg"`, `"soften"` (0-1); `"weight"` of a two-bone
//!   handle is the 0-1 blend of its solve over the input pose;
//! - per key: `"rotation": [x, y, z, w]`, the joint's model-space rotation target;
//! - top level: `"base": "<clip>"` (IK layered over that input clip), `"root_motion":
//!   "locked" | "free"`, `"limits": {"<joint>": {"x": [min_deg, max_deg], "y": ..., "z":
//!   ..., "order": "xyz"}}` (Euler angles of the joint's rotation relative to its rest
//!   rotation; an axis not given is free).

/// The HANDLES.json format as a user writes it (the CLI's `ik` help shows it).
pub const FORMAT: &str = "HANDLES.json:\n  \
    {\"fps\": 30, \"handles\": [{\"joint\": \"bone_12\", \"relative\": false, \"offset\": [0, 0.1, 0], \"weight\": 1,\n    \
    \"keys\": [{\"time\": 0, \"position\": [x, y, z]}, {\"time\": 2, \"position\": [x, y, z]}]}]}\n\
    Targets are model-space positions in the rig's length unit (\"relative\": offsets from the \
    effector's rest position), linear between keys. \"offset\" (optional) is the effector point \
    in the joint's frame, e.g. a bone's tip. Every ancestor of a handle may rotate; each frame \
    starts from the previous frame's solution.\n\
    Chain-aware fields (any of them: only the handles' chains move, each frame starts from the \
    input pose, the root is locked unless \"root_motion\": \"free\"): per handle \"root\", \
    \"pin\": true (no keys; \"orient\": true keeps the rotation too), \"solver\": \"two_bone\" \
    with \"pole\" [x,y,z] (also per key), \"twist_deg\", \"soften\" 0-1 and \"weight\" 0-1; per key \
    \"rotation\" [x,y,z,w] (model space); top level \"base\": \"<clip>\", \"root_motion\", \
    \"limits\": {\"joint\": {\"x\": [min_deg, max_deg], \"order\": \"xyz\"}} (rest frame; ASF \
    dof/limits apply too). Limits are clamps of Euler angles relative to rest.";

use std::collections::BTreeMap;
use std::path::Path;

use rigport_model::conventions::EulerOrder;
use rigport_model::glam::{Quat, Vec3};
use rigport_model::{
    find_clip, Clip, HandleSet, HandleSolver, HandleTrack, JointIndex, RootMotion, RotationLimit,
    Skeleton,
};
use serde::Deserialize;

use super::{token, JsonError, JsonProblem};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HandlesFile {
    fps: Option<f32>,
    handles: Vec<HandleEntry>,
    base: Option<String>,
    root_motion: Option<String>,
    #[serde(default)]
    limits: BTreeMap<String, LimitEntry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HandleEntry {
    joint: String,
    #[serde(default)]
    relative: bool,
    offset: Option<[f32; 3]>,
    weight: Option<f32>,
    keys: Option<Vec<KeyEntry>>,
    root: Option<String>,
    #[serde(default)]
    pin: bool,
    #[serde(default)]
    orient: bool,
    pole: Option<[f32; 3]>,
    twist_deg: Option<f32>,
    solver: Option<String>,
    soften: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyEntry {
    time: f32,
    position: [f32; 3],
    rotation: Option<[f32; 4]>,
    pole: Option<[f32; 3]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LimitEntry {
    x: Option<[f32; 2]>,
    y: Option<[f32; 2]>,
    z: Option<[f32; 2]>,
    order: Option<String>,
}

/// Reads a handles file for `skeleton`.
///
/// # Errors
/// Unreadable file, JSON syntax (line and column; JSON has no NaN, so a NaN target is a
/// syntax error), an unknown joint (handle, `root`, `limits`), no handles or no keys (keys
/// on a pin), times not strictly increasing or negative, non-finite values, a non-positive
/// weight or fps, a joint given twice, a `root` that is not an ancestor, a two-bone handle
/// without two ancestors (or with another `root`), a pole on a handle that is not two-bone
/// or at the chain's root, `orient` without `pin`, a zero quaternion, `soften` or a
/// two-bone `weight` outside 0-1, an unknown `solver` or `root_motion`, limits that are not
/// finite, beyond ±180° or with min > max.
pub fn read(path: &Path, skeleton: &Skeleton) -> Result<HandleSet, JsonError> {
    let file: HandlesFile = super::read(path)?;
    if let Some(fps) = file.fps {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(JsonError::at(path, "/fps", JsonProblem::BadFps(fps)));
        }
    }
    if file.handles.is_empty() {
        return Err(JsonError::at(
            path,
            "/handles",
            JsonProblem::Empty("handles"),
        ));
    }
    let root_motion = match file.root_motion.as_deref() {
        None => None,
        Some("locked") => Some(RootMotion::Locked),
        Some("free") => Some(RootMotion::Free),
        Some(other) => {
            return Err(JsonError::at(
                path,
                "/root_motion",
                JsonProblem::UnknownWord {
                    found: other.into(),
                    expected: "\"locked\" or \"free\"",
                },
            ))
        }
    };
    let rest = skeleton.model_rest_matrices();
    let parent = |j: JointIndex| skeleton.joints().get(j.get()).and_then(|x| x.parent);
    let mut tracks: Vec<HandleTrack> = Vec::with_capacity(file.handles.len());
    for (h, entry) in file.handles.into_iter().enumerate() {
        let err =
            |field: &str, problem| JsonError::at(path, format!("/handles/{h}{field}"), problem);
        let Some(joint) = skeleton.find(&entry.joint) else {
            return Err(err("/joint", JsonProblem::UnknownJoint(entry.joint)));
        };
        if tracks.iter().any(|t| t.joint == joint) {
            return Err(err("/joint", JsonProblem::DuplicateHandle(entry.joint)));
        }
        let solver = match entry.solver.as_deref() {
            None | Some("iterative") => HandleSolver::Iterative,
            Some("two_bone") => HandleSolver::TwoBone,
            Some(other) => {
                return Err(err(
                    "/solver",
                    JsonProblem::UnknownWord {
                        found: other.into(),
                        expected: "\"two_bone\" or \"iterative\"",
                    },
                ))
            }
        };
        let root = match &entry.root {
            None => None,
            Some(name) => {
                let Some(r) = skeleton.find(name) else {
                    return Err(err("/root", JsonProblem::UnknownJoint(name.clone())));
                };
                let is_ancestor =
                    std::iter::successors(parent(joint), |&p| parent(p)).any(|a| a == r);
                if !is_ancestor {
                    return Err(err(
                        "/root",
                        JsonProblem::NotAncestor {
                            root: name.clone(),
                            joint: entry.joint.clone(),
                        },
                    ));
                }
                Some(r)
            }
        };
        // The joint the chain hangs from: the pole must not sit on it.
        let chain_root = if solver == HandleSolver::TwoBone {
            let grand = parent(joint).and_then(parent);
            let Some(grand) = grand else {
                return Err(err(
                    "/solver",
                    JsonProblem::TwoBoneChain(format!(
                        "{:?} needs a parent and a grandparent",
                        entry.joint
                    )),
                ));
            };
            if root.is_some_and(|r| r != grand) {
                return Err(err(
                    "/root",
                    JsonProblem::TwoBoneChain(format!(
                        "a two-bone chain's root is the grandparent of {:?}, {:?}",
                        entry.joint,
                        skeleton.joint(grand).name
                    )),
                ));
            }
            Some(grand)
        } else {
            root
        };
        if entry.orient && !entry.pin {
            return Err(err(
                "/orient",
                JsonProblem::Needs("\"orient\"", "\"pin\": true"),
            ));
        }
        let two_bone_only = |field: &str, given: bool| {
            if given && solver != HandleSolver::TwoBone {
                Err(err(
                    &format!("/{field}"),
                    JsonProblem::Needs("this field", "\"solver\": \"two_bone\""),
                ))
            } else {
                Ok(())
            }
        };
        two_bone_only("pole", entry.pole.is_some())?;
        two_bone_only("twist_deg", entry.twist_deg.is_some())?;
        two_bone_only("soften", entry.soften.is_some())?;
        let twist_deg = entry.twist_deg.unwrap_or(0.0);
        if !twist_deg.is_finite() {
            return Err(err("/twist_deg", JsonProblem::NotFinite(vec![twist_deg])));
        }
        let soften = entry.soften.unwrap_or(0.0);
        if !(0.0..=1.0).contains(&soften) {
            return Err(err("/soften", JsonProblem::OutOfUnit(soften)));
        }
        let keys = entry.keys.unwrap_or_default();
        if entry.pin && !keys.is_empty() {
            return Err(err("/keys", JsonProblem::Needs("keys", "no \"pin\"")));
        }
        if !entry.pin && keys.is_empty() {
            return Err(err("/keys", JsonProblem::Empty("keys")));
        }
        let offset = entry.offset.unwrap_or_default();
        if offset.iter().any(|v| !v.is_finite()) {
            return Err(err("/offset", JsonProblem::NotFinite(offset.to_vec())));
        }
        let weight = entry.weight.unwrap_or(1.0);
        if !(weight.is_finite() && weight > 0.0) {
            return Err(err("/weight", JsonProblem::BadWeight(weight)));
        }
        if solver == HandleSolver::TwoBone && weight > 1.0 {
            return Err(err("/weight", JsonProblem::OutOfUnit(weight)));
        }
        let rest_effector = rest
            .get(joint.get())
            .map_or(Vec3::ZERO, |m| m.transform_point3(Vec3::from(offset)));
        let root_position = chain_root.and_then(|r| rest.get(r.get()).map(|m| m.w_axis.truncate()));
        // A pole target on the chain's root (at rest) defines no plane.
        let check_pole = |field: &str, pole: [f32; 3]| {
            if pole.iter().any(|v| !v.is_finite()) {
                return Err(err(field, JsonProblem::NotFinite(pole.to_vec())));
            }
            let at = if entry.relative {
                rest_effector + Vec3::from(pole)
            } else {
                Vec3::from(pole)
            };
            let scale = rest_effector.length().max(1.0);
            if root_position.is_some_and(|r| r.distance(at) <= 1e-6 * scale) {
                return Err(err(field, JsonProblem::PoleAtRoot));
            }
            Ok(Vec3::from(pole))
        };
        let handle_pole = entry.pole.map(|p| check_pole("/pole", p)).transpose()?;
        let mut times: Vec<f32> = Vec::with_capacity(keys.len());
        let mut positions = Vec::with_capacity(keys.len());
        let mut rotations = Vec::with_capacity(keys.len());
        let mut poles = Vec::with_capacity(keys.len());
        for (k, key) in keys.iter().enumerate() {
            if !(key.time.is_finite() && key.time >= 0.0) {
                return Err(err(
                    &format!("/keys/{k}/time"),
                    JsonProblem::BadTime(key.time),
                ));
            }
            if key.position.iter().any(|v| !v.is_finite()) {
                return Err(err(
                    &format!("/keys/{k}/position"),
                    JsonProblem::NotFinite(key.position.to_vec()),
                ));
            }
            if times.last().is_some_and(|&last| key.time <= last) {
                return Err(err(
                    &format!("/keys/{k}/time"),
                    JsonProblem::NotIncreasing(key.time),
                ));
            }
            let rotation = match key.rotation {
                None => None,
                Some(q) => {
                    let quat = Quat::from_array(q);
                    if !quat.is_finite() || quat.length_squared() < 1e-12 {
                        return Err(err(
                            &format!("/keys/{k}/rotation"),
                            JsonProblem::BadQuaternion(q),
                        ));
                    }
                    Some(quat.normalize())
                }
            };
            let pole = match key.pole {
                Some(p) => {
                    two_bone_only(&format!("keys/{k}/pole"), true)?;
                    Some(check_pole(&format!("/keys/{k}/pole"), p)?)
                }
                None => handle_pole,
            };
            poles.extend(pole);
            times.push(key.time);
            positions.push(Vec3::from(key.position));
            rotations.push(rotation);
        }
        if !poles.is_empty() && poles.len() != times.len() {
            return Err(err(
                "/keys",
                JsonProblem::Needs(
                    "\"pole\" on some keys",
                    "a pole on every key or on the handle",
                ),
            ));
        }
        if !rotations.iter().any(Option::is_some) {
            rotations.clear();
        }
        if entry.pin {
            if let Some(p) = handle_pole {
                poles.push(p);
            }
        }
        tracks.push(HandleTrack {
            joint,
            name: entry.joint,
            offset: Vec3::from(offset),
            weight,
            relative: entry.relative,
            times,
            positions,
            root,
            pin: entry.pin,
            orient: entry.orient,
            rotations,
            poles,
            twist_deg,
            solver,
            soften,
        });
    }
    let mut limits = Vec::with_capacity(file.limits.len());
    for (name, entry) in file.limits {
        let at = format!("/limits/{}", token(&name));
        let Some(joint) = skeleton.find(&name) else {
            return Err(JsonError::at(path, at, JsonProblem::UnknownJoint(name)));
        };
        let order = match entry.order.as_deref() {
            None => EulerOrder::Xyz,
            Some(o) => EulerOrder::parse(o).ok_or_else(|| {
                JsonError::at(
                    path,
                    format!("{at}/order"),
                    JsonProblem::UnknownOrder(o.into()),
                )
            })?,
        };
        let mut min = Vec3::splat(-180.0);
        let mut max = Vec3::splat(180.0);
        for (axis, pair) in [("x", entry.x), ("y", entry.y), ("z", entry.z)]
            .into_iter()
            .enumerate()
            .filter_map(|(i, (name, p))| p.map(|p| ((i, name), p)))
        {
            let (i, axis_name) = axis;
            let [lo, hi] = pair;
            if !(lo.is_finite() && hi.is_finite() && lo >= -180.0 && hi <= 180.0 && lo <= hi) {
                return Err(JsonError::at(
                    path,
                    format!("{at}/{axis_name}"),
                    JsonProblem::BadLimit(pair),
                ));
            }
            min[i] = lo;
            max[i] = hi;
        }
        limits.push(RotationLimit {
            joint,
            frame: Quat::IDENTITY,
            order,
            min_rad: min * std::f32::consts::PI / 180.0,
            max_rad: max * std::f32::consts::PI / 180.0,
        });
    }
    Ok(HandleSet {
        fps: file.fps,
        tracks,
        base: file.base,
        root_motion,
        limits,
    })
}

/// Checks that the file's `base` names one of `clips` (the input's).
///
/// # Errors
/// [`JsonProblem::UnknownClip`] at `/base`.
pub fn check_base(path: &Path, handles: &HandleSet, clips: &[Clip]) -> Result<(), JsonError> {
    match &handles.base {
        Some(base) => find_clip(clips, Some(base))
            .map(drop)
            .map_err(|e| JsonError::at(path, "/base", JsonProblem::UnknownClip(e))),
        None => Ok(()),
    }
}
