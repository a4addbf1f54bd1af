//! Blend shapes: each FBX blend channel as morph targets, in-between shapes included.
//!
//! A channel with shapes `S_1..S_n` at full weights `0 < f_1 < ... < f_n` deforms its mesh
//! piecewise linearly in its weight `w` (`DeformPercent` / 100): `(w / f_1) S_1` up to
//! `f_1`, then from `S_{k-1}` to `S_k` between `f_{k-1}` and `f_k`, extrapolating past
//! both ends (ufbx's `ufbxi_update_blend_channel`, the FBX SDK's definition). Morph targets
//! add linearly, so the channel becomes `n` targets, target `k` holding `S_k - S_{k-1}`
//! (`S_0 = 0`) with the weight [`Segment::weight`] of `w`: 0 below its span, the fraction
//! of its span reached, 1 above it; the first span is open below and the last above. A
//! clip's weight track gets a key where `w` crosses a full weight between two keys, so
//! that linear interpolation of the targets' weights follows the channel exactly.

use std::collections::HashMap;
use std::path::Path;

use rigport_model::glam::{Mat4, Vec3};
use rigport_model::{Mesh, MorphTarget, Warning};

use super::incomplete;

/// One morph target's share of a blend channel: the span of channel weight it covers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Segment {
    /// The channel's element id (its `DeformPercent` is animated under it).
    pub(super) channel: u32,
    /// The span's start (the previous full weight, 0 for the first).
    pub(super) from: f64,
    /// The span's end (this shape's full weight).
    pub(super) to: f64,
    /// Whether the span is the channel's first (open below) and last (open above).
    pub(super) first: bool,
    pub(super) last: bool,
}

impl Segment {
    /// The target's weight for channel weight `w`.
    pub(super) fn weight(&self, w: f64) -> f32 {
        let t = (w - self.from) / (self.to - self.from);
        let t = if self.first { t } else { t.max(0.0) };
        let t = if self.last { t } else { t.min(1.0) };
        t as f32
    }
}

/// The blend channels of `mesh` as morph targets of `m` (offsets through `to_space`'s
/// linear part), with their static weights; returns each target's [`Segment`].
pub(super) fn targets(
    mesh: &ufbx::Mesh,
    m: &mut Mesh,
    to_space: &Mat4,
    path: &Path,
    warnings: &mut Vec<Warning>,
) -> Vec<Segment> {
    let mut segments = Vec::new();
    for deformer in mesh.blend_deformers.iter() {
        for channel in deformer.channels.iter() {
            let name = channel.element.name.to_string();
            let keys: Vec<(f64, &ufbx::BlendShape)> = channel
                .keyframes
                .iter()
                .map(|k| (k.target_weight, &*k.shape))
                .collect();
            let increasing = keys.windows(2).all(|p| p[0].0 < p[1].0);
            let keys = match keys.first() {
                Some(&(f, _)) if f > 0.0 && increasing => keys,
                // Negative or repeated full weights: the full-weight shape alone.
                _ => {
                    let Some(shape) = channel.target_shape.as_ref() else {
                        continue;
                    };
                    if channel.keyframes.len() > 1 {
                        warnings.push(incomplete(
                            path,
                            &channel.element.name,
                            "the blend shape channel's in-between shapes have negative or \
                             repeated full weights: only its full-weight shape is imported"
                                .into(),
                        ));
                    }
                    vec![(1.0, &**shape)]
                }
            };
            let n = keys.len();
            let mut previous = vec![Vec3::ZERO; m.positions.len()];
            let mut from = 0.0;
            for (k, &(to, shape)) in keys.iter().enumerate() {
                let full = offsets(shape, m, to_space);
                let position_deltas = full.iter().zip(&previous).map(|(a, b)| *a - *b).collect();
                let segment = Segment {
                    channel: channel.element.element_id,
                    from,
                    to,
                    first: k == 0,
                    last: k + 1 == n,
                };
                m.morph_targets.push(MorphTarget {
                    name: match n {
                        1 => name.clone(),
                        _ => format!("{name} {:.0}-{:.0}%", from * 100.0, to * 100.0),
                    },
                    position_deltas,
                    normal_deltas: None,
                });
                m.morph_weights.push(segment.weight(channel.weight));
                segments.push(segment);
                previous = full;
                from = to;
            }
        }
    }
    segments
}

/// A shape's offset for each vertex of `m` (by its FBX control point).
fn offsets(shape: &ufbx::BlendShape, m: &Mesh, to_space: &Mat4) -> Vec<Vec3> {
    let by_point: HashMap<u32, Vec3> = shape
        .offset_vertices
        .iter()
        .zip(shape.position_offsets.iter())
        .map(|(point, offset)| {
            (
                *point,
                to_space.transform_vector3(super::skeleton::vec3(offset)),
            )
        })
        .collect();
    m.source_vertex
        .iter()
        .map(|p| by_point.get(p).copied().unwrap_or(Vec3::ZERO))
        .collect()
}

/// The times of `keys` (a channel weight, linear between keys) with, between two keys,
/// the times where the weight crosses one of `breaks`.
pub(super) fn with_crossings(keys: &[(f64, f64)], breaks: &[f64]) -> Vec<f64> {
    let mut times = Vec::with_capacity(keys.len());
    for pair in keys.windows(2) {
        let ((t0, w0), (t1, w1)) = (pair[0], pair[1]);
        times.push(t0);
        let (lo, hi) = (w0.min(w1), w0.max(w1));
        let mut crossings: Vec<f64> = breaks
            .iter()
            .filter(|&&b| lo < b && b < hi)
            .map(|&b| t0 + (b - w0) / (w1 - w0) * (t1 - t0))
            .collect();
        crossings.sort_by(f64::total_cmp);
        times.extend(crossings);
    }
    times.extend(keys.last().map(|k| k.0));
    times
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_sum_to_the_piecewise_linear_channel() {
        // Shapes at 0.5 and 1.0: S1 = 1, S2 = 3 (scalars for the test).
        let spans = [
            Segment {
                channel: 0,
                from: 0.0,
                to: 0.5,
                first: true,
                last: false,
            },
            Segment {
                channel: 0,
                from: 0.5,
                to: 1.0,
                first: false,
                last: true,
            },
        ];
        let deltas = [1.0, 2.0];
        let blend = |w: f64| -> f64 {
            spans
                .iter()
                .zip(deltas)
                .map(|(s, d)| f64::from(s.weight(w)) * d)
                .sum()
        };
        for (w, expected) in [
            (-0.5, -1.0),
            (0.25, 0.5),
            (0.5, 1.0),
            (0.75, 2.0),
            (1.0, 3.0),
            (1.5, 5.0),
        ] {
            assert!(
                (blend(w) - expected).abs() < 1e-6,
                "w {w}: {} vs {expected}",
                blend(w)
            );
        }
    }

    #[test]
    fn a_key_is_added_where_the_weight_crosses_a_full_weight() {
        let times = with_crossings(&[(0.0, 0.0), (1.0, 1.0), (2.0, 0.0)], &[0.5, 1.0]);
        assert_eq!(times, [0.0, 0.5, 1.0, 1.5, 2.0]);
    }
}
