//! Root motion: a clip's ground-plane travel (and heading) removed from the hips, or moved
//! onto a root joint, as game engines want their clips.
//!
//! The travel is the hips' **smoothed path** ([`path`](self) module docs: a local linear
//! regression over [`RootMotionOptions::window_s`], one gait cycle by default): `P(t)`, a
//! translation `s(t)` in the ground plane (perpendicular to the model-space up direction)
//! and, with [`RootMotionOptions::yaw`], a turn `θ(t)` about up by the smoothed heading's
//! change since the first key (the heading is the hips' axis furthest from up, projected
//! on the ground plane).
//!
//! - [`RootMotion::InPlace`]: the hips' model transform becomes `P(t)⁻¹ · H(t)`: the path
//!   is taken out, the hips' sway about it stays, and the up component is unchanged (`P`
//!   moves along the ground and turns about up). The change goes on the hips' own track
//!   when they are the top of their hierarchy, else on the child of the top joint that
//!   leads to them (conjugated by the top joint, so the top joint keeps its track), or on
//!   the top joint itself when its scale is not uniform.
//! - [`RootMotion::Extract`]: the same path is carried by the top joint: when the hips are
//!   the top, a new joint ([`ROOT_NAME`], made unique) is inserted above them with `P(t)`
//!   as its track and the hips get `P(t)⁻¹ · H(t)`; when another joint is the top (a glTF
//!   armature node, an existing root bone), that joint gets `P(t) · T(t)` and each of its
//!   children is compensated, so every joint below it keeps its model transform exactly.
//! - [`RootMotion::Keep`]: nothing changes.
//!
//! Every clip of the asset is changed the same way (each with its own path); changed joints
//! get `LINEAR` translation and rotation tracks at the clip's key times (scale tracks are
//! kept: `P` is rigid). The travel of each clip is returned ([`Travel`]).

mod change;
mod options;
mod path;

use glam::{DQuat, Vec3};
use rigport_model::{Asset, Clip, JointIndex};

use change::{changes, replace_tracks, uniform_scale, Move, Plan, Way};
pub use options::{
    RootMotion, RootMotionError, RootMotionOptions, RootMotionReport, Travel, DEFAULT_WINDOW_S,
    ROOT_NAME,
};
pub use path::smooth;

/// Changes the root motion of every clip of `asset` as `options` say (see the module
/// docs). `hips` is the hips (pelvis) joint, whose model-space position is the one measured;
/// `up` the model-space up direction (`rigport_model::SceneFrame::up_in_model`).
///
/// # Errors
/// [`RootMotionError::NoSuchJoint`], [`RootMotionError::BadWindow`]; a clip that does not
/// fit the skeleton or cannot be sampled. The asset is unchanged on error.
pub fn root_motion(
    asset: &mut Asset,
    hips: JointIndex,
    up: Vec3,
    options: &RootMotionOptions,
) -> Result<RootMotionReport, RootMotionError> {
    let mut report = RootMotionReport {
        travel: Vec::new(),
        root: None,
        added_joint: false,
    };
    if options.mode == RootMotion::Keep {
        return Ok(report);
    }
    let joints = asset.skeleton.len();
    if hips.get() >= joints {
        return Err(RootMotionError::NoSuchJoint {
            hips: hips.get(),
            joints,
        });
    }
    if !(options.window_s.is_finite() && options.window_s >= 0.0) {
        return Err(RootMotionError::BadWindow {
            window_s: options.window_s,
        });
    }
    let up = up.normalize_or(Vec3::Y);
    let mut paths = Vec::with_capacity(asset.clips.len());
    for clip in &asset.clips {
        paths.push(path::measure(
            &asset.skeleton,
            clip,
            hips,
            up,
            options.window_s,
        )?);
    }
    let chain = path::chain(&asset.skeleton, hips);
    let top = chain[0];
    let uniform = paths.iter().all(|p| uniform_scale(p, joints, top));
    // Which joints change, and how (see the module docs).
    let plan = match options.mode {
        RootMotion::InPlace if top == hips || !uniform => Plan::Root(top),
        RootMotion::InPlace => Plan::Children(top, vec![chain[1]], Way::Remove),
        RootMotion::Extract if top != hips && uniform => {
            let children = (0..joints)
                .map(|j| JointIndex(j as u32))
                .filter(|&j| asset.skeleton.joint(j).parent == Some(top))
                .collect();
            Plan::Children(top, children, Way::Carry)
        }
        _ => Plan::NewRoot(top),
    };
    // The joint is added first (remapping every track), so the clips are changed in the
    // new numbering; the paths were sampled in the old one.
    let root = match plan {
        Plan::NewRoot(top) => Some(
            asset
                .insert_parent(top, ROOT_NAME)
                .map_err(RootMotionError::Skeleton)?,
        ),
        _ => None,
    };
    let renumber = |j: JointIndex| match root {
        Some(r) if j >= r => JointIndex(j.0 + 1),
        _ => j,
    };
    let up = up.as_dvec3();
    for (clip, path) in asset.clips.iter_mut().zip(&paths) {
        let moves: Vec<Move> = (path.ground.iter().zip(&path.heading))
            .map(|(&s, &h)| Move {
                s,
                turn: if options.yaw {
                    DQuat::from_axis_angle(up, h - path.heading[0])
                } else {
                    DQuat::IDENTITY
                },
            })
            .collect();
        let mut changed = changes(path, &moves, &plan, joints);
        changed.iter_mut().for_each(|(j, _)| *j = renumber(*j));
        if let Some(root) = root {
            changed.push((root, moves.iter().map(|m| m.as_transform()).collect()));
        }
        replace_tracks(clip, &path.times, changed);
        report.travel.push(travel(clip, path));
    }
    report.added_joint = root.is_some();
    report.root = match (root, options.mode) {
        (Some(r), _) => Some(r),
        (None, RootMotion::Extract) => Some(top),
        _ => None,
    };
    Ok(report)
}

/// The travel of `clip`'s smoothed path.
fn travel(clip: &Clip, path: &path::ClipPath) -> Travel {
    let distance: f64 = path.ground.windows(2).map(|w| w[0].distance(w[1])).sum();
    let duration = match (path.times.first(), path.times.last()) {
        (Some(a), Some(b)) => b - a,
        _ => 0.0,
    };
    let turn = match (path.heading.first(), path.heading.last()) {
        (Some(a), Some(b)) => (b - a).to_degrees(),
        _ => 0.0,
    };
    Travel {
        clip: clip.name.clone(),
        distance: distance as f32,
        duration_s: duration,
        speed: if duration > 0.0 {
            (distance / f64::from(duration)) as f32
        } else {
            0.0
        },
        turn_deg: turn as f32,
    }
}

#[cfg(test)]
mod tests;
