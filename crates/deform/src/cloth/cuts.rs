//! Cuts: output frames where the body jumps to another pose instead of moving there.
//!
//! Mocap files often start on a reference pose one frame before the motion (the cgspeed
//! BVH release of the CMU database starts every file on a T-pose), and a looped clip
//! jumps back to its start. No garment can follow a body that moves half a metre in
//! 1/120 s: it tears (the demo's skirt reached 76% stretch on the cgspeed walk's first
//! frame). At a cut the simulation settles the garment again, as the pre-roll does before
//! frame 0: the garment is reset to its modelled shape, carried by the root's move from
//! rest to the pose after the cut, and the body blends from its rest pose to that pose and
//! holds it while the garment settles (`preroll`). The garment's state before the jump
//! belonged to another pose; starting from the shape it was modelled in makes the frames
//! after a cut the same as a clip starting there.
//!
//! A frame is a cut when some joint moves more than [`CUT_MIN`] of the body's diagonal
//! from the frame before, and more than [`CUT_RATIO`] times as far as any joint moves over
//! the neighbouring frames (the one before and the one after). Fast real motion is
//! smooth: a kick at 30 fps moves the foot about as far on the frames around its fastest
//! one, while a jump moves it far on one frame only.

use glam::Vec3;

/// How much farther than over its neighbouring frames the body must move on a frame for
/// it to be a cut.
pub const CUT_RATIO: f32 = 4.0;

/// The smallest jump, as a fraction of the body's diagonal, that counts as a cut (a
/// garment follows smaller ones: 5% of a person's diagonal is about 11 cm).
pub const CUT_MIN: f32 = 0.05;

/// A cut found in the clip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cut {
    /// The output frame after the jump (the garment is settled into it).
    pub frame: usize,
    /// How far the fastest joint jumped, as a fraction of the body's diagonal.
    pub jump: f32,
}

/// The cuts among frames whose joint positions are `joints[f]` (model space), for a body
/// of `diagonal`.
pub(crate) fn find(joints: &[Vec<Vec3>], diagonal: f32) -> Vec<Cut> {
    // moved[f]: the farthest any joint moved from frame f - 1 to frame f (moved[0] = 0).
    let moved: Vec<f32> = (0..joints.len())
        .map(|f| match f {
            0 => 0.0,
            _ => joints[f - 1]
                .iter()
                .zip(&joints[f])
                .map(|(a, b)| a.distance(*b))
                .fold(0.0, f32::max),
        })
        .collect();
    (1..moved.len())
        .filter_map(|f| {
            let d = moved[f];
            let before = if f >= 2 { moved[f - 1] } else { 0.0 };
            let after = moved.get(f + 1).copied().unwrap_or(0.0);
            (d > CUT_MIN * diagonal && d > CUT_RATIO * before.max(after)).then_some(Cut {
                frame: f,
                jump: d / diagonal,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn walk(frames: usize, step: f32) -> Vec<Vec<Vec3>> {
        (0..frames)
            .map(|f| vec![Vec3::ZERO, Vec3::new(step * f as f32, 1.0, 0.0)])
            .collect()
    }

    #[test]
    fn a_jump_after_a_reference_pose_is_a_cut() {
        let mut frames = walk(10, 0.01);
        // Frame 0 is a T-pose: the hand half a metre away.
        frames[0][1] += Vec3::new(0.0, 0.5, 0.0);
        let cuts = find(&frames, 2.0);
        assert_eq!(cuts.len(), 1);
        assert_eq!(cuts[0].frame, 1);
        assert!((cuts[0].jump - 0.25).abs() < 0.01, "{cuts:?}");
    }

    #[test]
    fn fast_smooth_motion_is_not_a_cut() {
        // 30 cm a frame, every frame: fast, but the garment is dragged, not teleported.
        assert!(find(&walk(10, 0.3), 2.0).is_empty());
        // A foot that stops dead after a fast swing: far on the frames before, too.
        let mut frames = walk(10, 0.3);
        for f in frames.iter_mut().skip(5) {
            f[1].x = 1.2;
        }
        assert!(find(&frames, 2.0).is_empty());
    }

    #[test]
    fn a_small_jump_is_followed_not_cut() {
        let mut frames = walk(10, 0.001);
        for f in frames.iter_mut().skip(5) {
            f[1].x += 0.08;
        }
        assert!(find(&frames, 2.0).is_empty());
        for f in frames.iter_mut().skip(5) {
            f[1].x += 0.08;
        }
        assert_eq!(find(&frames, 2.0)[0].frame, 5);
    }
}
