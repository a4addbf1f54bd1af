//! SkelAnimation prims: which tracks of a clip are written, the stage's frame rate and
//! time codes, and the time samples of each animation.

use std::collections::{BTreeMap, BTreeSet};

use rigport_model::{Asset, Clip, Interpolation, Track, TrackTarget, Transform, Warning};

use super::mesh::MeshPlan;
use super::sampler::{dot, Sampler};
use super::values::{to_half, zero, zeroed};
use crate::labels::mesh_label;
use rigport_usd::layer::Specifier;
use rigport_usd::sink::{AttrDecl, Data, LayerSink};

/// Frame rates tried, after the one the key spacing suggests, to make the keys integral.
const COMMON_RATES: [f64; 9] = [24.0, 25.0, 30.0, 48.0, 50.0, 60.0, 100.0, 120.0, 240.0];
/// The slowest frame rate chosen for the stage (film's).
const MIN_FRAME_RATE: f64 = 24.0;
/// Most extra samples one clip may get from resampling (keeps a mistaken hour-long clip
/// from producing gigabytes).
const MAX_RESAMPLED_FRAMES: f64 = 1_000_000.0;
/// Scale values whose half-precision rounding changes them by more than this (relative)
/// are reported.
const HALF_REPORT_TOLERANCE: f32 = 1e-5;

/// One SkelAnimation as it will be written.
pub(super) struct AnimPlan<'a> {
    pub(super) prim: String,
    /// Skeleton joints animated by the clip, in skeleton order.
    pub(super) joints: Vec<usize>,
    /// Translation, rotation (xyzw) and scale samplers per entry of `joints`.
    pub(super) trs: Vec<[Option<Sampler<'a>>; 3]>,
    /// Morph-weight sampler per mesh (with blend shapes) animated by the clip.
    pub(super) morphs: BTreeMap<usize, Sampler<'a>>,
    /// Key times in seconds (union over the kept tracks), ascending.
    pub(super) key_times: Vec<f64>,
    /// Whether a step or cubic-spline track needs extra samples between keys.
    pub(super) resample: bool,
    /// Location for warnings.
    pub(super) location: String,
}

/// Picks the tracks of one clip that will be written, reporting the others.
///
/// A joint whose tracks in the clip all hold its rest value (as Blender's glTF exporter
/// writes for every bone) is left out of the SkelAnimation's `joints`: UsdSkel then takes
/// it from the Skeleton's `restTransforms`, the same transform in double precision and
/// without half-precision scales. Its keys still count for the clip's times.
pub(super) fn plan_clip<'a>(
    asset: &Asset,
    clip: &'a Clip,
    prim: String,
    plans: &[MeshPlan],
    warnings: &mut Vec<Warning>,
) -> AnimPlan<'a> {
    let location = format!("clip {:?}", clip.name);
    let mut trs: BTreeMap<usize, [Option<&'a Track>; 3]> = BTreeMap::new();
    let mut morphs = BTreeMap::new();
    let mut seen = BTreeSet::new();
    let mut times: Vec<f32> = Vec::new();
    let mut resample = false;
    let needs_frames = |track: &Track| {
        track.times.len() >= 2
            && matches!(
                track.interpolation,
                Interpolation::Step | Interpolation::CubicSpline
            )
    };
    for (ti, track) in clip.tracks.iter().enumerate() {
        let dropped = |why: String| Warning::Repaired {
            location: format!("{location} track {ti}"),
            message: format!("track dropped: {why}"),
        };
        if !seen.insert(track.target) {
            warnings.push(dropped(
                "an earlier track of this clip animates the same property".into(),
            ));
            continue;
        }
        match track.target {
            TrackTarget::Translation(j) | TrackTarget::Rotation(j) | TrackTarget::Scale(j) => {
                let slot = match track.target {
                    TrackTarget::Translation(_) => 0,
                    TrackTarget::Rotation(_) => 1,
                    _ => 2,
                };
                let entry = trs.entry(j.get()).or_insert([None, None, None]);
                entry[slot] = Some(track);
            }
            TrackTarget::MorphWeights(m) => {
                let mi = m.get();
                if plans.get(mi).is_some_and(|p| p.points_cache) {
                    // Written as the mesh's points.timeSamples; its times are the clip's.
                    times.extend_from_slice(&track.times);
                    continue;
                }
                let targets = plans.get(mi).map_or(0, |p| p.channels.len());
                let label = asset
                    .meshes
                    .get(mi)
                    .map(|mesh| mesh_label(mi, mesh))
                    .unwrap_or_default();
                if targets == 0 {
                    warnings.push(dropped(format!("mesh {label:?} has no morph targets")));
                    continue;
                }
                if track.components() != targets {
                    warnings.push(dropped(format!(
                        "{} weights per key for the {targets} morph targets of mesh {label:?}",
                        track.components()
                    )));
                    continue;
                }
                resample |= needs_frames(track);
                morphs.insert(mi, Sampler::new(track));
            }
        }
        times.extend_from_slice(&track.times);
    }
    times.sort_by(f32::total_cmp);
    times.dedup_by(|a, b| a.to_bits() == b.to_bits());
    let joints_rest = asset.skeleton.joints();
    let mut joints = Vec::with_capacity(trs.len());
    let mut samplers = Vec::with_capacity(trs.len());
    for (j, tracks) in trs {
        let Some(rest) = joints_rest.get(j).map(|joint| joint.rest_local) else {
            continue;
        };
        if tracks.iter().flatten().all(|t| at_rest(t, &rest)) {
            continue;
        }
        resample |= tracks.iter().flatten().any(|t| needs_frames(t));
        joints.push(j);
        samplers.push(tracks.map(|t| t.map(Sampler::new)));
    }
    AnimPlan {
        prim,
        joints,
        trs: samplers,
        morphs,
        key_times: times.into_iter().map(f64::from).collect(),
        resample,
        location,
    }
}

/// Whether every key of a joint track holds the joint's rest value (cubic tangents zero):
/// translations and scales exactly (`-0 == 0`), rotations as the same unit quaternion up to sign
/// within 1e-7 per component (normalization noise).
fn at_rest(track: &Track, rest: &Transform) -> bool {
    let cubic = track.interpolation == Interpolation::CubicSpline;
    let c = track.components();
    let value: Vec<f32> = match track.target {
        TrackTarget::Translation(_) => rest.translation.to_array().to_vec(),
        TrackTarget::Scale(_) => rest.scale.to_array().to_vec(),
        TrackTarget::Rotation(_) => rest.rotation.to_array().to_vec(),
        TrackTarget::MorphWeights(_) => return false,
    };
    let rest_q = unit(rest.rotation.to_array().map(f64::from));
    let stride = if cubic { 3 * c } else { c };
    if c == 0 || track.values.len() != stride * track.times.len() {
        return false;
    }
    track.values.chunks_exact(stride).all(|key| {
        let (tangents_zero, v) = if cubic {
            let zero = key[..c].iter().chain(&key[2 * c..]).all(|&x| x == 0.0);
            (zero, &key[c..2 * c])
        } else {
            (true, key)
        };
        let same = match track.target {
            TrackTarget::Rotation(_) => {
                let q = unit([v[0], v[1], v[2], v[3]].map(f64::from));
                let sign = if dot(q.map(f64::from), rest_q.map(f64::from)) < 0.0 {
                    -1.0
                } else {
                    1.0
                };
                q.iter()
                    .zip(&rest_q)
                    .all(|(a, b)| (sign * a - b).abs() <= 1e-7)
            }
            _ => v.iter().zip(&value).all(|(a, b)| a == b),
        };
        tangents_zero && same
    })
}

/// Relative precision of an `f32` key time, with slack: 2⁻²¹ is four times the largest
/// relative rounding error of one `f32` operation (2⁻²³ spacing, halved, doubled twice), so
/// times computed as `k · frame_time` in `f32` pass while a frame off does not.
const F32_NOISE: f64 = 4.768_371_582_031_25e-7; // 2^-21

/// The stage rate for a clip's key times (seconds, ascending, distinct):
///
/// 1. three or more keys evenly spaced (within `f32` noise) at 24 or more per second: that rate,
///    `1 / spacing`, rounded to an integer when within `f32` noise of one, so BVH's
///    `Frame Time: 0.0333333` gives 30.00003 and keys land on integral time codes exactly
///    (rounding to 30 would shift key k by k·1e-6 frames, 1e-5 of the motion by the end
///    of a fast clip);
/// 2. else the first of: the rate the smallest key interval suggests (when at least 24),
///    24, 25, 30, 48, 50, 60, 100, 120, 240, and for sparse keys (say every 0.5 s, which
///    fit 2 per second, too slow to play or to resample) the smallest multiple of the
///    suggested rate from 24 up, that puts every key on an integral frame (within
///    [`frame_noise`]).
///
/// `None` for fewer than two keys or no fit.
pub(super) fn frame_rate(times: &[f64]) -> Option<f64> {
    let (&first, &last) = (times.first()?, times.last()?);
    let n = times.len();
    if n < 2 || last <= first {
        return None;
    }
    let spacing = (last - first) / (n - 1) as f64;
    // Two keys are always evenly spaced; a rate needs three.
    let even = n >= 3
        && times.iter().enumerate().all(|(k, &t)| {
            (t - (first + k as f64 * spacing)).abs() <= t.abs().max(spacing) * F32_NOISE
        });
    if even {
        let rate = 1.0 / spacing;
        if (MIN_FRAME_RATE..=10_000.0).contains(&rate) {
            let whole = rate.round();
            return Some(if (rate - whole).abs() <= rate * F32_NOISE {
                whole
            } else {
                rate
            });
        }
    }
    let min_gap = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|&d| d > 0.0)
        .fold(f64::INFINITY, f64::min);
    let suggested = (1.0 / min_gap).round();
    // The smallest gap's rate exactly when it is a ratio with a small denominator
    // (37.5 = 75/2 keys per second): keys dropped by a reducer leave uneven gaps, but
    // every key is still on that rate's frames. The gap of two f32 times is imprecise, so
    // the rate is refined over the whole span (frames between the first and last key at
    // the gap's rate), then snapped to k/n only when within f32 noise.
    let span = last - first;
    let frames = (span / min_gap).round();
    let exact = (frames >= 1.0).then(|| frames / span).and_then(|r| {
        (1..=8).find_map(|k| {
            let rk = r * k as f64;
            let whole = rk.round();
            ((rk - whole).abs() <= rk * F32_NOISE * 4.0 && whole > 0.0).then(|| whole / k as f64)
        })
    });
    let candidates: Vec<f64> = if suggested >= MIN_FRAME_RATE {
        exact
            .filter(|&e| e >= MIN_FRAME_RATE && e != suggested)
            .into_iter()
            .chain(std::iter::once(suggested))
            .chain(COMMON_RATES)
            .collect()
    } else {
        let multiple = suggested * (MIN_FRAME_RATE / suggested.max(1.0)).ceil();
        COMMON_RATES.into_iter().chain([multiple]).collect()
    };
    candidates
        .into_iter()
        .filter(|r| (1.0..=10_000.0).contains(r))
        .find(|&r| {
            times.iter().all(|&t| {
                let f = t * r;
                (f - f.round()).abs() <= frame_noise(f)
            })
        })
}

/// How far from an integer a time code may be and still count as on a frame: 1e-3
/// frames, or the `f32` noise of the key time it came from when larger. Key times written
/// with a few decimals (glTF exporters' `0.0416666` for 1/24 s, accumulated in `f32`) land
/// within 1e-5 frames of a frame; 1e-3 keeps real sub-frame keys apart. `check_usd.py`
/// maps dump times to time codes with the same rule.
fn frame_noise(tc: f64) -> f64 {
    1e-3_f64.max(tc.abs() * F32_NOISE)
}

/// A time code snapped to the nearest integer when within `f32` noise of it (see
/// [`frame_noise`]), so keys on frames are written as whole frames.
fn snap(tc: f64) -> f64 {
    let n = tc.round();
    if (tc - n).abs() <= frame_noise(tc) {
        // `+ 0.0` turns -0 into 0.
        n + 0.0
    } else {
        tc
    }
}

/// The `(time code, seconds)` samples of a clip: every key time, plus every frame at
/// `resample_fps` between the first and last key when a step or cubic-spline track needs
/// them (USD interpolates time samples linearly, slerping quaternions). Time codes that
/// snap to the same value are written once, keys first.
pub(super) fn sample_times(
    anim: &AnimPlan<'_>,
    tcps: f64,
    resample_fps: f64,
    warnings: &mut Vec<Warning>,
) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(anim.key_times.len());
    for &t in &anim.key_times {
        let tc = snap(t * tcps);
        if out.last().is_none_or(|&(last, _)| last != tc) {
            out.push((tc, t));
        }
    }
    let (Some(&first), Some(&last)) = (anim.key_times.first(), anim.key_times.last()) else {
        return out;
    };
    if !anim.resample {
        return out;
    }
    let k0 = (first * resample_fps).ceil();
    let k1 = (last * resample_fps).floor();
    if k1 - k0 > MAX_RESAMPLED_FRAMES {
        warnings.push(Warning::Repaired {
            location: anim.location.clone(),
            message: format!(
                "step and cubic-spline tracks sampled at their keys only ({} frames at {resample_fps} fps would be too many); USD interpolates linearly between them",
                k1 - k0
            ),
        });
        return out;
    }
    let keys: Vec<f64> = out.iter().map(|&(tc, _)| tc).collect();
    let tol = frame_noise(last * tcps);
    let mut k = k0;
    while k <= k1 {
        let t = k / resample_fps;
        let tc = snap(t * tcps);
        let i = keys.partition_point(|&x| x < tc);
        let clash = [i.checked_sub(1), Some(i)]
            .into_iter()
            .flatten()
            .filter_map(|i| keys.get(i))
            .any(|&x| (x - tc).abs() <= tol);
        if !clash {
            out.push((tc, t));
        }
        k += 1.0;
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    warnings.push(Warning::Repaired {
        location: anim.location.clone(),
        message: format!(
            "step and cubic-spline tracks sampled at {resample_fps} fps: USD interpolates time \
             samples linearly, so the motion is exact at every key and every 1/{resample_fps} s"
        ),
    });
    out
}

/// A quaternion `(w, x, y, z)` (USD's quatf order) from xyzw, `-0` as `0`.
fn wxyz(q: &[f32; 4]) -> [f32; 4] {
    zeroed([q[3], q[0], q[1], q[2]])
}

/// The rest pose of an animation's joints: translations, rotations (xyzw), scales (as
/// written, half-rounded).
struct PoseSample {
    t: Vec<[f32; 3]>,
    r: Vec<[f32; 4]>,
    s: Vec<[f32; 3]>,
}

/// Writes one SkelAnimation: defaults (the rest pose and default morph weights), then
/// time samples at `times`.
pub(super) fn write_animation(
    doc: &mut dyn LayerSink,
    asset: &Asset,
    plans: &[MeshPlan],
    joint_tokens: &[String],
    anim: &AnimPlan<'_>,
    times: &[(f64, f64)],
    warnings: &mut Vec<Warning>,
) {
    let joints = asset.skeleton.joints();
    let rest: Vec<Transform> = anim
        .joints
        .iter()
        .filter_map(|&j| joints.get(j).map(|joint| joint.rest_local))
        .collect();
    let mut half_error = HalfError::default();
    let rest_pose = PoseSample {
        t: rest.iter().map(|r| r.translation.to_array()).collect(),
        r: rest
            .iter()
            .map(|r| unit(r.rotation.to_array().map(f64::from)))
            .collect(),
        s: rest
            .iter()
            .map(|r| half_error.round(r.scale.to_array()))
            .collect(),
    };
    // Blend-shape channels of every mesh, in mesh order.
    let channels: Vec<&str> = plans
        .iter()
        .flat_map(|p| p.channels.iter().map(String::as_str))
        .collect();
    let default_weights: Vec<f32> = plans
        .iter()
        .zip(&asset.meshes)
        .flat_map(|(p, m)| {
            (0..p.channels.len()).map(|k| zero(m.morph_weights.get(k).copied().unwrap_or(0.0)))
        })
        .collect();

    doc.begin_prim(Specifier::Def, Some("SkelAnimation"), &anim.prim, &[]);
    if !channels.is_empty() {
        doc.attribute(
            AttrDecl::uniform("token[]", "blendShapes"),
            Some(Data::Strs(&channels)),
            &[],
        );
        let weights_decl = AttrDecl::new("float[]", "blendShapeWeights");
        doc.attribute(weights_decl, Some(Data::Floats(&default_weights)), &[]);
        if !anim.morphs.is_empty() && !times.is_empty() {
            doc.begin_time_samples(weights_decl);
            let mut weights = default_weights.clone();
            let mut buf = Vec::new();
            for &(tc, seconds) in times {
                let mut offset = 0;
                for (mi, plan) in plans.iter().enumerate() {
                    let n = plan.channels.len();
                    if let Some(sampler) = anim.morphs.get(&mi) {
                        buf.resize(n, 0.0);
                        sampler.sample(seconds, &mut buf);
                        for (w, v) in weights.iter_mut().skip(offset).zip(&buf) {
                            *w = zero(*v as f32);
                        }
                    }
                    offset += n;
                }
                doc.time_sample(tc, Data::Floats(&weights));
            }
            doc.end_time_samples();
        }
    }
    let tokens: Vec<&str> = anim
        .joints
        .iter()
        .filter_map(|&j| joint_tokens.get(j).map(String::as_str))
        .collect();
    doc.attribute(
        AttrDecl::uniform("token[]", "joints"),
        Some(Data::Strs(&tokens)),
        &[],
    );

    // Each attribute's time samples are computed as they are written (a pose at a time),
    // so a clip of millions of frames never holds its poses.
    let times = if anim.joints.is_empty() { &[] } else { times };
    let mut value = [0.0_f64; 4];
    write_attribute(
        doc,
        AttrDecl::new("quatf[]", "rotations"),
        &rest_pose.r,
        times,
        wxyz,
        |seconds, previous, out| {
            for (k, (samplers, rest)) in anim.trs.iter().zip(&rest).enumerate() {
                let mut q = match &samplers[1] {
                    Some(s) => {
                        s.sample(seconds, &mut value);
                        unit(value)
                    }
                    None => unit(rest.rotation.to_array().map(f64::from)),
                };
                // Sign-continuous samples, so any interpolation between them takes the
                // short arc.
                if let Some(prev) = previous.get(k) {
                    if dot(prev.map(f64::from), q.map(f64::from)) < 0.0 {
                        q = q.map(|c| -c);
                    }
                }
                out.push(q);
            }
        },
    );
    write_attribute(
        doc,
        AttrDecl::new("half3[]", "scales"),
        &rest_pose.s,
        times,
        |v| zeroed(*v),
        |seconds, _, out| {
            for (samplers, rest) in anim.trs.iter().zip(&rest) {
                out.push(match &samplers[2] {
                    Some(s) => {
                        s.sample(seconds, &mut value);
                        half_error.round([value[0], value[1], value[2]].map(|v| v as f32))
                    }
                    None => half_error.round(rest.scale.to_array()),
                });
            }
        },
    );
    write_attribute(
        doc,
        AttrDecl::new("float3[]", "translations"),
        &rest_pose.t,
        times,
        |v| zeroed(*v),
        |seconds, _, out| {
            for (samplers, rest) in anim.trs.iter().zip(&rest) {
                out.push(match &samplers[0] {
                    Some(s) => {
                        s.sample(seconds, &mut value);
                        [value[0], value[1], value[2]].map(|v| v as f32)
                    }
                    None => rest.translation.to_array(),
                });
            }
        },
    );
    doc.end_prim();
    if half_error.worst > HALF_REPORT_TOLERANCE {
        warnings.push(Warning::Repaired {
            location: anim.location.clone(),
            message: format!(
                "{} scale values rounded to half precision (SkelAnimation scales are half3[]); largest relative change {:.2e}",
                half_error.count, half_error.worst
            ),
        });
    }
}

/// Writes `decl = [rest...]` and, when `times` is not empty, `decl.timeSamples` with one
/// array per `(time code, seconds)`: `pose(seconds, previous, out)` pushes the values at
/// `seconds` into the empty `out`, `previous` holding those of the time before (empty at
/// the first). Each value goes to the sink as `written(value)`.
fn write_attribute<T, const N: usize>(
    doc: &mut dyn LayerSink,
    decl: AttrDecl<'_>,
    rest: &[T],
    times: &[(f64, f64)],
    written: impl Fn(&T) -> [f32; N],
    mut pose: impl FnMut(f64, &[T], &mut Vec<T>),
) where
    for<'v> &'v [[f32; N]]: Into<Data<'v>>,
{
    let mut out: Vec<[f32; N]> = rest.iter().map(&written).collect();
    doc.attribute(decl, Some(out.as_slice().into()), &[]);
    if times.is_empty() {
        return;
    }
    doc.begin_time_samples(decl);
    let mut previous: Vec<T> = Vec::new();
    let mut current: Vec<T> = Vec::with_capacity(rest.len());
    for &(tc, seconds) in times {
        current.clear();
        pose(seconds, &previous, &mut current);
        out.clear();
        out.extend(current.iter().map(&written));
        doc.time_sample(tc, out.as_slice().into());
        std::mem::swap(&mut previous, &mut current);
    }
    doc.end_time_samples();
}

/// Tracks the largest relative change made by rounding scales to half precision.
#[derive(Default)]
struct HalfError {
    worst: f32,
    count: usize,
}

impl HalfError {
    /// Rounds to half precision, recording the change.
    fn round(&mut self, v: [f32; 3]) -> [f32; 3] {
        v.map(|x| {
            let h = to_half(x);
            let rel = if x == 0.0 { 0.0 } else { ((h - x) / x).abs() };
            if rel > HALF_REPORT_TOLERANCE {
                self.count += 1;
            }
            self.worst = self.worst.max(rel);
            h
        })
    }
}

/// A unit quaternion (xyzw, `f32`) from an `f64` one.
fn unit(q: [f64; 4]) -> [f32; 4] {
    let len = dot(q, q).sqrt();
    if len > 0.0 {
        q.map(|c| (c / len) as f32)
    } else {
        [0.0, 0.0, 0.0, 1.0]
    }
}
