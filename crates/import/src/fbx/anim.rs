//! Animation: every animation stack as one clip, through ufbx's `bake_anim`.
//!
//! ufbx evaluates the stack's layers (weights, blend modes) and the node transforms
//! (pivots, pre/post rotation, rotation order, the converted axes) and bakes each animated
//! node's local translation, rotation and scale. Keys sit at the source's key times; ufbx
//! adds samples between keys only where the curves are not linear (cubic tangents), at its
//! default resample rate of 30 per second, so linear interpolation of the baked keys
//! follows the curves. Times are shifted so that the clip starts at 0 at the earlier of the
//! stack's start and its first key (keys may precede the stack's start). Blend shape
//! channels' `DeformPercent` (0-100) becomes morph weights (0-1).

use std::collections::{HashMap, HashSet};
use std::path::Path;

use rigport_model::{Clip, Interpolation, Track, TrackTarget};

use super::blend::with_crossings;
use super::mesh::Built;
use super::skeleton::{quat, vec3, Skel};
use crate::names::unique;
use crate::{ImportError, Location};

/// One baked stack.
pub(super) struct Baked {
    pub(super) name: String,
    pub(super) anim: ufbx::BakedAnimRoot,
}

/// Bakes every animation stack, in file order.
///
/// # Errors
/// ufbx cannot bake a stack (its message, at the file).
pub(super) fn bake(scene: &ufbx::Scene, path: &Path) -> Result<Vec<Baked>, ImportError> {
    scene
        .anim_stacks
        .iter()
        .map(|stack| {
            let anim =
                ufbx::bake_anim(scene, &stack.anim, ufbx::BakeOpts::default()).map_err(|e| {
                    ImportError::invalid(
                        Location::file(path),
                        format!(
                            "animation stack {:?} cannot be evaluated: {}",
                            &*stack.element.name, &*e.description
                        ),
                    )
                })?;
            Ok(Baked {
                name: stack.element.name.to_string(),
                anim,
            })
        })
        .collect()
}

/// The nodes (ufbx typed ids) any stack's layers have a curve on: those [`bake`] bakes,
/// unless inherit types make it bake their children and scale helpers too.
pub(super) fn curve_nodes(scene: &ufbx::Scene) -> HashSet<u32> {
    let mut nodes = HashSet::new();
    for stack in scene.anim_stacks.iter() {
        for layer in stack.anim.layers.iter() {
            for prop in layer.anim_props.iter() {
                if prop.element.type_ == ufbx::ElementType::Node {
                    nodes.insert(prop.element.typed_id);
                }
            }
        }
    }
    nodes
}

/// The nodes (ufbx typed ids) any stack animates: they become joints.
pub(super) fn animated_nodes(baked: &[Baked]) -> HashSet<u32> {
    baked
        .iter()
        .flat_map(|b| b.anim.nodes.iter().map(|n| n.typed_id))
        .collect()
}

/// One clip per baked stack, named after it (made unique, `clip` when unnamed).
pub(super) fn clips(baked: &[Baked], skel: &Skel, built: &Built) -> Vec<Clip> {
    let mut used = HashSet::new();
    baked
        .iter()
        .map(|b| {
            let start = b.anim.playback_time_begin.min(b.anim.key_time_min);
            let start = if start.is_finite() { start } else { 0.0 };
            let mut tracks = Vec::new();
            for node in b.anim.nodes.iter() {
                let Some(&joint) = skel.joint_of.get(&node.typed_id) else {
                    continue;
                };
                let t = keys(&node.translation_keys, start, |k| {
                    let v = vec3(&k.value);
                    [v.x, v.y, v.z].to_vec()
                });
                push(&mut tracks, TrackTarget::Translation(joint), t);
                let r = keys(&node.rotation_keys, start, |k| {
                    quat(&k.value).to_array().to_vec()
                });
                push(&mut tracks, TrackTarget::Rotation(joint), r);
                let s = keys(&node.scale_keys, start, |k| {
                    let v = vec3(&k.value);
                    [v.x, v.y, v.z].to_vec()
                });
                push(&mut tracks, TrackTarget::Scale(joint), s);
            }
            morph_tracks(&b.anim, start, built, &mut tracks);
            Clip {
                name: unique(&b.name, "clip", &mut used),
                tracks,
            }
        })
        .collect()
}

/// Times (seconds after `start`, strictly increasing in `f32`) and flat values of baked
/// keys.
fn keys<K: Timed>(keys: &[K], start: f64, value: impl Fn(&K) -> Vec<f32>) -> (Vec<f32>, Vec<f32>) {
    let mut times: Vec<f32> = Vec::with_capacity(keys.len());
    let mut values = Vec::new();
    for k in keys {
        let t = (k.time() - start).max(0.0) as f32;
        if times.last().is_some_and(|&last| t <= last) || !t.is_finite() {
            continue;
        }
        times.push(t);
        values.extend(value(k));
    }
    (times, values)
}

fn push(tracks: &mut Vec<Track>, target: TrackTarget, (times, values): (Vec<f32>, Vec<f32>)) {
    if times.is_empty() {
        return;
    }
    tracks.push(Track {
        target,
        interpolation: Interpolation::Linear,
        times,
        values,
    });
}

/// A baked key's time.
trait Timed {
    fn time(&self) -> f64;
}

impl Timed for ufbx::BakedVec3 {
    fn time(&self) -> f64 {
        self.time
    }
}

impl Timed for ufbx::BakedQuat {
    fn time(&self) -> f64 {
        self.time
    }
}

/// Morph weight tracks: per mesh, at the union of its animated channels' key times (and
/// where a channel's weight crosses a full weight, [`super::blend`]), each target's weight
/// for its channel's `DeformPercent` / 100 (unanimated channels keep their static weight).
fn morph_tracks(anim: &ufbx::BakedAnim, start: f64, built: &Built, tracks: &mut Vec<Track>) {
    let percent: HashMap<u32, &[ufbx::BakedVec3]> = anim
        .elements
        .iter()
        .filter_map(|e| {
            let prop = e.props.iter().find(|p| &*p.name == "DeformPercent")?;
            Some((e.element_id, &*prop.keys))
        })
        .collect();
    for (mesh, segments) in &built.channels {
        let mut times: Vec<f64> = Vec::new();
        for (id, keys) in &percent {
            let breaks: Vec<f64> = (segments.iter())
                .filter(|s| s.channel == *id && !s.last)
                .map(|s| s.to)
                .collect();
            if !segments.iter().any(|s| s.channel == *id) {
                continue;
            }
            let weights: Vec<(f64, f64)> =
                keys.iter().map(|k| (k.time, k.value.x / 100.0)).collect();
            times.extend(with_crossings(&weights, &breaks));
        }
        if times.is_empty() {
            continue;
        }
        times.sort_by(f64::total_cmp);
        times.dedup();
        let statics = &built.meshes[mesh.0 as usize].morph_weights;
        let mut out_times: Vec<f32> = Vec::new();
        let mut values = Vec::new();
        for &t in &times {
            let t32 = (t - start).max(0.0) as f32;
            if out_times.last().is_some_and(|&last| t32 <= last) {
                continue;
            }
            out_times.push(t32);
            for (k, segment) in segments.iter().enumerate() {
                let w = match percent.get(&segment.channel) {
                    Some(keys) => segment.weight(ufbx::evaluate_baked_vec3(keys, t).x / 100.0),
                    None => statics.get(k).copied().unwrap_or(0.0),
                };
                values.push(w);
            }
        }
        push(
            tracks,
            TrackTarget::MorphWeights(*mesh),
            (out_times, values),
        );
    }
}
