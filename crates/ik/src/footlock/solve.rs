//! The per-frame leg solve: ankle target from the pins, two-bone IK on hip and knee, foot
//! orientation kept (or turned onto the toe's pin).

use glam::{Mat4, Quat, Vec3};
use rigport_model::{JointIndex, Skeleton, Transform};

use super::contacts::{goal_at, Window};
use super::{FootlockError, Leg};
use crate::two_bone::{apply_correction, TwoBoneIkJob};
use rigport_eval::{EvalError, LocalToModelJob};

/// A leg with its pinned contacts.
#[derive(Clone, Debug)]
pub(crate) struct LegPlan {
    pub leg: Leg,
    /// The ankle's contacts.
    pub ankle: Vec<Window>,
    /// The toe's contacts (empty without a toe).
    pub toe: Vec<Window>,
}

/// The ankle's target and, when the toe is held, `(toe now, toe target, toe weight)`.
///
/// The ankle is carried along with the toe onto the toe's goal, then onto its own pin by
/// its weight. Outside its own contacts it yields to a held toe: it is moved onto the
/// sphere of the foot's length around the toe's target, so that aiming the foot puts the
/// toe exactly there.
fn ankle_target(
    ankle: Vec3,
    toe: Option<Vec3>,
    ankle_goal: Option<(f32, Vec3, bool)>,
    toe_goal: Option<(f32, Vec3, bool)>,
) -> (Vec3, Option<(Vec3, Vec3, f32)>) {
    let toe_target = match (toe, toe_goal) {
        (Some(t), Some((w, goal, _))) => Some((t, t.lerp(goal, w), w)),
        _ => None,
    };
    let base = toe_target.map_or(ankle, |(t, target, _)| ankle + (target - t));
    let mut target = match ankle_goal {
        Some((_, goal, true)) => goal,
        Some((w, goal, false)) => base.lerp(goal, w),
        None => base,
    };
    if let (Some((t, toe_at, w)), false) = (toe_target, matches!(ankle_goal, Some((_, _, true)))) {
        let length = (t - ankle).length();
        let dir = (target - toe_at).normalize_or_zero();
        if dir != Vec3::ZERO {
            target = target.lerp(toe_at + dir * length, w);
        }
    }
    (target, toe_target)
}

/// Solves frames one after another (the knee's bend direction carries over frames where the
/// input leg is straight).
pub(crate) struct Solver<'a> {
    plans: &'a [LegPlan],
    parents: Vec<Option<JointIndex>>,
    /// Per leg: the last clear bend direction of the knee (model space, unit).
    bend: Vec<Vec3>,
    /// The most a leg may lengthen (fraction of its length).
    max_stretch: f32,
    /// Per leg: the most it did lengthen.
    pub stretch: Vec<f32>,
    /// Per leg: frames whose ankle target the solve could not reach.
    pub unreached: Vec<usize>,
}

/// A knee is "bent" when it lies this fraction of the thigh's length off the hip-ankle
/// line; below that the direction is noise and the previous frame's is used.
const MIN_BEND: f32 = 0.02;

/// An ankle this fraction of the leg's length from its target counts as unreached (f32
/// rounding of the solve stays near 1e-7).
const UNREACHED: f32 = 1e-5;

/// The knee's bend direction: the part of hip->knee perpendicular to hip->ankle, unit, or
/// `None` for a (nearly) straight leg.
fn bend_of(hip: Vec3, knee: Vec3, ankle: Vec3) -> Option<Vec3> {
    let axis = (ankle - hip).normalize_or_zero();
    let thigh = knee - hip;
    let perp = thigh - axis * thigh.dot(axis);
    (perp.length() > MIN_BEND * thigh.length()).then(|| perp.normalize())
}

/// The shortest rotation taking the direction of `from` to that of `to` (any lengths;
/// identity when either is zero). Unlike `Quat::from_rotation_arc`, which returns the
/// identity below about 7e-4 rad (its `1 - 2ε` dot test), this stays exact for the tiny
/// corrections foot locking makes: the cross product carries small angles at full
/// precision.
pub(crate) fn arc(from: Vec3, to: Vec3) -> Quat {
    let scale = (from.length_squared() * to.length_squared()).sqrt();
    if scale == 0.0 || !scale.is_finite() {
        return Quat::IDENTITY;
    }
    let w = scale + from.dot(to);
    if w <= 1e-7 * scale {
        // Opposite directions: half a turn about any axis perpendicular to `from`.
        return Quat::from_axis_angle(
            from.normalize().any_orthonormal_vector(),
            std::f32::consts::PI,
        );
    }
    let c = from.cross(to);
    Quat::from_xyzw(c.x, c.y, c.z, w).normalize()
}

fn rotation(m: &Mat4) -> Quat {
    m.to_scale_rotation_translation().1.normalize()
}

impl<'a> Solver<'a> {
    /// `positions` are the source's model-space joint positions, frame-major; each leg's
    /// first clear bend seeds its pole for straight-legged frames before it.
    pub fn new(
        skeleton: &Skeleton,
        positions: &[Vec3],
        plans: &'a [LegPlan],
        joints: usize,
        max_stretch: f32,
    ) -> Result<Self, EvalError> {
        let bend = plans
            .iter()
            .map(|p| {
                positions
                    .chunks_exact(joints.max(1))
                    .find_map(|f| {
                        bend_of(
                            f[p.leg.hip.get()],
                            f[p.leg.knee.get()],
                            f[p.leg.ankle.get()],
                        )
                    })
                    .unwrap_or(Vec3::Z)
            })
            .collect();
        Ok(Self {
            plans,
            parents: skeleton.parents().collect(),
            bend,
            max_stretch,
            stretch: vec![0.0; plans.len()],
            unreached: vec![0; plans.len()],
        })
    }

    /// Solves frame `f`: `local` holds the source's local transforms and receives the
    /// locked leg rotations; `model` is scratch (one matrix per joint).
    pub fn frame(
        &mut self,
        f: usize,
        blend: usize,
        local: &mut [Transform],
        model: &mut [Mat4],
    ) -> Result<(), FootlockError> {
        let goals = |plan: &LegPlan| (goal_at(&plan.ankle, f, blend), goal_at(&plan.toe, f, blend));
        let busy = self.plans.iter().any(|p| !matches!(goals(p), (None, None)));
        LocalToModelJob {
            parents: &self.parents,
            local,
            root_model: Mat4::IDENTITY,
            model,
        }
        .run()?;
        let legs = self.plans.iter().zip(&mut self.bend);
        let tallies = self.stretch.iter_mut().zip(&mut self.unreached);
        for ((plan, bend), (max_stretch, unreached)) in legs.zip(tallies) {
            let leg = &plan.leg;
            let at = |j: JointIndex| model[j.get()].w_axis.truncate();
            let (hip, knee, ankle) = (at(leg.hip), at(leg.knee), at(leg.ankle));
            if let Some(b) = bend_of(hip, knee, ankle) {
                *bend = b;
            }
            if !busy {
                continue;
            }
            let (ankle_goal, toe_goal) = goals(plan);
            if ankle_goal.is_none() && toe_goal.is_none() {
                continue;
            }
            let toe = leg.toe.map(at);
            let (target, toe_target) = ankle_target(ankle, toe, ankle_goal, toe_goal);
            // A target beyond the straight leg's reach: lengthen thigh and shin alike, up
            // to the limit (Kovar, Schreiner & Gleicher 2002 allow the same small stretch).
            let reach = (knee - hip).length() + (ankle - knee).length();
            let stretch = ((target - hip).length() / reach).clamp(1.0, 1.0 + self.max_stretch);
            let (mut knee_model, mut ankle_model) = (model[leg.knee.get()], model[leg.ankle.get()]);
            if stretch > 1.0 {
                *max_stretch = max_stretch.max(stretch - 1.0);
                local[leg.knee.get()].translation *= stretch;
                local[leg.ankle.get()].translation *= stretch;
                let stretched_knee = hip + (knee - hip) * stretch;
                knee_model.w_axis = stretched_knee.extend(1.0);
                ankle_model.w_axis = (stretched_knee + (ankle - knee) * stretch).extend(1.0);
            }
            let hip_model = model[leg.hip.get()];
            let mut job = TwoBoneIkJob::new(hip_model, knee_model, ankle_model, target);
            // The knee bends where the input's does (the last clear bend when it is straight).
            job.pole = *bend;
            job.mid_axis = TwoBoneIkJob::bend_axis(hip_model, knee_model, ankle_model, *bend);
            let out = job.run()?;
            // World rotations and positions after the corrections (rotation times unit
            // scale, as in mocap rigs).
            let (hip_q, knee_q) = (rotation(&hip_model), rotation(&knee_model));
            let new_hip_q = hip_q * out.root_correction;
            let new_knee_q = new_hip_q * (hip_q.inverse() * knee_q) * out.mid_correction;
            let new_knee =
                hip + (new_hip_q * hip_q.inverse()) * (knee_model.w_axis.truncate() - hip);
            let new_ankle = new_knee
                + (new_knee_q * knee_q.inverse())
                    * (ankle_model.w_axis - knee_model.w_axis).truncate();
            // The job's `reached` is false at exactly full extension, where the stretch puts
            // targets on purpose: count the frames that really miss.
            if (new_ankle - target).length() > UNREACHED * reach {
                *unreached += 1;
            }
            let mut ankle_q = rotation(&ankle_model);
            if let Some((t, toe_at, w)) = toe_target {
                let aim = Quat::IDENTITY.slerp(arc(t - ankle, toe_at - new_ankle), w);
                ankle_q = (aim * ankle_q).normalize();
            }
            apply_correction(&mut local[leg.hip.get()], out.root_correction);
            apply_correction(&mut local[leg.knee.get()], out.mid_correction);
            local[leg.ankle.get()].rotation = (new_knee_q.inverse() * ankle_q).normalize();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_keeps_tiny_angles_that_from_rotation_arc_drops() {
        let from = Vec3::new(0.0, -0.9, 0.0);
        let to = Vec3::new(1e-4, -0.9, 0.0); // 1.1e-4 rad
        assert_eq!(
            Quat::from_rotation_arc(from.normalize(), to.normalize()),
            Quat::IDENTITY
        );
        let turned = arc(from, to) * from;
        assert!((turned - to * (from.length() / to.length())).length() < 1e-7);
        assert_eq!(arc(Vec3::ZERO, to), Quat::IDENTITY);
        let back = arc(Vec3::X, -Vec3::X) * Vec3::X;
        assert!((back + Vec3::X).length() < 1e-6);
    }
}
