//! Time-sampled points: a Mesh whose `points` hold several time samples (what a simulation
//! or a point cache writes, and what `rigport cloth` writes for a baked garment) plays
//! them.
//!
//! Each sample becomes a morph target, its offset from the rest points (the default value,
//! else the first sample) in the mesh's model-space vertices, and a morph-weight track
//! moves from one sample's target to the next: the linear interpolation of one-hot weights
//! is USD's linear interpolation of the points between two samples, and the first and last
//! samples hold before and after them, as USD holds them. The track is added to every clip
//! (a clip of its own, named after the mesh, when the stage has none).
//!
//! Samples whose point count differs from the rest points cannot be interpolated (USD
//! holds each one until the next); such a mesh keeps its rest points, with a warning.

use glam::DVec3;
use rigport_model::{Clip, Interpolation, MeshIndex, MorphTarget, Track, TrackTarget};

use super::blend::PointMap;
use super::importer::Importer;
use super::stage::Prim;
use super::values::{is_half_type, round_to_half, tuples};
use crate::ImportError;

/// One morph target per point sample, and the samples' times in seconds.
type Samples = (Vec<MorphTarget>, Vec<f32>);

/// The morph targets one Mesh's point samples became.
#[derive(Clone, Debug)]
pub(super) struct SampledPoints {
    /// The mesh.
    pub(super) mesh: MeshIndex,
    /// Its prim's name (a clip made for the samples is named after it).
    pub(super) name: String,
    /// Its prim's path (for the note).
    pub(super) path: String,
    /// Index of the first sample's target among the mesh's morph targets.
    pub(super) first_target: usize,
    /// Targets of the mesh in all (its blend shapes' and its samples').
    pub(super) targets: usize,
    /// The samples' times, seconds.
    pub(super) seconds: Vec<f32>,
}

impl<'l> Importer<'l, '_> {
    /// Whether `prim`'s `points` hold more than one time sample: they are then read as
    /// [`Importer::point_samples`] and not through the static value's warning.
    pub(super) fn has_point_samples(prim: &Prim<'l>) -> bool {
        prim.prop("points")
            .and_then(|p| p.samples.as_ref())
            .is_some_and(|s| s.len() > 1)
    }

    /// The morph targets of `prim`'s time-sampled points, offsets from `rest` (the points
    /// the mesh was built from, in the points' own space) mapped to model-space vertex
    /// deltas by `map`, with their times in seconds. `None` when the points hold fewer
    /// than two samples, or samples of another length (warned).
    ///
    /// # Errors
    /// A sample that is not a `point3f[]` or holds a non-finite value.
    pub(super) fn point_samples(
        &mut self,
        prim: &Prim<'l>,
        rest: &[[f64; 3]],
        map: &PointMap<'_>,
    ) -> Result<Option<Samples>, ImportError> {
        let path = prim.path.clone();
        let Some(prop) = prim.prop("points") else {
            return Ok(None);
        };
        let Some(samples) = prop.samples.as_ref().filter(|s| s.len() > 1) else {
            return Ok(None);
        };
        let half = prop.type_name.is_some_and(is_half_type);
        let mut targets = Vec::with_capacity(samples.len());
        let mut seconds = Vec::with_capacity(samples.len());
        for &(tc, value) in samples {
            let mut points = tuples::<3>(value).ok_or_else(|| {
                self.err_at(
                    prop.line,
                    &path,
                    format!("the points sample at time code {tc} must be a point3f[]"),
                )
            })?;
            if points.len() != rest.len() {
                self.incomplete(
                    &path,
                    format!(
                        "the points sample at time code {tc} has {} points, not {}: samples \
                         of changing size are not imported (the mesh keeps its rest points)",
                        points.len(),
                        rest.len()
                    ),
                );
                return Ok(None);
            }
            if half {
                for x in points.iter_mut().flatten() {
                    *x = f64::from(round_to_half(*x as f32));
                }
            }
            if points.iter().flatten().any(|x| !x.is_finite()) {
                return Err(self.err(
                    &path,
                    format!("the points sample at time code {tc} holds a non-finite value"),
                ));
            }
            let time = (tc / self.tcps) as f32;
            if seconds.last().is_some_and(|&last| time <= last) {
                // Two time codes that are the same f32 second: the first one stands.
                continue;
            }
            let offset = |p: usize| {
                let (a, b) = (points[p], rest[p]);
                map.linear * DVec3::new(a[0] - b[0], a[1] - b[1], a[2] - b[2])
            };
            let position_deltas = map
                .source_vertex
                .iter()
                .map(|&p| offset(p as usize).as_vec3())
                .collect();
            targets.push(MorphTarget {
                name: format!("points@{tc}"),
                position_deltas,
                normal_deltas: None,
            });
            seconds.push(time);
        }
        Ok(Some((targets, seconds)))
    }

    /// Adds one morph-weight track per mesh of `sampled` to every clip (to a clip of its
    /// own, named after the first such mesh, when there is none), and notes each mesh.
    pub(super) fn point_sample_tracks(&mut self, clips: &mut Vec<Clip>, sampled: &[SampledPoints]) {
        let Some(first) = sampled.first() else {
            return;
        };
        let tracks: Vec<Track> = sampled.iter().map(one_hot_track).collect();
        if clips.is_empty() {
            clips.push(Clip {
                name: first.name.clone(),
                tracks: Vec::new(),
            });
        }
        for clip in clips.iter_mut() {
            clip.tracks.extend(tracks.iter().cloned());
        }
        for s in sampled {
            self.note(
                &s.path,
                format!(
                    "{} time samples of points are imported as morph targets, played by a \
                     weight track in every clip",
                    s.seconds.len()
                ),
            );
        }
    }
}

/// The weight track of `s`: at its `k`-th time, weight 1 on its `k`-th sample's target and
/// 0 on every other target of the mesh.
fn one_hot_track(s: &SampledPoints) -> Track {
    let mut values = vec![0.0; s.seconds.len() * s.targets];
    for k in 0..s.seconds.len() {
        values[k * s.targets + s.first_target + k] = 1.0;
    }
    Track {
        target: TrackTarget::MorphWeights(s.mesh),
        interpolation: Interpolation::Linear,
        times: s.seconds.clone(),
        values,
    }
}
