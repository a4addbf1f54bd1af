//! `SkelAnimation` prims to [`Clip`]s: which animations are imported and in what order,
//! time codes to seconds, translation/rotation/scale tracks and their keys.

use std::collections::HashMap;

use rigport_model::glam::Quat;
use rigport_model::{Clip, Interpolation, JointIndex, Track, TrackTarget, Warning};

use super::importer::{resolve_path, Importer, SkelData};
use super::layer::{self, PrimSpec, Value};
use super::stage::{Prim, Stage};
use super::values::{self, is_half_type, numbers, round_to_half, tokens, tuples};
use crate::ImportError;

/// An animation attribute: sample times (time codes; `None` for a default value) and
/// one array per sample.
struct AnimAttr<const N: usize> {
    times: Option<Vec<f64>>,
    values: Vec<Vec<[f64; N]>>,
}

impl<const N: usize> AnimAttr<N> {
    /// No value: the joints keep their rest transforms (no tracks).
    fn empty() -> Self {
        Self {
            times: None,
            values: Vec::new(),
        }
    }
}

/// Drops keys whose `f32` time equals the previous one (distinct time codes that round to
/// the same second), keeping the later value, so times stay strictly increasing.
fn dedup_keys(times: Vec<f32>, values: Vec<f32>) -> (Vec<f32>, Vec<f32>) {
    let c = values.len().checked_div(times.len()).unwrap_or(0);
    if times.windows(2).all(|w| w[0] < w[1]) || c == 0 {
        return (times, values);
    }
    let mut out_t: Vec<f32> = Vec::with_capacity(times.len());
    let mut out_v: Vec<f32> = Vec::with_capacity(values.len());
    for (k, &t) in times.iter().enumerate() {
        let v = values.get(k * c..(k + 1) * c).unwrap_or_default();
        if out_t.last().is_some_and(|&l| l >= t) {
            out_v.truncate(out_v.len() - c);
            out_t.pop();
        }
        out_t.push(t);
        out_v.extend_from_slice(v);
    }
    (out_t, out_v)
}

/// Renames a clip `name_2`, `name_3`, ... when its name is taken.
fn unique_clip(mut clip: Clip, names: &mut HashMap<String, usize>) -> Clip {
    let base = clip.name.clone();
    let mut k = 1;
    while names.contains_key(&clip.name) {
        k += 1;
        clip.name = format!("{base}_{k}");
    }
    names.insert(clip.name.clone(), 1);
    clip
}

/// Whether variant `variant` of set `set` on the prim at `prim_path` defines a
/// SkelAnimation (found by walking the layer's specs, so unselected variants are only
/// composed when they hold one).
fn variant_defines_animation(
    root: &layer::PrimBody,
    prim_path: &str,
    set: &str,
    variant: &str,
) -> bool {
    fn defines(body: &layer::PrimBody) -> bool {
        body.children
            .iter()
            .any(|c| c.type_name.as_deref() == Some("SkelAnimation") || defines(&c.body))
            || body
                .variant_sets
                .iter()
                .any(|s| s.variants.iter().any(|(_, _, b)| defines(b)))
    }
    fn find<'a>(body: &'a layer::PrimBody, rest: &[&str], out: &mut Vec<&'a PrimSpec>) {
        let Some((first, tail)) = rest.split_first() else {
            return;
        };
        let mut bodies = vec![body];
        // Prims may also be defined inside variants of the parent.
        let mut k = 0;
        while let Some(b) = bodies.get(k).copied() {
            k += 1;
            for s in &b.variant_sets {
                for (_, _, vb) in &s.variants {
                    bodies.push(vb);
                }
            }
        }
        for b in bodies {
            for c in b.children.iter().filter(|c| c.name == *first) {
                if tail.is_empty() {
                    out.push(c);
                } else {
                    find(&c.body, tail, out);
                }
            }
        }
    }
    let parts: Vec<&str> = prim_path.split('/').filter(|s| !s.is_empty()).collect();
    let mut specs = Vec::new();
    find(root, &parts, &mut specs);
    specs.iter().any(|spec| {
        spec.body.variant_sets.iter().any(|s| {
            s.name == set
                && s.variants
                    .iter()
                    .any(|(v, _, b)| v == variant && defines(b))
        })
    })
}

impl<'l> Importer<'l, '_> {
    /// Every clip: the bound animation first, then the other SkelAnimations in document
    /// order, then those only found in unselected variants.
    pub(super) fn clips(
        &mut self,
        skel_index: usize,
        skel: &SkelData,
    ) -> Result<Vec<Clip>, ImportError> {
        let bound = self.stage.ancestry(skel_index).find_map(|p| {
            let targets = p.prop("skel:animationSource")?.targets?;
            Some((p.path.clone(), targets.first().cloned()))
        });
        let mut order: Vec<usize> = Vec::new();
        if let Some((owner, Some(target))) = &bound {
            let target = resolve_path(owner, target);
            match self.stage.index(&target) {
                Some(a)
                    if self.stage.in_scene(a)
                        && self.stage.prims.get(a).and_then(|p| p.type_name)
                            == Some("SkelAnimation") =>
                {
                    order.push(a)
                }
                Some(a) => {
                    return Err(self.err(
                        owner,
                        format!(
                            "skel:animationSource targets <{target}>, which is not a defined \
                             SkelAnimation{}",
                            self.behind_arc(a)
                        ),
                    ))
                }
                None => {
                    return Err(self.err(
                        owner,
                        format!(
                            "skel:animationSource targets <{target}>, which does not exist{}",
                            self.behind_arc_path(&target)
                        ),
                    ))
                }
            }
        }
        for i in 0..self.stage.prims.len() {
            if !order.contains(&i)
                && self.stage.in_scene(i)
                && self.stage.prims.get(i).and_then(|p| p.type_name) == Some("SkelAnimation")
            {
                order.push(i);
            }
        }
        let mut clips = Vec::new();
        let mut names: HashMap<String, usize> = HashMap::new();
        for a in order {
            let prim = self.prim(a).clone();
            if let Some(clip) = self.clip(&prim, skel)? {
                clips.push(unique_clip(clip, &mut names));
            }
        }
        // SkelAnimations that only unselected variants define.
        let layer = self.layer;
        let mut alternatives: Vec<(String, String, String)> = Vec::new();
        for (i, prim) in self.stage.prims.iter().enumerate() {
            if !self.stage.in_scene(i) {
                continue;
            }
            for (set, variants) in &prim.variant_sets {
                let chosen = prim
                    .selections
                    .iter()
                    .find(|(s, _)| s == set)
                    .map(|(_, v)| *v);
                for v in variants {
                    if Some(*v) != chosen
                        && variant_defines_animation(&layer.root, &prim.path, set, v)
                    {
                        alternatives.push((prim.path.clone(), set.to_string(), v.to_string()));
                    }
                }
            }
        }
        for (path, set, variant) in alternatives {
            let alt = Stage::compose(&layer.root, Some((&path, &set, &variant)));
            for (i, prim) in alt.prims.iter().enumerate() {
                let known = self
                    .stage
                    .index(&prim.path)
                    .is_some_and(|k| self.stage.in_scene(k));
                if known || prim.type_name != Some("SkelAnimation") || !alt.in_scene(i) {
                    continue;
                }
                let prim = prim.clone();
                if let Some(clip) = self.clip(&prim, skel)? {
                    clips.push(unique_clip(clip, &mut names));
                }
            }
        }
        Ok(clips)
    }

    /// One SkelAnimation as a clip; `None` (with a warning) when UsdSkel would ignore it.
    fn clip(&mut self, prim: &Prim<'l>, skel: &SkelData) -> Result<Option<Clip>, ImportError> {
        let path = prim.path.clone();
        let weights = self.blend_weights(prim)?;
        let anim_tokens: Vec<&str> = match self.static_attr(prim, "joints") {
            Some((joints_value, joints_prop)) => tokens(joints_value)
                .ok_or_else(|| self.err_at(joints_prop.line, &path, "joints must be a token[]"))?,
            None if weights.is_some() => Vec::new(),
            None => {
                self.incomplete(&path, "a SkelAnimation without joints: no clip");
                return Ok(None);
            }
        };
        let n = anim_tokens.len();
        let translations = self.anim_attr::<3>(prim, "translations", n)?;
        let rotations = self.anim_attr::<4>(prim, "rotations", n)?;
        let scales = self.anim_attr::<3>(prim, "scales", n)?;
        let (translations, rotations, scales) = match (translations, rotations, scales) {
            (Some(t), Some(r), Some(s)) => (t, r, s),
            // Blend-shape weights alone: the skeleton stays at rest.
            _ if weights.is_some() && n == 0 => {
                (AnimAttr::empty(), AnimAttr::empty(), AnimAttr::empty())
            }
            _ => {
                let missing: Vec<&str> = [
                    ("translations", prim.prop("translations")),
                    ("rotations", prim.prop("rotations")),
                    ("scales", prim.prop("scales")),
                ]
                .iter()
                .filter(|(_, p)| p.and_then(values::static_value).is_none())
                .map(|(n, _)| *n)
                .collect();
                self.incomplete(
                    &path,
                    format!(
                        "no {}: UsdSkel ignores a SkelAnimation without translations, rotations \
                         and scales, so {}{}",
                        missing.join(" or "),
                        if weights.is_some() {
                            "only its blend-shape weights are imported"
                        } else {
                            "it is not imported"
                        },
                        self.behind_arc_path(&format!("{path}/x"))
                    ),
                );
                if weights.is_none() {
                    return Ok(None);
                }
                (AnimAttr::empty(), AnimAttr::empty(), AnimAttr::empty())
            }
        };
        let map: Vec<Option<usize>> = anim_tokens
            .iter()
            .map(|t| skel.tokens.iter().position(|s| s == t))
            .collect();
        let unknown: Vec<&str> = anim_tokens
            .iter()
            .zip(&map)
            .filter(|(_, m)| m.is_none())
            .map(|(t, _)| *t)
            .collect();
        if !unknown.is_empty() {
            self.incomplete(
                &path,
                format!(
                    "{} joint(s) not in the Skeleton <{}> ignored: {}",
                    unknown.len(),
                    skel.path,
                    unknown.join(", ")
                ),
            );
        }
        // Key times: constant attributes get one key at the first sampled time.
        let weight_times = weights.as_ref().and_then(|(_, w)| w.times.clone());
        let first = [
            &translations.times,
            &rotations.times,
            &scales.times,
            &weight_times,
        ]
        .iter()
        .filter_map(|t| t.as_ref()?.first().copied())
        .fold(None, |acc: Option<f64>, t| {
            Some(acc.map_or(t, |a| a.min(t)))
        });
        let start = first.unwrap_or(0.0);
        let shift = if start < 0.0 { -start } else { 0.0 };
        if shift > 0.0 {
            self.warnings.push(Warning::Repaired {
                location: self.location(&path),
                message: format!(
                    "samples start at time code {start}: the clip is shifted by {} s to start at 0",
                    shift / self.tcps
                ),
            });
        }
        let seconds = |tc: f64| ((tc + shift) / self.tcps) as f32;
        let key_times = |times: &Option<Vec<f64>>| -> Vec<f32> {
            match times {
                Some(t) => t.iter().map(|&tc| seconds(tc)).collect(),
                None => vec![seconds(start)],
            }
        };
        let mut tracks = Vec::new();
        // Without transforms (a blend-shape-only animation) the joints stay at rest.
        let joint_tracks = !translations.values.is_empty();
        for (a, joint) in map.iter().enumerate().filter(|_| joint_tracks) {
            let Some(j) = joint.map(|j| JointIndex(j as u32)) else {
                continue;
            };
            let t_times = key_times(&translations.times);
            let r_times = key_times(&rotations.times);
            let s_times = key_times(&scales.times);
            let mut t_vals = Vec::with_capacity(t_times.len() * 3);
            for sample in &translations.values {
                let v = sample.get(a).copied().unwrap_or_default();
                t_vals.extend(v.iter().map(|&x| x as f32));
            }
            let mut r_vals = Vec::with_capacity(r_times.len() * 4);
            let mut prev: Option<Quat> = None;
            for sample in &rotations.values {
                let [w, x, y, z] = sample.get(a).copied().unwrap_or([1.0, 0.0, 0.0, 0.0]);
                let q = glam::DQuat::from_xyzw(x, y, z, w);
                let len = q.length();
                if len.is_nan() || len <= 1e-12 {
                    return Err(self.err(
                        &path,
                        format!(
                            "rotations of joint {:?} hold a zero quaternion",
                            anim_tokens.get(a).copied().unwrap_or("")
                        ),
                    ));
                }
                let mut q = (q / len).as_quat();
                // Sign-continuous: the shorter way from the previous key.
                if prev.is_some_and(|p| p.dot(q) < 0.0) {
                    q = -q;
                }
                prev = Some(q);
                r_vals.extend(q.to_array());
            }
            let mut s_vals = Vec::with_capacity(s_times.len() * 3);
            for sample in &scales.values {
                let v = sample.get(a).copied().unwrap_or([1.0; 3]);
                s_vals.extend(v.iter().map(|&x| x as f32));
            }
            for (target, times, values) in [
                (TrackTarget::Translation(j), t_times, t_vals),
                (TrackTarget::Rotation(j), r_times, r_vals),
                (TrackTarget::Scale(j), s_times, s_vals),
            ] {
                let (times, values) = dedup_keys(times, values);
                tracks.push(Track {
                    target,
                    interpolation: Interpolation::Linear,
                    times,
                    values,
                });
            }
        }
        if let Some((shape_tokens, w)) = &weights {
            let rows: Vec<Vec<f64>> = w
                .values
                .iter()
                .map(|s| s.iter().map(|x| x[0]).collect())
                .collect();
            tracks.extend(self.weight_tracks(
                shape_tokens,
                w.times.as_deref(),
                &rows,
                start,
                &seconds,
            ));
        }
        Ok(Some(Clip {
            name: prim.name.to_string(),
            tracks,
        }))
    }

    /// The SkelAnimation's `blendShapes` and `blendShapeWeights` (one value per shape per
    /// sample); `None` when it animates no blend shapes.
    fn blend_weights(
        &mut self,
        prim: &Prim<'l>,
    ) -> Result<Option<(Vec<&'l str>, AnimAttr<1>)>, ImportError> {
        let Some((v, prop)) = self.static_attr(prim, "blendShapes") else {
            if prim.prop("blendShapeWeights").is_some() {
                let path = prim.path.clone();
                self.incomplete(
                    &path,
                    "blendShapeWeights without blendShapes: UsdSkel applies none of them",
                );
            }
            return Ok(None);
        };
        let shapes = tokens(v)
            .ok_or_else(|| self.err_at(prop.line, &prim.path, "blendShapes must be a token[]"))?;
        let Some(w) = self.anim_attr::<1>(prim, "blendShapeWeights", shapes.len())? else {
            return Ok(None);
        };
        Ok(Some((shapes, w)))
    }

    /// A SkelAnimation array attribute: its samples (each `n` long) or its default.
    /// `None` when it has no value.
    fn anim_attr<const N: usize>(
        &self,
        prim: &Prim<'l>,
        name: &str,
        n: usize,
    ) -> Result<Option<AnimAttr<N>>, ImportError> {
        let Some(prop) = prim.prop(name) else {
            return Ok(None);
        };
        let half = prop.type_name.is_some_and(is_half_type);
        let read = |v: &Value, at: Option<f64>| -> Result<Vec<[f64; N]>, ImportError> {
            let when = at.map_or(String::new(), |t| format!(" at time {t}"));
            let read = if N == 1 {
                // Plain numbers (`float[] blendShapeWeights`).
                numbers(v).map(|xs| {
                    xs.into_iter()
                        .map(|x| {
                            let mut a = [0.0; N];
                            if let Some(s) = a.first_mut() {
                                *s = x;
                            }
                            a
                        })
                        .collect()
                })
            } else {
                tuples::<N>(v)
            };
            let mut vals: Vec<[f64; N]> = read.ok_or_else(|| {
                self.err_at(
                    prop.line,
                    &prim.path,
                    format!("{name}{when} must be an array of {N}-component values"),
                )
            })?;
            if vals.len() != n {
                return Err(self.err(
                    &prim.path,
                    format!("{name}{when} has {} values for {n} joints", vals.len()),
                ));
            }
            if half {
                for v in &mut vals {
                    for x in v.iter_mut() {
                        *x = f64::from(round_to_half(*x as f32));
                    }
                }
            }
            if vals.iter().flatten().any(|x| !x.is_finite()) {
                return Err(self.err(&prim.path, format!("{name}{when} holds a non-finite value")));
            }
            Ok(vals)
        };
        if let Some(samples) = &prop.samples {
            let live: Vec<&(f64, &Value)> =
                samples.iter().filter(|(_, v)| **v != Value::None).collect();
            if !live.is_empty() {
                let mut times = Vec::with_capacity(live.len());
                let mut values = Vec::with_capacity(live.len());
                for (t, v) in live {
                    if !t.is_finite() {
                        return Err(
                            self.err(&prim.path, format!("{name} has a non-finite time code"))
                        );
                    }
                    times.push(*t);
                    values.push(read(v, Some(*t))?);
                }
                return Ok(Some(AnimAttr {
                    times: Some(times),
                    values,
                }));
            }
        }
        match prop.default {
            Some(v) if *v != Value::None => Ok(Some(AnimAttr {
                times: None,
                values: vec![read(v, None)?],
            })),
            _ => Ok(None),
        }
    }
}
