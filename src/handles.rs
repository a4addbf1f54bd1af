//! `HANDLES.json`: IK handle tracks (`rigport ik`).

use std::path::Path;

use anyhow::{bail, Context, Result};
use rigport_model::glam::Vec3;
use rigport_model::{JointIndex, Skeleton};
use serde::Deserialize;

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

/// One handle: the joint, the effector point in the joint's frame, and its target track.
#[derive(Clone, Debug)]
pub struct HandleTrack {
    /// The driven joint.
    pub joint: JointIndex,
    /// Its name.
    pub name: String,
    /// The effector point in the joint's local frame (zero: the joint's origin).
    pub offset: Vec3,
    /// Weight in the solve.
    pub weight: f32,
    /// Whether positions are offsets from the effector's rest position.
    pub relative: bool,
    /// Key times in seconds, strictly increasing.
    pub times: Vec<f32>,
    /// Target positions (model space, or offsets when `relative`).
    pub positions: Vec<Vec3>,
}

impl HandleTrack {
    /// The target at time `t`: linear between keys, held before the first and after the last.
    pub fn at(&self, t: f32) -> Vec3 {
        let n = self.times.len();
        if n == 1 || t <= self.times[0] {
            return self.positions[0];
        }
        if t >= self.times[n - 1] {
            return self.positions[n - 1];
        }
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let u = (t - self.times[k]) / (self.times[k + 1] - self.times[k]);
        self.positions[k].lerp(self.positions[k + 1], u)
    }
}

impl HandleTrack {
    /// The model-space target at time `t`: [`HandleTrack::at`], plus `rest_effector` (the
    /// effector's model-space rest position, see [`rest_effectors`]) when the track is
    /// `relative`.
    pub fn target_at(&self, t: f32, rest_effector: Vec3) -> Vec3 {
        let p = self.at(t);
        if self.relative {
            rest_effector + p
        } else {
            p
        }
    }
}

/// Model-space rest position of each track's effector point (the joint's rest matrix
/// applied to its offset), in track order: what `relative` positions are offsets from.
pub fn rest_effectors(skeleton: &Skeleton, tracks: &[HandleTrack]) -> Vec<Vec3> {
    let rest = skeleton.model_rest_matrices();
    tracks
        .iter()
        .map(|t| {
            rest.get(t.joint.get())
                .map_or(Vec3::NAN, |m| m.transform_point3(t.offset))
        })
        .collect()
}

/// The model-space targets of a handles file over time, as `rigport ik` solves for them:
/// drawn as markers by `rigport render --handles` and the demo's reach picture.
pub struct Targets {
    tracks: Vec<HandleTrack>,
    rest_effectors: Vec<Vec3>,
}

impl Targets {
    /// The targets of `tracks` (loaded for `skeleton`).
    pub fn new(skeleton: &Skeleton, tracks: Vec<HandleTrack>) -> Self {
        let rest_effectors = rest_effectors(skeleton, &tracks);
        Self {
            tracks,
            rest_effectors,
        }
    }
}

impl rigport_render::Markers for Targets {
    fn markers_at(&self, time: f32, out: &mut Vec<Vec3>) {
        out.extend(
            self.tracks
                .iter()
                .zip(&self.rest_effectors)
                .map(|(t, &rest)| t.target_at(time, rest)),
        );
    }
}

/// The handles of a file, and its frame rate if it gives one.
pub struct Handles {
    /// Frames per second the file asks for.
    pub fps: Option<f32>,
    /// The handle tracks, in file order.
    pub tracks: Vec<HandleTrack>,
}

/// Reads a handles file for `skeleton`.
///
/// # Errors
/// Unreadable file, JSON syntax (line and column; JSON has no NaN, so a NaN target is a
/// syntax error), an unknown joint, no handles or no keys, times not strictly increasing
/// or negative, non-finite values, a non-positive weight or fps, a joint given twice.
pub fn load(path: &Path, skeleton: &Skeleton) -> Result<Handles> {
    let label = path.display().to_string();
    let text = std::fs::read_to_string(path).with_context(|| format!("{label}: cannot read"))?;
    let file: HandlesFile = serde_json::from_str(&text)
        .map_err(|e| anyhow::anyhow!("{label}:{}:{}: {e}", e.line(), e.column()))?;
    if let Some(fps) = file.fps {
        if !(fps.is_finite() && fps > 0.0) {
            bail!("{label}: at /fps: {fps} is not a positive frame rate");
        }
    }
    if file.handles.is_empty() {
        bail!("{label}: at /handles: no handles");
    }
    let mut tracks: Vec<HandleTrack> = Vec::with_capacity(file.handles.len());
    for (h, entry) in file.handles.into_iter().enumerate() {
        let at = format!("{label}: at /handles/{h}");
        let joint = skeleton
            .find(&entry.joint)
            .with_context(|| format!("{at}/joint: the rig has no joint named {:?}", entry.joint))?;
        if tracks.iter().any(|t| t.joint == joint) {
            bail!("{at}/joint: {:?} has a handle already", entry.joint);
        }
        if entry.keys.is_empty() {
            bail!("{at}/keys: no keys");
        }
        let offset = Vec3::from(entry.offset.unwrap_or_default());
        if !offset.is_finite() {
            bail!("{at}/offset: not finite");
        }
        let weight = entry.weight.unwrap_or(1.0);
        if !(weight.is_finite() && weight > 0.0) {
            bail!("{at}/weight: {weight} must be > 0");
        }
        let mut times = Vec::with_capacity(entry.keys.len());
        let mut positions = Vec::with_capacity(entry.keys.len());
        for (k, key) in entry.keys.iter().enumerate() {
            let p = Vec3::from(key.position);
            if !(key.time.is_finite() && key.time >= 0.0) {
                bail!(
                    "{at}/keys/{k}/time: {} must be a finite number of seconds >= 0",
                    key.time
                );
            }
            if !p.is_finite() {
                bail!("{at}/keys/{k}/position: {:?} is not finite", key.position);
            }
            if times.last().is_some_and(|&last| key.time <= last) {
                bail!(
                    "{at}/keys/{k}/time: {} s does not come after the previous key",
                    key.time
                );
            }
            times.push(key.time);
            positions.push(p);
        }
        tracks.push(HandleTrack {
            joint,
            name: entry.joint,
            offset,
            weight,
            relative: entry.relative,
            times,
            positions,
        });
    }
    Ok(Handles {
        fps: file.fps,
        tracks,
    })
}
