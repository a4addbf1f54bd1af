use std::collections::HashMap;
use std::fmt;

use glam::Mat4;

use crate::RotationLimit;
use crate::{JointIndex, Transform};

/// One joint of a [`Skeleton`].
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Unique, non-empty name.
    pub name: String,
    /// The parent joint; `None` for a root. Always smaller than this joint's own index.
    pub parent: Option<JointIndex>,
    /// Rest transform relative to the parent (or to the asset root for a root joint).
    pub rest_local: Transform,
}

/// A joint hierarchy stored parents-first, so forward kinematics is one linear pass.
///
/// Construct with [`Skeleton::new`], which checks every invariant and reports every problem.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skeleton {
    joints: Vec<Joint>,
    /// Rotation limits the source states (ASF `dof`/`limits`); IK honours them.
    limits: Vec<RotationLimit>,
}

/// One thing wrong with a joint list, as found by [`Skeleton::new`] or [`parents_first_order`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SkeletonProblem {
    /// A joint has an empty name.
    #[error("joint {index} has an empty name")]
    EmptyName {
        /// The joint's index.
        index: usize,
    },
    /// Two joints share a name.
    #[error("joints {first} and {second} are both named {name:?}")]
    DuplicateName {
        /// The name.
        name: String,
        /// Index of the first joint with it.
        first: usize,
        /// Index of the later joint with it.
        second: usize,
    },
    /// A parent index is not a joint.
    #[error("joint {index} names parent {parent}, but there are only {count} joints")]
    ParentOutOfRange {
        /// The joint's index.
        index: usize,
        /// The parent index it names.
        parent: usize,
        /// How many joints there are.
        count: usize,
    },
    /// A joint names itself as parent.
    #[error("joint {index} is its own parent")]
    SelfParent {
        /// The joint's index.
        index: usize,
    },
    /// A chain of parents loops.
    #[error("joints {joints:?} form a parent cycle")]
    Cycle {
        /// The joints on the cycle, in parent order.
        joints: Vec<usize>,
    },
    /// A parent comes after its child (the skeleton must be sorted parents-first).
    #[error("joint {index} comes before its parent {parent}")]
    ParentAfterChild {
        /// The joint's index.
        index: usize,
        /// Its parent's index.
        parent: usize,
    },
    /// A rest transform holds NaN or infinity.
    #[error("joint {index} ({name:?}) has a non-finite rest transform")]
    NonFinite {
        /// The joint's index.
        index: usize,
        /// The joint's name.
        name: String,
    },
}

impl Skeleton {
    /// Builds a skeleton from joints already in parents-first order.
    ///
    /// # Errors
    /// Every problem found: empty or duplicate names, parents out of range, self-parents,
    /// parents after children, non-finite rest transforms. Use [`parents_first_order`] first
    /// for sources that do not guarantee the order.
    pub fn new(joints: Vec<Joint>) -> Result<Self, Vec<SkeletonProblem>> {
        let mut problems = Vec::new();
        let mut seen: HashMap<&str, usize> = HashMap::with_capacity(joints.len());
        for (index, joint) in joints.iter().enumerate() {
            if joint.name.is_empty() {
                problems.push(SkeletonProblem::EmptyName { index });
            } else if let Some(&first) = seen.get(joint.name.as_str()) {
                problems.push(SkeletonProblem::DuplicateName {
                    name: joint.name.clone(),
                    first,
                    second: index,
                });
            } else {
                seen.insert(&joint.name, index);
            }
            if let Some(parent) = joint.parent {
                let parent = parent.get();
                if parent >= joints.len() {
                    problems.push(SkeletonProblem::ParentOutOfRange {
                        index,
                        parent,
                        count: joints.len(),
                    });
                } else if parent == index {
                    problems.push(SkeletonProblem::SelfParent { index });
                } else if parent > index {
                    problems.push(SkeletonProblem::ParentAfterChild { index, parent });
                }
            }
            if !joint.rest_local.is_finite() {
                problems.push(SkeletonProblem::NonFinite {
                    index,
                    name: joint.name.clone(),
                });
            }
        }
        if problems.is_empty() {
            Ok(Self {
                joints,
                limits: Vec::new(),
            })
        } else {
            Err(problems)
        }
    }

    /// The rotation limits the source rig states (an ASF's `dof` and `limits`), at most one
    /// per joint, ascending by joint. Only IK reads them; exporters ignore them.
    pub fn limits(&self) -> &[RotationLimit] {
        &self.limits
    }

    /// Sets the rotation limits, keeping those of joints of this skeleton (the last for a
    /// joint given twice), sorted by joint.
    pub fn set_limits(&mut self, limits: impl IntoIterator<Item = RotationLimit>) {
        let n = self.joints.len();
        let mut by_joint: Vec<Option<RotationLimit>> = vec![None; n];
        for l in limits {
            if let Some(slot) = by_joint.get_mut(l.joint.get()) {
                *slot = Some(l);
            }
        }
        self.limits = by_joint.into_iter().flatten().collect();
    }

    /// The joints, parents first.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// Whether there are no joints.
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// One joint.
    ///
    /// # Panics
    /// If `index` is out of range (indices come from this skeleton).
    pub fn joint(&self, index: JointIndex) -> &Joint {
        &self.joints[index.get()]
    }

    /// The index of the joint with this name.
    pub fn find(&self, name: &str) -> Option<JointIndex> {
        self.joints
            .iter()
            .position(|j| j.name == name)
            .map(|i| JointIndex(i as u32))
    }

    /// Parent index per joint (`None` for roots), in joint order.
    pub fn parents(&self) -> impl ExactSizeIterator<Item = Option<JointIndex>> + '_ {
        self.joints.iter().map(|j| j.parent)
    }

    /// The roots' indices.
    pub fn roots(&self) -> impl Iterator<Item = JointIndex> + '_ {
        self.joints
            .iter()
            .enumerate()
            .filter(|(_, j)| j.parent.is_none())
            .map(|(i, _)| JointIndex(i as u32))
    }

    /// Model-space rest matrices (one linear parents-first pass).
    pub fn model_rest_matrices(&self) -> Vec<Mat4> {
        let mut out: Vec<Mat4> = Vec::with_capacity(self.joints.len());
        for joint in &self.joints {
            let local = joint.rest_local.to_mat4();
            let model = match joint.parent {
                Some(p) => out[p.get()] * local,
                None => local,
            };
            out.push(model);
        }
        out
    }

    /// The slash-separated path of a joint from its root (`Hips/Spine/Chest`), as UsdSkel
    /// names joints.
    pub fn joint_path(&self, index: JointIndex) -> String {
        let mut names = vec![self.joints[index.get()].name.as_str()];
        let mut cur = self.joints[index.get()].parent;
        while let Some(p) = cur {
            names.push(&self.joints[p.get()].name);
            cur = self.joints[p.get()].parent;
        }
        names.reverse();
        names.join("/")
    }
}

impl fmt::Display for Skeleton {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, j) in self.joints.iter().enumerate() {
            match j.parent {
                Some(p) => writeln!(f, "{i:4} {} <- {}", j.name, self.joints[p.get()].name)?,
                None => writeln!(f, "{i:4} {} (root)", j.name)?,
            }
        }
        Ok(())
    }
}

/// Orders an arbitrary parent array parents-first.
///
/// `parents[i]` is joint `i`'s parent in the source numbering. Returns `order`, the source
/// indices in a parents-first order that keeps the source order wherever it already is
/// parents-first (roots and siblings keep their relative order). The caller remaps with
/// `new_index[order[k]] = k`.
///
/// # Errors
/// Every parent out of range, every self-parent, and every cycle (each reported once).
pub fn parents_first_order(parents: &[Option<usize>]) -> Result<Vec<usize>, Vec<SkeletonProblem>> {
    let n = parents.len();
    let mut problems = Vec::new();
    for (index, parent) in parents.iter().enumerate() {
        match *parent {
            Some(p) if p >= n => problems.push(SkeletonProblem::ParentOutOfRange {
                index,
                parent: p,
                count: n,
            }),
            Some(p) if p == index => problems.push(SkeletonProblem::SelfParent { index }),
            _ => {}
        }
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    // Cycle detection by walking up from each joint with a three-colour marking.
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        New,
        OnPath,
        Done,
    }
    let mut mark = vec![Mark::New; n];
    for start in 0..n {
        let mut path = Vec::new();
        let mut cur = Some(start);
        while let Some(c) = cur {
            match mark[c] {
                Mark::Done => break,
                Mark::OnPath => {
                    let from = path.iter().position(|&x| x == c).unwrap_or(0);
                    let mut joints: Vec<usize> = path[from..].to_vec();
                    joints.reverse();
                    problems.push(SkeletonProblem::Cycle { joints });
                    break;
                }
                Mark::New => {
                    mark[c] = Mark::OnPath;
                    path.push(c);
                    cur = parents[c];
                }
            }
        }
        for p in path {
            mark[p] = Mark::Done;
        }
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    // Depth-first from the roots, children in source order.
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut roots = Vec::new();
    for (i, p) in parents.iter().enumerate() {
        match p {
            Some(p) => children[*p].push(i),
            None => roots.push(i),
        }
    }
    // Keep the source order when it is already parents-first: a stable topological sort
    // (Kahn with the smallest ready index first).
    let mut order = Vec::with_capacity(n);
    let mut ready = std::collections::BinaryHeap::new();
    for r in roots {
        ready.push(std::cmp::Reverse(r));
    }
    while let Some(std::cmp::Reverse(i)) = ready.pop() {
        order.push(i);
        for &c in &children[i] {
            ready.push(std::cmp::Reverse(c));
        }
    }
    Ok(order)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn joint(name: &str, parent: Option<u32>) -> Joint {
        Joint {
            name: name.into(),
            parent: parent.map(JointIndex),
            rest_local: Transform::IDENTITY,
        }
    }

    #[test]
    fn reports_every_problem() {
        let mut bad = joint("c", Some(1));
        bad.rest_local.translation.x = f32::NAN;
        let problems = Skeleton::new(vec![
            joint("a", None),
            joint("a", Some(9)),
            bad,
            joint("", Some(3)),
        ])
        .unwrap_err();
        assert_eq!(problems.len(), 5, "{problems:?}");
        assert!(problems.contains(&SkeletonProblem::DuplicateName {
            name: "a".into(),
            first: 0,
            second: 1
        }));
        assert!(problems.contains(&SkeletonProblem::ParentOutOfRange {
            index: 1,
            parent: 9,
            count: 4
        }));
        assert!(problems.contains(&SkeletonProblem::SelfParent { index: 3 }));
        assert!(problems.contains(&SkeletonProblem::EmptyName { index: 3 }));
        assert!(matches!(
            problems[2],
            SkeletonProblem::NonFinite { index: 2, .. }
        ));
    }

    #[test]
    fn parent_after_child_is_rejected() {
        let problems = Skeleton::new(vec![joint("a", Some(1)), joint("b", None)]).unwrap_err();
        assert_eq!(
            problems,
            vec![SkeletonProblem::ParentAfterChild {
                index: 0,
                parent: 1
            }]
        );
    }

    #[test]
    fn sorts_parents_first_and_keeps_sorted_input() {
        assert_eq!(
            parents_first_order(&[None, Some(0), Some(1), Some(0)]).unwrap(),
            vec![0, 1, 2, 3]
        );
        let order = parents_first_order(&[Some(2), None, Some(1), Some(0)]).unwrap();
        assert_eq!(order, vec![1, 2, 0, 3]);
    }

    #[test]
    fn finds_cycles() {
        let problems = parents_first_order(&[None, Some(2), Some(3), Some(1)]).unwrap_err();
        assert_eq!(problems.len(), 1);
        let SkeletonProblem::Cycle { joints } = &problems[0] else {
            panic!("expected a cycle, got {problems:?}");
        };
        let mut sorted = joints.clone();
        sorted.sort();
        assert_eq!(sorted, vec![1, 2, 3]);
        assert_eq!(
            parents_first_order(&[Some(0)]).unwrap_err(),
            vec![SkeletonProblem::SelfParent { index: 0 }]
        );
    }

    #[test]
    fn joint_paths_and_rest_matrices() {
        let mut b = joint("b", Some(0));
        b.rest_local.translation = glam::Vec3::new(0.0, 2.0, 0.0);
        let mut a = joint("a", None);
        a.rest_local.translation = glam::Vec3::new(1.0, 0.0, 0.0);
        let s = Skeleton::new(vec![a, b, joint("c", Some(1))]).unwrap();
        assert_eq!(s.joint_path(JointIndex(2)), "a/b/c");
        let m = s.model_rest_matrices();
        assert_eq!(m[2].w_axis.truncate(), glam::Vec3::new(1.0, 2.0, 0.0));
    }
}
