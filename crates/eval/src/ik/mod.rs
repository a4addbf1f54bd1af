//! Inverse kinematics: damped least squares, pseudo-inverse, Jacobian transpose, CCD and
//! FABRIK solvers that move a pose so that chosen joints (handles) reach model-space
//! targets.
//!
//! # How to use it
//! Build an [`IkProblem`] once per skeleton and handle set (it fixes which joints move and
//! how), an [`IkScratch`] and an [`IkReport`] sized for it, then run one [`IkSolveJob`] per
//! frame. The pose is both input (warm start: the previous frame of a clip, or the rest
//! pose) and output; `run()` allocates nothing.
//!
//! ```
//! use rigport_eval::ik::{IkHandle, IkMethod, IkProblem, IkReport, IkScratch, IkSettings, IkSolveJob, Lambda};
//! use rigport_model::glam::Vec3;
//! use rigport_model::{Joint, JointIndex, Skeleton, Transform};
//!
//! // A two-bone arm along +X: shoulder (0) -> elbow (1) -> wrist (2), bones 1 long.
//! let joint = |name: &str, parent: Option<u32>, x: f32| Joint {
//!     name: name.into(),
//!     parent: parent.map(JointIndex),
//!     rest_local: Transform::from_translation(Vec3::new(x, 0.0, 0.0)),
//! };
//! let skeleton = Skeleton::new(vec![joint("shoulder", None, 0.0), joint("elbow", Some(0), 1.0), joint("wrist", Some(1), 1.0)]).unwrap();
//! let problem = IkProblem::new(&skeleton, &[JointIndex(2).into()], None, &[]).unwrap();
//! let mut scratch = IkScratch::new(&problem);
//! let mut report = IkReport::new(&problem);
//! let settings = IkSettings { method: IkMethod::Dls { lambda: Lambda::Adaptive }, tolerance: 1e-4, ..IkSettings::default() };
//! let mut pose: Vec<Transform> = skeleton.joints().iter().map(|j| j.rest_local).collect();
//! let targets = [IkHandle::new(JointIndex(2), Vec3::new(1.0, 1.0, 0.5))];
//! IkSolveJob { problem: &problem, targets: &targets, settings: &settings, pose: &mut pose, scratch: &mut scratch, report: &mut report }
//!     .run()
//!     .unwrap();
//! assert!(report.converged && report.residuals[0] <= 1e-4);
//! ```
//!
//! # Degrees of freedom and the Jacobian
//! Every movable joint has 3 rotational degrees of freedom: small rotations `ω` about the
//! axes of its **parent's** frame (the model frame for a root), applied as
//! `local.rotation ← exp(ω) · local.rotation`. Optionally each root above a handle also
//! translates (3 more, model-space axes). The Jacobian is analytic: a point `p` below joint
//! `j` (pivot `o`, parent linear part `A`) moves with `∂p/∂ω_k = A (e_k × A⁻¹ (p - o))`,
//! which is the textbook `axis × (p - o)` with world axes `A e_k` whenever `A` is a rotation
//! times a uniform scale (every importer's rigs; non-uniform parent scale is handled by the
//! `A⁻¹` and stays exact). Orientation rows use the angular velocity `A e_k / |A e_k|` (exact
//! for rotation times uniform scale) and are scaled by [`IkProblem::length_scale`] so that
//! they share the position rows' unit.
//!
//! # Methods
//! See [`IkMethod`]. The Jacobian methods use every degree of freedom (and root
//! translation); [`IkMethod::Ccd`] and [`IkMethod::Fabrik`] rotate joints only (they ignore
//! [`IkSettings::free_root_translation`]) and meet an orientation target by turning the
//! handle joint itself when it is movable.
//!
//! # Iteration, step clamping, sub-steps, limits
//! One iteration = one update of the pose (a Jacobian step, a CCD sweep or a FABRIK pass).
//! Each joint turns by at most [`IkSettings::max_step_rad`] per iteration (Jacobian steps are
//! scaled as a whole so their direction is kept; root translation counts
//! `|Δt| / length_scale` as its angle). Joint limits ([`JointLimit`]) are enforced by
//! projecting the local rotation after each update. When [`IkSettings::substep`] is set and
//! a target lies farther than that from its effector, the move is cut into equal portions
//! (at most [`MAX_SUBSTEPS`]) and each is solved in turn from the previous one's solution.
//! Each portion keeps the best pose it saw (smallest weighted squared error against its
//! goals) and ends on it, so without sub-steps the output is never worse than the warm
//! start, and it is never NaN for finite input. The solver is deterministic: no randomness,
//! no hashing, fixed visiting orders.

pub mod chains;
pub mod clip;
mod handles;
mod linalg;
mod solver;
#[cfg(test)]
mod tests;
pub mod two_bone;

use glam::{Affine3A, DVec3, Mat3, Quat, Vec3};
use rigport_model::conventions::EulerOrder;
use rigport_model::{JointIndex, Skeleton, Transform};

/// A target move is never cut into more portions than this, so a tiny
/// [`IkSettings::substep`] with a far target cannot stall a frame (each portion then moves
/// more than `substep`).
pub const MAX_SUBSTEPS: u32 = 256;

/// Adaptive damping: `λ² = ADAPTIVE_GAIN · |ẽ|² + ADAPTIVE_BIAS · length_scale²` (see
/// [`Lambda::Adaptive`]). Sugihara 2011 uses a gain of ½ and a bias of `1e-3` m² for robot
/// arms (with `1e-3 · length_scale²`, the corpus rigs of `examples/ik_bench.rs` need 5.6,
/// 10.3 and 4.4 iterations on average: armadillo, hand, humanoid). A gain of 0.1 and a bias
/// of `1e-5 · length_scale²` (chosen by a sweep over gains 0.01..0.5 and biases 1e-6..1e-3
/// on those rigs) need 5.1, 6.0 and 4.2, at the same 100% success: the larger bias
/// over-damps the hand's short finger bones near the solution (linear instead of
/// near-quadratic convergence).
pub const ADAPTIVE_GAIN: f32 = 0.1;

/// See [`ADAPTIVE_GAIN`]. Relative to the rig's size so the rule is unit-free.
pub const ADAPTIVE_BIAS: f32 = 1e-5;

/// Something wrong with an IK problem or a solve job's inputs. Found by [`IkProblem::new`] or
/// [`IkSolveJob::validate`], before any work.
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

/// A bound on a joint's rotation relative to its rest rotation: with `delta =
/// rest_rotation⁻¹ · local_rotation`, the bound applies to `delta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointLimit {
    /// `delta`'s rotation angle is at most `max_rad` (`0 ..= π`); a longer rotation is cut
    /// to that angle about the same axis.
    Angle {
        /// The largest angle, radians.
        max_rad: f32,
    },
    /// `delta`'s Euler angles in `order` (see [`EulerOrder`]; `[x, y, z]` radians whatever the
    /// order) stay within `min_rad ..= max_rad` per axis, each clamped after decomposition.
    Euler {
        /// The axis order the angles are read in.
        order: EulerOrder,
        /// Lower bounds `[x, y, z]`, radians.
        min_rad: Vec3,
        /// Upper bounds `[x, y, z]`, radians.
        max_rad: Vec3,
    },
    /// As [`JointLimit::Euler`], with the angles those of `frame⁻¹ · delta · frame`: axes of
    /// another frame than the rest frame (an ASF bone's `axis` frame; see
    /// [`rigport_model::RotationLimit`]).
    EulerInFrame {
        /// The frame the angles are read in, relative to the rest frame (unit).
        frame: Quat,
        /// The axis order the angles are read in.
        order: EulerOrder,
        /// Lower bounds `[x, y, z]`, radians.
        min_rad: Vec3,
        /// Upper bounds `[x, y, z]`, radians.
        max_rad: Vec3,
    },
}

impl From<&rigport_model::RotationLimit> for JointLimit {
    fn from(l: &rigport_model::RotationLimit) -> Self {
        if l.frame == Quat::IDENTITY {
            JointLimit::Euler {
                order: l.order,
                min_rad: l.min_rad,
                max_rad: l.max_rad,
            }
        } else {
            JointLimit::EulerInFrame {
                frame: l.frame,
                order: l.order,
                min_rad: l.min_rad,
                max_rad: l.max_rad,
            }
        }
    }
}

impl JointLimit {
    /// Projects `delta` (the rotation relative to rest) into the limit: the angle cut for
    /// [`JointLimit::Angle`], each Euler angle clamped after decomposition for the Euler
    /// variants (a clamp, not the nearest rotation within the limit).
    pub fn project(&self, delta: Quat) -> Quat {
        match *self {
            JointLimit::Angle { max_rad } => {
                let (axis, angle) = axis_angle(delta);
                if angle > max_rad && axis.is_finite() {
                    Quat::from_axis_angle(axis, max_rad)
                } else {
                    delta
                }
            }
            JointLimit::Euler {
                order,
                min_rad,
                max_rad,
            } => {
                let angles = euler_angles(order, delta);
                let clamped = Vec3::from(angles).clamp(min_rad, max_rad);
                order.to_quat(clamped.to_array())
            }
            JointLimit::EulerInFrame {
                frame,
                order,
                min_rad,
                max_rad,
            } => {
                let inner = JointLimit::Euler {
                    order,
                    min_rad,
                    max_rad,
                };
                (frame * inner.project(frame.conjugate() * delta * frame) * frame.conjugate())
                    .normalize()
            }
        }
    }

    /// How far `delta` (the rotation relative to rest) is outside the limit, radians: the
    /// largest Euler angle excess (Euler variants) or angle excess ([`JointLimit::Angle`]).
    pub fn excess_rad(&self, delta: Quat) -> f32 {
        match *self {
            JointLimit::Angle { max_rad } => (axis_angle(delta).1 - max_rad).max(0.0),
            JointLimit::Euler {
                order,
                min_rad,
                max_rad,
            } => {
                let a = Vec3::from(euler_angles(order, delta));
                (min_rad - a).max(a - max_rad).max_element().max(0.0)
            }
            JointLimit::EulerInFrame {
                frame,
                order,
                min_rad,
                max_rad,
            } => JointLimit::Euler {
                order,
                min_rad,
                max_rad,
            }
            .excess_rad(frame.conjugate() * delta * frame),
        }
    }

    fn check(&self, joint: usize) -> Result<(), IkError> {
        let bad = |why| Err(IkError::BadLimit { joint, why });
        match *self {
            JointLimit::Angle { max_rad } => {
                if !(0.0..=std::f32::consts::PI).contains(&max_rad) {
                    return bad("max_rad must be within 0..=pi");
                }
            }
            JointLimit::EulerInFrame { frame, .. } if !frame.is_finite() => {
                return bad("frame must be finite");
            }
            JointLimit::Euler {
                min_rad, max_rad, ..
            }
            | JointLimit::EulerInFrame {
                min_rad, max_rad, ..
            } => {
                if !min_rad.is_finite() || !max_rad.is_finite() {
                    return bad("bounds must be finite");
                }
                if min_rad.cmpgt(max_rad).any() {
                    return bad("min_rad > max_rad");
                }
            }
        }
        Ok(())
    }
}

/// The Euler angles `[x, y, z]` (radians) of `q` in `order`, the inverse of
/// [`EulerOrder::to_quat`].
pub fn euler_angles(order: EulerOrder, q: Quat) -> [f32; 3] {
    use glam::EulerRot;
    // The same table as `EulerOrder::to_quat`: glam names the outermost rotation first.
    match order {
        EulerOrder::Xyz => {
            let (z, y, x) = q.to_euler(EulerRot::ZYX);
            [x, y, z]
        }
        EulerOrder::Yzx => {
            let (x, z, y) = q.to_euler(EulerRot::XZY);
            [x, y, z]
        }
        EulerOrder::Zxy => {
            let (y, x, z) = q.to_euler(EulerRot::YXZ);
            [x, y, z]
        }
        EulerOrder::Xzy => {
            let (y, z, x) = q.to_euler(EulerRot::YZX);
            [x, y, z]
        }
        EulerOrder::Yxz => {
            let (z, x, y) = q.to_euler(EulerRot::ZXY);
            [x, y, z]
        }
        EulerOrder::Zyx => {
            let (x, y, z) = q.to_euler(EulerRot::XYZ);
            [x, y, z]
        }
    }
}

/// A unit quaternion's axis and angle (`0..=π`), accurate for small angles: `2·atan2(|v|, |w|)`
/// keeps the angle that glam's `acos(w)` loses below about `5e-4` rad in `f32`. The axis is
/// zero for the identity.
pub(crate) fn axis_angle(q: Quat) -> (Vec3, f32) {
    let q = if q.w < 0.0 { -q } else { q };
    let v = Vec3::new(q.x, q.y, q.z);
    let len = v.length();
    if len.is_nan() || len <= 0.0 || len.is_infinite() {
        return (Vec3::ZERO, 0.0);
    }
    (v / len, 2.0 * len.atan2(q.w))
}

/// The damping of [`IkMethod::Dls`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lambda {
    /// A constant `λ`, in the asset's length unit (`λ²` adds to `J Jᵀ`, whose entries are
    /// squared lengths). Buss & Kim 2005 suggest about a tenth of the chain's length
    /// for interactive use; smaller converges faster near targets, larger is smoother near
    /// singularities.
    Fixed(f32),
    /// `λ² = ADAPTIVE_GAIN · eᵀ W e + ADAPTIVE_BIAS · length_scale²`: damping that shrinks
    /// with the residual, the Levenberg–Marquardt rule `λ_k = μ‖F_k‖² (+ bias)` of Fan &
    /// Yuan, "On the quadratic convergence of the Levenberg–Marquardt method without
    /// nonsingularity assumption", Computing 74, 2005, as Sugihara applies it to IK
    /// ("Solvability-unconcerned inverse kinematics by the Levenberg–Marquardt method",
    /// IEEE T-RO 27(5), 2011). Heavy damping while far from the targets (or when they are
    /// unreachable), almost Gauss–Newton (near-quadratic convergence) close to them. See
    /// [`ADAPTIVE_GAIN`] for the constants.
    Adaptive,
}

/// The solver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IkMethod {
    /// Damped least squares (Tikhonov / Levenberg–Marquardt): `(Jᵀ W J + λ² I) Δθ = Jᵀ W e`,
    /// solved in the dual form `Δθ = Jᵀ W^{½} (J̃ J̃ᵀ + λ² I)⁻¹ ẽ` (with `J̃ = W^{½} J`) when
    /// there are fewer rows than columns (cheaper), by Cholesky in `f64`.
    Dls {
        /// The damping.
        lambda: Lambda,
    },
    /// Pseudo-inverse `Δθ = J̃⁺ ẽ` from a one-sided Jacobi SVD; singular values below
    /// `cutoff · σ_max` are dropped (`0 ..< 1`; e.g. `1e-3`). Undamped, so it relies on the
    /// step clamp near singularities.
    Pinv {
        /// The relative singular-value cutoff.
        cutoff: f32,
    },
    /// Jacobian transpose `Δθ = α J̃ᵀ ẽ` with Buss's step `α = ⟨ẽ, J̃J̃ᵀẽ⟩ / |J̃J̃ᵀẽ|²`
    /// (Buss 2004, "Introduction to inverse kinematics with Jacobian transpose,
    /// pseudoinverse and damped least squares methods", eq. 8). Cheap per iteration, slow to
    /// converge.
    Transpose,
    /// Cyclic coordinate descent (Wang & Chen 1991): one sweep visits the movable joints from
    /// the deepest to the root, turning each by the rotation that best maps its descendant
    /// effectors onto their targets (the shortest arc for one effector, Horn's weighted
    /// best fit for several).
    Ccd,
    /// FABRIK (Aristidou & Lasenby 2011, with the multiple-end-effector centroid rule): one
    /// backward and one forward pass over the movable joints' pivots and the effectors, then
    /// each joint, parents first, is turned by the smallest rotation (Horn's best fit when
    /// several child pivots hang off it) that maps its current child directions onto the
    /// solved ones, so the result is an ordinary pose.
    Fabrik,
}

impl IkMethod {
    /// The method's name as the CLI spells it: `dls`, `pinv`, `transpose`, `ccd`, `fabrik`.
    pub fn name(&self) -> &'static str {
        match self {
            IkMethod::Dls { .. } => "dls",
            IkMethod::Pinv { .. } => "pinv",
            IkMethod::Transpose => "transpose",
            IkMethod::Ccd => "ccd",
            IkMethod::Fabrik => "fabrik",
        }
    }

    /// The method named `name` (as [`IkMethod::name`]) with its default parameters
    /// (adaptive damping; pseudo-inverse cutoff `1e-3`).
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "dls" => IkMethod::Dls {
                lambda: Lambda::Adaptive,
            },
            "pinv" => IkMethod::Pinv { cutoff: 1e-3 },
            "transpose" => IkMethod::Transpose,
            "ccd" => IkMethod::Ccd,
            "fabrik" => IkMethod::Fabrik,
            _ => return None,
        })
    }
}

/// How to solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkSettings {
    /// The solver.
    pub method: IkMethod,
    /// Most iterations per solve (per portion when sub-stepping). 0 evaluates the warm
    /// start only.
    pub max_iterations: u32,
    /// A handle has converged when its effector is within this distance of its target
    /// (asset length unit, `>= 0`).
    pub tolerance: f32,
    /// ... and, if it has a target orientation, within this angle of it (radians, `>= 0`).
    pub orientation_tolerance_rad: f32,
    /// Largest rotation of one joint per iteration (radians, `> 0`).
    pub max_step_rad: f32,
    /// Largest target move per sub-step (asset length unit, `> 0`), or `None` to solve for
    /// the final targets at once.
    pub substep: Option<f32>,
    /// Whether the roots above the handles may translate (Jacobian methods only).
    pub free_root_translation: bool,
}

impl Default for IkSettings {
    /// Adaptive DLS, 100 iterations, tolerance `1e-4` length units and `1e-3` rad, steps
    /// of at most 0.5 rad, no sub-steps, fixed roots. Set `tolerance` for the asset's unit.
    fn default() -> Self {
        Self {
            method: IkMethod::Dls {
                lambda: Lambda::Adaptive,
            },
            max_iterations: 100,
            tolerance: 1e-4,
            orientation_tolerance_rad: 1e-3,
            max_step_rad: 0.5,
            substep: None,
            free_root_translation: false,
        }
    }
}

impl IkSettings {
    /// Checks every field's range.
    ///
    /// # Errors
    /// [`IkError::BadSetting`] for the first field out of range.
    pub fn validate(&self) -> Result<(), IkError> {
        let bad = |what, value, expected| {
            Err(IkError::BadSetting {
                what,
                value,
                expected,
            })
        };
        if !(self.tolerance >= 0.0 && self.tolerance.is_finite()) {
            return bad("tolerance", self.tolerance, "must be finite and >= 0");
        }
        if !(self.orientation_tolerance_rad >= 0.0 && self.orientation_tolerance_rad.is_finite()) {
            return bad(
                "orientation_tolerance_rad",
                self.orientation_tolerance_rad,
                "must be finite and >= 0",
            );
        }
        if !(self.max_step_rad > 0.0 && self.max_step_rad.is_finite()) {
            return bad("max_step_rad", self.max_step_rad, "must be finite and > 0");
        }
        if let Some(s) = self.substep {
            if !(s > 0.0 && s.is_finite()) {
                return bad("substep", s, "must be finite and > 0");
            }
        }
        match self.method {
            IkMethod::Dls {
                lambda: Lambda::Fixed(l),
            } if !(l >= 0.0 && l.is_finite()) => bad("lambda", l, "must be finite and >= 0"),
            IkMethod::Pinv { cutoff } if !(0.0..1.0).contains(&cutoff) => {
                bad("cutoff", cutoff, "must be within 0..1")
            }
            _ => Ok(()),
        }
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
struct Csr {
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Csr {
    fn from_rows(rows: impl Iterator<Item = Vec<u32>>) -> Self {
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

    fn row(&self, i: usize) -> &[u32] {
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
    parents: Vec<Option<JointIndex>>,
    rest_rotation: Vec<Quat>,
    effectors: Vec<IkEffector>,
    /// Joints whose model matrix the solver needs (handles, movable joints and their
    /// ancestors), ascending.
    fk_joints: Vec<u32>,
    /// Movable joints, ascending; a joint's position here is its *slot*.
    movable: Vec<u32>,
    /// Per joint: its slot, if movable.
    slot_of: Vec<Option<u32>>,
    /// Per slot.
    limits: Vec<Option<JointLimit>>,
    /// Per handle: the slots that are the handle joint or its ancestors, ascending.
    handle_slots: Csr,
    /// Per slot: the handles whose effector it moves.
    slot_handles: Csr,
    /// Per Jacobian column block (slots, then roots): the handles with rows in it
    /// (ascending): a slot's are the handles at or below it, a root's those below it.
    block_handles: Csr,
    /// The column blocks grouped by identical `block_handles` rows, ascending in each group.
    block_groups: Csr,
    /// Roots above (or equal to) some handle, ascending.
    roots: Vec<u32>,
    /// Per handle: its position in `roots`.
    handle_root: Vec<u32>,
    length_scale: f32,
    fabrik: FabrikTree,
}

/// FABRIK's point tree: the pivots of the slots that move an effector (parents first),
/// then one node per effector.
#[derive(Clone, Debug, Default)]
struct FabrikTree {
    /// Per node: the slot (pivot nodes) or `None` (effector nodes, see `handle`).
    slot: Vec<Option<u32>>,
    /// Per node: the parent node, `None` for a fixed base.
    parent: Vec<Option<u32>>,
    /// Per node: its children.
    children: Csr,
    /// Per node: the handle (effector nodes only).
    handle: Vec<Option<u32>>,
    /// Per slot: its node, if it is a pivot node.
    node_of_slot: Vec<Option<u32>>,
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

    fn build_fabrik_tree(&self) -> FabrikTree {
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
    fn max_rows(&self) -> usize {
        6 * self.effectors.len()
    }

    /// Most Jacobian columns (3 per movable joint, 3 per root when it translates).
    fn max_cols(&self) -> usize {
        3 * self.movable.len() + 3 * self.roots.len()
    }

    /// Model-space effector positions of a pose (one per handle), e.g. to make targets by
    /// forward kinematics or to measure residuals independently of a solve. Allocates.
    ///
    /// # Errors
    /// [`IkError::Length`] if `pose` is not one transform per joint.
    pub fn effector_positions(&self, pose: &[Transform]) -> Result<Vec<Vec3>, IkError> {
        if pose.len() != self.parents.len() {
            return Err(IkError::Length {
                what: "pose",
                expected: self.parents.len(),
                found: pose.len(),
            });
        }
        let mut model = vec![Affine3A::IDENTITY; pose.len()];
        solver::forward(self, pose, &mut model);
        Ok(self
            .effectors
            .iter()
            .map(|e| model[e.joint.get()].transform_point3(e.local_offset))
            .collect())
    }
}

/// Buffers for [`IkSolveJob`], sized once for one [`IkProblem`] by [`IkScratch::new`] and
/// reused for every solve of it (no allocation during a solve).
#[derive(Clone, Debug)]
pub struct IkScratch {
    joints: usize,
    handles: usize,
    cols: usize,
    model: Vec<Affine3A>,
    /// Whether every joint forward kinematics visits has scale 1 (set with `model`).
    unit_scale: bool,
    /// Per slot: the parent's linear part and its inverse.
    parent_lin: Vec<Mat3>,
    parent_inv: Vec<Mat3>,
    /// Per handle: effector position and joint rotation.
    eff: Vec<Vec3>,
    eff_rot: Vec<Quat>,
    /// Per handle: the (sub-step) goal and the sub-step start.
    goal: Vec<Vec3>,
    goal_rot: Vec<Option<Quat>>,
    start: Vec<Vec3>,
    start_rot: Vec<Quat>,
    /// Per handle: first Jacobian row.
    row_start: Vec<u32>,
    /// The Jacobian by column block: `max_rows` row entries per block.
    slab: Vec<DVec3>,
    /// One block group's rows and their entries, gathered row-major.
    gather_rows: Vec<u32>,
    gather: Vec<f64>,
    jac: Vec<f64>,
    err: Vec<f64>,
    sys: Vec<f64>,
    rhs: Vec<f64>,
    dtheta: Vec<f64>,
    tmp_rows: Vec<f64>,
    /// The pseudo-inverse's `G` and `σ²`.
    svd_work: Vec<f64>,
    best_pose: Vec<Transform>,
    /// FABRIK per node: current, backward and forward positions, backward accumulators,
    /// offsets in the parent pivot's joint frame, lengths, weights.
    fab_p: Vec<Vec3>,
    fab_b: Vec<Vec3>,
    fab_f: Vec<Vec3>,
    fab_sum: Vec<Vec3>,
    fab_w: Vec<f32>,
    fab_off: Vec<Vec3>,
    fab_len: Vec<f32>,
}

impl IkScratch {
    /// Buffers for `problem`.
    pub fn new(problem: &IkProblem) -> Self {
        let (n, h) = (problem.joint_count(), problem.handle_count());
        let (rows, cols) = (problem.max_rows(), problem.max_cols());
        let slots = problem.movable.len();
        let nodes = problem.fabrik.slot.len();
        let k = rows.min(cols);
        Self {
            joints: n,
            handles: h,
            cols,
            model: vec![Affine3A::IDENTITY; n],
            unit_scale: true,
            parent_lin: vec![Mat3::IDENTITY; slots],
            parent_inv: vec![Mat3::IDENTITY; slots],
            eff: vec![Vec3::ZERO; h],
            eff_rot: vec![Quat::IDENTITY; h],
            goal: vec![Vec3::ZERO; h],
            goal_rot: vec![None; h],
            start: vec![Vec3::ZERO; h],
            start_rot: vec![Quat::IDENTITY; h],
            row_start: vec![0; h + 1],
            slab: vec![DVec3::ZERO; rows * cols / 3],
            gather_rows: vec![0; rows],
            gather: vec![0.0; rows * cols],
            jac: vec![0.0; rows * cols],
            err: vec![0.0; rows],
            sys: vec![0.0; k * k],
            rhs: vec![0.0; rows.max(cols)],
            dtheta: vec![0.0; cols],
            tmp_rows: vec![0.0; rows],
            svd_work: vec![0.0; rows * rows + rows],
            best_pose: vec![Transform::IDENTITY; n],
            fab_p: vec![Vec3::ZERO; nodes],
            fab_b: vec![Vec3::ZERO; nodes],
            fab_f: vec![Vec3::ZERO; nodes],
            fab_sum: vec![Vec3::ZERO; nodes],
            fab_w: vec![0.0; nodes],
            fab_off: vec![Vec3::ZERO; nodes],
            fab_len: vec![0.0; nodes],
        }
    }
}

/// The outcome of a solve.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IkReport {
    /// Iterations run, summed over sub-steps.
    pub iterations: u32,
    /// Sub-steps the move was cut into (1 without sub-stepping).
    pub substeps: u32,
    /// Per handle: distance from effector to target after the solve (asset length unit).
    pub residuals: Vec<f32>,
    /// Per handle: angle to the target orientation after the solve (radians; 0 without
    /// one).
    pub orientation_residuals_rad: Vec<f32>,
    /// Whether every handle of non-zero weight is within the tolerances.
    pub converged: bool,
}

impl IkReport {
    /// A report sized for `problem`.
    pub fn new(problem: &IkProblem) -> Self {
        Self {
            iterations: 0,
            substeps: 0,
            residuals: vec![0.0; problem.handle_count()],
            orientation_residuals_rad: vec![0.0; problem.handle_count()],
            converged: false,
        }
    }
}

/// Solves one IK problem instance: moves `pose` so the handles' effectors reach their
/// targets.
///
/// The pose is in and out: the warm start (previous frame, or rest pose) and the
/// solution. Model space is the pose's forward kinematics with the identity above the
/// roots (as [`crate::LocalToModelJob`] with `root_model = IDENTITY`). Deterministic: the
/// same inputs give the same bits.
pub struct IkSolveJob<'a> {
    /// The compiled problem.
    pub problem: &'a IkProblem,
    /// One target per problem handle, same order.
    pub targets: &'a [IkHandle],
    /// How to solve.
    pub settings: &'a IkSettings,
    /// One local transform per skeleton joint: warm start in, solution out. Only movable
    /// joints' rotations (and, with `free_root_translation`, roots' translations) change.
    pub pose: &'a mut [Transform],
    /// Buffers from [`IkScratch::new`] for this problem.
    pub scratch: &'a mut IkScratch,
    /// Output, from [`IkReport::new`] for this problem.
    pub report: &'a mut IkReport,
}

impl IkSolveJob<'_> {
    /// Checks the inputs: lengths, that each target is for its handle's joint and is
    /// finite with a valid weight, a finite warm start, the settings' ranges, and that the
    /// scratch and report were made for this problem.
    ///
    /// # Errors
    /// [`IkError::Length`], [`IkError::TargetJoint`], [`IkError::NonFiniteTarget`],
    /// [`IkError::BadWeight`], [`IkError::NonFinitePose`], [`IkError::BadSetting`].
    pub fn validate(&self) -> Result<(), IkError> {
        let p = self.problem;
        let length = |what, expected: usize, found: usize| {
            if expected == found {
                Ok(())
            } else {
                Err(IkError::Length {
                    what,
                    expected,
                    found,
                })
            }
        };
        length("pose", p.joint_count(), self.pose.len())?;
        length("targets", p.handle_count(), self.targets.len())?;
        length("report", p.handle_count(), self.report.residuals.len())?;
        length(
            "report",
            p.handle_count(),
            self.report.orientation_residuals_rad.len(),
        )?;
        length("scratch", p.joint_count(), self.scratch.joints)?;
        length("scratch", p.handle_count(), self.scratch.handles)?;
        length("scratch", p.max_cols(), self.scratch.cols)?;
        length("scratch", p.fabrik.slot.len(), self.scratch.fab_p.len())?;
        for (handle, (t, e)) in self.targets.iter().zip(&p.effectors).enumerate() {
            if t.joint != e.joint {
                return Err(IkError::TargetJoint {
                    handle,
                    expected: e.joint,
                    found: t.joint,
                });
            }
            if !t.target.is_finite() {
                return Err(IkError::NonFiniteTarget {
                    handle,
                    what: "position",
                });
            }
            if let Some(q) = t.orientation {
                if !q.is_finite() || q.length_squared() < 1e-12 {
                    return Err(IkError::NonFiniteTarget {
                        handle,
                        what: "orientation",
                    });
                }
            }
            if !(t.weight >= 0.0 && t.weight.is_finite()) {
                return Err(IkError::BadWeight {
                    handle,
                    weight: t.weight,
                });
            }
        }
        if let Some(joint) = self.pose.iter().position(|t| !t.is_finite()) {
            return Err(IkError::NonFinitePose { joint });
        }
        self.settings.validate()
    }

    /// Validates, then solves. Allocates nothing.
    ///
    /// Unreachable targets give a best-effort pose (the closest the method gets) with the
    /// residuals reported and `converged == false`; degenerate input (a target at the
    /// joint, a straight chain, zero-length bones) gives a finite pose.
    ///
    /// # Errors
    /// As [`IkSolveJob::validate`].
    pub fn run(&mut self) -> Result<(), IkError> {
        self.validate()?;
        solver::solve(
            self.problem,
            self.targets,
            self.settings,
            self.pose,
            self.scratch,
            self.report,
        );
        Ok(())
    }
}
