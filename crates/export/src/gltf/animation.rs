//! Clips -> glTF animations: one sampler per track, channels on joint or mesh nodes.

use std::collections::{BTreeMap, BTreeSet};

use gltf_json as json;
use json::accessor::Type;
use json::animation::{Interpolation as GltfInterpolation, Property};
use json::validation::Checked;
use json::Index;
use rigport_model::{Asset, Clip, Interpolation, Track, TrackTarget, Warning};

use super::buffer::{Bounds, Builder};
use super::document::mesh_label;
use super::{quat_dot, unit_quat};

/// Writes one glTF animation per clip that has an exportable track.
///
/// `mesh_nodes[m]` is the node of mesh `m` (the target of its morph-weight tracks). Key
/// times are shared: tracks with bit-identical time arrays use one input accessor, across
/// clips too.
pub(crate) fn write_animations(
    b: &mut Builder,
    asset: &Asset,
    mesh_nodes: &[usize],
    warnings: &mut Vec<Warning>,
) {
    let mut inputs: BTreeMap<Vec<u32>, Index<json::Accessor>> = BTreeMap::new();
    for clip in &asset.clips {
        let mut seen = BTreeSet::new();
        let mut channels = Vec::new();
        let mut samplers = Vec::new();
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
                        warnings.push(dropped(
                            &location,
                            format!("mesh {:?} has no morph targets", mesh_label(m.get(), mesh)),
                        ));
                        continue;
                    }
                    if track.components() != targets {
                        warnings.push(dropped(
                            &location,
                            format!(
                                "{} weights per key for the {targets} morph targets of mesh {:?}",
                                track.components(),
                                mesh_label(m.get(), mesh)
                            ),
                        ));
                        continue;
                    }
                    (mesh_nodes[m.get()], Property::MorphTargetWeights)
                }
            };
            // ANIMATION_DUPLICATE_TARGETS: one channel per node and path in an animation.
            if !seen.insert(track.target) {
                warnings.push(dropped(
                    &location,
                    "an earlier track of this clip animates the same property".into(),
                ));
                continue;
            }

            let mut interpolation = track.interpolation;
            let mut values = sampler_values(track);
            if interpolation == Interpolation::CubicSpline && track.times.len() < 2 {
                // glTF requires two keys for CUBICSPLINE
                // (ANIMATION_SAMPLER_INPUT_ACCESSOR_TOO_FEW_ELEMENTS). One key is a
                // constant, which STEP with the key's value states exactly.
                let c = track.components();
                values = values[c..2 * c].to_vec();
                interpolation = Interpolation::Step;
                warnings.push(Warning::Note {
                    location: location.clone(),
                    message: "one-key cubic spline written as STEP (CUBICSPLINE needs two keys)"
                        .into(),
                });
            }

            let key: Vec<u32> = track.times.iter().map(|t| t.to_bits()).collect();
            let input = match inputs.get(&key) {
                Some(&acc) => acc,
                None => {
                    // Sampler inputs require min/max (ANIMATION_SAMPLER_INPUT_ACCESSOR_WITHOUT_BOUNDS).
                    let acc = b.floats(&track.times, Type::Scalar, None, Bounds::MinMax);
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
            let output = b.floats(&values, type_, None, Bounds::None);
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
