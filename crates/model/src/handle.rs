//! IK handle tracks: model-space targets over time for chosen joints (`HANDLES.json`).

use glam::{Quat, Vec3};

use crate::conventions::EulerOrder;
use crate::JointIndex;

/// How a handle is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HandleSolver {
    /// The clip's iterative solver (`rigport ik --solver`), over the handle's chain.
    #[default]
    Iterative,
    /// The analytic two-bone solve: the handle joint is the tip, its parent the mid joint,
    /// its grandparent the root.
    TwoBone,
}

/// Whether the skeleton's root joints may move in an IK solve.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RootMotion {
    /// Roots keep their input translation and rotation.
    #[default]
    Locked,
    /// Roots may rotate and translate (iterative solvers).
    Free,
}

/// A joint's rotation limit: Euler angles of its rotation relative to rest, read in a
/// frame. With `delta = rest_rotation⁻¹ · local_rotation`, the angles `[x, y, z]` (radians)
/// of `frame⁻¹ · delta · frame` in `order` stay within `min_rad ..= max_rad` per axis
/// (`frame` is the identity for limits given in the joint's rest frame; an ASF bone's
/// `axis` rotation for its `dof`/`limits`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationLimit {
    /// The limited joint.
    pub joint: JointIndex,
    /// The frame the angles are read in, relative to the joint's rest frame.
    pub frame: Quat,
    /// The order the angles are applied in.
    pub order: EulerOrder,
    /// Lower bounds `[x, y, z]`, radians.
    pub min_rad: Vec3,
    /// Upper bounds `[x, y, z]`, radians (`>= min_rad`).
    pub max_rad: Vec3,
}

/// One handle: a joint, the effector point in the joint's frame, and its target track.
#[derive(Clone, Debug, PartialEq)]
pub struct HandleTrack {
    /// The driven joint.
    pub joint: JointIndex,
    /// Its name.
    pub name: String,
    /// The effector point in the joint's local frame (zero: the joint's origin).
    pub offset: Vec3,
    /// Weight in the solve, finite and `> 0`.
    pub weight: f32,
    /// Whether positions are offsets from the effector's rest position (model space).
    pub relative: bool,
    /// Key times in seconds, at least one, finite, `>= 0` and strictly increasing.
    pub times: Vec<f32>,
    /// Target positions, one per key (model space, or offsets when `relative`).
    pub positions: Vec<Vec3>,
    /// The topmost joint the solve may rotate for this handle (an ancestor of `joint`);
    /// `None`: every ancestor (up to the skeleton's root).
    pub root: Option<JointIndex>,
    /// A pin: no keys (`times` is empty); the effector keeps the model-space position it
    /// has in the input pose at the first frame.
    pub pin: bool,
    /// With `pin`: the joint keeps its input model-space rotation at the first frame too.
    pub orient: bool,
    /// Per key: a model-space rotation target for the joint (xyzw, normalized), or empty
    /// when no key has one.
    pub rotations: Vec<Option<Quat>>,
    /// Per key: the pole target (model space, or offset from the effector's rest position
    /// when `relative`), or empty without a pole.
    pub poles: Vec<Vec3>,
    /// Turn of the limb's plane about the root-to-target axis, degrees (two-bone).
    pub twist_deg: f32,
    /// The solver for this handle.
    pub solver: HandleSolver,
    /// Two-bone softening, `0..=1` (see `rigport_ik::two_bone`).
    pub soften: f32,
}

impl HandleTrack {
    /// A keyed position handle with today's defaults (no chain root, no pin, no rotation
    /// or pole, the iterative solver).
    pub fn keyed(joint: JointIndex, name: &str, times: Vec<f32>, positions: Vec<Vec3>) -> Self {
        Self {
            joint,
            name: name.into(),
            offset: Vec3::ZERO,
            weight: 1.0,
            relative: false,
            times,
            positions,
            root: None,
            pin: false,
            orient: false,
            rotations: Vec::new(),
            poles: Vec::new(),
            twist_deg: 0.0,
            solver: HandleSolver::Iterative,
            soften: 0.0,
        }
    }

    /// Whether the handle uses any field beyond position keys, offset, weight and
    /// `relative` (then the clip is solved by the chain-aware solver).
    pub fn uses_chains(&self) -> bool {
        self.root.is_some()
            || self.pin
            || self.rotations.iter().any(Option::is_some)
            || !self.poles.is_empty()
            || self.solver != HandleSolver::Iterative
    }
}

/// The handles of one handles file.
#[derive(Clone, Debug, PartialEq)]
pub struct HandleSet {
    /// Frames per second the source asks for, finite and `> 0`.
    pub fps: Option<f32>,
    /// At least one track, at most one per joint, in source order.
    pub tracks: Vec<HandleTrack>,
    /// The input clip the solve is layered over (each frame starts from its pose).
    pub base: Option<String>,
    /// Whether the roots may move; `None`: not given (locked).
    pub root_motion: Option<RootMotion>,
    /// Rotation limits from the handles file.
    pub limits: Vec<RotationLimit>,
}

impl HandleSet {
    /// Whether the set needs the chain-aware solver (any track does, a base clip, limits or
    /// an explicit root motion).
    pub fn uses_chains(&self) -> bool {
        self.tracks.iter().any(HandleTrack::uses_chains)
            || self.base.is_some()
            || self.root_motion.is_some()
            || !self.limits.is_empty()
    }
}
