//! Small clips and skeletons for the tests of the evaluator and of the crates built on it
//! (`rigport-anim`, `rigport-ik`, `rigport-deform`), which enable the `test-support`
//! feature as a dev-dependency. Not part of the public API.

use glam::{EulerRot, Quat, Vec3};
use rigport_model::{
    Clip, Interpolation, Joint, JointIndex, Skeleton, Track, TrackTarget, Transform,
};

use crate::sample::{bake, rest_locals, ChannelMask, CompiledClip, SampleJob};

/// A chain of `n` joints with distinct rest transforms.
pub fn chain(n: usize) -> Skeleton {
    let joints = (0..n)
        .map(|i| Joint {
            name: format!("j{i}"),
            parent: i.checked_sub(1).map(|p| JointIndex(p as u32)),
            rest_local: Transform {
                translation: Vec3::new(0.1 * i as f32, 1.0, -0.2),
                rotation: Quat::from_rotation_z(0.1 * i as f32),
                scale: Vec3::splat(1.0 + 0.01 * i as f32),
            },
        })
        .collect();
    Skeleton::new(joints).expect("a chain is a valid skeleton")
}

/// A smooth clip on `skeleton`: per joint a rotation of the form
/// `euler(a·sin(w·t + p), a/2·cos(w·t), 0.3·sin(2w·t))` (`params[j % len] = (a, w, p)`),
/// plus a root translation walking along +X and +Z with a vertical bob, keyed `frames`
/// times at `fps` (LINEAR, via [`bake`] so keys are unit and sign-continuous).
pub fn smooth_clip(joints: usize, frames: usize, fps: f32, params: &[(f32, f32, f32)]) -> Clip {
    let times: Vec<f32> = (0..frames).map(|k| k as f32 / fps).collect();
    let mut poses = Vec::with_capacity(frames * joints);
    for &t in &times {
        for j in 0..joints {
            let (a, w, p) = params[j % params.len()];
            poses.push(Transform {
                translation: Vec3::new(1.3 * t, 1.0 + 0.05 * (6.0 * t).sin(), 0.2 * t),
                rotation: Quat::from_euler(
                    EulerRot::ZYX,
                    a * (w * t + p).sin(),
                    0.5 * a * (w * t).cos(),
                    0.3 * (2.0 * w * t).sin(),
                ),
                scale: Vec3::ONE,
            });
        }
    }
    let mut mask = ChannelMask::none(joints);
    mask.rotation = vec![true; joints];
    mask.translation[0] = true;
    bake("smooth", &times, &poses, &mask).expect("the smooth clip bakes")
}

pub fn track(
    target: TrackTarget,
    interpolation: Interpolation,
    times: &[f32],
    values: &[f32],
) -> Track {
    Track {
        target,
        interpolation,
        times: times.to_vec(),
        values: values.to_vec(),
    }
}

pub fn rot(j: u32) -> TrackTarget {
    TrackTarget::Rotation(JointIndex(j))
}

pub fn tra(j: u32) -> TrackTarget {
    TrackTarget::Translation(JointIndex(j))
}

pub fn sample_at(clip: &Clip, skeleton: &Skeleton, time: f32) -> Vec<Transform> {
    let compiled = CompiledClip::new(clip, skeleton).expect("the clip fits the skeleton");
    let rest = rest_locals(skeleton);
    let mut out = vec![Transform::IDENTITY; skeleton.len()];
    SampleJob {
        clip: &compiled,
        time,
        rest: &rest,
        output: &mut out,
    }
    .run()
    .expect("sampling a compiled clip");
    out
}

/// Angle in radians between the rotations two quaternions represent.
///
/// Kahan's `2·atan2(|a−b|, |a+b|)` (times 2: quaternions use half angles); `acos` of a
/// float32 dot product near 1 is off by ~1e-3 rad for identical inputs.
pub fn angle(a: Quat, b: Quat) -> f32 {
    let (a, b) = (a.normalize(), b.normalize());
    let b = if a.dot(b) < 0.0 { -b } else { b };
    4.0 * (a - b).length().atan2((a + b).length())
}
