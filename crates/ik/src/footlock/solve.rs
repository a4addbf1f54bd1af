//! The per-frame leg solve: ankle target from the pins, two-bone IK on hip and knee, foot
//! orientation kept (or turned onto the toe's pin).

use glam::{Mat4, Quat, Vec3};
use rigport_model::{JointIndex, Skeleton, Transform};

use super::contacts::{goal_at, Window};
use super::{FootlockError, Leg};
use crate::two_bone::{apply_correction, soft_distance, TwoBoneIkJob};
use rigport_eval::LocalToModelJob;

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

/// The leg's shape limits of the solve, from [`super::FootlockOptions`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    /// Fraction of the leg's length over which its reach is softened (soft IK).
    pub soft: f32,
    /// The most a leg may lengthen (fraction of its length).
    pub max_stretch: f32,
    /// The most the knee angle may change per second beyond the source's own change,
    /// radians per second.
    pub knee_speed_rad: f32,
}

impl Limits {
    /// The knee-to-target distance the soft leg aims at, and the stretch that puts the
    /// ankle there, for a target `d` from the hip of a leg of bones `a` and `b`, with the
    /// soft zone scaled by `weight` (so that a leg easing in starts as the source's).
    fn reach(&self, d: f32, a: f32, b: f32, weight: f32) -> (f32, f32) {
        let soft = f64::from((self.soft * weight).clamp(0.0, 1.0));
        let (d_soft, _) = soft_distance(f64::from(d), f64::from(a), f64::from(b), soft);
        let d_soft = d_soft as f32;
        let stretch = if d_soft > 0.0 {
            (d / d_soft).clamp(1.0, 1.0 + self.max_stretch)
        } else {
            1.0
        };
        (d_soft, stretch)
    }

    /// The farthest target from the hip (fraction of the leg's length) that the soft,
    /// stretched leg reaches exactly.
    pub fn reach_limit(&self) -> f32 {
        let reached = |d: f32| {
            let (d_soft, s) = self.reach(d, 0.5, 0.5, 1.0);
            d_soft * s >= d * (1.0 - 1e-6)
        };
        let (mut lo, mut hi) = (0.5f32, 1.0 + self.max_stretch);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if reached(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }
}

/// The angle at the knee between thigh and shin, radians (π: straight).
pub(crate) fn knee_angle(hip: Vec3, knee: Vec3, ankle: Vec3) -> f32 {
    (hip - knee).angle_between(ankle - knee)
}

/// The hip-to-ankle distance of bones `a` and `b` meeting at the knee angle `theta`.
fn span(a: f32, b: f32, theta: f32) -> f32 {
    (a * a + b * b - 2.0 * a * b * theta.cos()).max(0.0).sqrt()
}

/// A point on the sphere of radius `foot` around `toe` as near `target`'s direction as
/// possible while within `radius` of `hip`: the ankle target of a foot held by its toe,
/// turned towards the hip when the source's would be out of the leg's reach.
fn within_reach(target: Vec3, toe: Vec3, hip: Vec3, radius: f32) -> Vec3 {
    let foot = (target - toe).length();
    let (from, to) = (
        (target - toe).normalize_or_zero(),
        (hip - toe).normalize_or_zero(),
    );
    if (target - hip).length() <= radius || from == Vec3::ZERO || to == Vec3::ZERO {
        return target;
    }
    let at = |t: f32| toe + foot * from.lerp(to, t).normalize_or(to);
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        if (at(mid) - hip).length() <= radius {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    at(hi)
}

/// Solves frames one after another (the knee's bend direction and angle carry over
/// frames).
pub(crate) struct Solver<'a> {
    plans: &'a [LegPlan],
    parents: Vec<Option<JointIndex>>,
    /// The source's model-space joint positions, frame-major.
    source: &'a [Vec3],
    /// The clip's key times, seconds.
    times: &'a [f32],
    /// Per leg: the last clear bend direction of the knee (model space, unit).
    bend: Vec<Vec3>,
    limits: Limits,
    /// Per leg: the previous frame's knee angle, locked and source (radians).
    previous: Vec<Option<(f32, f32)>>,
    /// Per leg: the most it did lengthen.
    pub stretch: Vec<f32>,
    /// Per leg: frames inside contacts whose target the solve could not reach.
    pub unreached: Vec<usize>,
    /// Per leg: the largest change of the knee angle in one frame beyond the source's
    /// change, radians.
    pub knee_step: Vec<f32>,
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
    /// `positions` are the source's model-space joint positions, frame-major, at `times`;
    /// each leg's first clear bend seeds its pole for straight-legged frames before it.
    pub fn new(
        skeleton: &Skeleton,
        positions: &'a [Vec3],
        times: &'a [f32],
        plans: &'a [LegPlan],
        limits: Limits,
    ) -> Self {
        let joints = skeleton.len().max(1);
        let bend = plans
            .iter()
            .map(|p| {
                positions
                    .chunks_exact(joints)
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
        Self {
            plans,
            parents: skeleton.parents().collect(),
            source: positions,
            times,
            bend,
            limits,
            previous: vec![None; plans.len()],
            stretch: vec![0.0; plans.len()],
            unreached: vec![0; plans.len()],
            knee_step: vec![0.0; plans.len()],
        }
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
        if busy {
            LocalToModelJob {
                parents: &self.parents,
                local,
                root_model: Mat4::IDENTITY,
                model,
            }
            .run()?;
        }
        let joints = local.len();
        let source = &self.source[f * joints..(f + 1) * joints];
        let dt = if f > 0 {
            self.times[f] - self.times[f - 1]
        } else {
            0.0
        };
        for (i, plan) in self.plans.iter().enumerate() {
            let leg = &plan.leg;
            let src = |j: JointIndex| source[j.get()];
            let (hip, knee, ankle) = (src(leg.hip), src(leg.knee), src(leg.ankle));
            if let Some(b) = bend_of(hip, knee, ankle) {
                self.bend[i] = b;
            }
            let theta_src = knee_angle(hip, knee, ankle);
            let (ankle_goal, toe_goal) = goals(plan);
            if ankle_goal.is_none() && toe_goal.is_none() {
                self.previous[i] = Some((theta_src, theta_src));
                continue;
            }
            let inside = |g: Option<(f32, Vec3, bool)>| g.is_some_and(|(_, _, inside)| inside);
            let weight = |g: Option<(f32, Vec3, bool)>| g.map_or(0.0, |(w, _, _)| w);
            let held = inside(ankle_goal) || inside(toe_goal);
            let w = weight(ankle_goal).max(weight(toe_goal)).clamp(0.0, 1.0);
            let toe = leg.toe.map(src);
            let (a, b) = ((knee - hip).length(), (ankle - knee).length());
            let (mut target, toe_target) = ankle_target(ankle, toe, ankle_goal, toe_goal);
            if let (Some((_, toe_at, _)), false) = (toe_target, inside(ankle_goal)) {
                let radius = self.limits.reach_limit() * (a + b);
                target = within_reach(target, toe_at, hip, radius);
            }
            // Soft IK: the leg aims short of full extension as the target nears it, and
            // lengthens (up to the limit) to make up the difference, so the knee never
            // snaps straight.
            let d = (target - hip).length();
            let (d_soft, stretch) = self.limits.reach(d, a, b, w);
            let mut theta = if a > 0.0 && b > 0.0 {
                ((a * a + b * b - d_soft * d_soft) / (2.0 * a * b))
                    .clamp(-1.0, 1.0)
                    .acos()
            } else {
                theta_src
            };
            // The knee may not turn faster than the source's own turn plus the limit.
            if let Some((out_prev, src_prev)) = self.previous[i] {
                let step = self.limits.knee_speed_rad * dt;
                let expected = out_prev + (theta_src - src_prev);
                theta = theta.clamp(expected - step, expected + step);
            }
            let aim = span(a, b, theta) * stretch;
            let dir = (target - hip).normalize_or((ankle - hip).normalize_or(Vec3::NEG_Y));
            let job_target = hip + dir * aim;

            let (mut knee_model, mut ankle_model) = (model[leg.knee.get()], model[leg.ankle.get()]);
            if stretch > 1.0 {
                self.stretch[i] = self.stretch[i].max(stretch - 1.0);
                local[leg.knee.get()].translation *= stretch;
                local[leg.ankle.get()].translation *= stretch;
                let stretched_knee = hip + (knee - hip) * stretch;
                knee_model.w_axis = stretched_knee.extend(1.0);
                ankle_model.w_axis = (stretched_knee + (ankle - knee) * stretch).extend(1.0);
            }
            let hip_model = model[leg.hip.get()];
            let mut job = TwoBoneIkJob::new(hip_model, knee_model, ankle_model, job_target);
            // The knee bends where the input's does (the last clear bend when it is straight).
            job.pole = self.bend[i];
            job.mid_axis =
                TwoBoneIkJob::bend_axis(hip_model, knee_model, ankle_model, self.bend[i]);
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
            if held && (new_ankle - target).length() > UNREACHED * (a + b) {
                self.unreached[i] += 1;
            }
            let theta_out = knee_angle(hip, new_knee, new_ankle);
            if let Some((out_prev, src_prev)) = self.previous[i] {
                let excess = ((theta_out - out_prev) - (theta_src - src_prev)).abs();
                self.knee_step[i] = self.knee_step[i].max(excess);
            }
            self.previous[i] = Some((theta_out, theta_src));
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
