//! `HANDLES.json` targets over time (`rigport ik`, `rigport render --handles`).

use std::path::Path;

use anyhow::Result;
use rigport_model::glam::Vec3;
use rigport_model::{HandleSet, HandleTrack, Skeleton};

/// The target of `track` at time `t`: linear between keys, held before the first and
/// after the last.
pub fn at(track: &HandleTrack, t: f32) -> Vec3 {
    let n = track.times.len();
    if n == 1 || t <= track.times[0] {
        return track.positions[0];
    }
    if t >= track.times[n - 1] {
        return track.positions[n - 1];
    }
    let k = track.times.partition_point(|&x| x <= t) - 1;
    let u = (t - track.times[k]) / (track.times[k + 1] - track.times[k]);
    track.positions[k].lerp(track.positions[k + 1], u)
}

/// The model-space target at time `t`: [`at`], plus `rest_effector` (the effector's
/// model-space rest position, see [`rest_effectors`]) when the track is `relative`.
pub fn target_at(track: &HandleTrack, t: f32, rest_effector: Vec3) -> Vec3 {
    let p = at(track, t);
    if track.relative {
        rest_effector + p
    } else {
        p
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
                .map(|(t, &rest)| target_at(t, time, rest)),
        );
    }
}

/// Reads a handles file for `skeleton` (`rigport_import::json::handles::read`).
///
/// # Errors
/// The file's errors.
pub fn load(path: &Path, skeleton: &Skeleton) -> Result<HandleSet> {
    Ok(rigport_import::json::handles::read(path, skeleton)?)
}
