//! `KEYS.json`: keyframed poses that become a clip (`rigport animate`).

use std::path::Path;

use anyhow::{bail, Context, Result};
use rigport_eval::sample::{bake, ChannelMask};
use rigport_eval::Pose;
use rigport_model::glam::Vec3;
use rigport_model::{Clip, Skeleton, Transform};
use serde::Deserialize;

use crate::pose;

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

/// Reads a keys file into a clip for `skeleton`: one LINEAR key per entry (whole poses:
/// unlisted joints at rest), rotation tracks for every joint any key rotates, a translation
/// track on the first root when any key moves it. `default_name` names the clip when the
/// file does not.
///
/// # Errors
/// Unreadable file, JSON syntax (line and column), a key with neither or both of
/// `time`/`frame`, `frame` without `fps`, negative, non-finite or repeated times, pose
/// errors as in `eval --pose`, no keys.
pub fn load(path: &Path, skeleton: &Skeleton, default_name: &str) -> Result<Clip> {
    let file_label = path.display().to_string();
    let text =
        std::fs::read_to_string(path).with_context(|| format!("{file_label}: cannot read"))?;
    let file: KeysFile = serde_json::from_str(&text)
        .map_err(|e| anyhow::anyhow!("{file_label}:{}:{}: {e}", e.line(), e.column()))?;
    if file.keys.is_empty() {
        bail!("{file_label}: at /keys: no keys");
    }
    if let Some(fps) = file.fps {
        if !(fps.is_finite() && fps > 0.0) {
            bail!("{file_label}: at /fps: {fps} is not a positive frame rate");
        }
    }
    let root = skeleton
        .roots()
        .next()
        .context("the skeleton has no joints")?;
    let mut keyed: Vec<(f32, usize, Pose)> = Vec::with_capacity(file.keys.len());
    let mut rotated = vec![false; skeleton.len()];
    let mut moved = false;
    for (k, key) in file.keys.into_iter().enumerate() {
        let at = format!("{file_label}: at /keys/{k}");
        let time = match (key.time, key.frame, file.fps) {
            (Some(t), None, _) => t,
            (None, Some(f), Some(fps)) => f / fps,
            (None, Some(_), None) => bail!("{at}: \"frame\" needs \"fps\" at the top level"),
            _ => bail!("{at}: give exactly one of \"time\" (seconds) or \"frame\""),
        };
        if !(time.is_finite() && time >= 0.0) {
            bail!("{at}: time {time} must be a finite number of seconds >= 0");
        }
        for joint in key.pose.keys() {
            if let Some(j) = skeleton.find(joint) {
                rotated[j.get()] = true;
            }
        }
        let mut pose = pose::from_entries(key.pose, skeleton, &format!("{at}/pose"))?;
        if let Some(t) = key.translation {
            if t.iter().any(|v| !v.is_finite()) {
                bail!("{at}/translation: {t:?} is not finite");
            }
            moved = true;
            pose.local[root.get()].translation += Vec3::from(t);
        }
        keyed.push((time, k, pose));
    }
    keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
    for pair in keyed.windows(2) {
        if pair[0].0 == pair[1].0 {
            bail!(
                "{file_label}: keys {} and {} are both at {} s",
                pair[0].1,
                pair[1].1,
                pair[0].0
            );
        }
    }
    let times: Vec<f32> = keyed.iter().map(|k| k.0).collect();
    let frames: Vec<Transform> = keyed
        .iter()
        .flat_map(|k| k.2.local.iter().copied())
        .collect();
    let mut mask = ChannelMask {
        translation: vec![false; skeleton.len()],
        rotation: rotated,
        scale: vec![false; skeleton.len()],
    };
    mask.translation[root.get()] = moved;
    if !mask.rotation.iter().any(|r| *r) && !moved {
        // A clip of rest poses still needs a track to exist and last as long as its keys.
        mask.rotation[root.get()] = true;
    }
    let name = file.name.unwrap_or_else(|| default_name.to_string());
    bake(&name, &times, &frames, &mask).with_context(|| format!("{file_label}: cannot bake"))
}
