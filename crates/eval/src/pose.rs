//! Poses: a local transform per joint, built from the rest pose and per-joint changes.

use glam::{Mat4, Quat};
use rigport_model::{RestRotation, Skeleton, Transform};

use crate::{EvalError, LocalToModelJob};

/// A local transform per skeleton joint.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// One local transform per joint, in skeleton order.
    pub local: Vec<Transform>,
}

impl Pose {
    /// The skeleton's rest pose.
    pub fn rest(skeleton: &Skeleton) -> Self {
        Self {
            local: skeleton.joints().iter().map(|j| j.rest_local).collect(),
        }
    }

    /// Applies a rotation in a joint's rest frame: `local = rest_local * delta`, i.e. the
    /// joint's local rotation becomes `rest_rotation * delta` (translation and scale kept).
    ///
    /// # Errors
    /// [`EvalError::UnknownJoint`] if the skeleton has no joint of that name.
    pub fn rotate_named(
        &mut self,
        skeleton: &Skeleton,
        joint: &str,
        delta: Quat,
    ) -> Result<(), EvalError> {
        let index = skeleton
            .find(joint)
            .ok_or_else(|| EvalError::UnknownJoint(joint.to_string()))?;
        let local = &mut self.local[index.get()];
        local.rotation = (local.rotation * delta).normalize();
        Ok(())
    }

    /// Applies rotations in their joints' rest frames, as [`Pose::rotate_named`] does
    /// (joints outside the pose are skipped: rotations resolved against another skeleton).
    pub fn apply(&mut self, rotations: &[RestRotation]) {
        for r in rotations {
            if let Some(local) = self.local.get_mut(r.joint.get()) {
                local.rotation = (local.rotation * r.rotation).normalize();
            }
        }
    }

    /// Model-space matrices of this pose (allocates the output; use [`LocalToModelJob`] with
    /// a reused buffer in loops).
    ///
    /// # Errors
    /// If the pose does not have one transform per joint.
    pub fn model_matrices(&self, skeleton: &Skeleton) -> Result<Vec<Mat4>, EvalError> {
        let parents: Vec<_> = skeleton.parents().collect();
        let mut model = vec![Mat4::IDENTITY; parents.len()];
        LocalToModelJob {
            parents: &parents,
            local: &self.local,
            root_model: Mat4::IDENTITY,
            model: &mut model,
        }
        .run()?;
        Ok(model)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use rigport_model::{Joint, JointIndex};

    #[test]
    fn delta_is_applied_in_the_rest_frame() {
        let rest_rot = Quat::from_rotation_z(0.5);
        let skel = Skeleton::new(vec![
            Joint {
                name: "a".into(),
                parent: None,
                rest_local: Transform {
                    rotation: rest_rot,
                    ..Transform::IDENTITY
                },
            },
            Joint {
                name: "b".into(),
                parent: Some(JointIndex(0)),
                rest_local: Transform::from_translation(Vec3::X),
            },
        ])
        .unwrap();
        let mut pose = Pose::rest(&skel);
        let delta = Quat::from_rotation_y(0.3);
        pose.rotate_named(&skel, "a", delta).unwrap();
        assert!(pose.local[0].rotation.abs_diff_eq(rest_rot * delta, 1e-6));
        let model = pose.model_matrices(&skel).unwrap();
        let expect = (rest_rot * delta) * Vec3::X;
        assert!(model[1].w_axis.truncate().abs_diff_eq(expect, 1e-6));
        assert_eq!(
            pose.rotate_named(&skel, "zz", delta),
            Err(EvalError::UnknownJoint("zz".into()))
        );
    }
}
