//! The pre-roll: before frame 0 the body moves from the pose the garment was modelled on
//! (the rest pose) to the clip's first pose, and holds it while the garment settles, so
//! that frame 0 shows a settled garment rather than one snapped onto a posed body.
//!
//! Roots (joints without a parent) take their first-frame transform from the start, and
//! the garment is carried there rigidly by the first root's move ([`carry`]): a clip
//! starting metres from the origin, or turned, does not drag the garment across the scene.
//! Every other joint blends from rest to its first-frame transform (translation and scale
//! lerped, rotation slerped) over the first [`PREROLL_BLEND`] of the pre-roll, eased in and
//! out (smoothstep), then holds it.
//!
//! While the body holds, the garment settles by kinetic damping, as dynamic relaxation
//! finds the static shape of cables and membranes (Barnes 1999, "Form finding and
//! analysis of tension structures by dynamic relaxation"): whenever the garment's kinetic
//! energy passes a peak, every velocity is zeroed. It falls freely (no heavy damping
//! slowing it to a crawl) and stops at the bottom of its first swings.

use glam::Mat4;
use rigport_model::{Skeleton, Transform};

/// Default pre-roll, seconds: 0.5 s blending, 1.5 s holding. A flag 2.5 units long
/// falling from horizontal (the USTC course's arm, a body diagonal of 4.2 units) still
/// moves at 0.23 units/s at its end (0.038 after a 3 s pre-roll, 1.7 after 1 s); the
/// demo's skirt, which hangs close to its modelled shape, far less.
pub const PREROLL: f32 = 2.0;

/// The share of the pre-roll over which the body blends to the first pose (the rest holds
/// it).
pub const PREROLL_BLEND: f32 = 0.25;

/// The body's blend weight at fraction `u` (0..=1) of the pre-roll: 0 = rest, 1 = first
/// pose.
pub(crate) fn weight(u: f32) -> f32 {
    let x = (u / PREROLL_BLEND).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Local transforms between `rest` and `first` at weight `s` into `out` (roots at
/// `first` always).
pub(crate) fn blend(
    skeleton: &Skeleton,
    rest: &[Transform],
    first: &[Transform],
    s: f32,
    out: &mut [Transform],
) {
    for (j, ((o, r), f)) in out.iter_mut().zip(rest).zip(first).enumerate() {
        let root = skeleton
            .joints()
            .get(j)
            .is_none_or(|joint| joint.parent.is_none());
        *o = if root {
            *f
        } else {
            Transform {
                translation: r.translation.lerp(f.translation, s),
                rotation: r.rotation.slerp(f.rotation, s).normalize(),
                scale: r.scale.lerp(f.scale, s),
            }
        };
    }
}

/// The rigid move that carries the garment with the first root from its rest transform to
/// its first-frame one (identity without a root, or when the move is not finite).
pub(crate) fn carry(skeleton: &Skeleton, rest: &[Transform], first: &[Transform]) -> Mat4 {
    let Some(root) = skeleton.roots().next().map(|j| j.get()) else {
        return Mat4::IDENTITY;
    };
    let (Some(r), Some(f)) = (rest.get(root), first.get(root)) else {
        return Mat4::IDENTITY;
    };
    // Rotation and translation only: a scaled root would change the garment's rest
    // lengths.
    let m = Mat4::from_rotation_translation(f.rotation, f.translation)
        * Mat4::from_rotation_translation(r.rotation, r.translation).inverse();
    if m.is_finite() {
        m
    } else {
        Mat4::IDENTITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weight_eases_then_holds() {
        assert_eq!(weight(0.0), 0.0);
        assert_eq!(weight(PREROLL_BLEND * 0.5), 0.5);
        assert_eq!(weight(PREROLL_BLEND), 1.0);
        assert_eq!(weight(1.0), 1.0);
    }
}
