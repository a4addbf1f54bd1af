//! `HANDLES.json`: IK handle tracks (`rigport ik`, `rigport render --handles`).
//!
//! ```json
//! {"fps": 30, "handles": [
//!   {"joint": "fingertip_l", "relative": true, "offset": [0.16, 0, 0], "weight": 1,
//!    "keys": [{"time": 0, "position": [0, 0, 0]}, {"time": 1, "position": [-0.35, 0.15, 0.35]}]}
//! ]}
//! ```

use std::path::Path;

use rigport_model::glam::Vec3;
use rigport_model::{HandleSet, HandleTrack, Skeleton};
use serde::Deserialize;

use super::{JsonError, JsonProblem};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HandlesFile {
    fps: Option<f32>,
    handles: Vec<HandleEntry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HandleEntry {
    joint: String,
    #[serde(default)]
    relative: bool,
    offset: Option<[f32; 3]>,
    weight: Option<f32>,
    keys: Vec<KeyEntry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyEntry {
    time: f32,
    position: [f32; 3],
}

/// Reads a handles file for `skeleton`.
///
/// # Errors
/// Unreadable file, JSON syntax (line and column; JSON has no NaN, so a NaN target is a
/// syntax error), an unknown joint, no handles or no keys, times not strictly increasing
/// or negative, non-finite values, a non-positive weight or fps, a joint given twice.
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
        if entry.keys.is_empty() {
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
        let mut times: Vec<f32> = Vec::with_capacity(entry.keys.len());
        let mut positions = Vec::with_capacity(entry.keys.len());
        for (k, key) in entry.keys.iter().enumerate() {
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
            times.push(key.time);
            positions.push(Vec3::from(key.position));
        }
        tracks.push(HandleTrack {
            joint,
            name: entry.joint,
            offset: Vec3::from(offset),
            weight,
            relative: entry.relative,
            times,
            positions,
        });
    }
    Ok(HandleSet {
        fps: file.fps,
        tracks,
    })
}
