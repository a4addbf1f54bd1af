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
//! use rigport_ik::{IkHandle, IkMethod, IkProblem, IkReport, IkScratch, IkSettings, IkSolveJob, Lambda};
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
pub mod footlock;
mod handles;
mod limits;
mod linalg;
pub mod naming;
mod problem;
pub mod retarget;
mod solver;
#[cfg(test)]
mod tests;
pub mod two_bone;

use glam::{Affine3A, DVec3, Mat3, Quat, Vec3};
use rigport_model::Transform;

pub(crate) use limits::axis_angle;
pub use limits::{euler_angles, JointLimit};
pub use problem::{IkEffector, IkError, IkHandle, IkProblem};

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

impl IkProblem {
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

impl JointLimit {
    /// Checks the bounds (`joint` names it in the error).
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
/// roots (as [`rigport_eval::LocalToModelJob`] with `root_model = IDENTITY`). Deterministic: the
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
