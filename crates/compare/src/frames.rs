//! A clip compared frame by frame: both sides evaluated at each time (the candidate at
//! that time plus an offset), in parallel over fixed chunks of frames merged in order, so
//! the result does not depend on the thread count; and the search for the time offset
//! that makes two clips agree.

use rayon::prelude::*;
use rigport_eval::sample::CompiledClip;

use crate::deviation::{ClipDeviation, JointPair, MeshPair};
use crate::side::{Posed, Scratch, Side};
use crate::CompareError;

/// Frames per parallel chunk.
const CHUNK: usize = 8;
/// Shifts tried each way when searching a time offset, in frames.
const MAX_SHIFT_FRAMES: i32 = 30;
/// Times probed per shift when searching a time offset.
const PROBES: usize = 64;

/// What is compared: each side's clip (`None`: the rest pose), the times (seconds, on the
/// reference's clock) and the candidate's offset (its time = reference time + `offset`).
#[derive(Clone, Copy)]
pub struct Sampling<'c> {
    /// The reference's clip.
    pub reference: Option<&'c CompiledClip<'c>>,
    /// The candidate's clip.
    pub candidate: Option<&'c CompiledClip<'c>>,
    /// Times to compare.
    pub times: &'c [f32],
    /// Seconds added to each time for the candidate.
    pub offset: f32,
    /// The candidate's own time for each of `times`, when it differs from `time + offset`
    /// (its key at a time `f32` rounding moved off the reference's): `None` for all.
    pub candidate_times: Option<&'c [f32]>,
}

/// Compares `reference` and `candidate` at every time of `sampling`.
///
/// # Errors
/// A clip does not fit its skeleton, or a pose cannot be evaluated.
pub fn compare_frames(
    reference: &Side<'_>,
    candidate: &Side<'_>,
    joints: &[JointPair],
    meshes: &[MeshPair],
    sampling: &Sampling<'_>,
) -> Result<ClipDeviation, CompareError> {
    let chunks: Vec<(usize, &[f32])> = sampling
        .times
        .chunks(CHUNK)
        .enumerate()
        .map(|(k, c)| (k * CHUNK, c))
        .collect();
    let partials = chunks
        .par_iter()
        .map(|&(first, times)| -> Result<ClipDeviation, CompareError> {
            let mut dev = ClipDeviation::new(meshes);
            let (mut rs, mut cs) = (Scratch::default(), Scratch::default());
            let (mut rp, mut cp) = (Posed::default(), Posed::default());
            for (k, &t) in times.iter().enumerate() {
                reference.evaluate(sampling.reference, t, true, &mut rs, &mut rp)?;
                let own = sampling.candidate_times.and_then(|c| c.get(first + k));
                let tc = own.copied().unwrap_or(t + sampling.offset);
                candidate.evaluate(sampling.candidate, tc, true, &mut cs, &mut cp)?;
                dev.add_frame(first + k, t, &rp, &cp, joints, meshes);
            }
            Ok(dev)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut total = ClipDeviation::new(meshes);
    for part in &partials {
        total.merge(part);
    }
    Ok(total)
}

/// The time offset (seconds, candidate time minus reference time) that brings the paired
/// joints of the candidate's clip within `within` metres of the reference's at every
/// probed time where both play, if there is one other than 0. Shifts are whole frames
/// (the finer of both clips' key spacings) from 0 and from the difference of the clips'
/// starts, up to 30 frames each way, probed at up to 64 of `times`.
///
/// # Errors
/// As [`compare_frames`].
pub fn find_time_offset(
    reference: &Side<'_>,
    candidate: &Side<'_>,
    joints: &[JointPair],
    clips: (&CompiledClip<'_>, &CompiledClip<'_>),
    times: &[f32],
    within: f64,
) -> Result<Option<f32>, CompareError> {
    let (rc, cc) = clips;
    let period = [rc.fps(), cc.fps()]
        .into_iter()
        .flatten()
        .map(|fps| 1.0 / fps)
        .fold(f32::INFINITY, f32::min);
    if !period.is_finite() || times.is_empty() || joints.is_empty() {
        return Ok(None);
    }
    let step = times.len().div_ceil(PROBES).max(1);
    let probes: Vec<f32> = times.iter().step_by(step).copied().collect();
    let mut scratch = Scratch::default();
    let mut posed = Posed::default();
    let mut wanted = Vec::with_capacity(probes.len());
    for &t in &probes {
        reference.evaluate(Some(rc), t, false, &mut scratch, &mut posed)?;
        wanted.push(posed.joint_positions.clone());
    }
    let start_gap = cc.start() - rc.start();
    let mut shifts: Vec<f32> = (-MAX_SHIFT_FRAMES..=MAX_SHIFT_FRAMES)
        .flat_map(|k| [k as f32 * period, start_gap + k as f32 * period])
        .filter(|s| s.abs() >= 0.5 * period)
        .collect();
    shifts.sort_by(f32::total_cmp);
    shifts.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    let slack = 1e-4 * period;
    let mut best: Option<(f64, f32)> = None;
    let mut scratch = Scratch::default();
    for &shift in &shifts {
        let mut worst = 0.0f64;
        let mut overlap = 0;
        for (t, want) in probes.iter().zip(&wanted) {
            let tc = t + shift;
            if tc < cc.start() - slack || tc > cc.end() + slack {
                continue;
            }
            overlap += 1;
            candidate.evaluate(Some(cc), tc, false, &mut scratch, &mut posed)?;
            for pair in joints {
                if let (Some(a), Some(b)) = (
                    want.get(pair.reference),
                    posed.joint_positions.get(pair.candidate),
                ) {
                    worst = worst.max(a.distance(*b));
                }
            }
            if worst > within {
                break;
            }
        }
        if 2 * overlap < probes.len() || worst > within {
            continue;
        }
        if best.is_none_or(|(w, _)| worst < w) {
            best = Some((worst, shift));
        }
    }
    Ok(best.map(|(_, shift)| shift))
}
