//! Whether a motion's skeleton is the rig's, so that its clips are taken as they are
//! rather than retargeted.
//!
//! Two skeletons are the same when they have the same joints in the same order (names and
//! parents), the same unit and scene frame, and every joint's rest transform agrees within
//! [`TRANSLATION_TOLERANCE`] of the rig's size (the largest extent of its rest joint
//! positions), [`ROTATION_TOLERANCE_RAD`] and [`SCALE_TOLERANCE`]. The same file read
//! twice agrees exactly; the tolerances absorb what a round trip through a float32 format
//! (glTF, `.usdc`) leaves, about 1e-7 of the size, and are far below any difference of two
//! real skeletons (the CMU subjects' bones differ by 1e-2 of the height and more).

use rigport_model::glam::Vec3;
use rigport_model::{Asset, Skeleton, Transform};

/// Largest difference of a joint's rest translation, as a fraction of the rig's size.
pub(crate) const TRANSLATION_TOLERANCE: f32 = 1e-4;
/// Largest angle between a joint's rest rotations, in radians.
pub(crate) const ROTATION_TOLERANCE_RAD: f32 = 1e-4;
/// Largest difference of a joint's rest scale, per axis.
pub(crate) const SCALE_TOLERANCE: f32 = 1e-4;

/// Whether `motion`'s skeleton is `rig`'s (see the module docs).
pub(crate) fn same_skeleton(rig: &Asset, motion: &Asset) -> bool {
    let (a, b) = (&rig.skeleton, &motion.skeleton);
    let unit = match (rig.meters_per_unit, motion.meters_per_unit) {
        (Some(x), Some(y)) => (x - y).abs() <= 1e-9 * x.abs(),
        (x, y) => x == y,
    };
    if a.len() != b.len() || !unit || rig.frame != motion.frame {
        return false;
    }
    let size = size(a);
    a.joints().iter().zip(b.joints()).all(|(x, y)| {
        x.name == y.name && x.parent == y.parent && close(&x.rest_local, &y.rest_local, size)
    })
}

/// The largest extent of `skeleton`'s rest joint positions (at least the smallest positive
/// float).
fn size(skeleton: &Skeleton) -> f32 {
    let points = skeleton.model_rest_matrices();
    let (lo, hi) = points.iter().map(|m| m.w_axis.truncate()).fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    (hi - lo).max_element().max(f32::MIN_POSITIVE)
}

fn close(a: &Transform, b: &Transform, size: f32) -> bool {
    (a.translation - b.translation).abs().max_element() <= TRANSLATION_TOLERANCE * size
        && a.rotation.angle_between(b.rotation) <= ROTATION_TOLERANCE_RAD
        && (a.scale - b.scale).abs().max_element() <= SCALE_TOLERANCE
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_skeleton_is_its_own_and_not_a_moved_one() {
        let path = std::path::Path::new("../../fixtures/bvh/end_sites.bvh");
        let Ok(walk) = rigport_import::bvh::import(path) else {
            panic!("fixture")
        };
        let rig = walk.asset;
        assert!(same_skeleton(&rig, &rig.clone()));
        let mut moved = rig.clone();
        let joints: Vec<_> = moved.skeleton.joints().to_vec();
        let mut last = joints.clone();
        if let Some(j) = last.last_mut() {
            j.rest_local.translation.x += 1e-3 * size(&rig.skeleton);
        }
        let Ok(skeleton) = Skeleton::new(last) else {
            panic!("valid")
        };
        moved.skeleton = skeleton;
        assert!(!same_skeleton(&rig, &moved));
        let mut nudged = joints;
        if let Some(j) = nudged.last_mut() {
            j.rest_local.translation.x += 1e-6 * size(&rig.skeleton);
        }
        let Ok(skeleton) = Skeleton::new(nudged) else {
            panic!("valid")
        };
        moved.skeleton = skeleton;
        assert!(same_skeleton(&rig, &moved));
    }
}
