//! Forward kinematics: local transforms to model-space matrices.

use glam::Mat4;
use rigport_model::{JointIndex, Transform};

use crate::EvalError;

/// Computes model-space matrices from local transforms in one parents-first pass.
///
/// `model[i] = model[parent[i]] * local[i].to_mat4()` (column vectors), roots use
/// `root_model * local[i]` (identity by default).
pub struct LocalToModelJob<'a> {
    /// Parent of each joint, parents before children (as [`rigport_model::Skeleton`] stores).
    pub parents: &'a [Option<JointIndex>],
    /// Local transform of each joint (same length as `parents`).
    pub local: &'a [Transform],
    /// Transform applied above every root.
    pub root_model: Mat4,
    /// Output: model-space matrix of each joint (same length as `parents`).
    pub model: &'a mut [Mat4],
}

impl LocalToModelJob<'_> {
    /// Checks sizes and that every parent precedes its child.
    ///
    /// # Errors
    /// [`EvalError::Length`] or [`EvalError::Index`].
    pub fn validate(&self) -> Result<(), EvalError> {
        let n = self.parents.len();
        for (what, found) in [("local", self.local.len()), ("model", self.model.len())] {
            if found != n {
                return Err(EvalError::Length {
                    what,
                    expected: n,
                    found,
                });
            }
        }
        for (i, p) in self.parents.iter().enumerate() {
            if let Some(p) = p {
                if p.get() >= i {
                    return Err(EvalError::Index {
                        what: "parents",
                        index: i,
                    });
                }
            }
        }
        Ok(())
    }

    /// Runs the job. Allocates nothing.
    ///
    /// # Errors
    /// As [`LocalToModelJob::validate`], which it calls first.
    pub fn run(&mut self) -> Result<(), EvalError> {
        self.validate()?;
        for i in 0..self.parents.len() {
            let local = self.local[i].to_mat4();
            self.model[i] = match self.parents[i] {
                Some(p) => self.model[p.get()] * local,
                None => self.root_model * local,
            };
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3};
    use proptest::prelude::*;

    /// The naive reference: recursive, walks to the root for every joint.
    fn naive_model(parents: &[Option<JointIndex>], local: &[Transform], i: usize) -> Mat4 {
        let l = local[i].to_mat4();
        match parents[i] {
            Some(p) => naive_model(parents, local, p.get()) * l,
            None => l,
        }
    }

    fn transform() -> impl Strategy<Value = Transform> {
        (
            prop::array::uniform3(-2.0f32..2.0),
            prop::array::uniform3(-3.2f32..3.2),
            prop::array::uniform3(0.5f32..1.5),
        )
            .prop_map(|(t, r, s)| Transform {
                translation: Vec3::from(t),
                rotation: Quat::from_euler(glam::EulerRot::ZYX, r[0], r[1], r[2]),
                scale: Vec3::from(s),
            })
    }

    proptest! {
        #[test]
        fn one_pass_equals_naive_recursion(
            raw_parents in prop::collection::vec(any::<prop::sample::Index>(), 1..24),
            local in prop::collection::vec(transform(), 24),
        ) {
            // Joint 0 is a root; joint i's parent is some earlier joint, or none.
            let parents: Vec<Option<JointIndex>> = raw_parents.iter().enumerate().map(|(i, ix)| {
                if i == 0 { None } else {
                    let p = ix.index(i + 1);
                    (p < i).then_some(JointIndex(p as u32))
                }
            }).collect();
            let local = &local[..parents.len()];
            let mut model = vec![Mat4::IDENTITY; parents.len()];
            LocalToModelJob { parents: &parents, local, root_model: Mat4::IDENTITY, model: &mut model }.run().unwrap();
            for (i, m) in model.iter().enumerate() {
                let reference = naive_model(&parents, local, i);
                prop_assert!(m.abs_diff_eq(reference, 1e-3 * (1.0 + reference.abs().to_cols_array().iter().fold(0.0f32, |a, b| a.max(*b)))),
                    "joint {i}: {m} vs {reference}");
            }
        }
    }

    #[test]
    fn rejects_child_before_parent_and_bad_lengths() {
        let parents = [Some(JointIndex(1)), None];
        let local = [Transform::IDENTITY; 2];
        let mut model = [Mat4::IDENTITY; 2];
        let mut job = LocalToModelJob {
            parents: &parents,
            local: &local,
            root_model: Mat4::IDENTITY,
            model: &mut model,
        };
        assert_eq!(
            job.run(),
            Err(EvalError::Index {
                what: "parents",
                index: 0
            })
        );
        let mut short = [Mat4::IDENTITY; 1];
        let job = LocalToModelJob {
            parents: &[None, None],
            local: &local,
            root_model: Mat4::IDENTITY,
            model: &mut short,
        };
        assert!(matches!(
            job.validate(),
            Err(EvalError::Length { what: "model", .. })
        ));
    }
}
