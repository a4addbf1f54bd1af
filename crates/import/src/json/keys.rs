//! `KEYS.json`: keyframed whole poses (`rigport animate`).
//!
//! ```json
//! {"name": "wave", "fps": 30, "keys": [
//!   {"frame": 0, "pose": {}},
//!   {"frame": 15, "pose": {"hand_l": {"euler_deg": [0, 0, 40]}}, "translation": [0, -0.02, 0]}
//! ]}
//! ```
//! Each key gives `time` (seconds) or `frame` (with the top-level `fps`), a pose as in
//! [`super::pose`] (unlisted joints at rest) and optionally a translation of the first root.

/// The KEYS.json format as a user writes it (the CLI's `animate` help shows it).
pub const FORMAT: &str = "KEYS.json:\n  \
    {\"name\": \"wave\", \"fps\": 30, \"keys\": [\n    \
    {\"time\": 0.0, \"pose\": {}},\n    \
    {\"time\": 0.5, \"pose\": {\"bone_5\": {\"euler_deg\": [0, 0, 45], \"order\": \"xyz\"}}, \"translation\": [0, 0.1, 0]},\n    \
    {\"frame\": 30, \"pose\": {\"bone_5\": {\"quat\": [0, 0, 0, 1]}}}]}\n\
    Each key is a whole pose: joints it does not list are at rest. Pose entries are those of a \
    POSE.json. \"time\" is in seconds; \"frame\" needs \"fps\". \"translation\" moves \
    the root from its rest position (root motion, the rig's length unit). Between keys, \
    rotations are slerped and translations lerped (glTF LINEAR).";

use std::path::Path;

use rigport_model::glam::Vec3;
use rigport_model::{PoseKey, PoseKeys, Skeleton};
use serde::Deserialize;

use super::{JsonError, JsonProblem};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct KeysFile {
    name: Option<String>,
    fps: Option<f32>,
    keys: Vec<Key>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Key {
    time: Option<f32>,
    frame: Option<f32>,
    #[serde(default)]
    pose: serde_json::Map<String, serde_json::Value>,
    translation: Option<[f32; 3]>,
}

/// Reads a keys file for `skeleton`; the keys come back sorted by time.
///
/// # Errors
/// Unreadable file, JSON syntax (line and column), no keys, a bad `fps`, a key with neither
/// or both of `time`/`frame`, `frame` without `fps`, negative, non-finite or repeated
/// times, a non-finite translation, pose errors as in [`super::pose::read`].
pub fn read(path: &Path, skeleton: &Skeleton) -> Result<PoseKeys, JsonError> {
    let file: KeysFile = super::read(path)?;
    if file.keys.is_empty() {
        return Err(JsonError::at(path, "/keys", JsonProblem::Empty("keys")));
    }
    if let Some(fps) = file.fps {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(JsonError::at(path, "/fps", JsonProblem::BadFps(fps)));
        }
    }
    let mut keys = Vec::with_capacity(file.keys.len());
    for (k, key) in file.keys.into_iter().enumerate() {
        let at = format!("/keys/{k}");
        let time = match (key.time, key.frame, file.fps) {
            (Some(t), None, _) => t,
            (None, Some(f), Some(fps)) => f / fps,
            (None, Some(_), None) => {
                return Err(JsonError::at(path, at, JsonProblem::FrameNeedsFps))
            }
            _ => return Err(JsonError::at(path, at, JsonProblem::TimeChoice)),
        };
        if !(time.is_finite() && time >= 0.0) {
            return Err(JsonError::at(path, at, JsonProblem::BadTime(time)));
        }
        let rotations = super::pose::entries_of(key.pose, skeleton, path, &format!("{at}/pose"))?;
        let translation = match key.translation {
            Some(t) if t.iter().any(|v| !v.is_finite()) => {
                return Err(JsonError::at(
                    path,
                    format!("{at}/translation"),
                    JsonProblem::NotFinite(t.to_vec()),
                ))
            }
            t => t.map(Vec3::from),
        };
        keys.push(PoseKey {
            time,
            index: k,
            rotations,
            translation,
        });
    }
    keys.sort_by(|a, b| a.time.total_cmp(&b.time));
    for pair in keys.windows(2) {
        if pair[0].time == pair[1].time {
            return Err(JsonError::at(
                path,
                "/keys",
                JsonProblem::SameTime {
                    first: pair[0].index,
                    second: pair[1].index,
                    time: pair[0].time,
                },
            ));
        }
    }
    Ok(PoseKeys {
        name: file.name,
        keys,
    })
}
