//! Clips: each `<animation_clip>` of `<library_animation_clips>` (its `start`/`end` and
//! the `<instance_animation>`s it plays) as a named clip; without any, the whole timeline
//! as one clip named after the file.
//!
//! A node's channels change values inside its transform elements, so its local matrix is
//! evaluated (elements composed again, then split into translation, rotation and scale)
//! at the union of its channels' key times within the clip, plus the clip's start and end.
//! Between two of those times every `LINEAR` channel moves linearly; where a `<rotate>`
//! angle moves more than 90 degrees, samples are added so no step turns more than that
//! (slerp between them then follows the angle exactly for one moving axis: the full turns
//! between keys are kept); where a channel is `BEZIER` or `HERMITE`, samples are added at
//! 30 per second. Nodes whose channels are all `STEP` get step tracks. Times start at 0 at
//! the clip's start (for the whole timeline: at 0, or at the first key if it is earlier).

use std::collections::{BTreeMap, HashSet};

use rigport_model::glam::{DMat4, Quat};
use rigport_model::{Clip, Interpolation, MeshIndex, Track, TrackTarget, Transform};

use super::anim::{Channel, Interp, Target};
use super::scene::Scene;
use super::skeleton::Skel;
use super::transform::{self, Kind};
use super::xml::{child, children, Doc, Node};
use crate::names::unique;
use crate::ImportError;

/// Samples added per second over `BEZIER`/`HERMITE` segments.
const CURVE_RATE: f64 = 30.0;
/// The largest `<rotate>` angle step between samples, in degrees.
const MAX_ANGLE_STEP_DEG: f64 = 90.0;
/// At most this many samples per key interval (a bound for absurd time spans).
const MAX_SUBDIVISIONS: usize = 4096;

/// A morph controller's meshes and their default weights.
pub(super) struct MorphUse {
    pub(super) controller: String,
    pub(super) mesh: MeshIndex,
    pub(super) defaults: Vec<f32>,
}

/// One clip's time window and the `<animation>`s it plays (`None`: every channel).
struct Window<'a, 'i> {
    name: String,
    start: f64,
    end: Option<f64>,
    animations: Option<Vec<Node<'a, 'i>>>,
}

/// Every clip (see the module doc).
///
/// # Errors
/// An `<instance_animation>` naming no element.
pub(super) fn build(
    doc: &Doc,
    scene: &Scene,
    channels: &[Channel],
    skel: &Skel,
    morphs: &[MorphUse],
    file_name: &str,
) -> Result<Vec<Clip>, ImportError> {
    if channels.is_empty() {
        return Ok(Vec::new());
    }
    let mut windows = Vec::new();
    if let Some(library) = child(doc.root(), "library_animation_clips") {
        for clip in children(library, "animation_clip") {
            let num = |a: &str| clip.attribute(a).and_then(|v| v.trim().parse::<f64>().ok());
            let name = clip
                .attribute("name")
                .or(clip.attribute("id"))
                .unwrap_or("")
                .to_string();
            windows.push(Window {
                name,
                start: num("start").filter(|s| s.is_finite()).unwrap_or(0.0),
                end: num("end").filter(|e| e.is_finite()),
                animations: Some(
                    children(clip, "instance_animation")
                        .map(|i| doc.link(i, "url", "animation"))
                        .collect::<Result<_, _>>()?,
                ),
            });
        }
    }
    if windows.is_empty() {
        let first = channels
            .iter()
            .filter_map(|c| c.sampler.times.first().copied())
            .fold(0.0, f64::min);
        windows.push(Window {
            name: file_name.to_string(),
            start: first,
            end: None,
            animations: None,
        });
    }
    let mut used = HashSet::new();
    Ok(windows
        .iter()
        .map(|w| {
            let chosen: Vec<&Channel> = channels
                .iter()
                .filter(|c| match &w.animations {
                    None => true,
                    Some(list) => c.animations.iter().any(|a| list.contains(a)),
                })
                .collect();
            Clip {
                name: unique(&w.name, "clip", &mut used),
                tracks: tracks(scene, &chosen, skel, morphs, w),
            }
        })
        .collect())
}

fn tracks(
    scene: &Scene,
    chosen: &[&Channel],
    skel: &Skel,
    morphs: &[MorphUse],
    w: &Window,
) -> Vec<Track> {
    let mut by_node: BTreeMap<usize, Vec<&Channel>> = BTreeMap::new();
    let mut by_morph: BTreeMap<&str, Vec<&Channel>> = BTreeMap::new();
    for c in chosen {
        match &c.target {
            Target::Transform { node, .. } => by_node.entry(*node).or_default().push(c),
            Target::Morph { controller, .. } => {
                by_morph.entry(controller.as_str()).or_default().push(c);
            }
        }
    }
    let mut out = Vec::new();
    let mut buf = Vec::new();
    for (node, chans) in by_node {
        let Some(joint) = skel.joint_of[node] else {
            continue;
        };
        let grid = grid(scene, &chans, w);
        let mut elements = scene.nodes[node].transforms.clone();
        let mut trs: Vec<Transform> = Vec::with_capacity(grid.len());
        for &t in &grid {
            for c in &chans {
                let Target::Transform {
                    element, component, ..
                } = c.target
                else {
                    continue;
                };
                c.sampler.sample(t, &mut buf);
                let values = &mut elements[element].values;
                match component {
                    Some(k) => {
                        if let (Some(v), Some(x)) = (values.get_mut(k), buf.first()) {
                            *v = *x;
                        }
                    }
                    None => values.clone_from(&buf),
                }
            }
            let m: DMat4 = transform::compose(&elements);
            trs.push(Transform::from_mat4(&m.as_mat4()));
        }
        let step = chans
            .iter()
            .all(|c| c.sampler.interp.iter().all(|&i| i == Interp::Step));
        let interpolation = if step {
            Interpolation::Step
        } else {
            Interpolation::Linear
        };
        let times: Vec<f32> = grid.iter().map(|t| (t - w.start) as f32).collect();
        let (times, keep) = increasing(&times);
        let kept = || keep.iter().map(|&k| &trs[k]);
        let mut previous: Option<Quat> = None;
        let rotations = kept().flat_map(|t| {
            let mut q = t.rotation;
            if previous.is_some_and(|p| p.dot(q) < 0.0) {
                q = -q;
            }
            previous = Some(q);
            q.to_array()
        });
        let rotations: Vec<f32> = rotations.collect();
        let track = |target, values| Track {
            target,
            interpolation,
            times: times.clone(),
            values,
        };
        out.push(track(
            TrackTarget::Translation(joint),
            kept().flat_map(|t| t.translation.to_array()).collect(),
        ));
        out.push(track(TrackTarget::Rotation(joint), rotations));
        out.push(track(
            TrackTarget::Scale(joint),
            kept().flat_map(|t| t.scale.to_array()).collect(),
        ));
    }
    for (controller, chans) in by_morph {
        let grid = grid(scene, &chans, w);
        for m in morphs.iter().filter(|m| m.controller == controller) {
            let mut values = Vec::with_capacity(grid.len() * m.defaults.len());
            for &t in &grid {
                let mut weights = m.defaults.clone();
                for c in &chans {
                    let Target::Morph { index, .. } = c.target else {
                        continue;
                    };
                    c.sampler.sample(t, &mut buf);
                    match index {
                        Some(k) => {
                            if let (Some(v), Some(x)) = (weights.get_mut(k), buf.first()) {
                                *v = *x as f32;
                            }
                        }
                        None => {
                            for (v, x) in weights.iter_mut().zip(&buf) {
                                *v = *x as f32;
                            }
                        }
                    }
                }
                values.push(weights);
            }
            let times: Vec<f32> = grid.iter().map(|t| (t - w.start) as f32).collect();
            let (times, keep) = increasing(&times);
            out.push(Track {
                target: TrackTarget::MorphWeights(m.mesh),
                interpolation: Interpolation::Linear,
                times,
                values: keep
                    .iter()
                    .flat_map(|&k| values[k].iter().copied())
                    .collect(),
            });
        }
    }
    out.retain(|t| !t.times.is_empty());
    out
}

/// Times that are `>= 0` and strictly increasing in `f32`, and the indices kept.
fn increasing(times: &[f32]) -> (Vec<f32>, Vec<usize>) {
    let mut out: Vec<f32> = Vec::with_capacity(times.len());
    let mut keep = Vec::with_capacity(times.len());
    for (k, &t) in times.iter().enumerate() {
        if t < 0.0 || !t.is_finite() || out.last().is_some_and(|&last| t <= last) {
            continue;
        }
        out.push(t);
        keep.push(k);
    }
    (out, keep)
}

/// The sample times of `chans` within the window (see the module doc).
fn grid(scene: &Scene, chans: &[&Channel], w: &Window) -> Vec<f64> {
    let mut keys: Vec<f64> = chans
        .iter()
        .flat_map(|c| c.sampler.times.iter().copied())
        .collect();
    let last = keys.iter().copied().fold(f64::MIN, f64::max);
    let end = w.end.unwrap_or(last);
    if w.animations.is_some() {
        keys.push(w.start);
        keys.push(end);
    }
    keys.retain(|&t| t >= w.start && t <= end);
    keys.sort_by(f64::total_cmp);
    keys.dedup();
    let mut out = Vec::with_capacity(keys.len());
    let mut buf = Vec::new();
    for pair in keys.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        out.push(a);
        let mut n = 1usize;
        for c in chans {
            let Some(k) = c.sampler.segment(0.5 * (a + b)) else {
                continue;
            };
            if matches!(c.sampler.interp[k], Interp::Bezier | Interp::Hermite) {
                n = n.max(((b - a) * CURVE_RATE).ceil() as usize);
            }
            if let Some(angle) = angle_of(scene, c) {
                c.sampler.sample(a, &mut buf);
                let va = buf.get(angle).copied().unwrap_or(0.0);
                c.sampler.sample(b, &mut buf);
                let vb = buf.get(angle).copied().unwrap_or(0.0);
                n = n.max(((vb - va).abs() / MAX_ANGLE_STEP_DEG).ceil() as usize);
            }
        }
        let n = n.min(MAX_SUBDIVISIONS);
        for s in 1..n {
            out.push(a + (b - a) * s as f64 / n as f64);
        }
    }
    out.extend(keys.last());
    out
}

/// Which value of a channel's samples is a `<rotate>` angle, if any.
fn angle_of(scene: &Scene, c: &Channel) -> Option<usize> {
    let Target::Transform {
        node,
        element,
        component,
    } = c.target
    else {
        return None;
    };
    if scene.nodes[node].transforms[element].kind != Kind::Rotate {
        return None;
    }
    match component {
        None => Some(3),
        Some(3) => Some(0),
        Some(_) => None,
    }
}
