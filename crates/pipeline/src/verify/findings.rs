//! The comparison itself: both assets seen +Y up in metres, paired (`pairing`), the
//! placement fitted on the paired joints at rest, vertex maps, and each chosen clip pair
//! compared at its times, at a time offset when that explains it ([`Findings`]).

use rigport_compare::deviation::{ClipDeviation, MeshPair};
use rigport_compare::frames::{Sampling, compare_frames, find_time_offset};
use rigport_compare::glam::{DMat4, DVec3};
use rigport_compare::side::{Posed, Scratch, Side};
use rigport_compare::similarity::{self, Similarity};
use rigport_compare::vertex_map::map_vertices;
use rigport_eval::sample::{CompiledClip, FrameGrid};
use rigport_model::Asset;

use super::options::{Clips, Times, VerifyOptions};
use super::pairing;
use crate::PipelineError;

/// A clip pair's comparison.
pub(crate) struct ClipResult {
    /// Reference and candidate clip indices (`None`: the rest pose).
    pub clips: (Option<usize>, Option<usize>),
    /// Times compared (seconds, reference clock).
    pub times: Vec<f32>,
    /// How the times were chosen.
    pub times_kind: Times,
    /// The candidate's time offset found, if any.
    pub offset: Option<f32>,
    /// The deviations (at that offset).
    pub deviation: ClipDeviation,
    /// Within the tolerance.
    pub passed: bool,
}

/// Everything the report says.
pub(crate) struct Findings<'a> {
    pub labels: (String, String),
    pub assets: (&'a Asset, &'a Asset),
    pub diagonal: f64,
    pub tolerance: f64,
    pub joints: pairing::Paired,
    pub meshes: pairing::Paired,
    pub mesh_pairs: Vec<MeshPair>,
    pub morphs_only: Vec<(usize, Vec<String>, Vec<String>)>,
    pub clips: pairing::Paired,
    pub placement: Option<Similarity>,
    pub results: Vec<ClipResult>,
}

impl Findings<'_> {
    /// The distance within the tolerance (metres).
    pub(crate) fn within(&self) -> f64 {
        self.tolerance * self.diagonal
    }

    /// The verdict.
    pub(crate) fn passed(&self) -> bool {
        self.placement.is_none()
            && self.meshes.only_reference.is_empty()
            && self.meshes.only_candidate.is_empty()
            && self.clips.only_reference.is_empty()
            && self.clips.only_candidate.is_empty()
            && self.morphs_only.is_empty()
            && self.results.iter().all(|r| r.passed && r.offset.is_none())
    }
}

/// A side's model space -> +Y up metres.
pub(crate) fn frame_of(asset: &Asset) -> DMat4 {
    asset.frame.model_to_gltf(asset.meters_per_unit)
}

/// The error of a comparison step.
fn failed(what: &str, e: rigport_compare::CompareError) -> PipelineError {
    PipelineError::step(what.to_string(), e)
}

/// Pairs, fits, maps and compares.
pub(crate) fn compare<'a>(
    reference: &'a Asset,
    candidate: &'a Asset,
    labels: (String, String),
    options: &VerifyOptions,
) -> Result<Findings<'a>, PipelineError> {
    let ref_side = Side::new(reference, frame_of(reference))
        .map_err(|e| failed(&format!("{}: cannot be evaluated", labels.0), e))?;
    let mut cand_side = Side::new(candidate, frame_of(candidate))
        .map_err(|e| failed(&format!("{}: cannot be evaluated", labels.1), e))?;
    let (joints, joint_pairs) = pairing::pair_joints(&reference.skeleton, &candidate.skeleton);
    let mesh_names = |a: &Asset| a.meshes.iter().map(|m| m.name.clone()).collect::<Vec<_>>();
    let (rm, cm) = (mesh_names(reference), mesh_names(candidate));
    let meshes = pairing::pair_names(&as_strs(&rm), &as_strs(&cm), true);
    let clip_names = |a: &Asset| a.clips.iter().map(|c| c.name.clone()).collect::<Vec<_>>();
    let (rc, cc) = (clip_names(reference), clip_names(candidate));
    let clips = pairing::pair_names(&as_strs(&rc), &as_strs(&cc), true);

    let rest = |side: &Side<'_>| -> Result<Posed, PipelineError> {
        let mut posed = Posed::default();
        side.evaluate(None, 0.0, true, &mut Scratch::default(), &mut posed)
            .map_err(|e| failed("the rest pose cannot be evaluated", e))?;
        Ok(posed)
    };
    let ref_rest = rest(&ref_side)?;
    let diagonal = diagonal(&ref_rest);
    let within = options.tolerance * diagonal;

    // A unit, an axis or a placement: the paired joints at rest, one carried onto the
    // other by a similarity to within the tolerance (times the scale, as the candidate's
    // numbers are that much larger).
    let cand_rest = rest(&cand_side)?;
    let (a, b): (Vec<DVec3>, Vec<DVec3>) = joint_pairs
        .iter()
        .map(|p| {
            (
                ref_rest.joint_positions[p.reference],
                cand_rest.joint_positions[p.candidate],
            )
        })
        .unzip();
    let placement = similarity::fit(&a, &b)
        .filter(|(s, residual)| *residual <= within.max(1e-9) * s.scale.max(1.0))
        .map(|(s, _)| s)
        .filter(|s| !s.is_identity(within));
    if let Some(s) = placement {
        let undone = s.inverse() * cand_side.to_frame();
        cand_side = cand_side.with_frame(undone);
    }
    let cand_rest = if placement.is_some() {
        rest(&cand_side)?
    } else {
        cand_rest
    };

    let mut mesh_pairs = Vec::new();
    let mut morphs_only = Vec::new();
    for &(r, c, _) in &meshes.pairs {
        let map = map_vertices(
            (&ref_rest.positions[r], &reference.meshes[r].source_vertex),
            (&cand_rest.positions[c], &candidate.meshes[c].source_vertex),
            1e-4 * diagonal,
            1e-6 * diagonal,
        );
        mesh_pairs.push(MeshPair {
            reference: r,
            candidate: c,
            map,
        });
        let targets = |a: &Asset, m: usize| -> Vec<String> {
            a.meshes[m]
                .morph_targets
                .iter()
                .map(|t| t.name.clone())
                .collect()
        };
        let (rt, ct) = (targets(reference, r), targets(candidate, c));
        let morphs = pairing::pair_names(&as_strs(&rt), &as_strs(&ct), true);
        if !morphs.only_reference.is_empty() || !morphs.only_candidate.is_empty() {
            let names =
                |all: &[String], only: &[usize]| only.iter().map(|&k| all[k].clone()).collect();
            morphs_only.push((
                r,
                names(&rt, &morphs.only_reference),
                names(&ct, &morphs.only_candidate),
            ));
        }
    }

    let chosen: Vec<(Option<usize>, Option<usize>)> = match &options.clips {
        _ if reference.clips.is_empty() && candidate.clips.is_empty() => vec![(None, None)],
        Clips::All => clips
            .pairs
            .iter()
            .map(|&(r, c, _)| (Some(r), Some(c)))
            .collect(),
        Clips::First | Clips::Named(_) => {
            let name = match &options.clips {
                Clips::Named(n) => Some(n.as_str()),
                _ => None,
            };
            let r = reference
                .clip_index(name)
                .map_err(|e| PipelineError::Invalid(format!("{}: {e}", labels.0)))?;
            let c = r.and_then(|r| clips.pairs.iter().find(|p| p.0 == r).map(|p| p.1));
            match (r, c) {
                (Some(r), Some(c)) => vec![(Some(r), Some(c))],
                _ => Vec::new(),
            }
        }
    };
    let mut results = Vec::new();
    for (r, c) in chosen {
        results.push(compare_clip(
            (&ref_side, &cand_side),
            (r, c),
            (&joint_pairs, &mesh_pairs),
            options,
            within,
        )?);
    }
    Ok(Findings {
        labels,
        assets: (reference, candidate),
        diagonal,
        tolerance: options.tolerance,
        joints,
        meshes,
        mesh_pairs,
        morphs_only,
        clips,
        placement,
        results,
    })
}

/// One clip pair compared at its times, and at a time offset when that explains it.
fn compare_clip(
    sides: (&Side<'_>, &Side<'_>),
    clips: (Option<usize>, Option<usize>),
    pairs: (&[rigport_compare::deviation::JointPair], &[MeshPair]),
    options: &VerifyOptions,
    within: f64,
) -> Result<ClipResult, PipelineError> {
    let (rs, cs) = sides;
    let (rc, cc) = (
        compile_clip(rs.asset(), clips.0)?,
        compile_clip(cs.asset(), clips.1)?,
    );
    let times = times(rc.as_ref(), cc.as_ref(), options.times)?;
    let own = cc.as_ref().map(|c| own_key_times(&times, &c.key_times()));
    let mut sampling = Sampling {
        reference: rc.as_ref(),
        candidate: cc.as_ref(),
        times: &times,
        offset: 0.0,
        candidate_times: own.as_deref(),
    };
    let cannot = |e| failed("the clips cannot be compared", e);
    let deviation = compare_frames(rs, cs, pairs.0, pairs.1, &sampling).map_err(cannot)?;
    let measure = |d: &ClipDeviation| {
        if d.vertices.count > 0 {
            d.vertices.max
        } else {
            d.joint_positions.max
        }
    };
    let mut result = ClipResult {
        clips,
        times_kind: options.times,
        offset: None,
        passed: measure(&deviation) <= within,
        deviation,
        times: times.clone(),
    };
    if let (false, Some(r), Some(c)) = (result.passed, rc.as_ref(), cc.as_ref()) {
        if let Some(offset) =
            find_time_offset(rs, cs, pairs.0, (r, c), &times, within).map_err(cannot)?
        {
            let slack = 1e-4 / c.fps().unwrap_or(30.0);
            let shifted: Vec<f32> = times
                .iter()
                .copied()
                .filter(|t| t + offset >= c.start() - slack && t + offset <= c.end() + slack)
                .collect();
            sampling.times = &shifted;
            sampling.offset = offset;
            sampling.candidate_times = None;
            let deviation = compare_frames(rs, cs, pairs.0, pairs.1, &sampling).map_err(cannot)?;
            if measure(&deviation) <= within {
                result = ClipResult {
                    offset: Some(offset),
                    passed: true,
                    deviation,
                    times: shifted.clone(),
                    ..result
                };
            }
        }
    }
    Ok(result)
}

/// Clip `k` of `asset`, compiled (`None` for `None`).
///
/// # Errors
/// The clip does not fit the skeleton.
pub(crate) fn compile_clip(
    asset: &Asset,
    k: Option<usize>,
) -> Result<Option<CompiledClip<'_>>, PipelineError> {
    k.and_then(|k| asset.clips.get(k))
        .map(|clip| {
            CompiledClip::new(clip, &asset.skeleton).map_err(|e| {
                PipelineError::step(format!("clip {:?} does not fit the skeleton", clip.name), e)
            })
        })
        .transpose()
}

/// Whether two key times are one key moved by `f32` rounding (a few units in the last
/// place: a time written as a USD time code and read back, a clip start subtracted).
fn same_key(a: f32, b: f32) -> bool {
    (a - b).abs() <= 8.0 * f32::EPSILON * a.abs().max(b.abs()).max(1.0)
}

/// For each of `times`, the candidate's key at that time when it has one within rounding
/// (evaluated there, not a rounding step into its next segment), else the time itself.
fn own_key_times(times: &[f32], keys: &[f32]) -> Vec<f32> {
    times
        .iter()
        .map(|&t| {
            let at = keys.partition_point(|&k| k < t);
            let near = [at.checked_sub(1), Some(at)].into_iter().flatten();
            (near.filter_map(|i| keys.get(i).copied()))
                .find(|&k| same_key(k, t))
                .unwrap_or(t)
        })
        .collect()
}

/// The times to compare two clips at (`[0]` for the rest pose).
fn times(
    reference: Option<&CompiledClip<'_>>,
    candidate: Option<&CompiledClip<'_>>,
    kind: Times,
) -> Result<Vec<f32>, PipelineError> {
    let keys = |c: Option<&CompiledClip<'_>>| c.map(CompiledClip::key_times).unwrap_or_default();
    let (rk, ck) = (keys(reference), keys(candidate));
    let mut out = match kind {
        // A candidate key within `f32` rounding of a reference key is that key.
        Times::KeyUnion => {
            let own: Vec<f32> = (ck.iter().copied())
                .filter(|&c| !rk.iter().any(|&r| same_key(r, c)))
                .collect();
            [rk, own].concat()
        }
        Times::AtKeys => {
            let shared: Vec<f32> = rk
                .iter()
                .copied()
                .filter(|t| ck.iter().any(|u| (t - u).abs() <= 1e-5))
                .collect();
            if shared.is_empty() { rk } else { shared }
        }
        Times::Fps(fps) => {
            let all = [reference, candidate];
            let start = all
                .iter()
                .flatten()
                .map(|c| c.start())
                .fold(f32::INFINITY, f32::min);
            let end = all
                .iter()
                .flatten()
                .map(|c| c.end())
                .fold(f32::NEG_INFINITY, f32::max);
            if start.is_finite() && end.is_finite() {
                FrameGrid::new(start, end, fps)?.into_times()
            } else {
                Vec::new()
            }
        }
    };
    out.sort_by(f32::total_cmp);
    out.dedup_by(|a, b| (*a - *b).abs() <= 1e-6);
    if out.is_empty() {
        out.push(0.0);
    }
    Ok(out)
}

/// The diagonal of the bounding box of the reference's vertices at rest (of its joints
/// when it has none), at least 1e-9 m.
fn diagonal(rest: &Posed) -> f64 {
    let points: Vec<DVec3> = rest.positions.iter().flatten().copied().collect();
    let points = if points.is_empty() {
        &rest.joint_positions
    } else {
        &points
    };
    let Some(&first) = points.first() else {
        return 1e-9;
    };
    let (lo, hi) = points
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (hi - lo).length().max(1e-9)
}

/// Borrowed names.
fn as_strs(names: &[String]) -> Vec<&str> {
    names.iter().map(String::as_str).collect()
}
