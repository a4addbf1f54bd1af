//! An IK problem: what can go wrong ([`IkError`]), the effectors and handles, and the
//! problem compiled once per skeleton and handle set ([`IkProblem`]) that every solver
//! walks.

use glam::{Quat, Vec3};
use rigport_model::{JointIndex, Skeleton};

use crate::limits::JointLimit;

/// Something wrong with an IK problem or a solve job's inputs. Found by [`IkProblem::new`] or
/// [`crate::IkSolveJob::validate`], before any work.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IkError {
    /// A problem with no handle.
    #[error("an IK problem needs at least one handle")]
    NoHandles,
    /// A joint index is not a joint of the skeleton.
    #[error("{what}: {index} is not a joint (the skeleton has {count})")]
    JointOutOfRange {
        /// Which list (`"handles"`, `"movable"`, `"limits"`).
        what: &'static str,
        /// The index given.
        index: usize,
        /// The skeleton's joint count.
        count: usize,
    },
    /// A buffer has the wrong length for the problem.
    #[error("{what}: expected {expected} elements, found {found}")]
    Length {
        /// Which buffer (`"pose"`, `"targets"`, `"report"`, `"scratch"`).
        what: &'static str,
        /// The length the problem requires.
        expected: usize,
        /// Its length.
        found: usize,
    },
    /// A target names another joint than the problem's handle at the same position.
    #[error("target {handle} is for {found}, but the problem's handle {handle} is {expected}")]
    TargetJoint {
        /// Handle position in the list.
        handle: usize,
        /// The problem's handle joint.
        expected: JointIndex,
        /// The target's joint.
        found: JointIndex,
    },
    /// A target position or orientation holds NaN or infinity, or its orientation is zero.
    #[error("target {handle}: {what} is not finite (or is a zero quaternion)")]
    NonFiniteTarget {
        /// Handle position in the list.
        handle: usize,
        /// `"position"` or `"orientation"`.
        what: &'static str,
    },
    /// A handle weight is negative, NaN or infinite.
    #[error("target {handle}: weight {weight} must be finite and >= 0")]
    BadWeight {
        /// Handle position in the list.
        handle: usize,
        /// The weight.
        weight: f32,
    },
    /// An effector offset holds NaN or infinity.
    #[error("handle {handle}: effector offset is not finite")]
    NonFiniteOffset {
        /// Handle position in the list.
        handle: usize,
    },
    /// A joint of the warm-start pose holds NaN or infinity.
    #[error("pose: joint {joint} is not finite")]
    NonFinitePose {
        /// The joint.
        joint: usize,
    },
    /// A setting is out of its range.
    #[error("setting {what} = {value}: {expected}")]
    BadSetting {
        /// The field (`"tolerance"`, `"max_step_rad"`, ...).
        what: &'static str,
        /// Its value.
        value: f32,
        /// What it must be.
        expected: &'static str,
    },
    /// A joint limit is malformed (NaN, negative angle, `min > max`).
    #[error("limits: the limit of joint {joint} is invalid ({why})")]
    BadLimit {
        /// The joint.
        joint: usize,
        /// What is wrong.
        why: &'static str,
    },
}

/// A point that a handle drives: a joint's origin, or a point fixed in its frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkEffector {
    /// The handle joint.
    pub joint: JointIndex,
    /// The driven point in the joint's local frame (asset length unit); zero for the
    /// joint's origin. A bone's tip is its child's rest translation.
    pub local_offset: Vec3,
}

impl IkEffector {
    /// The origin of `joint`.
    pub fn at(joint: JointIndex) -> Self {
        Self {
            joint,
            local_offset: Vec3::ZERO,
        }
    }
}

impl From<JointIndex> for IkEffector {
    fn from(joint: JointIndex) -> Self {
        Self::at(joint)
    }
}

/// One handle's target for one solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkHandle {
    /// The handle joint; must equal the problem's handle at the same position.
    pub joint: JointIndex,
    /// Where the effector should be, model space (asset length unit).
    pub target: Vec3,
    /// Relative importance (`>= 0`; 0 switches the handle off for this solve).
    pub weight: f32,
    /// The joint's target model-space rotation, if any (need not be normalized).
    pub orientation: Option<Quat>,
}

impl IkHandle {
    /// A position target of weight 1.
    pub fn new(joint: JointIndex, target: Vec3) -> Self {
        Self {
            joint,
            target,
            weight: 1.0,
            orientation: None,
        }
    }
}

/// Compressed rows of indices: row `i` is `items[start[i]..start[i + 1]]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Csr {
    pub(crate) start: Vec<u32>,
    pub(crate) items: Vec<u32>,
}

impl Csr {
    pub(crate) fn from_rows(rows: impl Iterator<Item = Vec<u32>>) -> Self {
        let mut out = Csr {
            start: vec![0],
            items: Vec::new(),
        };
        for r in rows {
            out.items.extend(r);
            out.start.push(out.items.len() as u32);
        }
        out
    }

    pub(crate) fn row(&self, i: usize) -> &[u32] {
        match (self.start.get(i), self.start.get(i + 1)) {
            (Some(&a), Some(&b)) => self.items.get(a as usize..b as usize).unwrap_or(&[]),
            _ => &[],
        }
    }
}

/// An IK problem compiled once: the skeleton's topology and rest rotations, the handles'
/// effectors, which joints move (each with an optional limit), and the index tables the
/// solvers walk. Immutable; share it between frames and threads.
#[derive(Clone, Debug)]
pub struct IkProblem {
    pub(crate) parents: Vec<Option<JointIndex>>,
    pub(crate) rest_rotation: Vec<Quat>,
    pub(crate) effectors: Vec<IkEffector>,
    /// Joints whose model matrix the solver needs (handles, movable joints and their
    /// ancestors), ascending.
    pub(crate) fk_joints: Vec<u32>,
    /// Movable joints, ascending; a joint's position here is its *slot*.
    pub(crate) movable: Vec<u32>,
    /// Per joint: its slot, if movable.
    pub(crate) slot_of: Vec<Option<u32>>,
    /// Per slot.
    pub(crate) limits: Vec<Option<JointLimit>>,
    /// Per handle: the slots that are the handle joint or its ancestors, ascending.
    pub(crate) handle_slots: Csr,
    /// Per slot: the handles whose effector it moves.
    pub(crate) slot_handles: Csr,
    /// Per Jacobian column block (slots, then roots): the handles with rows in it
    /// (ascending): a slot's are the handles at or below it, a root's those below it.
    pub(crate) block_handles: Csr,
    /// The column blocks grouped by identical `block_handles` rows, ascending in each group.
    pub(crate) block_groups: Csr,
    /// Roots above (or equal to) some handle, ascending.
    pub(crate) roots: Vec<u32>,
    /// Per handle: its position in `roots`.
    pub(crate) handle_root: Vec<u32>,
    pub(crate) length_scale: f32,
    pub(crate) fabrik: FabrikTree,
}

/// FABRIK's point tree: the pivots of the slots that move an effector (parents first),
/// then one node per effector.
#[derive(Clone, Debug, Default)]
pub(crate) struct FabrikTree {
    /// Per node: the slot (pivot nodes) or `None` (effector nodes, see `handle`).
    pub(crate) slot: Vec<Option<u32>>,
    /// Per node: the parent node, `None` for a fixed base.
    pub(crate) parent: Vec<Option<u32>>,
    /// Per node: its children.
    pub(crate) children: Csr,
    /// Per node: the handle (effector nodes only).
    pub(crate) handle: Vec<Option<u32>>,
    /// Per slot: its node, if it is a pivot node.
    pub(crate) node_of_slot: Vec<Option<u32>>,
}

impl IkProblem {
    /// Compiles a problem.
    ///
    /// - `handles`: the effectors, in the order targets will be given.
    /// - `movable`: the joints the solver may turn; `None` for every ancestor of a handle
    ///   (and the handle joint itself when its effector has an offset, since then its
    ///   rotation moves the effector). Pass the handle joints too when orientation targets
    ///   should be met by turning them. Repeats are ignored.
    /// - `limits`: per-joint limits; entries for joints that do not move are unused, a later
    ///   entry for the same joint replaces an earlier one.
    ///
    /// # Errors
    /// [`IkError::NoHandles`]; [`IkError::JointOutOfRange`] for a joint index in any list;
    /// [`IkError::NonFiniteOffset`]; [`IkError::BadLimit`].
    pub fn new(
        skeleton: &Skeleton,
        handles: &[IkEffector],
        movable: Option<&[JointIndex]>,
        limits: &[(JointIndex, JointLimit)],
    ) -> Result<Self, IkError> {
        let n = skeleton.len();
        if handles.is_empty() {
            return Err(IkError::NoHandles);
        }
        let check = |what, j: JointIndex| {
            if j.get() < n {
                Ok(j.get())
            } else {
                Err(IkError::JointOutOfRange {
                    what,
                    index: j.get(),
                    count: n,
                })
            }
        };
        for (h, e) in handles.iter().enumerate() {
            check("handles", e.joint)?;
            if !e.local_offset.is_finite() {
                return Err(IkError::NonFiniteOffset { handle: h });
            }
        }
        let parents: Vec<Option<JointIndex>> = skeleton.parents().collect();
        let ancestors = |j: usize| {
            std::iter::successors(parents.get(j).copied().flatten(), |p| {
                parents.get(p.get()).copied().flatten()
            })
            .map(JointIndex::get)
        };
        let mut is_movable = vec![false; n];
        match movable {
            Some(list) => {
                for &j in list {
                    is_movable[check("movable", j)?] = true;
                }
            }
            None => {
                for e in handles {
                    for a in ancestors(e.joint.get()) {
                        is_movable[a] = true;
                    }
                    if e.local_offset != Vec3::ZERO {
                        is_movable[e.joint.get()] = true;
                    }
                }
            }
        }
        let mut limit_of: Vec<Option<JointLimit>> = vec![None; n];
        for (j, l) in limits {
            let j = check("limits", *j)?;
            l.check(j)?;
            limit_of[j] = Some(*l);
        }
        let movable: Vec<u32> = (0..n as u32).filter(|&j| is_movable[j as usize]).collect();
        let mut slot_of = vec![None; n];
        for (s, &j) in movable.iter().enumerate() {
            slot_of[j as usize] = Some(s as u32);
        }
        let limits = movable.iter().map(|&j| limit_of[j as usize]).collect();
        let handle_slots = Csr::from_rows(handles.iter().map(|e| {
            let j = e.joint.get();
            let mut slots: Vec<u32> = std::iter::once(j)
                .chain(ancestors(j))
                .filter_map(|a| slot_of[a])
                .collect();
            slots.sort_unstable();
            slots
        }));
        // A slot moves an effector when it is a strict ancestor of the handle joint, or the
        // handle joint itself with an offset effector.
        let moves = |s: u32, h: usize| {
            let e = &handles[h];
            movable[s as usize] as usize != e.joint.get() || e.local_offset != Vec3::ZERO
        };
        let slot_handles = Csr::from_rows((0..movable.len() as u32).map(|s| {
            (0..handles.len())
                .filter(|&h| handle_slots.row(h).contains(&s) && moves(s, h))
                .map(|h| h as u32)
                .collect()
        }));
        // Forward kinematics covers the handles, the movable joints and their ancestors.
        let mut needed = vec![false; n];
        for j in handles
            .iter()
            .map(|e| e.joint.get())
            .chain(movable.iter().map(|&j| j as usize))
        {
            needed[j] = true;
            for a in ancestors(j) {
                needed[a] = true;
            }
        }
        let fk_joints = (0..n as u32).filter(|&j| needed[j as usize]).collect();
        let root_of = |j: usize| ancestors(j).last().unwrap_or(j) as u32;
        let mut roots: Vec<u32> = handles.iter().map(|e| root_of(e.joint.get())).collect();
        roots.sort_unstable();
        roots.dedup();
        let handle_root: Vec<u32> = handles
            .iter()
            .map(|e| {
                let r = root_of(e.joint.get());
                roots.iter().position(|&x| x == r).unwrap_or(0) as u32
            })
            .collect();
        // Length scale: the largest side of the bounding box of the rest joints and effectors.
        let rest_model = skeleton.model_rest_matrices();
        let points =
            rest_model
                .iter()
                .map(|m| m.w_axis.truncate())
                .chain(handles.iter().filter_map(|e| {
                    rest_model
                        .get(e.joint.get())
                        .map(|m| m.transform_point3(e.local_offset))
                }));
        let (lo, hi) = points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
        let side = (hi - lo).max_element();
        let length_scale = if side.is_finite() && side > 0.0 {
            side
        } else {
            1.0
        };
        let block_handles = Csr::from_rows(
            (0..movable.len() as u32)
                .map(|s| {
                    (0..handles.len() as u32)
                        .filter(|&h| handle_slots.row(h as usize).contains(&s))
                        .collect()
                })
                .chain((0..roots.len() as u32).map(|r| {
                    (0..handles.len() as u32)
                        .filter(|&h| handle_root[h as usize] == r)
                        .collect()
                })),
        );
        // Blocks with the same handles share their rows: the DLS normal matrix sums their
        // products in one pass (the hand's palm joints, a limb's joints below its root).
        let mut groups: Vec<(Vec<u32>, Vec<u32>)> = Vec::new();
        for b in 0..block_handles.start.len().saturating_sub(1) {
            let hs = block_handles.row(b);
            match groups.iter_mut().find(|(h, _)| h.as_slice() == hs) {
                Some((_, blocks)) => blocks.push(b as u32),
                None => groups.push((hs.to_vec(), vec![b as u32])),
            }
        }
        let block_groups = Csr::from_rows(groups.into_iter().map(|(_, blocks)| blocks));
        let mut problem = IkProblem {
            parents,
            rest_rotation: skeleton
                .joints()
                .iter()
                .map(|j| j.rest_local.rotation)
                .collect(),
            effectors: handles.to_vec(),
            fk_joints,
            movable,
            slot_of,
            limits,
            handle_slots,
            slot_handles,
            block_handles,
            block_groups,
            roots,
            handle_root,
            length_scale,
            fabrik: FabrikTree::default(),
        };
        problem.fabrik = problem.build_fabrik_tree();
        Ok(problem)
    }

    pub(crate) fn build_fabrik_tree(&self) -> FabrikTree {
        let slots = self.movable.len();
        let mut t = FabrikTree {
            node_of_slot: vec![None; slots],
            ..FabrikTree::default()
        };
        // The nearest slot at or above `j` that is a pivot node.
        let pivot_at_or_above = |t: &FabrikTree, mut j: Option<JointIndex>| {
            while let Some(x) = j {
                if let Some(node) = self.slot_of[x.get()].and_then(|s| t.node_of_slot[s as usize]) {
                    return Some(node);
                }
                j = self.parents[x.get()];
            }
            None
        };
        for s in 0..slots {
            if self.slot_handles.row(s).is_empty() {
                continue;
            }
            let j = self.movable[s] as usize;
            let parent = pivot_at_or_above(&t, self.parents[j]);
            t.node_of_slot[s] = Some(t.slot.len() as u32);
            t.slot.push(Some(s as u32));
            t.parent.push(parent);
            t.handle.push(None);
        }
        for (h, e) in self.effectors.iter().enumerate() {
            let start = if e.local_offset != Vec3::ZERO {
                Some(e.joint)
            } else {
                self.parents[e.joint.get()]
            };
            let parent = pivot_at_or_above(&t, start);
            t.slot.push(None);
            t.parent.push(parent);
            t.handle.push(Some(h as u32));
        }
        let nodes = t.slot.len();
        t.children = Csr::from_rows((0..nodes as u32).map(|i| {
            (0..nodes as u32)
                .filter(|&c| t.parent[c as usize] == Some(i))
                .collect()
        }));
        t
    }

    /// Number of handles.
    pub fn handle_count(&self) -> usize {
        self.effectors.len()
    }

    /// Number of skeleton joints (the pose length).
    pub fn joint_count(&self) -> usize {
        self.parents.len()
    }

    /// The handles' effectors, in order.
    pub fn effectors(&self) -> &[IkEffector] {
        &self.effectors
    }

    /// The movable joints, ascending.
    pub fn movable(&self) -> impl ExactSizeIterator<Item = JointIndex> + '_ {
        self.movable.iter().map(|&j| JointIndex(j))
    }

    /// The rig's size: the largest side of the bounding box of the model-space rest joint
    /// positions and effectors (asset length unit; 1 if that is 0). Scales orientation rows
    /// and the adaptive damping bias.
    pub fn length_scale(&self) -> f32 {
        self.length_scale
    }

    /// Most Jacobian rows (3 per handle, 3 more for each orientation target).
    pub(crate) fn max_rows(&self) -> usize {
        6 * self.effectors.len()
    }

    /// Most Jacobian columns (3 per movable joint, 3 per root when it translates).
    pub(crate) fn max_cols(&self) -> usize {
        3 * self.movable.len() + 3 * self.roots.len()
    }
}
