//! UsdSkel blend shapes: the `BlendShape` prims a Mesh binds (`skel:blendShapes` +
//! `skel:blendShapeTargets`) become the mesh's morph targets, and a SkelAnimation's
//! `blendShapes` / `blendShapeWeights` become morph-weight tracks.
//!
//! Inbetweens become further morph targets. UsdSkel (`UsdSkelBlendShapeQuery::
//! ComputeSubShapeWeights`) places a shape's sub-shapes on a line of weights: the null shape
//! at 0, the primary at 1, each inbetween at its `weight`; a channel weight `w` between two
//! neighbours gives them `1 - a` and `a` (`a` the fraction of the way), and below the first
//! or above the last one the end segment is extended. Each sub-shape's weight is therefore a
//! piecewise-linear function of `w` with kinks at the inner weights; the weight tracks get a
//! key wherever the (linearly interpolated) channel weight crosses one of them, so linear
//! interpolation of the sub-shape weights equals UsdSkel's evaluation at every time, not
//! only at the source's time samples.

use glam::{DMat3, DVec3};
use rigport_model::glam::Vec3;
use rigport_model::{Interpolation, MorphTarget, Track, TrackTarget};

use super::importer::{resolve_path, Importer};
use super::shapes::Channel;
use super::stage::Prim;
use super::values::{self, number, numbers, tokens, tuples};
use crate::ImportError;

/// How a mesh's points map into its model vertices, for turning point offsets into
/// per-vertex deltas.
pub(super) struct PointMap<'a> {
    /// Points of the Mesh prim.
    pub(super) points: usize,
    /// For each model vertex, its point.
    pub(super) source_vertex: &'a [u32],
    /// Linear part of the points -> model space transform (deltas are vectors).
    pub(super) linear: DMat3,
    /// Whether the mesh has per-point normals that normal offsets apply to.
    pub(super) vertex_normals: bool,
}

/// The weight of each sub-shape of a channel at channel weight `w`, as UsdSkel computes it
/// (see the module doc): `(target, weight)` pairs, the null shape left out.
pub(super) fn sub_shape_weights(knots: &[(f64, Option<usize>)], w: f64) -> Vec<(usize, f64)> {
    let n = knots.len();
    if n < 2 {
        return Vec::new();
    }
    // The segment holding w; the end segments extend outwards.
    let mut i = 0;
    while i + 2 < n && w > knots[i + 1].0 {
        i += 1;
    }
    let (wa, a) = knots[i];
    let (wb, b) = knots[i + 1];
    let t = (w - wa) / (wb - wa);
    let mut out = Vec::with_capacity(2);
    if let Some(a) = a {
        out.push((a, 1.0 - t));
    }
    if let Some(b) = b {
        out.push((b, t));
    }
    out
}

impl<'l> Importer<'l, '_> {
    /// The morph targets and channels of the Mesh prim `prim` (empty when it binds no blend
    /// shapes).
    ///
    /// # Errors
    /// A target that is not a BlendShape, offsets or point indices that do not fit.
    pub(super) fn blend_shapes(
        &mut self,
        prim: &Prim<'l>,
        map: &PointMap<'_>,
    ) -> Result<(Vec<MorphTarget>, Vec<Channel>), ImportError> {
        let path = prim.path.clone();
        let names: Vec<String> = match prim.prop("skel:blendShapes").and_then(values::static_value)
        {
            Some((v, _)) => tokens(v)
                .ok_or_else(|| self.err(&path, "skel:blendShapes must be a token[]"))?
                .into_iter()
                .map(str::to_string)
                .collect(),
            None => Vec::new(),
        };
        let targets: Vec<String> = prim
            .prop("skel:blendShapeTargets")
            .and_then(|p| p.targets)
            .map(|t| t.iter().map(|t| resolve_path(&path, t)).collect())
            .unwrap_or_default();
        if names.is_empty() && targets.is_empty() {
            return Ok((Vec::new(), Vec::new()));
        }
        if names.len() != targets.len() {
            // UsdSkelBindingAPI::ValidateBlendShapes rejects the whole binding.
            self.incomplete(
                &path,
                format!(
                    "skel:blendShapes names {} shapes but skel:blendShapeTargets has {} \
                     targets: UsdSkel applies none of them, and neither does rigport",
                    names.len(),
                    targets.len()
                ),
            );
            return Ok((Vec::new(), Vec::new()));
        }
        let mut morphs = Vec::new();
        let mut channels = Vec::new();
        for (token, target) in names.iter().zip(&targets) {
            let Some(ti) = self.stage.index(target) else {
                return Err(self.err(
                    &path,
                    format!(
                        "skel:blendShapeTargets targets <{target}>, which does not exist{}",
                        self.behind_arc_path(target)
                    ),
                ));
            };
            let shape = self.prim(ti).clone();
            if shape.type_name != Some("BlendShape") || !self.stage.in_scene(ti) {
                return Err(self.err(
                    &path,
                    format!(
                        "skel:blendShapeTargets targets <{target}>, which is not a defined \
                         BlendShape ({})",
                        shape.type_name.unwrap_or("untyped")
                    ),
                ));
            }
            let channel = self.blend_shape(&shape, token, map, &mut morphs)?;
            channels.push(channel);
        }
        Ok((morphs, channels))
    }

    /// One BlendShape prim: its primary shape and inbetweens appended to `morphs`.
    fn blend_shape(
        &mut self,
        shape: &Prim<'l>,
        token: &str,
        map: &PointMap<'_>,
        morphs: &mut Vec<MorphTarget>,
    ) -> Result<Channel, ImportError> {
        let path = shape.path.clone();
        let indices: Option<Vec<usize>> =
            match shape.prop("pointIndices").and_then(values::static_value) {
                Some((v, _)) => {
                    let nums = numbers(v)
                        .ok_or_else(|| self.err(&path, "pointIndices must be an int[]"))?;
                    Some(
                        nums.iter()
                            .enumerate()
                            .map(|(k, &x)| {
                                Some(x)
                                    .filter(|x| x.fract() == 0.0 && *x >= 0.0)
                                    .map(|x| x as usize)
                                    .filter(|&x| x < map.points)
                                    .ok_or_else(|| {
                                        self.err(
                                            &path,
                                            format!(
                                                "pointIndices[{k}] = {x} is out of range for {} \
                                             points",
                                                map.points
                                            ),
                                        )
                                    })
                            })
                            .collect::<Result<_, _>>()?,
                    )
                }
                None => None,
            };
        let entries = indices.as_ref().map_or(map.points, Vec::len);
        // An attribute of offsets, `entries` long; `None` when not authored.
        let offsets = |this: &Self, name: &str| -> Result<Option<Vec<DVec3>>, ImportError> {
            let Some((v, _)) = shape.prop(name).and_then(values::static_value) else {
                return Ok(None);
            };
            let t = tuples::<3>(v)
                .ok_or_else(|| this.err(&path, format!("{name} must be a vector3f[]")))?;
            if t.len() != entries {
                return Err(this.err(
                    &path,
                    format!(
                        "{name} has {} offsets for {entries} {}",
                        t.len(),
                        if indices.is_some() {
                            "pointIndices"
                        } else {
                            "points"
                        }
                    ),
                ));
            }
            if t.iter().flatten().any(|x| !x.is_finite()) {
                return Err(this.err(&path, format!("{name} holds a non-finite value")));
            }
            Ok(Some(t.into_iter().map(DVec3::from_array).collect()))
        };
        let mut dropped_normals = false;
        // Per model vertex deltas from sparse or dense point offsets.
        let mut target =
            |name: String, pos: Option<Vec<DVec3>>, nor: Option<Vec<DVec3>>| -> usize {
                let spread = |offs: &[DVec3]| -> Vec<Vec3> {
                    let mut per_point = vec![DVec3::ZERO; map.points];
                    match &indices {
                        Some(ix) => {
                            for (&p, d) in ix.iter().zip(offs) {
                                per_point[p] += *d;
                            }
                        }
                        None => per_point.copy_from_slice(offs),
                    }
                    map.source_vertex
                        .iter()
                        .map(|&p| {
                            (map.linear * per_point.get(p as usize).copied().unwrap_or_default())
                                .as_vec3()
                        })
                        .collect()
                };
                let position_deltas = match &pos {
                    Some(o) => spread(o),
                    None => vec![Vec3::ZERO; map.source_vertex.len()],
                };
                let normal_deltas = match nor {
                    Some(o) if map.vertex_normals => Some(spread(&o)),
                    Some(_) => {
                        dropped_normals = true;
                        None
                    }
                    None => None,
                };
                morphs.push(MorphTarget {
                    name,
                    position_deltas,
                    normal_deltas,
                });
                morphs.len() - 1
            };
        let primary_pos = offsets(self, "offsets")?;
        let primary_nor = offsets(self, "normalOffsets")?;
        let primary = target(token.to_string(), primary_pos, primary_nor);
        let mut knots: Vec<(f64, Option<usize>)> = vec![(0.0, None), (1.0, Some(primary))];
        let mut inbetweens: Vec<(&str, f64)> = Vec::new();
        for (name, prop) in &shape.props {
            let Some(ib) = name.strip_prefix("inbetweens:") else {
                continue;
            };
            if ib.contains(':') || prop.type_name.is_none() {
                continue; // `inbetweens:x:normalOffsets`
            }
            let Some(w) = prop.meta("weight").and_then(number) else {
                self.incomplete(
                    &path,
                    format!("{name} has no weight: UsdSkel ignores it, and so does rigport"),
                );
                continue;
            };
            if !w.is_finite() || w == 0.0 || w == 1.0 || inbetweens.iter().any(|&(_, o)| o == w) {
                self.incomplete(
                    &path,
                    format!(
                        "{name} has weight {w}, which the null shape (0), the primary shape (1) \
                         or another inbetween already takes: ignored"
                    ),
                );
                continue;
            }
            inbetweens.push((ib, w));
        }
        inbetweens.sort_by(|a, b| a.1.total_cmp(&b.1));
        for (ib, w) in inbetweens {
            let pos = offsets(self, &format!("inbetweens:{ib}"))?;
            let nor = offsets(self, &format!("inbetweens:{ib}:normalOffsets"))?;
            let t = target(format!("{token}_{ib}"), pos, nor);
            knots.push((w, Some(t)));
        }
        knots.sort_by(|a, b| a.0.total_cmp(&b.0));
        if dropped_normals {
            self.incomplete(
                &path,
                "normal offsets are not imported: the mesh's normals are not per point \
                 (vertex interpolation), which UsdSkel's normal offsets address",
            );
        }
        Ok(Channel {
            token: token.to_string(),
            knots,
        })
    }

    /// Morph-weight tracks of one SkelAnimation for every mesh with blend shapes.
    ///
    /// `anim_tokens` are the animation's `blendShapes`; `times` its weight samples' time
    /// codes (`None`: one default value) and `values` one weight array per sample;
    /// `seconds` turns a time code into clip seconds.
    pub(super) fn weight_tracks(
        &self,
        anim_tokens: &[&str],
        times: Option<&[f64]>,
        values: &[Vec<f64>],
        start: f64,
        seconds: &dyn Fn(f64) -> f32,
    ) -> Vec<Track> {
        let mut tracks = Vec::new();
        for shapes in &self.mesh_shapes {
            let map: Vec<Option<usize>> = shapes
                .channels
                .iter()
                .map(|c| anim_tokens.iter().position(|t| *t == c.token))
                .collect();
            if map.iter().all(Option::is_none) {
                continue;
            }
            let weight_at = |k: usize, c: usize| -> f64 {
                map[c]
                    .and_then(|a| values.get(k)?.get(a).copied())
                    .unwrap_or(0.0)
            };
            // Key times (time codes): the samples, plus every crossing of an inner knot.
            let sample_times: Vec<f64> = match times {
                Some(t) => t.to_vec(),
                None => vec![start],
            };
            let mut keys: Vec<(f64, usize, f64)> = Vec::new(); // (time, segment, fraction)
            for (k, &t) in sample_times.iter().enumerate() {
                keys.push((t, k, 0.0));
                let Some(&t1) = sample_times.get(k + 1) else {
                    continue;
                };
                let mut cross: Vec<f64> = Vec::new();
                for (c, ch) in shapes.channels.iter().enumerate() {
                    let (w0, w1) = (weight_at(k, c), weight_at(k + 1, c));
                    let inner = ch.knots.get(1..ch.knots.len().saturating_sub(1));
                    for &(kw, _) in inner.unwrap_or_default() {
                        let f = (kw - w0) / (w1 - w0);
                        if f.is_finite() && f > 0.0 && f < 1.0 {
                            cross.push(f);
                        }
                    }
                }
                cross.sort_by(f64::total_cmp);
                cross.dedup();
                keys.extend(cross.into_iter().map(|f| (t + f * (t1 - t), k, f)));
            }
            let mut out_t: Vec<f32> = Vec::with_capacity(keys.len());
            let mut out_v: Vec<f32> = Vec::with_capacity(keys.len() * shapes.targets);
            for (t, k, f) in keys {
                let mut row = vec![0.0f64; shapes.targets];
                for (c, ch) in shapes.channels.iter().enumerate() {
                    let w0 = weight_at(k, c);
                    let w = if f == 0.0 {
                        w0
                    } else {
                        w0 + f * (weight_at(k + 1, c) - w0)
                    };
                    for (target, sw) in sub_shape_weights(&ch.knots, w) {
                        if let Some(slot) = row.get_mut(target) {
                            *slot += sw;
                        }
                    }
                }
                let st = seconds(t);
                // Distinct time codes that round to the same f32 second: keep the later.
                if out_t.last().is_some_and(|&l| l >= st) {
                    out_t.pop();
                    out_v.truncate(out_v.len() - shapes.targets);
                }
                out_t.push(st);
                out_v.extend(row.iter().map(|&x| x as f32));
            }
            tracks.push(Track {
                target: TrackTarget::MorphWeights(shapes.mesh),
                interpolation: Interpolation::Linear,
                times: out_t,
                values: out_v,
            });
        }
        tracks
    }
}

#[cfg(test)]
mod tests {
    use super::sub_shape_weights;

    /// Values printed by usd-core's `UsdSkel.BlendShapeQuery.ComputeSubShapeWeights` for a
    /// shape with inbetweens at -0.5, 0.25 and 0.75 (targets 0 = primary, 1 = -0.5,
    /// 2 = 0.25, 3 = 0.75).
    #[test]
    fn sub_shape_weights_match_usdskel() {
        let knots = [
            (-0.5, Some(1)),
            (0.0, None),
            (0.25, Some(2)),
            (0.75, Some(3)),
            (1.0, Some(0)),
        ];
        let cases: [(f64, &[(usize, f64)]); 8] = [
            (-1.0, &[(1, 2.0)]),
            (-0.25, &[(1, 0.5)]),
            (0.1, &[(2, 0.4)]),
            (0.25, &[(2, 1.0)]),
            (0.5, &[(2, 0.5), (3, 0.5)]),
            (1.0, &[(3, 0.0), (0, 1.0)]),
            (1.5, &[(3, -2.0), (0, 3.0)]),
            (2.0, &[(3, -4.0), (0, 5.0)]),
        ];
        for (w, want) in cases {
            let got: Vec<(usize, f64)> = sub_shape_weights(&knots, w)
                .into_iter()
                .filter(|&(_, x)| x != 0.0)
                .collect();
            let want: Vec<(usize, f64)> = want.iter().copied().filter(|&(_, x)| x != 0.0).collect();
            assert_eq!(got.len(), want.len(), "w = {w}: {got:?} vs {want:?}");
            for ((a, x), (b, y)) in got.iter().zip(&want) {
                assert_eq!(a, b, "w = {w}");
                assert!((x - y).abs() < 1e-12, "w = {w}: {x} vs {y}");
            }
        }
    }
}
