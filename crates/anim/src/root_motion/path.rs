//! The hips' path over a clip: the hips' model-space position and heading at every key
//! time, their smoothed ground-plane path, and the travel it makes.
//!
//! Smoothing is a local linear regression (a straight line fitted by least squares to the
//! samples within `window / 2` of each time, read at that time). Inside the clip it equals
//! a centred moving average (the window is symmetric), so over one gait cycle it removes
//! the sway a cycle repeats; at the clip's ends, where the window is cut off, the fitted
//! line still follows a steady walk exactly, which a moving average would pull towards the
//! inside. A window of 0 (or shorter than a frame) keeps every sample: the path is the
//! hips' own ground position and heading.

use std::f64::consts::TAU;

use glam::{DMat4, DQuat, DVec3, Vec3};
use rigport_eval::sample::{rest_locals, sample_frames, CompiledClip};
use rigport_model::{Clip, JointIndex, Skeleton, Transform};

use super::RootMotionError;

/// A clip sampled at its key times, with the hips' path.
pub(super) struct ClipPath {
    /// The clip's key times (seconds), strictly increasing.
    pub times: Vec<f32>,
    /// Local transforms, `times.len() × joints`, frame-major.
    pub frames: Vec<Transform>,
    /// The smoothed path per time: ground-plane position (model space, no up component).
    pub ground: Vec<DVec3>,
    /// The smoothed heading per time (radians about up, counter-clockwise, unwrapped).
    pub heading: Vec<f64>,
}

/// `skeleton`'s joint `j` as a TRS in f64.
pub(super) fn trs(t: &Transform) -> (DVec3, DQuat, DVec3) {
    (
        t.translation.as_dvec3(),
        t.rotation.as_dquat().normalize(),
        t.scale.as_dvec3(),
    )
}

fn matrix(t: &Transform) -> DMat4 {
    let (translation, rotation, scale) = trs(t);
    DMat4::from_scale_rotation_translation(scale, rotation, translation)
}

/// The joints from the top of `joint`'s hierarchy down to `joint`, top first.
pub(super) fn chain(skeleton: &Skeleton, joint: JointIndex) -> Vec<JointIndex> {
    let mut out = vec![joint];
    while let Some(p) = out.last().and_then(|&j| skeleton.joint(j).parent) {
        out.push(p);
    }
    out.reverse();
    out
}

/// Samples `clip` at its key times and measures the hips' smoothed path (see the module
/// docs). `up` is the model-space up direction (unit length); `window_s` the smoothing
/// window in seconds.
pub(super) fn measure(
    skeleton: &Skeleton,
    clip: &Clip,
    hips: JointIndex,
    up: Vec3,
    window_s: f32,
) -> Result<ClipPath, RootMotionError> {
    let compiled = CompiledClip::new(clip, skeleton).map_err(RootMotionError::Clip)?;
    let times = compiled.key_times();
    let frames = sample_frames(&compiled, &rest_locals(skeleton), &times)
        .map_err(RootMotionError::Sample)?;
    let joints = skeleton.len();
    let chain = chain(skeleton, hips);
    let up = up.as_dvec3();
    let (e1, _) = up.any_orthonormal_pair();
    let e2 = up.cross(e1);
    let mut ground = Vec::with_capacity(times.len());
    let mut heading = Vec::with_capacity(times.len());
    // The hips axis whose heading is followed: the one furthest from up in the first frame.
    let mut axis: Option<DVec3> = None;
    for local in frames.chunks_exact(joints.max(1)) {
        let model = chain
            .iter()
            .fold(DMat4::IDENTITY, |m, j| m * matrix(&local[j.get()]));
        let p = model.w_axis.truncate();
        ground.push(p - p.dot(up) * up);
        let axis = *axis.get_or_insert_with(|| {
            [DVec3::X, DVec3::Y, DVec3::Z]
                .into_iter()
                .min_by(|a, b| {
                    let (a, b) = (model.transform_vector3(*a), model.transform_vector3(*b));
                    (a.normalize_or_zero().dot(up).abs())
                        .total_cmp(&b.normalize_or_zero().dot(up).abs())
                })
                .unwrap_or(DVec3::X)
        });
        let d = model.transform_vector3(axis);
        let angle = d.dot(e2).atan2(d.dot(e1));
        heading.push(match heading.last() {
            Some(&previous) => previous + wrap(angle - previous),
            None => angle,
        });
    }
    let seconds: Vec<f64> = times.iter().map(|&t| f64::from(t)).collect();
    let window = f64::from(window_s.max(0.0));
    let smoothed = |values: &[f64]| smooth(&seconds, values, window);
    let x = smoothed(&ground.iter().map(|g| g.dot(e1)).collect::<Vec<_>>());
    let y = smoothed(&ground.iter().map(|g| g.dot(e2)).collect::<Vec<_>>());
    Ok(ClipPath {
        ground: x.iter().zip(&y).map(|(&x, &y)| x * e1 + y * e2).collect(),
        heading: smoothed(&heading),
        times,
        frames,
    })
}

/// `angle` wrapped into `(-π, π]`.
fn wrap(angle: f64) -> f64 {
    let a = angle.rem_euclid(TAU);
    if a > TAU / 2.0 {
        a - TAU
    } else {
        a
    }
}

/// Local linear regression of `values` over `times` (seconds, increasing): at each time,
/// the least-squares line through the samples within `window / 2`, read at that time. A
/// window holding one sample (or samples at one time) gives the sample's own value.
pub fn smooth(times: &[f64], values: &[f64], window: f64) -> Vec<f64> {
    let half = window / 2.0;
    let (mut lo, mut hi) = (0, 0);
    let mut out = Vec::with_capacity(values.len());
    for (i, (&t, &v)) in times.iter().zip(values).enumerate() {
        while times[lo] < t - half {
            lo += 1;
        }
        hi = hi.max(i + 1);
        while hi < times.len() && times[hi] <= t + half {
            hi += 1;
        }
        let (ts, vs) = (&times[lo..hi], &values[lo..hi]);
        let n = ts.len() as f64;
        // Centred on `t`, so the intercept is the value at `t`.
        let mean_t = ts.iter().map(|&s| s - t).sum::<f64>() / n;
        let mean_v = vs.iter().sum::<f64>() / n;
        let (mut stt, mut stv) = (0.0, 0.0);
        for (&s, &w) in ts.iter().zip(vs) {
            let dt = s - t - mean_t;
            stt += dt * dt;
            stv += dt * (w - mean_v);
        }
        out.push(if n < 2.0 || stt <= 0.0 {
            if n < 2.0 {
                v
            } else {
                mean_v
            }
        } else {
            mean_v - (stv / stt) * mean_t
        });
    }
    out
}
