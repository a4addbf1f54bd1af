//! Retargeting: put a clip made for one skeleton onto another.
//!
//! [`retarget`] takes a source skeleton with a clip, a target skeleton and a [`JointMap`]
//! (built in: [`auto_map`]; from a file: `rigport_import::json::map`), and returns a clip
//! for the target:
//!
//! 0. **Reference.** The source's rest pose, or its clip's first frame when the rest pose
//!    does not stand (Bandai Namco's BVH lays every bone along +x at rest) and the target's
//!    does; "rest" below means this reference for the source.
//! 1. **Frames.** Each skeleton's facing ([`align::facing`]: where the toes point, else
//!    where the knees bend) and model-space up direction give a rotation `Q` taking the
//!    source's model space onto the target's (a Z-up ASF onto a Y-up rig, a walk along -z
//!    onto a rig facing +z).
//! 2. **Rest-pose alignment.** Per mapped joint, the rotation relative to the source's
//!    rest pose is taken in world (model) space, `D = R_s(t) R_s,rest⁻¹`, and applied to
//!    the target's rest world rotation after a swing `A` that turns the target's rest bone
//!    onto the source's (`align::swings`): `R_t(t) = Q D Q⁻¹ A R_t,rest`. So a T-pose
//!    source drives an A-pose target (its arms follow the source's world directions), and
//!    rest orientations that differ per joint (ASF, CSCI 520, glTF) or are the identity
//!    (Pinocchio) do not matter. Then each such bone is turned by the shortest arc onto
//!    the source's bone direction of this frame (towards the next mapped joint), so joints
//!    the source has and the target lacks (a second neck joint) still bend it; the twist
//!    about the bone stays the transferred one. Local rotations follow from the parents'
//!    world rotations.
//!    Unmapped target joints keep their rest pose relative to their parent; every target
//!    joint keeps its rest translation (its bone lengths), except, when the hips' path is
//!    not scaled, joints with the source's rest offset take its animated translation.
//! 3. **Hips.** The target's pelvis point goes where the source's is, in `Q` and scaled
//!    about the model origin: horizontally by the ratio of leg lengths (hip to knee to
//!    ankle), vertically by the ratio of hip heights (pelvis above the ankles in rest);
//!    the target's root translation moves it there. Root orientation is the root's mapped
//!    rotation (step 2).
//! 4. **Hands** (optional): each arm's shoulder and elbow turn (analytic two-bone IK,
//!    [`crate::two_bone`]) so the wrist is at the source's wrist in the same scaled
//!    frame as the hips; the hand keeps its world orientation.
//! 5. **Feet** (optional): the feet are planted with [`crate::footlock`] on the target.
//!
//! Before the transfer the map is checked against the bodies both skeletons' structure shows
//! ([`roles`]): a limb of the source that drives nothing, or drives a limb of another role,
//! makes the map partial, an error unless [`RetargetOptions::allow_partial`] (then a
//! warning).
//!
//! The [`RetargetReport`] lists every body role with its source and target joints, and gives, per limb (each chain of mapped joints from a branching
//! joint down to a mapped leaf), how far the end effector's path relative to the limb's
//! first joint strays from the source's path scaled by the limb-length ratio, in target
//! limb lengths; and each foot's slide during its contacts.
//!
//! ```
//! use rigport_ik::retarget::{auto_map, retarget, RetargetInput, RetargetOptions};
//! use rigport_model::glam::Vec3;
//!
//! // The demo character's wave, onto the demo character itself: the same motion.
//! let demo = rigport_demo::build(1)?;
//! let asset = &demo.asset;
//! let clip = &asset.clips[0];
//! let map = auto_map(&asset.skeleton, &asset.skeleton, Vec3::Y, Vec3::Y, Some(clip))?;
//! let input = RetargetInput {
//!     source: &asset.skeleton,
//!     source_up: Vec3::Y,
//!     clip,
//!     target: &asset.skeleton,
//!     target_up: Vec3::Y,
//!     map: &map,
//! };
//! let out = retarget(&input, &RetargetOptions::default())?;
//! assert_eq!(out.report.scale_vertical, 1.0);
//! assert!(out.report.limbs.iter().all(|l| l.max_error < 1e-4));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod align;
pub mod maps;
mod report;
pub mod roles;
#[cfg(test)]
mod tests;

pub use maps::{auto_map, JointMap, MapPair};
pub use report::{LimbError, RetargetReport, Retargeted, RoleRow};
pub use roles::{find_body, Body, Limb, MapProblem};

use glam::{Mat4, Quat, Vec3};
use rigport_model::{Clip, JointIndex, Skeleton, Transform, Warning};

use crate::footlock::{
    find_feet, footlock, leg_of, FootReport, FootlockError, FootlockOptions, Leg,
};
use crate::two_bone::{apply_correction, TwoBoneIkError, TwoBoneIkJob};
use align::rotation;
use rigport_eval::sample::{
    bake, rest_locals, sample_frames, ChannelMask, CompiledClip, SampleError,
};
use rigport_eval::{EvalError, LocalToModelJob};

/// Why a clip could not be retargeted.
#[derive(Debug, thiserror::Error)]
pub enum RetargetError {
    /// Neither the skeletons' structure nor a built-in convention finds enough body roles
    /// in both.
    #[error("no joint map: the skeletons' structure shows no two bodies with at least 5 roles in common, and they share no known naming convention (CMU ASF, cgspeed BVH, Mixamo, Bandai Namco BVH, rigport demo, Pinocchio human template) nor joint names; give a map file")]
    NoMap,
    /// The map leaves a limb of the source unmoved, or puts a limb on another.
    #[error("the joint map is partial: {}", .0.iter().map(ToString::to_string).collect::<Vec<_>>().join("; "))]
    PartialMap(Vec<MapProblem>),
    /// A map pair names a joint out of range.
    #[error("the map names joint {joint} of the {side}, which has {joints} joints")]
    MapIndex {
        /// `"source"` or `"target"`.
        side: &'static str,
        /// The index.
        joint: usize,
        /// The skeleton's joint count.
        joints: usize,
    },
    /// Two map pairs drive one target joint.
    #[error("target joint {0:?} is mapped twice")]
    MappedTwice(String),
    /// The clip has no key times.
    #[error("the clip has no keys")]
    NoFrames,
    /// The clip does not fit the source skeleton, or the result cannot be baked.
    #[error(transparent)]
    Sample(#[from] SampleError),
    /// Forward kinematics failed.
    #[error(transparent)]
    Eval(#[from] EvalError),
    /// Foot planting failed.
    #[error("planting the feet: {0}")]
    Footlock(#[from] FootlockError),
    /// A hand's two-bone solve was given non-finite input.
    #[error(transparent)]
    TwoBone(#[from] TwoBoneIkError),
}

/// What [`retarget`] does besides the transfer.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RetargetOptions {
    /// Plant the target's feet during their contacts ([`crate::footlock`]).
    pub plant_feet: bool,
    /// Turn the arms so the wrists follow the source's, scaled (step 4 of the module docs).
    pub match_hands: bool,
    /// Foot-locking settings for `plant_feet` (and for finding contacts in the report).
    pub footlock: FootlockOptions,
    /// Retarget with a partial map ([`RetargetError::PartialMap`]) and warn about it
    /// (`Warning::Incomplete`) rather than fail.
    pub allow_partial: bool,
}

/// The skeletons, clip and map [`retarget`] works on. Up directions are unit vectors in
/// each skeleton's model space (`crate::footlock::up_in_model`).
#[derive(Clone, Copy, Debug)]
pub struct RetargetInput<'a> {
    /// The skeleton the clip animates.
    pub source: &'a Skeleton,
    /// Up in the source's model space.
    pub source_up: Vec3,
    /// The motion.
    pub clip: &'a Clip,
    /// The skeleton to animate.
    pub target: &'a Skeleton,
    /// Up in the target's model space.
    pub target_up: Vec3,
    /// Which source joint drives which target joint.
    pub map: &'a JointMap,
}

/// Largest extent of the joints' rest positions (at least `f32::MIN_POSITIVE`).
fn rest_height(rest: &[Mat4]) -> f32 {
    let (lo, hi) = rest.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), m| (lo.min(m.w_axis.truncate()), hi.max(m.w_axis.truncate())),
    );
    (hi - lo).max_element().max(f32::MIN_POSITIVE)
}

/// Mean leg length (hip to knee to ankle) and mean hip height (pelvis above the ankles,
/// along `up`) in the rest pose; `None` without legs.
fn leg_measures(rest: &[Mat4], legs: &[Leg], pelvis: JointIndex, up: Vec3) -> Option<(f32, f32)> {
    if legs.is_empty() {
        return None;
    }
    let at = |j: JointIndex| rest[j.get()].w_axis.truncate();
    let n = legs.len() as f32;
    let length = legs
        .iter()
        .map(|l| at(l.hip).distance(at(l.knee)) + at(l.knee).distance(at(l.ankle)))
        .sum::<f32>()
        / n;
    let height = legs
        .iter()
        .map(|l| (at(pelvis) - at(l.ankle)).dot(up))
        .sum::<f32>()
        / n;
    (length > 0.0 && height > 0.0).then_some((length, height))
}

/// Model-space positions of every joint for every frame, frame-major.
fn positions(skeleton: &Skeleton, frames: &[Transform]) -> Result<Vec<Vec3>, EvalError> {
    let parents: Vec<Option<JointIndex>> = skeleton.parents().collect();
    let mut model = vec![Mat4::IDENTITY; parents.len()];
    let mut out = Vec::with_capacity(frames.len());
    for local in frames.chunks_exact(parents.len().max(1)) {
        LocalToModelJob {
            parents: &parents,
            local,
            root_model: Mat4::IDENTITY,
            model: &mut model,
        }
        .run()?;
        out.extend(model.iter().map(|m| m.w_axis.truncate()));
    }
    Ok(out)
}

/// Model matrices of one frame of local transforms.
fn model_of(skeleton: &Skeleton, local: &[Transform]) -> Result<Vec<Mat4>, EvalError> {
    let parents: Vec<Option<JointIndex>> = skeleton.parents().collect();
    let mut model = vec![Mat4::IDENTITY; parents.len()];
    LocalToModelJob {
        parents: &parents,
        local,
        root_model: Mat4::IDENTITY,
        model: &mut model,
    }
    .run()?;
    Ok(model)
}

/// The source joint of each target joint.
fn sources_of(input: &RetargetInput<'_>) -> Result<Vec<Option<JointIndex>>, RetargetError> {
    let (source, target) = (input.source, input.target);
    let mut out = vec![None; target.len()];
    let check = |side, j: JointIndex, joints: usize| {
        (j.get() < joints)
            .then_some(())
            .ok_or(RetargetError::MapIndex {
                side,
                joint: j.get(),
                joints,
            })
    };
    for p in &input.map.pairs {
        check("source", p.source, source.len())?;
        check("target", p.target, target.len())?;
        if out[p.target.get()].replace(p.source).is_some() {
            return Err(RetargetError::MappedTwice(
                target.joint(p.target).name.clone(),
            ));
        }
    }
    check("source", input.map.pelvis.0, source.len())?;
    check("target", input.map.pelvis.1, target.len())?;
    Ok(out)
}

/// Retargets `input.clip` onto `input.target` (see the module docs).
///
/// # Errors
/// A map that names joints out of range or a target joint twice; a clip without keys or
/// that does not fit the source; foot planting that fails (no feet found on the target,
/// fewer than two frames).
pub fn retarget(
    input: &RetargetInput<'_>,
    options: &RetargetOptions,
) -> Result<Retargeted, RetargetError> {
    let (source, target) = (input.source, input.target);
    let source_of = sources_of(input)?;
    let compiled = CompiledClip::new(input.clip, source)?;
    let times = compiled.key_times();
    if times.is_empty() {
        return Err(RetargetError::NoFrames);
    }
    let source_frames = sample_frames(&compiled, &rest_locals(source), &times)?;
    let source_pos = positions(source, &source_frames)?;
    let rest_t = target.model_rest_matrices();
    let (up_s, up_t) = (unit_or_y(input.source_up), unit_or_y(input.target_up));
    let (pelvis_s, pelvis_t) = input.map.pelvis;
    let body_s = roles::find_body(source, up_s, Some(input.clip));
    let body_t = roles::find_body(target, up_t, None);
    let mut warnings = Vec::new();
    if let Some(body) = &body_s {
        let pairs: Vec<(JointIndex, JointIndex)> = input
            .map
            .pairs
            .iter()
            .map(|p| (p.source, p.target))
            .collect();
        let problems = roles::check_pairs(&pairs, source, body, target, body_t.as_ref());
        if !problems.is_empty() {
            if !options.allow_partial {
                return Err(RetargetError::PartialMap(problems));
            }
            warnings.push(Warning::Incomplete {
                location: format!("retarget map ({})", input.map.how),
                message: format!(
                    "the map is partial, the result lacks the motion of: {}",
                    problems
                        .iter()
                        .map(ToString::to_string)
                        .collect::<Vec<_>>()
                        .join("; ")
                ),
            });
        }
    }
    let role_rows = {
        let pairs: Vec<(JointIndex, JointIndex)> = input
            .map
            .pairs
            .iter()
            .map(|p| (p.source, p.target))
            .collect();
        report::role_rows(source, target, &pairs, body_s.as_ref(), body_t.as_ref())
    };
    let roles_s = body_s.map_or_else(|| maps::roles_of(source, up_s), |b| b.roles);
    let roles_t = body_t.map_or_else(|| maps::roles_of(target, up_t), |b| b.roles);
    let legs_s = legs_of(source, &roles_s);
    let legs_t = legs_of(target, &roles_t);
    // The source's reference pose: its rest pose, or the clip's first frame when the rest
    // pose does not stand (Bandai Namco's BVH rest pose lays every bone along +x) and the
    // target's does.
    let stands_t = |m: &[Mat4]| {
        leg_measures(m, &legs_t, pelvis_t, up_t)
            .is_some_and(|(length, height)| height > 0.5 * length)
    };
    let (rest_s, reference) = {
        let rest = source.model_rest_matrices();
        let stands = |m: &[Mat4]| {
            leg_measures(m, &legs_s, pelvis_s, up_s)
                .is_some_and(|(length, height)| height > 0.5 * length)
        };
        let target_stands = legs_t.is_empty() || stands_t(&rest_t);
        if legs_s.is_empty() || stands(&rest) || !target_stands {
            (rest, "rest pose")
        } else {
            let first = model_of(source, &source_frames[..source.len()])?;
            (first, "first frame")
        }
    };

    // Frames and scales.
    let q = align::frame_rotation(
        up_s,
        align::facing(&rest_s, &roles_s, up_s),
        up_t,
        align::facing(&rest_t, &roles_t, up_t),
    );
    let (scale_h, scale_v) = match (
        leg_measures(&rest_s, &legs_s, pelvis_s, up_s),
        leg_measures(&rest_t, &legs_t, pelvis_t, up_t),
    ) {
        (Some((ls, hs)), Some((lt, ht))) => (lt / ls, ht / hs),
        _ => {
            let r = rest_height(&rest_t) / rest_height(&rest_s);
            (r, r)
        }
    };
    // The source's offsets (model space), turned and scaled into the target's.
    let to_target = |v: Vec3| {
        let v = q * v;
        let vertical = v.dot(up_t) * up_t;
        (v - vertical) * scale_h + vertical * scale_v
    };

    // Per-joint transfer.
    let mut limb = vec![false; target.len()];
    for p in &input.map.pairs {
        let is_limb = p.role.is_some_and(|r| {
            ["Shoulder", "Arm", "Hand", "Leg", "Foot", "Toes"]
                .iter()
                .any(|part| r.contains(part))
        });
        limb[p.target.get()] = is_limb;
    }
    let (swings, aims) = align::swings(&rest_s, target, &source_of, &limb, q);
    let rest_rot_s: Vec<Quat> = rest_s.iter().map(rotation).collect();
    let rest_rot_t: Vec<Quat> = rest_t.iter().map(rotation).collect();
    let rest_local_t = rest_locals(target);
    let parents_t: Vec<Option<JointIndex>> = target.parents().collect();
    let root_t = root_of(target, pelvis_t);
    let (n_s, n_t) = (source.len(), target.len());
    // Joints whose bone is the source's (same rest offset, hips path unscaled): their
    // animated translations are copied (a BVH with position channels on every joint).
    let rest_local_s = rest_locals(source);
    let same_bones: Vec<(usize, usize)> = if scale_h == 1.0 && scale_v == 1.0 {
        source_of
            .iter()
            .enumerate()
            .filter_map(|(t, s)| {
                let s = (*s)?.get();
                let (a, b) = (rest_local_s[s].translation, rest_local_t[t].translation);
                (a.distance(b) <= 1e-6 * a.length().max(1e-6)).then_some((t, s))
            })
            .collect()
    } else {
        Vec::new()
    };
    // Their offsets move: the rest direction towards them does not hold, so they are not
    // aimed at.
    let mut copied = vec![false; n_t];
    for &(t, _) in &same_bones {
        copied[t] = true;
    }
    let mut frames = Vec::with_capacity(times.len() * n_t);
    let mut world = vec![Quat::IDENTITY; n_t];
    let mut model = vec![Mat4::IDENTITY; n_t];
    let arms = if options.match_hands {
        arms(input)
    } else {
        Vec::new()
    };
    let mut hand_error = vec![0.0f32; arms.len()];
    let height = rest_height(&rest_t);
    for (f, src) in source_frames.chunks_exact(n_s.max(1)).enumerate() {
        let src_pos = &source_pos[f * n_s..(f + 1) * n_s];
        let mut local = rest_local_t.clone();
        for &(t, s) in &same_bones {
            local[t].translation = src[s].translation;
        }
        // World rotations of the source this frame.
        let src_world = |s: JointIndex| -> Quat {
            let mut r = src[s.get()].rotation;
            let mut cur = source.joint(s).parent;
            while let Some(p) = cur {
                r = src[p.get()].rotation * r;
                cur = source.joint(p).parent;
            }
            r
        };
        for t in 0..n_t {
            let parent = parents_t[t].map_or(Quat::IDENTITY, |p| world[p.get()]);
            world[t] = match source_of[t] {
                Some(s) => {
                    let delta = src_world(s) * rest_rot_s[s.get()].inverse();
                    let w = (q * delta * q.inverse() * swings[t] * rest_rot_t[t]).normalize();
                    // The bone points where the source's does this frame (the source may
                    // have joints between the two that the target lacks).
                    let aim = aims[t].filter(|(c, _)| !copied[c.get()]);
                    match aim.and_then(|(c, dir)| Some((source_of[c.get()]?, dir))) {
                        Some((sc, dir)) => {
                            align::aim(w, dir, q * (src_pos[sc.get()] - src_pos[s.get()]))
                        }
                        None => w,
                    }
                }
                None => parent * rest_local_t[t].rotation,
            };
            local[t].rotation = (parent.inverse() * world[t]).normalize();
        }
        // Hips: move the root so the pelvis point lands on the scaled source pelvis.
        LocalToModelJob {
            parents: &parents_t,
            local: &local,
            root_model: Mat4::IDENTITY,
            model: &mut model,
        }
        .run()?;
        let wanted = to_target(src_pos[pelvis_s.get()]);
        let shift = wanted - model[pelvis_t.get()].w_axis.truncate();
        local[root_t.get()].translation += shift;
        if !arms.is_empty() {
            for m in &mut model {
                m.w_axis += shift.extend(0.0);
            }
            for (arm, err) in arms.iter().zip(&mut hand_error) {
                let goal = to_target(src_pos[arm.source_hand.get()]);
                *err = err.max(match_hand(arm, goal, &mut local, &parents_t, &mut model)? / height);
            }
        }
        frames.extend_from_slice(&local);
    }

    let mut mask = ChannelMask::none(n_t);
    for (t, s) in source_of.iter().enumerate() {
        mask.rotation[t] = s.is_some();
    }
    mask.translation[root_t.get()] = true;
    for &(t, _) in &same_bones {
        mask.translation[t] = true;
    }
    mask.rotation[root_t.get()] = true;
    let mut clip = bake(&input.clip.name, &times, &frames, &mask)?;

    let (feet, planted) = plant(input, options, &legs_t, up_t, &mut clip, &mut warnings)?;
    let final_pos = {
        let compiled = CompiledClip::new(&clip, target)?;
        positions(target, &sample_frames(&compiled, &rest_local_t, &times)?)?
    };
    let limbs = limb_errors(input, &source_of, &source_pos, &final_pos, |v| q * v);
    let name_t = |j: JointIndex| target.joint(j).name.clone();
    let unmapped: Vec<String> = (0..n_t)
        .filter(|&t| source_of[t].is_none())
        .map(|t| name_t(JointIndex(t as u32)))
        .collect();
    if !unmapped.is_empty() {
        warnings.push(Warning::Note {
            location: format!("retarget onto {} joints", n_t),
            message: format!(
                "{} target joint(s) keep their rest pose: {}",
                unmapped.len(),
                unmapped.join(", ")
            ),
        });
    }
    let report = RetargetReport {
        map: input.map.how.clone(),
        pairs: input
            .map
            .pairs
            .iter()
            .map(|p| {
                (
                    source.joint(p.source).name.clone(),
                    name_t(p.target),
                    p.role,
                )
            })
            .collect(),
        unmapped,
        roles: role_rows,
        reference,
        scale_vertical: scale_v,
        scale_horizontal: scale_h,
        frames: times.len(),
        height,
        limbs,
        feet,
        planted,
        hands: arms
            .iter()
            .zip(&hand_error)
            .map(|(a, &e)| (a.label.clone(), e))
            .collect(),
    };
    Ok(Retargeted {
        clip,
        report,
        warnings,
    })
}

/// The legs [`retarget`] finds on a target skeleton and plants (`up`: model-space up): by
/// the body roles its rest pose shows, else by its naming convention ([`find_feet`]).
/// Empty when it shows no legs.
///
/// ```
/// use rigport_model::glam::Vec3;
///
/// let demo = rigport_demo::build(1)?;
/// let legs = rigport_ik::retarget::target_legs(&demo.asset.skeleton, Vec3::Y);
/// assert_eq!(legs.len(), 2);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn target_legs(skeleton: &Skeleton, up: Vec3) -> Vec<Leg> {
    let up = unit_or_y(up);
    let roles = roles::find_body(skeleton, up, None)
        .map_or_else(|| maps::roles_of(skeleton, up), |b| b.roles);
    legs_of(skeleton, &roles)
}

/// The legs of a skeleton: by the body roles of its convention (upper leg, lower leg, foot,
/// toes), else as [`find_feet`] finds them.
fn legs_of(skeleton: &Skeleton, roles: &[(&'static str, JointIndex)]) -> Vec<Leg> {
    let find = |role: String| roles.iter().find(|(r, _)| *r == role).map(|(_, j)| *j);
    let by_role: Vec<Leg> = ["Left", "Right"]
        .iter()
        .filter_map(|side| {
            let ankle = find(format!("{side}Foot"))?;
            let knee = find(format!("{side}LowerLeg"))?;
            let hip = find(format!("{side}UpperLeg"))?;
            let toe = find(format!("{side}Toes"));
            let leg = leg_of(skeleton, &side.to_lowercase(), ankle, toe).ok()?;
            (leg.knee == knee && leg.hip == hip).then_some(leg)
        })
        .collect();
    if by_role.is_empty() {
        find_feet(skeleton).map(|l| l.0).unwrap_or_default()
    } else {
        by_role
    }
}

/// `v` normalized, or +Y when it has no direction.
fn unit_or_y(v: Vec3) -> Vec3 {
    let u = v.normalize_or_zero();
    if u == Vec3::ZERO {
        Vec3::Y
    } else {
        u
    }
}

/// The root above `j`.
fn root_of(skeleton: &Skeleton, j: JointIndex) -> JointIndex {
    let mut cur = j;
    while let Some(p) = skeleton.joint(cur).parent {
        cur = p;
    }
    cur
}

/// Plants the feet (or, without `plant_feet`, only measures their slide).
fn plant(
    input: &RetargetInput<'_>,
    options: &RetargetOptions,
    legs: &[Leg],
    up: Vec3,
    clip: &mut Clip,
    warnings: &mut Vec<Warning>,
) -> Result<(Vec<FootReport>, bool), RetargetError> {
    let result = if legs.is_empty() {
        Err(FootlockError::NoFeet)
    } else {
        footlock(input.target, clip, legs, up, &options.footlock)
    };
    match result {
        Ok(locked) => {
            let mut feet = locked.feet;
            if options.plant_feet {
                *clip = locked.clip;
                warnings.extend(locked.warnings);
            } else {
                for f in &mut feet {
                    f.after = f.before;
                    f.stretch = 0.0;
                    f.unreached = 0;
                }
            }
            Ok((feet, options.plant_feet))
        }
        Err(e) if options.plant_feet => Err(e.into()),
        Err(_) => Ok((Vec::new(), false)),
    }
}

/// An arm whose wrist follows the source's.
#[derive(Clone, Debug)]
struct Arm {
    label: String,
    upper: JointIndex,
    lower: JointIndex,
    hand: JointIndex,
    source_hand: JointIndex,
}

/// The target's arms with upper arm, forearm and hand mapped by role.
fn arms(input: &RetargetInput<'_>) -> Vec<Arm> {
    let find = |role: &str| input.map.pairs.iter().find(|p| p.role == Some(role));
    let mut out = Vec::new();
    for side in ["Left", "Right"] {
        let (Some(u), Some(l), Some(h)) = (
            find(&format!("{side}UpperArm")),
            find(&format!("{side}LowerArm")),
            find(&format!("{side}Hand")),
        ) else {
            continue;
        };
        let (upper, lower, hand) = (u.target, l.target, h.target);
        if input.target.joint(hand).parent == Some(lower)
            && input.target.joint(lower).parent == Some(upper)
        {
            out.push(Arm {
                label: side.to_lowercase(),
                upper,
                lower,
                hand,
                source_hand: h.source,
            });
        }
    }
    out
}

/// Turns one arm so its wrist reaches `goal`; returns the distance left. `model` holds
/// the frame's model matrices and is updated for the arm's joints.
fn match_hand(
    arm: &Arm,
    goal: Vec3,
    local: &mut [Transform],
    parents: &[Option<JointIndex>],
    model: &mut [Mat4],
) -> Result<f32, RetargetError> {
    let (u, l, h) = (arm.upper.get(), arm.lower.get(), arm.hand.get());
    let hand_world = rotation(&model[h]);
    let job = TwoBoneIkJob::new(model[u], model[l], model[h], goal);
    let out = job.run()?;
    apply_correction(&mut local[u], out.root_correction);
    apply_correction(&mut local[l], out.mid_correction);
    let parent_of = |j: usize| parents[j].map_or(Mat4::IDENTITY, |p| model[p.get()]);
    model[u] = parent_of(u) * local[u].to_mat4();
    model[l] = model[u] * local[l].to_mat4();
    local[h].rotation = (rotation(&model[l]).inverse() * hand_world).normalize();
    model[h] = model[l] * local[h].to_mat4();
    Ok(model[h].w_axis.truncate().distance(goal))
}

/// The limbs whose end-effector error [`retarget`] reports, target joints from first to
/// end. With body roles: each arm from the upper arm to the hand (or the forearm when the
/// target has no hand joint), each leg from the upper leg to the foot (the ankle), the
/// neck to the head. Without: every chain of mapped joints from below a branching joint
/// down to a mapped joint with nothing mapped below it.
fn limb_chains(input: &RetargetInput<'_>, mapped: &[bool]) -> Vec<Vec<JointIndex>> {
    let target = input.target;
    let mut out = Vec::new();
    if input.map.pairs.iter().any(|p| p.role.is_some()) {
        let find = |role: String| {
            input
                .map
                .pairs
                .iter()
                .find(|p| p.role == Some(role.as_str()))
        };
        let mut limbs: Vec<[String; 3]> = Vec::new();
        for side in ["Left", "Right"] {
            limbs.push(["UpperArm", "LowerArm", "Hand"].map(|p| format!("{side}{p}")));
            limbs.push(["UpperLeg", "LowerLeg", "Foot"].map(|p| format!("{side}{p}")));
        }
        limbs.push(["Neck".into(), "Neck1".into(), "Head".into()]);
        for roles in limbs {
            let chain: Vec<JointIndex> = roles
                .into_iter()
                .filter_map(|r| find(r).map(|p| p.target))
                .collect();
            if chain.len() >= 2 {
                out.push(chain);
            }
        }
        out.sort_by_key(|c| c[c.len() - 1]);
        return out;
    }
    for end in 0..target.len() {
        let e = JointIndex(end as u32);
        if !mapped[end] || !align::mapped_below(target, mapped, e).is_empty() {
            continue;
        }
        let mut chain = vec![e];
        let mut cur = align::mapped_above(target, mapped, e);
        while let Some(c) = cur {
            if align::mapped_below(target, mapped, c).len() != 1 {
                break;
            }
            chain.push(c);
            cur = align::mapped_above(target, mapped, c);
        }
        if chain.len() >= 2 {
            chain.reverse();
            out.push(chain);
        }
    }
    out
}

/// Each limb's end-effector error (see [`LimbError`]); `turn` is `Q`.
fn limb_errors(
    input: &RetargetInput<'_>,
    source_of: &[Option<JointIndex>],
    source_pos: &[Vec3],
    target_pos: &[Vec3],
    turn: impl Fn(Vec3) -> Vec3,
) -> Vec<LimbError> {
    let (source, target) = (input.source, input.target);
    let (n_s, n_t) = (source.len(), target.len());
    let mapped: Vec<bool> = source_of.iter().map(Option::is_some).collect();
    let (rest_s, rest_t) = (source.model_rest_matrices(), target.model_rest_matrices());
    let mut out = Vec::new();
    for chain in limb_chains(input, &mapped) {
        let end = chain[chain.len() - 1].get();
        let e = JointIndex(end as u32);
        let src: Vec<JointIndex> = chain.iter().filter_map(|t| source_of[t.get()]).collect();
        let length_of = |rest: &[Mat4], joints: &[JointIndex]| {
            joints
                .windows(2)
                .map(|w| rest[w[0].get()].w_axis.distance(rest[w[1].get()].w_axis))
                .sum::<f32>()
        };
        let (lt, ls) = (length_of(&rest_t, &chain), length_of(&rest_s, &src));
        if lt <= 0.0 || ls <= 0.0 || src.len() != chain.len() {
            continue;
        }
        let (first_t, first_s, last_s) = (chain[0].get(), src[0].get(), src[src.len() - 1].get());
        let frames = target_pos.len() / n_t.max(1);
        let (mut max, mut sum) = (0.0f32, 0.0f64);
        for f in 0..frames {
            let t = |j: usize| target_pos[f * n_t + j];
            let s = |j: usize| source_pos[f * n_s + j];
            let want = turn(s(last_s) - s(first_s)) * (lt / ls);
            let err = (t(end) - t(first_t) - want).length() / lt;
            max = max.max(err);
            sum += f64::from(err);
        }
        let role = input
            .map
            .pairs
            .iter()
            .find(|p| p.target == e)
            .and_then(|p| p.role);
        out.push(LimbError {
            label: role.map_or_else(|| target.joint(e).name.clone(), str::to_string),
            target: chain
                .iter()
                .map(|&j| target.joint(j).name.clone())
                .collect(),
            source: src.iter().map(|&j| source.joint(j).name.clone()).collect(),
            length: lt,
            max_error: max,
            mean_error: (sum / frames.max(1) as f64) as f32,
        });
    }
    out
}
