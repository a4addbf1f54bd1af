//! Which parts of the body the garment collides with: the bones it was modelled near,
//! and the chains they hang from.
//!
//! A garment is modelled on the body at rest, and the parts it lies on or hangs beside
//! there are the ones it is made to meet: a skirt's hips and thighs, a sleeve's arm. The
//! bones above them carry it (a flag tied to a hand falls along the upper arm). Other
//! parts swinging into it (a hand hanging beside a flared skirt on a walk) do not keep
//! the garment a thickness away, unless
//! [`ClothOptions::collide_all`](super::ClothOptions::collide_all) asks for the whole
//! body: with them as full colliders, the demo's skirt was pinched between hand and thigh
//! on every stride of the corpus's cgspeed walk and tore to 140% stretch. They push it
//! softly instead (the solver's `collide_others`): a particle deeper in them than 3/4 of
//! the thickness goes half way back to that depth per substep, and half way between the
//! hand and the hip when pinched there. The measurements
//! ([`FrameStats`](super::FrameStats)) look at the whole body either way.
//!
//! A joint is near when a skinned vertex whose heaviest joint it is lies inside the
//! garment's rest bounding box grown by [`NEAR`] of the body's diagonal. The garment
//! collides with the near joints and all their ancestors: their capsules, and the body
//! triangles with a corner they carry.

use glam::Vec3;

/// How far around the garment's rest bounding box, as a fraction of the body's
/// diagonal, the body collides with it (18 cm on a person).
pub const NEAR: f32 = 0.1;

/// Per joint: whether the garment at rest `garment` collides with it, for a body of
/// `diagonal` whose vertices at rest `body` have heaviest joints `heaviest`, and a
/// skeleton with `parents`.
pub(crate) fn colliding_joints(
    garment: &[Vec3],
    body: &[Vec3],
    heaviest: &[Option<usize>],
    parents: &[Option<usize>],
    diagonal: f32,
) -> Vec<bool> {
    let region = Region::around(garment, diagonal);
    let mut kept = vec![false; parents.len()];
    for (p, j) in body.iter().zip(heaviest) {
        if let Some(j) = *j {
            if j < kept.len() && region.holds(*p) {
                kept[j] = true;
            }
        }
    }
    // Parents come first, so one pass from the leaves up reaches every ancestor.
    for j in (0..parents.len()).rev() {
        if kept[j] {
            if let Some(p) = parents[j].filter(|&p| p < j) {
                kept[p] = true;
            }
        }
    }
    kept
}

/// The garment's rest bounding box, grown by [`NEAR`] of the body's diagonal.
#[derive(Clone, Copy, Debug)]
struct Region {
    lo: Vec3,
    hi: Vec3,
}

impl Region {
    /// The region around a garment at rest `positions` on a body of `diagonal`.
    pub(crate) fn around(positions: &[Vec3], diagonal: f32) -> Self {
        let (lo, hi) = positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let grow = Vec3::splat(NEAR * diagonal);
        Self {
            lo: lo - grow,
            hi: hi + grow,
        }
    }

    /// Whether `p` is inside.
    pub(crate) fn holds(&self, p: Vec3) -> bool {
        p.cmpge(self.lo).all() && p.cmple(self.hi).all()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_skirt_meets_the_hips_and_legs_not_the_arms() {
        // Joints: 0 hips, 1 spine, 2 chest, 3 arm, 4 thigh. A skirt from the waist (1.0)
        // to above the knees (0.58); a 2 m body.
        let parents = [None, Some(0), Some(1), Some(2), Some(0)];
        let skirt = [Vec3::new(-0.37, 0.58, -0.37), Vec3::new(0.37, 1.0, 0.37)];
        let body = [
            (Vec3::new(0.1, 1.0, 0.0), 1), // the waist, on the spine
            (Vec3::new(0.1, 0.7, 0.0), 4), // the thigh
            (Vec3::new(0.1, 1.4, 0.0), 2), // the chest
            (Vec3::new(0.8, 1.4, 0.0), 3), // the arm held out
        ];
        let (at, heaviest): (Vec<Vec3>, Vec<Option<usize>>) =
            body.iter().map(|&(p, j)| (p, Some(j))).unzip();
        let kept = colliding_joints(&skirt, &at, &heaviest, &parents, 2.0);
        assert_eq!(kept, [true, true, false, false, true]);
        // A flag tied to the hand of an arm (0 shoulder, 1 elbow): the upper arm carries it.
        let flag = [Vec3::new(-1.0, -2.5, 4.0), Vec3::new(1.0, -0.5, 4.0)];
        let arm = [Vec3::new(0.0, -0.5, 1.0), Vec3::new(0.0, -0.5, 3.9)];
        let kept = colliding_joints(&flag, &arm, &[Some(0), Some(1)], &[None, Some(0)], 4.2);
        assert_eq!(kept, [true, true]);
    }
}
