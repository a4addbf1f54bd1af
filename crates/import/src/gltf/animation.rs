//! Animations: one clip per glTF animation, key times and unit rotations checked.

use ::gltf::accessor::Dimensions;
use ::gltf::animation::util::ReadOutputs;
use ::gltf::animation::{Interpolation as GltfInterpolation, Property};
use rigport_model::{Clip, Interpolation, JointIndex, Mesh, MeshIndex, Track, TrackTarget};

use crate::ImportError;

use super::accessor::{FLOAT, FLOAT_OR_NORM};
use super::importer::{Importer, UNIT_QUAT_TOLERANCE};

/// How far from 1 a rotation key's length may be and still be kept as stored: 1e-4, past
/// the rounding of 16-bit normalized components (about 2e-5 at most).
const QUANTIZED_LENGTH: f32 = 1e-4;

impl<'a> Importer<'a> {
    pub(super) fn clips(
        &mut self,
        node_joint: &[Option<JointIndex>],
        node_meshes: &[Vec<MeshIndex>],
        meshes: &[Mesh],
    ) -> Result<Vec<Clip>, ImportError> {
        let mut clips = Vec::new();
        for anim in self.doc.animations() {
            let a = anim.index();
            let name = anim
                .name()
                .filter(|s| !s.is_empty())
                .map_or_else(|| format!("animation_{a}"), str::to_string);
            let mut tracks = Vec::new();
            for channel in anim.channels() {
                let ch_at = format!("/animations/{a}/channels/{}", channel.index());
                let sampler = channel.sampler();
                let s_at = format!("/animations/{a}/samplers/{}", sampler.index());
                // gltf-json 1.4 does not validate channel targets: check them before the
                // accessors that unwrap them.
                let json_target = self
                    .doc
                    .as_json()
                    .animations
                    .get(a)
                    .and_then(|anim| anim.channels.get(channel.index()))
                    .map(|ch| &ch.target);
                let Some(json_target) = json_target else {
                    return Err(self.err(ch_at, "channel not found"));
                };
                let node_count = self.doc.nodes().len();
                if json_target.node.value() >= node_count {
                    return Err(self.err(
                        format!("{ch_at}/target/node"),
                        format!(
                            "node {} does not exist ({node_count} nodes)",
                            json_target.node.value()
                        ),
                    ));
                }
                if !matches!(
                    json_target.path,
                    ::gltf::json::validation::Checked::Valid(_)
                ) {
                    self.note(
                        &format!("{ch_at}/target/path"),
                        "unknown target path; channel skipped".into(),
                    );
                    continue;
                }
                let target = channel.target();
                let node = target.node().index();
                let Some(joint) = node_joint.get(node).copied().flatten() else {
                    self.note(
                        &format!("{ch_at}/target/node"),
                        format!("node {node} is not in the imported scene; channel skipped"),
                    );
                    continue;
                };
                let interpolation = match sampler.interpolation() {
                    GltfInterpolation::Linear => Interpolation::Linear,
                    GltfInterpolation::Step => Interpolation::Step,
                    GltfInterpolation::CubicSpline => Interpolation::CubicSpline,
                };
                let per_key = if interpolation == Interpolation::CubicSpline {
                    3
                } else {
                    1
                };
                let times = self.read_times(&sampler.input(), &format!("{s_at}/input"))?;
                let keys = times.len();
                let out_at = format!("{s_at}/output");
                let output = sampler.output();
                let property = target.property();
                let (components, types) = match property {
                    Property::Translation | Property::Scale => (Dimensions::Vec3, FLOAT),
                    Property::Rotation => (Dimensions::Vec4, FLOAT_OR_NORM),
                    Property::MorphTargetWeights => (Dimensions::Scalar, FLOAT_OR_NORM),
                };
                let count = self.check(&output, components, types, &out_at)?;
                let zeros = count * components.multiplicity();
                let values: Vec<f32> = match channel.reader(self.data()).read_outputs() {
                    _ if Self::zero_filled(&output) => vec![0.0; zeros],
                    Some(ReadOutputs::Translations(it)) | Some(ReadOutputs::Scales(it)) => {
                        it.flatten().collect()
                    }
                    Some(ReadOutputs::Rotations(it)) => it.into_f32().flatten().collect(),
                    Some(ReadOutputs::MorphTargetWeights(it)) => it.into_f32().collect(),
                    None => return Err(self.err(out_at, "data unavailable")),
                };
                if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                    return Err(self.err(out_at, format!("value {k} is not finite")));
                }
                let track = |target, values| Track {
                    target,
                    interpolation,
                    times: times.clone(),
                    values,
                };
                if property == Property::MorphTargetWeights {
                    let Some(instanced) = node_meshes.get(node).filter(|m| !m.is_empty()) else {
                        self.note(
                            &ch_at,
                            format!(
                                "node {node} instances no triangle mesh; weights channel skipped"
                            ),
                        );
                        continue;
                    };
                    for &mi in instanced {
                        let targets = meshes.get(mi.get()).map_or(0, |m| m.morph_targets.len());
                        if targets == 0 {
                            self.note(
                                &ch_at,
                                format!(
                                    "mesh {mi} has no morph targets; weights channel skipped \
                                     for it"
                                ),
                            );
                            continue;
                        }
                        if count != keys * per_key * targets {
                            return Err(self.err(
                                out_at,
                                format!(
                                    "{count} weights for {keys} keys of a mesh with {targets} \
                                     morph targets ({interpolation:?})"
                                ),
                            ));
                        }
                        tracks.push(track(TrackTarget::MorphWeights(mi), values.clone()));
                    }
                    continue;
                }
                if count != keys * per_key {
                    return Err(self.err(
                        out_at,
                        format!(
                            "{count} outputs for {keys} keys ({interpolation:?} needs {})",
                            keys * per_key
                        ),
                    ));
                }
                let target = match property {
                    Property::Translation => TrackTarget::Translation(joint),
                    Property::Scale => TrackTarget::Scale(joint),
                    _ => TrackTarget::Rotation(joint),
                };
                let values = if property == Property::Rotation {
                    let quantized = output.data_type() != gltf::accessor::DataType::F32;
                    self.unit_rotations(values, interpolation, quantized, &out_at)?
                } else {
                    values
                };
                tracks.push(track(target, values));
            }
            clips.push(Clip { name, tracks });
        }
        Ok(clips)
    }

    /// Key times: seconds, finite, `>= 0`, strictly increasing (glTF 2.0 §3.11).
    fn read_times(&self, acc: &::gltf::Accessor<'a>, at: &str) -> Result<Vec<f32>, ImportError> {
        let times = self.read_scalars(acc, at)?;
        if let Some(k) = times.iter().position(|t| !(t.is_finite() && *t >= 0.0)) {
            return Err(self.err(
                at,
                format!("key {k} time {} is negative or not finite", times[k]),
            ));
        }
        if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(self.err(
                at,
                format!(
                    "key times must increase strictly: key {} at {} follows {}",
                    k + 1,
                    times[k + 1],
                    times[k]
                ),
            ));
        }
        Ok(times)
    }

    /// Normalizes LINEAR/STEP rotation keys (warning when one is off by more than the
    /// validator's tolerance); cubic-spline keys are kept with their tangents, only reported.
    /// Integer keys (`quantized`: normalized `SHORT` or `BYTE`, meshopt's quaternion filter)
    /// within [`QUANTIZED_LENGTH`] of unit length are kept as stored: they cannot be
    /// exactly unit, and three.js composes them as they are, scaled by the squared length,
    /// which `rigport eval` shows too (`SampleJob::run_as_stored`); every other command
    /// samples them normalized.
    fn unit_rotations(
        &mut self,
        mut values: Vec<f32>,
        interpolation: Interpolation,
        quantized: bool,
        at: &str,
    ) -> Result<Vec<f32>, ImportError> {
        let cubic = interpolation == Interpolation::CubicSpline;
        let mut off = 0usize;
        let mut worst = 0.0f32;
        for (k, q) in values.chunks_exact_mut(4).enumerate() {
            if cubic && k % 3 != 1 {
                continue;
            }
            let len = q.iter().map(|c| c * c).sum::<f32>().sqrt();
            if len.is_nan() || len <= 1e-6 {
                return Err(self.err(
                    at,
                    format!("rotation {k} has length {len}; it must be a unit quaternion"),
                ));
            }
            if (len - 1.0).abs() > UNIT_QUAT_TOLERANCE {
                off += 1;
                worst = worst.max((len - 1.0).abs());
            }
            let as_stored = quantized && (len - 1.0).abs() <= QUANTIZED_LENGTH;
            if !cubic && !as_stored {
                q.iter_mut().for_each(|c| *c /= len);
            }
        }
        if off > 0 {
            let message = format!(
                "{off} rotation keys are not unit quaternions (largest |length - 1| {worst:.6}); {}",
                if cubic { "kept (cubic spline)" } else { "normalized" }
            );
            if cubic {
                self.note(at, message);
            } else {
                self.repaired(at, message);
            }
        }
        Ok(values)
    }
}
