//! Clips -> glTF animations: one sampler per track, channels on joint or mesh nodes.
//!
//! Constant tracks are written small: a track whose every key equals the property's rest
//! value (the joint node's TRS, or the mesh's default morph weights) is not written at all,
//! since a property without a channel keeps that value (glTF 2.0 §3.11 "Animations"); a
//! constant track at another value keeps only its first and last key. Every animation still
//! spans its clip's full time range: when the tracks that set the range's ends would all be
//! dropped, the first of them is kept with its first and last key.

use std::collections::{BTreeMap, BTreeSet};

use gltf_json as json;
use json::accessor::Type;
use json::animation::{Interpolation as GltfInterpolation, Property};
use json::validation::Checked;
use json::Index;
use rigport_model::quantize::{component_to_i16, rotation_to_i16, rotation_to_i8};
use rigport_model::{Asset, Clip, Interpolation, Track, TrackTarget, Transform, Warning};

use super::buffer::{Bounds, Builder};
use super::{quat_dot, unit_quat, GltfOptions};
use crate::labels::mesh_label;

/// Writes one glTF animation per clip that has an exportable track.
///
/// `mesh_nodes[m]` is the node of mesh `m` (the target of its morph-weight tracks). Key
/// times are shared: tracks with bit-identical time arrays use one input accessor, across
/// clips too. `opts.compact` writes rotations as 16-bit integers (with meshopt: at
/// `opts.rotation_bits` per track).
pub(crate) fn write_animations(
    b: &mut Builder,
    asset: &Asset,
    mesh_nodes: &[usize],
    opts: &GltfOptions,
    warnings: &mut Vec<Warning>,
) {
    let rotations_i16 = opts.compact;
    let mut inputs: BTreeMap<Vec<u32>, Index<json::Accessor>> = BTreeMap::new();
    for (ci, clip) in asset.clips.iter().enumerate() {
        // Per-track warnings, flushed in track order once the clip is planned and written.
        let mut track_warnings: Vec<(usize, Warning)> = Vec::new();
        let mut seen = BTreeSet::new();
        // Tracks that survive the checks, in clip order.
        let mut planned: Vec<Planned> = Vec::new();
        for (ti, track) in clip.tracks.iter().enumerate() {
            let location = format!("clip {:?} track {ti}", clip.name);
            let (node, path) = match track.target {
                TrackTarget::Translation(j) => (j.get(), Property::Translation),
                TrackTarget::Rotation(j) => (j.get(), Property::Rotation),
                TrackTarget::Scale(j) => (j.get(), Property::Scale),
                TrackTarget::MorphWeights(m) => {
                    let mesh = &asset.meshes[m.get()];
                    let targets = mesh.morph_targets.len();
                    // glTF: a weights channel needs a mesh with morph targets
                    // (ANIMATION_CHANNEL_TARGET_NODE_WEIGHTS_NO_MORPHS) and one weight per
                    // target per key (ANIMATION_SAMPLER_OUTPUT_ACCESSOR_INVALID_COUNT).
                    if targets == 0 {
                        let why =
                            format!("mesh {:?} has no morph targets", mesh_label(m.get(), mesh));
                        track_warnings.push((ti, dropped(&location, why)));
                        continue;
                    }
                    if track.components() != targets {
                        let why = format!(
                            "{} weights per key for the {targets} morph targets of mesh {:?}",
                            track.components(),
                            mesh_label(m.get(), mesh)
                        );
                        track_warnings.push((ti, dropped(&location, why)));
                        continue;
                    }
                    (mesh_nodes[m.get()], Property::MorphTargetWeights)
                }
            };
            // ANIMATION_DUPLICATE_TARGETS: one channel per node and path in an animation.
            if !seen.insert(track.target) {
                let why = "an earlier track of this clip animates the same property";
                track_warnings.push((ti, dropped(&location, why.into())));
                continue;
            }
            planned.push(Planned {
                track: ti,
                node,
                path,
                fate: constancy(asset, track),
            });
        }
        keep_time_range(clip, &mut planned);

        let mut channels = Vec::new();
        let mut samplers = Vec::new();
        for &Planned {
            track: ti,
            node,
            path,
            fate,
        } in &planned
        {
            let track = &clip.tracks[ti];
            let location = format!("clip {:?} track {ti}", clip.name);
            let mut interpolation = track.interpolation;
            let (times, mut values) = match fate {
                Constancy::AtRest => continue,
                Constancy::Constant => end_keys(track),
                Constancy::Varying => (track.times.clone(), sampler_values(track)),
            };
            if interpolation == Interpolation::CubicSpline && times.len() < 2 {
                // glTF requires two keys for CUBICSPLINE
                // (ANIMATION_SAMPLER_INPUT_ACCESSOR_TOO_FEW_ELEMENTS). One key is a
                // constant, which STEP with the key's value states exactly.
                let c = track.components();
                values = values[c..2 * c].to_vec();
                interpolation = Interpolation::Step;
                let message = "one-key cubic spline written as STEP (CUBICSPLINE needs two keys)";
                track_warnings.push((
                    ti,
                    Warning::Note {
                        location: location.clone(),
                        message: message.into(),
                    },
                ));
            }

            let key: Vec<u32> = times.iter().map(|t| t.to_bits()).collect();
            let input = match inputs.get(&key) {
                Some(&acc) => acc,
                None => {
                    // Sampler inputs require min/max (ANIMATION_SAMPLER_INPUT_ACCESSOR_WITHOUT_BOUNDS).
                    let acc = b.animation_floats(&times, Type::Scalar, Bounds::MinMax);
                    inputs.insert(key, acc);
                    acc
                }
            };
            let type_ = match path {
                Property::Translation | Property::Scale => Type::Vec3,
                Property::Rotation => Type::Vec4,
                Property::MorphTargetWeights => Type::Scalar,
            };
            // Animation data views carry no target (they are not vertex or index data).
            let cubic = interpolation == Interpolation::CubicSpline;
            let cubic_shorts = (rotations_i16 && cubic && path == Property::Rotation)
                .then(|| cubic_i16(fate, track))
                .flatten();
            let output = if let Some(shorts) = cubic_shorts {
                b.animation_shorts(&shorts)
            } else if rotations_i16 && path == Property::Rotation && !cubic {
                let raw = match fate {
                    Constancy::Constant => track.key_value(0).repeat(times.len()),
                    _ => track.values.clone(),
                };
                let bits = opts
                    .rotation_bits
                    .get(ci)
                    .and_then(|c| c.get(ti))
                    .copied()
                    .filter(|&k| k > 0)
                    .unwrap_or(16);
                if bits < 16 && opts.compression == rigport_model::Compression::None {
                    // Core glTF's one precision under 16 bits.
                    b.animation_bytes(&i8_rotations(&raw))
                } else {
                    b.animation_rotations(&raw, bits, i16_rotations)
                }
            } else {
                b.animation_floats(&values, type_, Bounds::None)
            };
            let sampler = Index::push(
                &mut samplers,
                json::animation::Sampler {
                    extensions: None,
                    extras: None,
                    input,
                    interpolation: Checked::Valid(match interpolation {
                        Interpolation::Step => GltfInterpolation::Step,
                        Interpolation::Linear => GltfInterpolation::Linear,
                        Interpolation::CubicSpline => GltfInterpolation::CubicSpline,
                    }),
                    output,
                },
            );
            channels.push(json::animation::Channel {
                sampler,
                target: json::animation::Target {
                    extensions: None,
                    extras: None,
                    node: Index::new(node as u32),
                    path: Checked::Valid(path),
                },
                extensions: None,
                extras: None,
            });
        }
        // Stable: a track's own warnings keep their order.
        track_warnings.sort_by_key(|&(ti, _)| ti);
        warnings.extend(track_warnings.into_iter().map(|(_, w)| w));
        if channels.is_empty() {
            warnings.push(Warning::Repaired {
                location: clip_location(clip),
                message: "clip has no exportable track; not written".into(),
            });
            continue;
        }
        b.root.push(json::Animation {
            extensions: None,
            extras: None,
            channels,
            name: (!clip.name.is_empty()).then(|| clip.name.clone()),
            samplers,
        });
    }
}

/// A track that passed the checks and will be written (unless at rest).
#[derive(Clone, Copy, Debug)]
struct Planned {
    /// Index in the clip's tracks.
    track: usize,
    /// The node it animates.
    node: usize,
    /// The property.
    path: Property,
    /// How it is written.
    fate: Constancy,
}

/// What a track's keys hold, as far as writing it small goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Constancy {
    /// Every key equals the property's rest value: the channel can go.
    AtRest,
    /// Every key equals the first, which is not the rest value: two keys say it exactly.
    Constant,
    /// Written as it is.
    Varying,
}

/// Relative tolerance for equal translations, scales and morph weights: `f32` values that
/// went through a unit conversion or a matrix decomposition differ from the "same" value
/// by a few ulps (2^-23 ≈ 1.2e-7 each).
const VALUE_TOLERANCE: f64 = 1e-6;
/// Rotations are equal when `|dot| >= 1 - ROTATION_TOLERANCE` (q and -q are one rotation);
/// 1e-7 is an angle of about 9e-4 rad (0.05°).
const ROTATION_TOLERANCE: f64 = 1e-7;

/// Whether two values of a property are equal for [`constancy`].
fn same_value(rotation: bool, a: &[f32], b: &[f32]) -> bool {
    if rotation {
        let (Ok(a), Ok(b)) = (<[f32; 4]>::try_from(a), <[f32; 4]>::try_from(b)) else {
            return false;
        };
        // Non-degenerate: checked before building.
        return quat_dot(unit_quat(a), unit_quat(b)).abs() >= 1.0 - ROTATION_TOLERANCE;
    }
    let norm = |v: &[f32]| v.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>().sqrt();
    let diff = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
        .sum::<f64>()
        .sqrt();
    a.len() == b.len() && diff <= VALUE_TOLERANCE * norm(a).max(norm(b))
}

/// Classifies a track against the value its property has without a channel: the joint
/// node's rest TRS, or the mesh's default morph weights (zeros when it states none).
///
/// A cubic spline is constant only when every tangent is exactly zero; otherwise the curve
/// moves between equal keys.
fn constancy(asset: &Asset, track: &Track) -> Constancy {
    let joint_rest = |j: rigport_model::JointIndex| {
        asset
            .skeleton
            .joints()
            .get(j.get())
            .map_or(Transform::IDENTITY, |joint| joint.rest_local)
    };
    let rest: Vec<f32> = match track.target {
        TrackTarget::Translation(j) => joint_rest(j).translation.to_array().to_vec(),
        TrackTarget::Rotation(j) => joint_rest(j).rotation.to_array().to_vec(),
        TrackTarget::Scale(j) => joint_rest(j).scale.to_array().to_vec(),
        TrackTarget::MorphWeights(m) => match asset.meshes.get(m.get()) {
            Some(mesh) if mesh.morph_weights.is_empty() => vec![0.0; mesh.morph_targets.len()],
            Some(mesh) => mesh.morph_weights.clone(),
            None => return Constancy::Varying,
        },
    };
    let rotation = matches!(track.target, TrackTarget::Rotation(_));
    let c = track.components();
    if c == 0 || track.times.is_empty() {
        return Constancy::Varying;
    }
    if track.interpolation == Interpolation::CubicSpline {
        let tangents_zero = track
            .values
            .chunks_exact(3 * c)
            .all(|key| key[..c].iter().chain(&key[2 * c..]).all(|&t| t == 0.0));
        if !tangents_zero {
            return Constancy::Varying;
        }
    }
    let first = track.key_value(0);
    if !(1..track.times.len()).all(|k| same_value(rotation, first, track.key_value(k))) {
        return Constancy::Varying;
    }
    if same_value(rotation, first, &rest) {
        Constancy::AtRest
    } else {
        Constancy::Constant
    }
}

/// Keeps the animation as long as its clip: the clip's time range is that of every
/// planned track; when the written tracks do not reach its end (or start), the first
/// at-rest track that does is written after all, with its first and last key.
fn keep_time_range(clip: &Clip, planned: &mut [Planned]) {
    let range = |track: &Track| Some((*track.times.first()?, *track.times.last()?));
    let span = |written: bool, planned: &[Planned]| {
        planned
            .iter()
            .filter(|p| !written || p.fate != Constancy::AtRest)
            .filter_map(|p| range(clip.tracks.get(p.track)?))
            .fold(None, |acc: Option<(f32, f32)>, (lo, hi)| {
                Some(acc.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))))
            })
    };
    let Some((start, end)) = span(false, planned) else {
        return;
    };
    // The end first: it is the clip's duration.
    for (at_end, target) in [(true, end), (false, start)] {
        let covered = match span(true, planned) {
            Some((lo, _)) if !at_end => lo <= target,
            Some((_, hi)) => hi >= target,
            None => false,
        };
        if covered {
            continue;
        }
        let pick = planned.iter_mut().find(|p| {
            p.fate == Constancy::AtRest
                && clip
                    .tracks
                    .get(p.track)
                    .and_then(range)
                    .is_some_and(|(lo, hi)| if at_end { hi == target } else { lo == target })
        });
        if let Some(p) = pick {
            p.fate = Constancy::Constant;
        }
    }
}

/// A constant track's first and last key, both with the first key's value (normalized for
/// rotations; a cubic spline's tangents are zero). One key stays one key.
fn end_keys(track: &Track) -> (Vec<f32>, Vec<f32>) {
    let per_key = track.values.len() / track.times.len().max(1);
    let mut values = sampler_values(&Track {
        target: track.target,
        interpolation: track.interpolation,
        times: track.times.iter().take(1).copied().collect(),
        values: track.values.iter().take(per_key).copied().collect(),
    });
    let times: Vec<f32> = match (track.times.first(), track.times.last()) {
        (Some(&first), Some(&last)) if last > first => vec![first, last],
        (Some(&first), _) => vec![first],
        _ => Vec::new(),
    };
    if times.len() == 2 {
        values.extend_from_within(..);
    }
    (times, values)
}

/// `clip "name"`.
fn clip_location(clip: &Clip) -> String {
    format!("clip {:?}", clip.name)
}

/// The warning for a track that is not written.
fn dropped(location: &str, why: String) -> Warning {
    Warning::Repaired {
        location: location.to_owned(),
        message: format!("track dropped: {why}"),
    }
}

/// LINEAR or STEP rotation keys (flat xyzw) as 16-bit normalized components: each key
/// rounded from its own value ([`rotation_to_i16`], which the key reducer measures), then
/// made sign-continuous as [`sampler_values`] does (rounding is odd, so flipping after it
/// equals flipping before).
fn i16_rotations(values: &[f32]) -> Vec<i16> {
    sign_continuous(values, rotation_to_i16)
}

/// [`i16_rotations`] as 8-bit normalized components ([`rotation_to_i8`]).
fn i8_rotations(values: &[f32]) -> Vec<i8> {
    sign_continuous(values, rotation_to_i8)
}

/// Rotation keys (flat xyzw) through an odd integer `encode`, each key's sign flipped when
/// it opposes the previous one as encoded.
fn sign_continuous<T>(values: &[f32], encode: fn([f32; 4]) -> [T; 4]) -> Vec<T>
where
    T: Copy + Into<i64> + std::ops::Neg<Output = T>,
{
    let mut out = Vec::with_capacity(values.len());
    let mut previous: Option<[T; 4]> = None;
    for key in values.chunks_exact(4) {
        let mut q = encode([key[0], key[1], key[2], key[3]]);
        let dot = |p: [T; 4], q: [T; 4]| -> i64 {
            p.iter().zip(&q).map(|(&a, &b)| a.into() * b.into()).sum()
        };
        if previous.is_some_and(|p| dot(p, q) < 0) {
            q = q.map(|c| -c);
        }
        out.extend_from_slice(&q);
        previous = Some(q);
    }
    out
}

/// A varying CUBICSPLINE rotation track's values and tangents as 16-bit normalized
/// components, each rounded on its own as it is in the track (not normalized, no sign
/// change: what the key reducer measures, `component_as_i16`); `None` when a component is
/// outside `[-1, 1]` (a tangent, in units per second, can be), which floats then hold.
fn cubic_i16(fate: Constancy, track: &Track) -> Option<Vec<i16>> {
    if fate != Constancy::Varying {
        return None;
    }
    track.values.iter().map(|&c| component_to_i16(c)).collect()
}

/// The sampler output values of a track (flat, same layout as [`Track::values`]).
///
/// Rotations are normalized (validator tolerance 0.00769 on unit length) and made
/// sign-continuous: each key takes the sign whose dot product with the previous key is
/// non-negative. The model's LINEAR rotations take the shortest arc; with continuous signs
/// every viewer does, whether or not its slerp checks the sign.
/// For cubic splines only the value is normalized (tangents are derivatives, not
/// rotations); when a value's sign flips, its tangents flip with it, which keeps the curve
/// the same up to the overall sign (q and −q are one rotation).
fn sampler_values(track: &Track) -> Vec<f32> {
    let mut values = track.values.clone();
    if matches!(track.target, TrackTarget::Rotation(_)) {
        let cubic = track.interpolation == Interpolation::CubicSpline;
        let (stride, offset) = if cubic { (12, 4) } else { (4, 0) };
        let mut previous: Option<[f32; 4]> = None;
        for key in values.chunks_exact_mut(stride) {
            let value = &mut key[offset..offset + 4];
            // Non-degenerate: checked before building.
            let mut q = unit_quat([value[0], value[1], value[2], value[3]]);
            let flip = previous.is_some_and(|p| quat_dot(p, q) < 0.0);
            if flip {
                q = q.map(|c| -c);
            }
            value.copy_from_slice(&q);
            if flip && cubic {
                for k in (0..4).chain(8..12) {
                    key[k] = -key[k];
                }
            }
            previous = Some(q);
        }
    }
    values
}
