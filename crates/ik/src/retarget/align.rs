//! Rest-pose alignment: which way a skeleton faces, the rotation taking the source's
//! model space onto the target's, and the per-joint swings that put the target's rest
//! bones along the source's.

use glam::{Mat4, Quat, Vec3};
use rigport_model::{JointIndex, Skeleton};

/// The rotation part of a model matrix (rotation times a positive scale per axis).
pub(crate) fn rotation(m: &Mat4) -> Quat {
    let c = |v: glam::Vec4| v.truncate().normalize_or_zero();
    Quat::from_mat3(&glam::Mat3::from_cols(
        c(m.x_axis),
        c(m.y_axis),
        c(m.z_axis),
    ))
    .normalize()
}

/// `v` without its component along the unit vector `up`.
fn horizontal(v: Vec3, up: Vec3) -> Vec3 {
    v - v.dot(up) * up
}

/// The direction a skeleton faces in its rest pose, a unit vector perpendicular to `up`:
/// where the toes point from the ankles (mocap skeletons), else where the knees bend
/// (Pinocchio's template has no toe joint, and its knees bend forward a little), else the
/// model's +z (the convention of the formats rigport reads), else +x.
///
/// `roles` names the joints by body role (see [`super::maps::ROLES`]).
/// `rest` holds the model matrices of the pose to look at (the rest pose, or a reference
/// pose), one per joint.
pub fn facing(rest: &[Mat4], roles: &[(&'static str, JointIndex)], up: Vec3) -> Vec3 {
    let at = |role: &str| {
        roles
            .iter()
            .find(|(r, _)| *r == role)
            .and_then(|(_, j)| rest.get(j.get()))
            .map(|m| m.w_axis.truncate())
    };
    let mut toes = Vec3::ZERO;
    let mut knees = Vec3::ZERO;
    for side in ["Left", "Right"] {
        let joint = |part: &str| at(&format!("{side}{part}"));
        if let (Some(ankle), Some(toe)) = (joint("Foot"), joint("Toes")) {
            toes += horizontal(toe - ankle, up);
        }
        if let (Some(hip), Some(knee), Some(ankle)) =
            (joint("UpperLeg"), joint("LowerLeg"), joint("Foot"))
        {
            knees += horizontal(knee - 0.5 * (hip + ankle), up);
        }
    }
    let scale = rest
        .iter()
        .map(|m| m.w_axis.truncate().length())
        .fold(0.0f32, f32::max)
        .max(f32::MIN_POSITIVE);
    for candidate in [toes, knees] {
        if candidate.length() > 1e-3 * scale {
            return candidate.normalize();
        }
    }
    let z = horizontal(Vec3::Z, up);
    if z.length() > 1e-3 {
        z.normalize()
    } else {
        horizontal(Vec3::X, up).normalize_or(Vec3::X)
    }
}

/// The rotation taking the source's (up, forward) onto the target's: the model-space
/// change of frame applied to the source's motion. Both pairs are unit and perpendicular.
pub fn frame_rotation(
    source_up: Vec3,
    source_fwd: Vec3,
    target_up: Vec3,
    target_fwd: Vec3,
) -> Quat {
    let basis = |up: Vec3, fwd: Vec3| glam::Mat3::from_cols(up.cross(fwd), up, fwd);
    let m = basis(target_up, target_fwd) * basis(source_up, source_fwd).transpose();
    Quat::from_mat3(&m).normalize()
}

/// The nearest mapped joints below `t` (the first mapped joint down each branch).
pub(crate) fn mapped_below(skeleton: &Skeleton, mapped: &[bool], t: JointIndex) -> Vec<JointIndex> {
    let mut out = Vec::new();
    // Parents come first, so one pass over the later joints finds the descendants.
    let mut inside = vec![false; skeleton.len()];
    if let Some(x) = inside.get_mut(t.get()) {
        *x = true;
    }
    for (j, joint) in skeleton.joints().iter().enumerate().skip(t.get() + 1) {
        let Some(p) = joint.parent else { continue };
        // A joint is in the search when its parent is, and the parent is `t` or unmapped.
        if inside[p.get()] && (p == t || !mapped[p.get()]) {
            inside[j] = true;
            if mapped[j] {
                out.push(JointIndex(j as u32));
            }
        }
    }
    out
}

/// The nearest mapped proper ancestor of `t`.
pub(crate) fn mapped_above(
    skeleton: &Skeleton,
    mapped: &[bool],
    t: JointIndex,
) -> Option<JointIndex> {
    let mut cur = skeleton.joint(t).parent;
    while let Some(p) = cur {
        if mapped[p.get()] {
            return Some(p);
        }
        cur = skeleton.joint(p).parent;
    }
    None
}

/// Largest angle between a target rest bone and its source bone that the swing corrects,
/// radians (150 degrees), for bones outside the arms and legs. A T pose against an A pose
/// differs by about 45 degrees, a T pose against arms hanging down with bent elbows (a
/// running first frame used as reference) by up to 145; torso bones further apart are not
/// the same anatomy (Pinocchio's spine hangs from the shoulders, pointing down where a
/// mocap spine points up: 165 degrees on `human_model1`), and keep the frame alignment
/// alone.
pub const MAX_SWING_RAD: f32 = 5.0 * std::f32::consts::PI / 6.0;

/// Per target joint, the model-space swing `A` that turns its rest bone onto the source's
/// reference bone (`rest_s`: the source's model matrices in its reference pose) as seen in the target's frame (`q` applied): the shortest arc from the
/// direction towards its one mapped joint below to the same direction in the source.
/// Joints with several mapped branches below keep the identity; joints with none inherit
/// the swing of their nearest mapped ancestor, so hands stay aligned with forearms.
///
/// Also returns, per target joint with a swing, its one mapped joint below and the
/// direction towards it in the joint's own rest frame (for [`aim`]).
///
/// `limb` marks the target joints of arms and legs (by role), whose bones are the same
/// anatomy however far apart the poses are: the angle limit does not apply to them.
pub(crate) fn swings(
    rest_s: &[Mat4],
    target: &Skeleton,
    source_of: &[Option<JointIndex>],
    limb: &[bool],
    q: Quat,
) -> (Vec<Quat>, Vec<Option<(JointIndex, Vec3)>>) {
    let rest_t = target.model_rest_matrices();
    let pos = |m: &[Mat4], j: JointIndex| m[j.get()].w_axis.truncate();
    let mapped: Vec<bool> = source_of.iter().map(Option::is_some).collect();
    let mut out = vec![Quat::IDENTITY; target.len()];
    let mut aims = vec![None; target.len()];
    for t in 0..target.len() {
        let tj = JointIndex(t as u32);
        let Some(s) = source_of[t] else { continue };
        let below = mapped_below(target, &mapped, tj);
        out[t] = match below.as_slice() {
            [] => mapped_above(target, &mapped, tj).map_or(Quat::IDENTITY, |a| out[a.get()]),
            [c] => {
                let Some(sc) = source_of[c.get()] else {
                    continue;
                };
                let dt = pos(&rest_t, *c) - pos(&rest_t, tj);
                let ds = q * (pos(rest_s, sc) - pos(rest_s, s));
                let (dt, ds) = (dt.normalize_or_zero(), ds.normalize_or_zero());
                let apart = dt.angle_between(ds) >= MAX_SWING_RAD && !limb[t];
                if dt == Vec3::ZERO || ds == Vec3::ZERO || apart {
                    Quat::IDENTITY
                } else {
                    let local = rotation(&rest_t[t]).inverse() * dt;
                    aims[t] = Some((*c, local.normalize_or_zero()));
                    Quat::from_rotation_arc(dt, ds)
                }
            }
            _ => Quat::IDENTITY,
        };
    }
    (out, aims)
}

/// `world` (a joint's model-space rotation) turned by the shortest arc that points its bone
/// (`local_dir`, in the joint's frame) along `wanted` (model space); unchanged when
/// `wanted` has no direction. Keeps the transferred twist about the bone.
pub(crate) fn aim(world: Quat, local_dir: Vec3, wanted: Vec3) -> Quat {
    let wanted = wanted.normalize_or_zero();
    let current = (world * local_dir).normalize_or_zero();
    if wanted == Vec3::ZERO || current == Vec3::ZERO {
        return world;
    }
    (Quat::from_rotation_arc(current, wanted) * world).normalize()
}
