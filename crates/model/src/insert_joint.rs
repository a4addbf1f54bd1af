//! Adding a joint to an asset's skeleton without breaking what refers to joints.
//!
//! The skeleton is parents-first and joints are referred to by index from skins
//! ([`crate::SkinBinding::joints`]), clip tracks, mesh attachments, IK handles and rotation
//! limits. [`Asset::insert_parent`] puts the new joint at its child's index, so every index
//! from there on moves up by one and is remapped in each of those places; influences index
//! a skin's joint palette, not the skeleton, and inverse bind matrices belong to palette
//! entries, so neither changes (the new joint is in no palette).

use crate::{Asset, Joint, JointIndex, Skeleton, SkeletonProblem, TrackTarget, Transform};

impl Asset {
    /// Inserts a joint named `name` (made unique with `_1`, `_2`, ... when taken) between
    /// `child` and its parent (above a root: the new joint becomes the root), with an
    /// identity rest transform, so the rest pose, every skin and every clip deform exactly
    /// as before. Returns the new joint's index (`child`'s old index; `child` moves to the
    /// next one).
    ///
    /// # Errors
    /// A skeleton problem if `child` is out of range (nothing is changed then).
    pub fn insert_parent(
        &mut self,
        child: JointIndex,
        name: &str,
    ) -> Result<JointIndex, Vec<SkeletonProblem>> {
        let at = child.get();
        let count = self.skeleton.len();
        if at >= count {
            return Err(vec![SkeletonProblem::ParentOutOfRange {
                index: count,
                parent: at,
                count,
            }]);
        }
        let shift = |j: JointIndex| {
            if j.get() >= at {
                JointIndex(j.0 + 1)
            } else {
                j
            }
        };
        let mut name = name.to_string();
        let taken = |n: &str| self.skeleton.find(n).is_some();
        if taken(&name) {
            let base = name.clone();
            name = (1u32..)
                .map(|k| format!("{base}_{k}"))
                .find(|n| !taken(n))
                .unwrap_or(base);
        }
        let old = self.skeleton.joints();
        let mut joints: Vec<Joint> = Vec::with_capacity(count + 1);
        joints.extend(old[..at].iter().cloned());
        joints.push(Joint {
            name,
            parent: old[at].parent,
            rest_local: Transform::IDENTITY,
        });
        for (i, joint) in old.iter().enumerate().skip(at) {
            let parent = if i == at {
                Some(child)
            } else {
                joint.parent.map(shift)
            };
            joints.push(Joint {
                parent,
                ..joint.clone()
            });
        }
        let limits: Vec<_> = self
            .skeleton
            .limits()
            .iter()
            .map(|l| crate::RotationLimit {
                joint: shift(l.joint),
                ..*l
            })
            .collect();
        let mut skeleton = Skeleton::new(joints)?;
        skeleton.set_limits(limits);
        self.skeleton = skeleton;
        for skin in &mut self.skins {
            skin.joints.iter_mut().for_each(|j| *j = shift(*j));
        }
        for mesh in &mut self.meshes {
            mesh.attached_to = mesh.attached_to.map(shift);
        }
        self.ik_handles.iter_mut().for_each(|j| *j = shift(*j));
        for track in self.clips.iter_mut().flat_map(|c| c.tracks.iter_mut()) {
            track.target = match track.target {
                TrackTarget::Translation(j) => TrackTarget::Translation(shift(j)),
                TrackTarget::Rotation(j) => TrackTarget::Rotation(shift(j)),
                TrackTarget::Scale(j) => TrackTarget::Scale(shift(j)),
                weights @ TrackTarget::MorphWeights(_) => weights,
            };
        }
        Ok(child)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Clip, Influences, Interpolation, MeshIndex, SkinBinding, Track};
    use glam::{Mat4, Vec3};

    fn joint(name: &str, parent: Option<u32>, x: f32) -> Joint {
        Joint {
            name: name.into(),
            parent: parent.map(JointIndex),
            rest_local: Transform::from_translation(Vec3::new(x, 0.0, 0.0)),
        }
    }

    #[test]
    fn inserting_above_a_root_shifts_every_reference() {
        let skeleton = Skeleton::new(vec![
            joint("prop", None, 5.0),
            joint("root", None, 1.0),
            joint("leg", Some(1), 2.0),
        ])
        .expect("valid");
        let mut asset = Asset {
            skeleton,
            skins: vec![SkinBinding {
                mesh: MeshIndex(0),
                joints: vec![JointIndex(2), JointIndex(0)],
                inv_bind: vec![Mat4::IDENTITY; 2],
                influences: Influences::default(),
                method: Default::default(),
            }],
            clips: vec![Clip {
                name: "c".into(),
                tracks: vec![Track {
                    target: TrackTarget::Translation(JointIndex(1)),
                    interpolation: Interpolation::Linear,
                    times: vec![0.0],
                    values: vec![0.0; 3],
                }],
            }],
            ik_handles: vec![JointIndex(2)],
            ..Asset::default()
        };
        let rest_before = asset.skeleton.model_rest_matrices();
        let new = asset
            .insert_parent(JointIndex(1), "root")
            .expect("inserted");
        assert_eq!(new, JointIndex(1));
        let s = &asset.skeleton;
        assert_eq!(s.joint(new).name, "root_1");
        assert_eq!(s.joint(new).parent, None);
        assert_eq!(s.joint(JointIndex(2)).parent, Some(new));
        assert_eq!(s.joint(JointIndex(3)).parent, Some(JointIndex(2)));
        assert_eq!(asset.skins[0].joints, vec![JointIndex(3), JointIndex(0)]);
        assert_eq!(asset.ik_handles, vec![JointIndex(3)]);
        assert_eq!(
            asset.clips[0].tracks[0].target,
            TrackTarget::Translation(JointIndex(2))
        );
        let rest_after = asset.skeleton.model_rest_matrices();
        for (before, after) in [(0, 0), (1, 2), (2, 3)] {
            assert_eq!(rest_before[before], rest_after[after]);
        }
        assert!(asset.insert_parent(JointIndex(9), "x").is_err());
    }
}
