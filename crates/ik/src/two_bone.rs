//! Analytic two-bone IK: a root, a mid and a tip joint (shoulder, elbow, wrist; hip, knee,
//! ankle) turned so that the tip reaches a target, with the mid joint bending about a fixed
//! hinge axis and the limb's plane fixed by a pole vector.
//!
//! The job is the runtime step of the kind ozz-animation's `IKTwoBoneJob` defines (target,
//! pole vector, mid axis, twist, soften, weight, `reached`), written from the geometry:
//!
//! 1. **Distance.** The root-to-target distance `d₀` becomes the wanted root-to-tip distance
//!    `d`: clamped to `[|l₁ − l₂|, l₁ + l₂]`, and with `soften = s > 0`, eased once it passes
//!    `(1 − s)·L` (`L = l₁ + l₂`) by `d = dₐ + d_s·(1 − e^{−(d₀ − dₐ)/d_s})` (`dₐ = (1 − s)·L`,
//!    `d_s = s·L`): continuous with a continuous slope at `dₐ`, and approaching `L` without
//!    reaching it, so the limb straightens gradually instead of snapping (the usual "soft IK"
//!    rule of Softimage and Unreal's `SoftIK`).
//! 2. **Mid joint.** It turns about `mid_axis` (the hinge, in its own frame) by the angle that
//!    makes the root-to-tip distance `d`, exactly, for any hinge not parallel to a bone: with
//!    `s` and `e` the root and the tip seen from the mid joint, `s·R(φ)e` is the sinusoid
//!    `A + B cos φ + C sin φ`, solved in closed form. Of its two solutions it takes the one
//!    that bends the limb to the positive side: after the turn `mid_axis · (s × e) ≥ 0`
//!    (a positive turn about `mid_axis` opens the elbow, as in ozz).
//! 3. **Root joint.** The shortest arc that points the root-to-tip line at the target,
//!    then a turn about that line that puts the mid joint in the half-plane spanned by the
//!    line and the pole vector (on the pole's side), rotated by `twist_rad` about the line.
//!
//! Everything is computed in `f64` from the `f32` inputs, so the solve itself adds no error
//! above the rounding of its `f32` outputs (about `1e-7` of the chain length).
//!
//! Model space is the space of the three joint matrices (the skeleton's, from
//! [`rigport_eval::LocalToModelJob`]); the corrections are exact for joint matrices that are a
//! rotation times a positive uniform scale (every importer's rigs). Non-uniform scale on
//! the root or mid joint bends the result (ozz has the same restriction).

use glam::{DMat3, DQuat, DVec3, Mat4, Quat, Vec3};
use rigport_model::Transform;

/// How far from unit length `mid_axis` may be (`| |a| − 1 | ≤` this).
pub const MID_AXIS_UNIT_TOLERANCE: f32 = 1e-3;

/// Why a [`TwoBoneIkJob`] cannot run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TwoBoneIkError {
    /// An input holds NaN or infinity.
    #[error("two-bone IK: {0} is not finite")]
    NotFinite(&'static str),
    /// `mid_axis` is not a unit vector.
    #[error("two-bone IK: mid_axis has length {0}, expected 1")]
    MidAxis(f32),
    /// `soften` or `weight` is outside `0..=1`.
    #[error("two-bone IK: {what} = {value}, expected 0..=1")]
    Range {
        /// `"soften"` or `"weight"`.
        what: &'static str,
        /// The value.
        value: f32,
    },
}

/// One analytic two-bone solve. Inputs are in model space unless said otherwise; see the
/// [module documentation](self) for the method.
///
/// ```
/// use rigport_ik::two_bone::TwoBoneIkJob;
/// use rigport_model::glam::{Mat4, Quat, Vec3};
///
/// // An arm along +X: shoulder at 0, elbow at 1, wrist at 2 (model = local: no parents
/// // above the shoulder, identity rotations).
/// let shoulder = Mat4::IDENTITY;
/// let elbow = Mat4::from_translation(Vec3::X);
/// let wrist = Mat4::from_translation(2.0 * Vec3::X);
/// let mut job = TwoBoneIkJob::new(shoulder, elbow, wrist, Vec3::new(1.0, 1.0, 0.0));
/// job.pole = Vec3::Y; // the elbow goes up, not down
/// job.mid_axis = TwoBoneIkJob::bend_axis(shoulder, elbow, wrist, job.pole);
/// let out = job.run()?;
/// assert!(out.reached);
/// // Apply: local rotation ← local rotation · correction; then forward kinematics.
/// let shoulder2 = shoulder * Mat4::from_quat(out.root_correction);
/// let elbow2 = shoulder2 * Mat4::from_translation(Vec3::X) * Mat4::from_quat(out.mid_correction);
/// let wrist2 = elbow2 * Mat4::from_translation(Vec3::X);
/// assert!(wrist2.w_axis.truncate().distance(Vec3::new(1.0, 1.0, 0.0)) < 1e-6);
/// assert!(elbow2.w_axis.y > 0.0); // on the pole's side
/// # Ok::<(), rigport_ik::two_bone::TwoBoneIkError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoBoneIkJob {
    /// The root joint's model matrix (shoulder, hip).
    pub root_model: Mat4,
    /// The mid joint's model matrix (elbow, knee); a descendant of the root.
    pub mid_model: Mat4,
    /// The tip joint's model matrix (wrist, ankle), or of any point rigidly attached below
    /// the mid joint (an effector); a descendant of the mid joint.
    pub tip_model: Mat4,
    /// Where the tip should go, model space.
    pub target: Vec3,
    /// The pole vector, model space, a direction from the root: the mid joint ends in the
    /// half-plane spanned by the root-to-target line and this vector. When it is parallel
    /// to that line (or zero) the limb's plane is kept as it is.
    pub pole: Vec3,
    /// The mid joint's hinge, a unit vector in the mid joint's local frame (see
    /// [`TwoBoneIkJob::bend_axis`]). A positive rotation about it opens the angle between
    /// the bones; the solve bends the limb so it closes towards the positive side.
    pub mid_axis: Vec3,
    /// Extra turn of the limb's plane about the root-to-target line, radians (right-handed).
    pub twist_rad: f32,
    /// `0..=1`: the fraction of the chain's length over which the limb eases into full
    /// extension (0: none, the limb goes straight exactly at full reach). Note: ozz's
    /// `soften` is `1 −` this.
    pub soften: f32,
    /// `0..=1`: blend of the corrections from identity (slerp); 0 leaves the limb as it is.
    pub weight: f32,
}

/// The result of a [`TwoBoneIkJob`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoBoneIkOutput {
    /// Rotation to post-multiply onto the root joint's local rotation
    /// (`local.rotation = local.rotation * root_correction`; see [`apply_correction`]).
    pub root_correction: Quat,
    /// Rotation to post-multiply onto the mid joint's local rotation: a rotation about
    /// `mid_axis`.
    pub mid_correction: Quat,
    /// Whether the tip lands on the target: the target is within `[|l₁ − l₂|, l₁ + l₂]`
    /// of the root, softening did not pull it in, and `weight` is 1.
    pub reached: bool,
}

impl Default for TwoBoneIkOutput {
    fn default() -> Self {
        Self {
            root_correction: Quat::IDENTITY,
            mid_correction: Quat::IDENTITY,
            reached: false,
        }
    }
}

/// Applies a correction from [`TwoBoneIkOutput`] to a joint's local transform.
pub fn apply_correction(local: &mut Transform, correction: Quat) {
    local.rotation = (local.rotation * correction).normalize();
}

fn position(m: &Mat4) -> DVec3 {
    m.w_axis.truncate().as_dvec3()
}

/// The rotation of a matrix that is a rotation times a uniform scale (columns normalized).
fn rotation(m: &Mat4) -> DQuat {
    let c = |v: glam::Vec4| v.truncate().as_dvec3().normalize_or_zero();
    let r = DMat3::from_cols(c(m.x_axis), c(m.y_axis), c(m.z_axis));
    DQuat::from_mat3(&r).normalize()
}

/// The unit part of `v` perpendicular to the unit vector `u`, if it is not tiny against
/// `scale`.
fn perpendicular(v: DVec3, u: DVec3, scale: f64) -> Option<DVec3> {
    let p = v - v.dot(u) * u;
    let len = p.length();
    (len > 1e-9 * scale && len.is_finite()).then(|| p / len)
}

/// The wanted root-to-tip distance for a target `d0` away (step 1 of the module docs), and
/// whether it is the target's distance.
pub(crate) fn soft_distance(d0: f64, l1: f64, l2: f64, soften: f64) -> (f64, bool) {
    let full = l1 + l2;
    let near = (l1 - l2).abs();
    let da = (1.0 - soften) * full;
    let ds = full - da;
    if ds > 0.0 && d0 > da {
        let d = da + ds * (1.0 - (-(d0 - da) / ds).exp());
        return (d.clamp(near, full), false);
    }
    if d0 > full {
        return (full, false);
    }
    if d0 < near {
        return (near, false);
    }
    (d0, true)
}

impl TwoBoneIkJob {
    /// A job for these joints and target with no pole preference (the pole is the current
    /// bend direction: the limb's plane is kept), the hinge from the current bend
    /// ([`TwoBoneIkJob::bend_axis`]), no twist, no softening, weight 1.
    pub fn new(root_model: Mat4, mid_model: Mat4, tip_model: Mat4, target: Vec3) -> Self {
        let (r, m, t) = (
            position(&root_model),
            position(&mid_model),
            position(&tip_model),
        );
        // The mid joint's offset from the root-to-tip line: the limb's current plane.
        let line = (t - r).normalize_or_zero();
        let pole = (m - r) - (m - r).dot(line) * line;
        let pole = pole.as_vec3();
        Self {
            root_model,
            mid_model,
            tip_model,
            target,
            pole,
            mid_axis: Self::bend_axis(root_model, mid_model, tip_model, pole),
            twist_rad: 0.0,
            soften: 0.0,
            weight: 1.0,
        }
    }

    /// A hinge axis for the mid joint, in its local frame: the normal of the plane the limb
    /// bends in now (so the solve keeps bending it the same way), or, when the limb is
    /// straight, the axis that bends it towards `pole` (model-space direction), or, when
    /// `pole` is parallel to the limb too, any axis perpendicular to it.
    pub fn bend_axis(root_model: Mat4, mid_model: Mat4, tip_model: Mat4, pole: Vec3) -> Vec3 {
        let (r, m, t) = (
            position(&root_model),
            position(&mid_model),
            position(&tip_model),
        );
        let (s, e) = (r - m, t - m);
        let scale = s.length() * e.length();
        let bent = s.cross(e);
        let model_axis = if bent.length() > 1e-6 * scale {
            bent.normalize()
        } else {
            let line = (t - r).normalize_or(DVec3::X);
            match perpendicular(pole.as_dvec3(), line, pole.as_dvec3().length().max(1e-30)) {
                Some(w) => line.cross(w),
                None => line.any_orthonormal_vector(),
            }
        };
        (rotation(&mid_model).inverse() * model_axis)
            .normalize()
            .as_vec3()
    }

    /// Checks that the inputs are finite, `mid_axis` is a unit vector and `soften` and
    /// `weight` are within `0..=1`.
    ///
    /// # Errors
    /// [`TwoBoneIkError`].
    pub fn validate(&self) -> Result<(), TwoBoneIkError> {
        let finite = [
            ("root_model", self.root_model.is_finite()),
            ("mid_model", self.mid_model.is_finite()),
            ("tip_model", self.tip_model.is_finite()),
            ("target", self.target.is_finite()),
            ("pole", self.pole.is_finite()),
            ("mid_axis", self.mid_axis.is_finite()),
            ("twist_rad", self.twist_rad.is_finite()),
        ];
        if let Some((what, _)) = finite.iter().find(|(_, ok)| !ok) {
            return Err(TwoBoneIkError::NotFinite(what));
        }
        let len = self.mid_axis.length();
        if (len - 1.0).abs() > MID_AXIS_UNIT_TOLERANCE {
            return Err(TwoBoneIkError::MidAxis(len));
        }
        for (what, value) in [("soften", self.soften), ("weight", self.weight)] {
            if !(0.0..=1.0).contains(&value) {
                return Err(TwoBoneIkError::Range { what, value });
            }
        }
        Ok(())
    }

    /// Validates, then solves. Allocates nothing; deterministic.
    ///
    /// Degenerate limbs (a zero-length bone, a hinge parallel to a bone, a target at the
    /// root) give finite corrections that do what they can (identity for the part that is
    /// undefined) and `reached == false` unless the target is met anyway.
    ///
    /// # Errors
    /// As [`TwoBoneIkJob::validate`].
    pub fn run(&self) -> Result<TwoBoneIkOutput, TwoBoneIkError> {
        self.validate()?;
        if self.weight <= 0.0 {
            return Ok(TwoBoneIkOutput::default());
        }
        let (r, m, t) = (
            position(&self.root_model),
            position(&self.mid_model),
            position(&self.tip_model),
        );
        let target = self.target.as_dvec3();
        let (l1, l2) = ((m - r).length(), (t - m).length());
        let full = l1 + l2;
        let scale = full.max(f64::MIN_POSITIVE);

        // Step 1: the wanted distance, and the direction to the target.
        let to_target = target - r;
        let d0 = to_target.length();
        let u = if d0 > 1e-12 * scale {
            to_target / d0
        } else {
            (t - r).try_normalize().unwrap_or(DVec3::X)
        };
        let (d, on_target) = soft_distance(d0, l1, l2, f64::from(self.soften));

        // Step 2: the mid joint's turn about its hinge (model-space axis `h`).
        let mid_rot = rotation(&self.mid_model);
        let hinge_local = self.mid_axis.as_dvec3().normalize();
        let h = mid_rot * hinge_local;
        let (s, e) = (r - m, t - m);
        let (sh, eh) = (s.dot(h), e.dot(h));
        let a = sh * eh;
        let b = s.dot(e) - a;
        let c = s.dot(h.cross(e));
        let amplitude = b.hypot(c);
        let phi = if amplitude > 1e-12 * scale * scale {
            let k = 0.5 * (s.length_squared() + e.length_squared() - d * d) - a;
            let alpha = (k / amplitude).clamp(-1.0, 1.0).acos();
            let phi = c.atan2(b) + alpha;
            // Wrap to (-π, π] so the weighted blend takes the short way.
            (phi + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
        } else {
            0.0
        };
        let mid_turn = DQuat::from_axis_angle(h, phi);
        let tip_after_mid = m + mid_turn * e;

        // Step 3: the root's turn: aim, then the plane.
        let aim = DQuat::from_rotation_arc((tip_after_mid - r).try_normalize().unwrap_or(u), u);
        let mid_aimed = aim * (m - r);
        let mut root_turn = aim;
        if let Some(w) = perpendicular(self.pole.as_dvec3(), u, self.pole.as_dvec3().length()) {
            let w = DQuat::from_axis_angle(u, f64::from(self.twist_rad)) * w;
            let wanted = u.cross(w);
            // The limb's plane normal now: from the triangle, or from the hinge when the
            // limb is straight (same sign: a positive bend about the hinge puts the mid
            // joint on the side where `u × (mid − root)` is along the hinge).
            let current = perpendicular(mid_aimed, u, l1.max(f64::MIN_POSITIVE))
                .map(|p| u.cross(p))
                .or_else(|| perpendicular(aim * h, u, 1.0));
            if let Some(n) = current {
                let angle = u.dot(n.cross(wanted)).atan2(n.dot(wanted));
                root_turn = DQuat::from_axis_angle(u, angle) * aim;
            }
        }
        let root_rot = rotation(&self.root_model);
        let mut root_c = (root_rot.inverse() * root_turn * root_rot).normalize();
        let mut mid_c = DQuat::from_axis_angle(hinge_local, phi);
        if self.weight < 1.0 {
            let w = f64::from(self.weight);
            let shortest = |q: DQuat| if q.w < 0.0 { -q } else { q };
            root_c = DQuat::IDENTITY.slerp(shortest(root_c), w);
            mid_c = DQuat::IDENTITY.slerp(shortest(mid_c), w);
        }
        Ok(TwoBoneIkOutput {
            root_correction: root_c.as_quat().normalize(),
            mid_correction: mid_c.as_quat().normalize(),
            reached: on_target && self.weight >= 1.0,
        })
    }
}
