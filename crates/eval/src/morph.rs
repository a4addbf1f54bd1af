//! Morph targets: each mesh's weights for one frame, and the shape they give before
//! skinning.
//!
//! glTF 2.0 (§3.7.2.2, "Morph Targets") defines a morphed position as
//! `base + Σ weightᵢ · targetᵢ`, applied to the mesh before its skin; UsdSkel applies blend
//! shapes before skinning as well. A mesh's weights are its defaults
//! ([`rigport_model::Mesh::morph_weights`], glTF's `mesh.weights`), replaced at each time
//! by a clip's morph-weight track when the clip animates that mesh. Time-sampled USD points arrive as morph targets with such a
//! track (one target per sample), so they play the same way.
//!
//! ```
//! use rigport_eval::morph::{morph_positions, MorphWeights};
//! use rigport_model::glam::Vec3;
//! use rigport_model::{Asset, Mesh, MorphTarget};
//!
//! let target = MorphTarget { name: "up".into(), position_deltas: vec![Vec3::Y], normal_deltas: None };
//! let mesh = Mesh { positions: vec![Vec3::ZERO], morph_targets: vec![target], morph_weights: vec![0.5],
//!     ..Mesh::default() };
//! let asset = Asset { meshes: vec![mesh], ..Asset::default() };
//! let weights = MorphWeights::rest(&asset);
//! assert_eq!(weights.mesh(0), [0.5]);
//! let mesh = &asset.meshes[0];
//! let mut out = Vec::new();
//! assert!(morph_positions(&mesh.positions, &mesh.morph_targets, weights.mesh(0), &mut out));
//! assert_eq!(out, [Vec3::new(0.0, 0.5, 0.0)]);
//! ```

use glam::Vec3;
use rigport_model::{Asset, MorphTarget, TrackTarget};

use crate::sample::{sample_weights, CompiledClip, SampleError};

/// The morph-target weights of every mesh of an asset for one frame: one weight per target.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphWeights {
    per_mesh: Vec<Vec<f32>>,
}

impl MorphWeights {
    /// Each mesh's default weights ([`rigport_model::Mesh::morph_weights`]; 0 for a target
    /// it lists no weight for).
    pub fn rest(asset: &Asset) -> Self {
        let per_mesh = asset
            .meshes
            .iter()
            .map(|m| {
                let mut w = m.morph_weights.clone();
                w.resize(m.morph_targets.len(), 0.0);
                w
            })
            .collect();
        Self { per_mesh }
    }

    /// Sets the weights of every mesh `clip` animates to their values at `time` (each
    /// track's value is held before its first key and after its last); other meshes keep
    /// theirs. A track with more components than its mesh has targets fills the targets
    /// it covers; one with fewer leaves the rest as they were.
    ///
    /// # Errors
    /// A track whose values do not fill whole keys, or a time that is not finite.
    pub fn sample(&mut self, clip: &CompiledClip<'_>, time: f32) -> Result<(), SampleError> {
        let mut scratch = Vec::new();
        for track in clip.weight_tracks() {
            let TrackTarget::MorphWeights(mesh) = track.target else {
                continue;
            };
            let Some(weights) = self.per_mesh.get_mut(mesh.get()) else {
                continue;
            };
            scratch.clear();
            scratch.resize(track.components(), 0.0);
            sample_weights(track, time, &mut scratch)?;
            for (w, s) in weights.iter_mut().zip(&scratch) {
                *w = *s;
            }
        }
        Ok(())
    }

    /// The weights of mesh `index` (empty for a mesh without targets or out of range).
    pub fn mesh(&self, index: usize) -> &[f32] {
        self.per_mesh.get(index).map_or(&[], Vec::as_slice)
    }
}

/// `rest` with each of `targets` added at its weight, into `out` (resized to `rest`'s
/// length). Returns `false`, leaving `out` as it was, when no weight is non-zero: the shape
/// is `rest` itself. Targets with fewer deltas than `rest` has positions move only the
/// positions they cover.
pub fn morph_positions(
    rest: &[Vec3],
    targets: &[MorphTarget],
    weights: &[f32],
    out: &mut Vec<Vec3>,
) -> bool {
    if weights.iter().zip(targets).all(|(&w, _)| w == 0.0) {
        return false;
    }
    out.clear();
    out.extend_from_slice(rest);
    for (target, &w) in targets.iter().zip(weights) {
        if w == 0.0 {
            continue;
        }
        for (p, d) in out.iter_mut().zip(&target.position_deltas) {
            *p += *d * w;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use rigport_model::{Clip, Interpolation, Mesh, MeshIndex, Skeleton, Track};

    fn two_targets() -> Asset {
        let target = |d: Vec3| MorphTarget {
            name: String::new(),
            position_deltas: vec![d, d],
            normal_deltas: None,
        };
        Asset {
            meshes: vec![
                Mesh {
                    positions: vec![Vec3::ZERO, Vec3::X],
                    morph_targets: vec![target(Vec3::Y), target(Vec3::Z)],
                    ..Mesh::default()
                },
                Mesh {
                    positions: vec![Vec3::ONE],
                    ..Mesh::default()
                },
            ],
            ..Asset::default()
        }
    }

    #[test]
    fn a_clip_sets_the_weights_of_the_meshes_it_animates() {
        let asset = two_targets();
        let clip = Clip {
            name: "blink".into(),
            tracks: vec![Track {
                target: TrackTarget::MorphWeights(MeshIndex(0)),
                interpolation: Interpolation::Linear,
                times: vec![0.0, 1.0],
                values: vec![0.0, 0.0, 1.0, 0.5],
            }],
        };
        let compiled = CompiledClip::new(&clip, &Skeleton::default()).unwrap();
        let mut weights = MorphWeights::rest(&asset);
        assert_eq!(weights.mesh(0), [0.0, 0.0]);
        assert!(weights.mesh(1).is_empty() && weights.mesh(7).is_empty());
        weights.sample(&compiled, 0.5).unwrap();
        assert_eq!(weights.mesh(0), [0.5, 0.25]);
        // Held after the last key.
        weights.sample(&compiled, 3.0).unwrap();
        assert_eq!(weights.mesh(0), [1.0, 0.5]);
        let mesh = &asset.meshes[0];
        let mut out = vec![Vec3::NAN];
        assert!(morph_positions(
            &mesh.positions,
            &mesh.morph_targets,
            weights.mesh(0),
            &mut out
        ));
        assert_eq!(out, [Vec3::new(0.0, 1.0, 0.5), Vec3::new(1.0, 1.0, 0.5)]);
        // All weights zero: the rest shape, and `out` is left alone.
        let mut untouched = vec![Vec3::NAN];
        assert!(!morph_positions(
            &mesh.positions,
            &mesh.morph_targets,
            &[0.0, 0.0],
            &mut untouched
        ));
        assert!(untouched[0].is_nan());
    }
}
