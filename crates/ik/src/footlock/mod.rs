//! Foot locking: find where a clip's feet touch the ground and hold them there.
//!
//! Motion capture feet slide: marker noise, solver error and retargeting move a planted
//! foot by a few millimetres to centimetres. [`footlock`] cleans that up in four steps:
//!
//! 1. **Detect.** The clip is sampled at its own key times. For each foot's ankle and toe
//!    joint, a frame is in contact when the joint is both low (height above its lowest
//!    point within [`GROUND_WINDOW`] seconds under [`FootlockOptions::height`] skeleton
//!    heights) and slow
//!    (speed under [`FootlockOptions::speed`] skeleton heights per second, central
//!    differences). A contact lasts while height and speed stay under
//!    [`FootlockOptions::hysteresis`] times those thresholds, and contacts shorter than
//!    [`FootlockOptions::min_contact`] seconds (or of one frame) are dropped. The skeleton
//!    height is the
//!    largest extent of the joints' rest positions; "up" is the asset's up axis in model
//!    space ([`up_in_model`]).
//! 2. **Pin.** Each contact gets one model-space point, held for the whole contact:
//!    [`PinAt::Mean`] (default) the joint's mean position over the contact, so the largest
//!    correction is about half the source's slide; [`PinAt::First`] its touch-down
//!    position. A contact that begins while the foot's other joint is already pinned is
//!    pinned rigidly to it (same offset as in the source at that frame), so that a flat foot
//!    can hold heel and toe at once. The pin is then moved (by at most 5% of the leg's
//!    reach) to the nearest point the soft, stretched leg reaches from the hip at every
//!    frame of the contact; the frames where it still cannot (the heel landing or lifting
//!    with the hip far ahead) are left out of the contact, so the foot is held exactly
//!    wherever a contact is reported.
//! 3. **Solve.** Each frame, a foot with a pinned (or blending) joint gets an ankle target:
//!    the ankle's pin, or the ankle moved with the toe onto the toe's pin (turned towards
//!    the hip when that would be out of the leg's reach). The analytic two-bone job
//!    ([`crate::two_bone`]) turns hip and knee so the ankle meets it, with the pole taken
//!    from the input knee's direction (so the knee bends where the source's did, never
//!    flips). Three limits keep the knee smooth:
//!    - **Soft IK.** Past `1 -` [`FootlockOptions::soft`] of the leg's length the reach is
//!      eased (`d = dₐ + d_s·(1 − e^{−(d₀ − dₐ)/d_s})`, the "soft IK" of Softimage and
//!      Unreal), so the leg never straightens to hit a target and its knee angle changes
//!      smoothly as a target nears full extension; thigh and shin lengthen alike to make
//!      up the difference, by at most [`FootlockOptions::max_stretch`] (default 2%; the
//!      small bone-length change of Kovar, Schreiner and Gleicher, "Footskate cleanup for
//!      motion capture editing", 2002). The soft zone grows with the blend weight, so a
//!      leg easing in starts exactly as the source's.
//!    - **Knee speed.** The knee angle changes per frame by at most the source's change
//!      plus [`FootlockOptions::max_knee_speed_deg`] times the frame's duration; a frame
//!      held back there falls short of its target (counted in [`FootReport::unreached`]).
//!
//!    The ankle keeps its input world orientation, turned just enough to put the toe on
//!    its pin when the toe is held.
//! 4. **Blend.** Over [`FootlockOptions::blend`] seconds before a contact and after it, the
//!    target eases (smoothstep) from the input position to the pin and back, so the leg does
//!    not pop.
//!
//! When no foot has a contact, the clip is returned as it was with a
//! [`Warning::NoContacts`] that says why ([`diagnose`]): no foot stays under the contact
//! speed while on the ground, and whether the feet move too fast for a human, which
//! suggests the clip plays at the wrong frame rate.
//!
//! The result is the input clip with the rotation tracks of each leg's hip, knee and ankle
//! re-keyed at the clip's key times (and the translation tracks of knee and ankle when
//! the leg was lengthened); every other track is the input's, untouched. The
//! [`FootReport`]s give each foot's contacts and its slide before and after: per contact
//! frame, how far the ankle or toe is from where it was at the contact's first frame, in
//! skeleton heights (largest and mean over all contact frames of the foot).
//!
//! ```
//! use rigport_ik::footlock::{find_feet, footlock, FootlockOptions};
//! use rigport_model::glam::{Quat, Vec3};
//! use rigport_model::{Clip, Interpolation, Joint, JointIndex, Skeleton, Track, TrackTarget, Transform};
//!
//! // One leg, 0.95 units tall: hips -> LeftUpLeg -> LeftLeg (knee) -> LeftFoot -> LeftToeBase.
//! let joint = |name: &str, parent: Option<u32>, t: Vec3| Joint {
//!     name: name.into(),
//!     parent: parent.map(JointIndex),
//!     rest_local: Transform::from_translation(t),
//! };
//! let skeleton = Skeleton::new(vec![
//!     joint("Hips", None, Vec3::new(0.0, 1.0, 0.0)),
//!     joint("LeftUpLeg", Some(0), Vec3::new(0.1, 0.0, 0.0)),
//!     joint("LeftLeg", Some(1), Vec3::new(0.0, -0.45, 0.05)),
//!     joint("LeftFoot", Some(2), Vec3::new(0.0, -0.45, -0.05)),
//!     joint("LeftToeBase", Some(3), Vec3::new(0.0, -0.05, 0.1)),
//! ]).expect("a valid skeleton");
//! // The hips drift 2 cm forward over one second at 30 fps: the planted foot slides along.
//! let times: Vec<f32> = (0..31).map(|f| f as f32 / 30.0).collect();
//! let values = times.iter().flat_map(|t| [0.0, 1.0, 0.02 * t]).collect();
//! let clip = Clip {
//!     name: "drift".into(),
//!     tracks: vec![Track {
//!         target: TrackTarget::Translation(JointIndex(0)),
//!         interpolation: Interpolation::Linear,
//!         times: times.clone(),
//!         values,
//!     }],
//! };
//! let (legs, convention) = find_feet(&skeleton)?;
//! assert_eq!((legs.len(), convention), (1, "cgspeed BVH / Mixamo"));
//! let locked = footlock(&skeleton, &clip, &legs, Vec3::Y, &FootlockOptions::default())?;
//! let foot = &locked.feet[0];
//! assert_eq!(foot.contacts.len(), 2); // the ankle's and the toe's, the whole clip
//! assert!(foot.before.max > 0.02); // 2 cm of a 0.95-unit skeleton
//! assert!(foot.after.max < 1e-5);
//! // Only the leg's rotations were re-keyed; the hips' translation track is the input's.
//! assert!(locked.clip.tracks.contains(&clip.tracks[0]));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod contacts;
pub mod diagnose;
mod solve;
#[cfg(test)]
mod tests;

pub use crate::naming::{find_feet, leg_of, named_feet, resolve_feet, NAMED_FEET};
pub use contacts::PinAt;

use glam::{Mat4, Vec3};
use rigport_model::{Clip, JointIndex, SceneFrame, Skeleton, TrackTarget, Transform, Warning};

use contacts::{Thresholds, Window};
use rigport_eval::sample::{
    bake, rest_locals, sample_frames, ChannelMask, CompiledClip, SampleError,
};
use rigport_eval::{EvalError, LocalToModelJob};

/// One leg: the joints the solve turns (hip, knee, ankle) and the foot joints it watches
/// (ankle, and the toe when the skeleton has one).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Leg {
    /// A label for reports (`"left"`, `"right"`, or the ankle's name).
    pub label: String,
    /// The thigh's joint (at the hip).
    pub hip: JointIndex,
    /// The shin's joint (at the knee), the hip's child.
    pub knee: JointIndex,
    /// The foot's joint (at the ankle), the knee's child.
    pub ankle: JointIndex,
    /// The toe joint (at the ball of the foot), below the ankle.
    pub toe: Option<JointIndex>,
}

/// Seconds either side of a frame over which a joint's lowest height is its ground there:
/// longer than a walking stride's half (about 0.5 s), so that every window of a walk holds
/// a stance, and short enough that ground that slopes or a capture volume that tilts (the
/// corpus's cgspeed walk climbs 3% of the actor's height over its 3 s) does not hide the
/// later contacts.
pub const GROUND_WINDOW: f32 = 1.0;

/// Detection and blending settings. Lengths are in skeleton heights (see the module docs),
/// times in seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootlockOptions {
    /// A contact starts below this height above the joint's lowest point in the clip.
    pub height: f32,
    /// ... and below this speed, skeleton heights per second.
    pub speed: f32,
    /// A contact lasts while height and speed stay under this multiple of the thresholds
    /// (at least 1).
    pub hysteresis: f32,
    /// Contacts shorter than this are ignored (and always those of a single frame).
    pub min_contact: f32,
    /// Seconds over which the leg eases into and out of each contact (at least one frame).
    pub blend: f32,
    /// Where a contact's pin is.
    pub pin_at: PinAt,
    /// How much a leg may lengthen (fraction of its length, thigh and shin alike) when a
    /// pin lies beyond the soft leg's reach; 0 keeps bone lengths and leaves such frames
    /// short of their pins.
    pub max_stretch: f32,
    /// Soft IK: the fraction of the leg's length, short of full extension, from which its
    /// reach is eased (`0..1`; 0 lets the leg snap straight). The leg never straightens to
    /// hit a target; the stretch makes up the difference.
    pub soft: f32,
    /// The most the knee angle may change per second beyond the source's own change,
    /// degrees per second (1200: 10° a frame at 120 fps).
    pub max_knee_speed_deg: f32,
}

impl Default for FootlockOptions {
    /// Thresholds for human mocap, chosen on the corpus's CMU (ASF/AMC and cgspeed BVH)
    /// and Bandai Namco walks, runs, dances and kicks: a planted ankle stays within 1% of
    /// the height of its local lowest point (1.7 cm on a 1.7 m actor; the heel rising at
    /// toe-off passes that within a few frames) and moves slower than 0.2 heights per
    /// second (0.34 m/s; a swinging foot moves at 2-5 m/s, a planted one at 120 fps shows
    /// 0.02-0.1 heights per second of marker noise); hysteresis 1.5; contacts of at least
    /// 0.03 s (a running stance lasts about 0.1 s); blends over 0.1 s; mean pins, moved
    /// into the leg's reach; legs may grow by up to 2% (a bone-length change the eye does
    /// not catch) and soften over the last 2% of their length (the knee stays under about
    /// 171°); the knee turns at most 1200°/s (10° a frame at 120 fps) faster than the
    /// source's.
    fn default() -> Self {
        Self {
            height: 0.01,
            speed: 0.2,
            hysteresis: 1.5,
            min_contact: 0.03,
            blend: 0.1,
            pin_at: PinAt::Mean,
            max_stretch: 0.02,
            soft: 0.02,
            max_knee_speed_deg: 1200.0,
        }
    }
}

/// Why a clip could not be foot-locked.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FootlockError {
    /// A foot joint named by the caller is not in the skeleton.
    #[error("no joint named {name:?}")]
    UnknownJoint {
        /// The name given.
        name: String,
    },
    /// No joint of the skeleton has a known ankle name.
    #[error("no feet found: none of the known ankle names ({}) nor Pinocchio's human template; name the feet explicitly", known_ankles())]
    NoFeet,
    /// A named ankle lacks a knee and hip above it, or a toe is not below its ankle.
    #[error("joint {joint:?} cannot be a foot: {why}")]
    NotALeg {
        /// The joint's name.
        joint: String,
        /// Why.
        why: String,
    },
    /// Two feet share a hip, knee or ankle.
    #[error("two feet share the leg joint {joint:?}")]
    SharedLeg {
        /// The joint's name.
        joint: String,
    },
    /// No legs were given.
    #[error("no feet to lock")]
    NoLegs,
    /// An option is out of range.
    #[error("{name} {value}: {expected}")]
    Option {
        /// The option.
        name: &'static str,
        /// Its value.
        value: f32,
        /// What it must be.
        expected: &'static str,
    },
    /// The clip has fewer than two frames.
    #[error("the clip has {frames} key time(s); foot locking needs at least 2 frames")]
    TooShort {
        /// Its key-time count.
        frames: usize,
    },
    /// The clip does not fit the skeleton, or the result cannot be baked.
    #[error(transparent)]
    Sample(#[from] SampleError),
    /// Forward kinematics failed.
    #[error(transparent)]
    Eval(#[from] EvalError),
    /// A leg's two-bone solve was given non-finite input.
    #[error(transparent)]
    TwoBone(#[from] crate::two_bone::TwoBoneIkError),
}

/// The ankle names [`find_feet`] knows, for messages.
fn known_ankles() -> String {
    NAMED_FEET
        .iter()
        .flat_map(|(_, sides)| sides.iter().map(|(ankle, _)| *ankle))
        .collect::<Vec<_>>()
        .join(", ")
}

/// One contact of one joint.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// The joint's name (the ankle or the toe).
    pub joint: String,
    /// First frame in contact (index into the clip's key times).
    pub start_frame: usize,
    /// Last frame in contact (inclusive).
    pub end_frame: usize,
    /// Time of the first frame, seconds.
    pub start_time: f32,
    /// Time of the last frame, seconds.
    pub end_time: f32,
    /// Where the joint is held, model space (the asset's length unit).
    pub pin: Vec3,
    /// The joint's largest distance, over the contact, from its position at the contact's
    /// first frame in the input clip, skeleton heights.
    pub slide_before: f32,
    /// ... and in the locked clip.
    pub slide_after: f32,
}

/// How far a foot's joints move during their contacts, in skeleton heights.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Slide {
    /// Largest distance, over every contact frame, of the joint from its position at the
    /// contact's first frame.
    pub max: f32,
    /// Mean of that distance over every contact frame.
    pub mean: f32,
}

/// One foot's contacts and slides.
#[derive(Clone, Debug, PartialEq)]
pub struct FootReport {
    /// The leg's label.
    pub label: String,
    /// The ankle joint's name.
    pub ankle: String,
    /// The toe joint's name, when there is one.
    pub toe: Option<String>,
    /// Contacts of the ankle, then of the toe, each in time order.
    pub contacts: Vec<Contact>,
    /// Slide in the input clip.
    pub before: Slide,
    /// Slide in the locked clip.
    pub after: Slide,
    /// The most the leg was lengthened to reach a pin (fraction of its length; see
    /// [`FootlockOptions::max_stretch`]).
    pub stretch: f32,
    /// Frames inside contacts whose target the leg did not reach (beyond even the
    /// stretched leg, or the knee's speed limit held it back).
    pub unreached: usize,
    /// The largest change of the knee angle in one frame beyond the source's change in
    /// that frame, degrees.
    pub knee_step_deg: f32,
}

/// A foot-locked clip and its report.
#[derive(Clone, Debug, PartialEq)]
pub struct Footlocked {
    /// The clip (same name as the input).
    pub clip: Clip,
    /// One report per leg, in leg order.
    pub feet: Vec<FootReport>,
    /// Frames (key times) processed.
    pub frames: usize,
    /// The frame rate implied by the key times (median spacing).
    pub fps: f32,
    /// The skeleton height (asset length unit) the thresholds and slides are relative to.
    pub height: f32,
    /// A [`Warning::NoContacts`] when no foot has a contact (with why); a note per foot
    /// without contacts when others have some; an [`Warning::Incomplete`] per foot with
    /// frames short of their targets.
    pub warnings: Vec<Warning>,
}

/// The scene's up direction in model space (unit length): [`SceneFrame::up_in_model`].
pub fn up_in_model(frame: &SceneFrame) -> Vec3 {
    frame.up_in_model()
}

/// Largest extent of the joints' rest positions (at least `f32::MIN_POSITIVE`).
fn rest_height(skeleton: &Skeleton) -> f32 {
    let rest = skeleton.model_rest_matrices();
    let (lo, hi) = rest.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), m| (lo.min(m.w_axis.truncate()), hi.max(m.w_axis.truncate())),
    );
    (hi - lo).max_element().max(f32::MIN_POSITIVE)
}

impl FootlockOptions {
    /// Checks every field.
    ///
    /// # Errors
    /// [`FootlockError::Option`] naming the first bad field.
    pub fn validate(&self) -> Result<(), FootlockError> {
        let checks: [(&'static str, f32, bool, &'static str); 8] = [
            ("height", self.height, self.height > 0.0, "expected > 0"),
            ("speed", self.speed, self.speed > 0.0, "expected > 0"),
            (
                "hysteresis",
                self.hysteresis,
                self.hysteresis >= 1.0,
                "expected >= 1",
            ),
            (
                "min_contact",
                self.min_contact,
                self.min_contact >= 0.0,
                "expected >= 0",
            ),
            ("blend", self.blend, self.blend >= 0.0, "expected >= 0"),
            (
                "max_stretch",
                self.max_stretch,
                self.max_stretch >= 0.0,
                "expected >= 0",
            ),
            (
                "soft",
                self.soft,
                (0.0..1.0).contains(&self.soft),
                "expected in [0, 1)",
            ),
            (
                "max_knee_speed_deg",
                self.max_knee_speed_deg,
                self.max_knee_speed_deg > 0.0,
                "expected > 0",
            ),
        ];
        for (name, value, ok, expected) in checks {
            if !(value.is_finite() && ok) {
                return Err(FootlockError::Option {
                    name,
                    value,
                    expected,
                });
            }
        }
        Ok(())
    }
}

/// Model-space positions of every joint for every frame, frame-major.
fn model_positions(
    parents: &[Option<JointIndex>],
    frames: &[Transform],
    model: &mut [Mat4],
    out: &mut Vec<Vec3>,
) -> Result<(), EvalError> {
    let joints = parents.len();
    out.clear();
    for local in frames.chunks_exact(joints.max(1)) {
        LocalToModelJob {
            parents,
            local,
            root_model: Mat4::IDENTITY,
            model,
        }
        .run()?;
        out.extend(model.iter().map(|m| m.w_axis.truncate()));
    }
    Ok(())
}

/// One joint's positions over all frames.
fn column(positions: &[Vec3], joints: usize, j: JointIndex) -> Vec<Vec3> {
    positions
        .iter()
        .skip(j.get())
        .step_by(joints.max(1))
        .copied()
        .collect()
}

/// Locks the feet of `legs` in `clip` (see the module docs). `up` is the up direction in
/// model space ([`up_in_model`]).
///
/// # Errors
/// [`FootlockError::NoLegs`], a bad option, a clip with fewer than two key times, or a clip
/// that does not fit the skeleton.
pub fn footlock(
    skeleton: &Skeleton,
    clip: &Clip,
    legs: &[Leg],
    up: Vec3,
    options: &FootlockOptions,
) -> Result<Footlocked, FootlockError> {
    options.validate()?;
    if legs.is_empty() {
        return Err(FootlockError::NoLegs);
    }
    let up = up.normalize_or_zero();
    let up = if up == Vec3::ZERO { Vec3::Y } else { up };
    let compiled = CompiledClip::new(clip, skeleton)?;
    let times = compiled.key_times();
    if times.len() < 2 {
        return Err(FootlockError::TooShort {
            frames: times.len(),
        });
    }
    let fps = compiled.fps().unwrap_or(30.0);
    let height = rest_height(skeleton);
    let joints = skeleton.len();
    let parents: Vec<Option<JointIndex>> = skeleton.parents().collect();
    let source = sample_frames(&compiled, &rest_locals(skeleton), &times)?;
    let mut model = vec![Mat4::IDENTITY; joints];
    let mut before = Vec::new();
    model_positions(&parents, &source, &mut model, &mut before)?;

    let frames_of = |seconds: f32| (seconds * fps).round().max(0.0) as usize;
    let thresholds = Thresholds {
        height_on: options.height * height,
        speed_on: options.speed * height,
        height_off: options.height * options.hysteresis * height,
        speed_off: options.speed * options.hysteresis * height,
        min_frames: frames_of(options.min_contact).max(2),
    };
    let blend = frames_of(options.blend).max(1);
    let mut speeds = Vec::new();
    let mut windows_of = |p: &[Vec3]| {
        let heights: Vec<f32> = p.iter().map(|x| x.dot(up)).collect();
        let ground = contacts::local_ground(&heights, frames_of(GROUND_WINDOW));
        let v = contacts::speeds(p, &times);
        let per_height: Vec<f32> = v.iter().map(|x| x / height).collect();
        let low: Vec<bool> = heights
            .iter()
            .zip(&ground)
            .map(|(h, g)| h - g <= thresholds.height_on)
            .collect();
        speeds.push(diagnose::FootSpeeds::of(
            &per_height,
            &low,
            thresholds.min_frames,
        ));
        contacts::detect(&heights, &v, &ground, &thresholds)
    };
    let limits = solve::Limits {
        soft: options.soft,
        max_stretch: options.max_stretch,
        knee_speed_rad: options.max_knee_speed_deg.to_radians(),
    };
    let reach = limits.reach_limit();
    // Per leg: ankle and toe positions, contact windows with pins.
    let mut plans = Vec::with_capacity(legs.len());
    for leg in legs {
        let ankle = column(&before, joints, leg.ankle);
        let toe = leg.toe.map(|t| column(&before, joints, t));
        let ankle_ranges = windows_of(&ankle);
        let toe_ranges = toe.as_deref().map(&mut windows_of).unwrap_or_default();
        let hips = column(&before, joints, leg.hip);
        let knees = column(&before, joints, leg.knee);
        let leg_length = (knees[0] - hips[0]).length() + (ankle[0] - knees[0]).length();
        let foot = toe.as_ref().map_or(0.0, |t| (t[0] - ankle[0]).length());
        let radius = reach * leg_length;
        let (aw, tw) = contacts::pin_windows(
            &ankle_ranges,
            &toe_ranges,
            &ankle,
            toe.as_deref(),
            options.pin_at,
            [
                contacts::Reach {
                    hips: &hips,
                    radius,
                },
                contacts::Reach {
                    hips: &hips,
                    radius: radius + foot,
                },
            ],
        );
        plans.push(solve::LegPlan {
            leg: leg.clone(),
            ankle: aw,
            toe: tw,
        });
    }

    let mut locked = source.clone();
    let mut solver = solve::Solver::new(skeleton, &before, &times, &plans, limits);
    for (f, local) in locked.chunks_exact_mut(joints).enumerate() {
        solver.frame(f, blend, local, &mut model)?;
    }
    let mut after = Vec::new();
    model_positions(&parents, &locked, &mut model, &mut after)?;

    let mut mask = ChannelMask::none(joints);
    for (leg, &stretch) in legs.iter().zip(&solver.stretch) {
        for j in [leg.hip, leg.knee, leg.ankle] {
            mask.rotation[j.get()] = true;
        }
        if stretch > 0.0 {
            mask.translation[leg.knee.get()] = true;
            mask.translation[leg.ankle.get()] = true;
        }
    }
    let baked = bake(&clip.name, &times, &locked, &mask)?;
    let mut out = clip.clone();
    let rebaked = |channel: &[bool], j: JointIndex| channel.get(j.get()).copied().unwrap_or(false);
    out.tracks.retain(|t| match t.target {
        TrackTarget::Rotation(j) => !rebaked(&mask.rotation, j),
        TrackTarget::Translation(j) => !rebaked(&mask.translation, j),
        _ => true,
    });
    out.tracks.extend(baked.tracks);
    if plans.iter().all(|p| p.ankle.is_empty() && p.toe.is_empty()) {
        // Nothing was locked: the input clip, not a re-keyed copy of it.
        out = clip.clone();
    }

    let feet: Vec<FootReport> = plans
        .iter()
        .enumerate()
        .map(|(i, plan)| FootReport {
            stretch: solver.stretch[i],
            unreached: solver.unreached[i],
            knee_step_deg: solver.knee_step[i].to_degrees(),
            ..report(skeleton, plan, &times, &before, &after, joints, height)
        })
        .collect();
    let mut warnings = Vec::new();
    let none = feet.iter().all(|f| f.contacts.is_empty());
    if none {
        warnings.push(no_contacts(&clip.name, &speeds, fps, options));
    }
    for foot in &feet {
        let location = format!("clip {:?}, foot {} ({})", clip.name, foot.label, foot.ankle);
        if foot.contacts.is_empty() {
            if !none {
                warnings.push(Warning::Note {
                    location,
                    message: "no contact found; left as it was".into(),
                });
            }
        } else if foot.unreached > 0 {
            warnings.push(Warning::Incomplete {
                location,
                message: format!(
                    "{} frame(s) out of reach even with the leg {:.0}% longer; the foot slides {:.2e} of the height there",
                    foot.unreached,
                    100.0 * options.max_stretch,
                    foot.after.max
                ),
            });
        }
    }
    Ok(Footlocked {
        clip: out,
        feet,
        warnings,
        frames: times.len(),
        fps,
        height,
    })
}

/// One leg's report from the source and locked positions.
fn report(
    skeleton: &Skeleton,
    plan: &solve::LegPlan,
    times: &[f32],
    before: &[Vec3],
    after: &[Vec3],
    joints: usize,
    height: f32,
) -> FootReport {
    let name = |j: JointIndex| skeleton.joint(j).name.clone();
    let leg = &plan.leg;
    let mut contacts = Vec::new();
    let mut slides = [(0.0f32, 0.0f64, 0usize); 2];
    let joints_and_windows: Vec<(JointIndex, &[Window])> =
        std::iter::once((leg.ankle, &plan.ankle[..]))
            .chain(leg.toe.map(|t| (t, &plan.toe[..])))
            .collect();
    for (j, windows) in joints_and_windows {
        let (src, out) = (column(before, joints, j), column(after, joints, j));
        for w in windows {
            let one = std::slice::from_ref(w);
            contacts.push(Contact {
                joint: name(j),
                start_frame: w.start,
                end_frame: w.end,
                start_time: times[w.start],
                end_time: times[w.end],
                pin: w.pin,
                slide_before: contacts::slide(one, &src).0 / height,
                slide_after: contacts::slide(one, &out).0 / height,
            });
        }
        for (slide, positions) in slides.iter_mut().zip([&src, &out]) {
            let (max, sum, n) = contacts::slide(windows, positions);
            slide.0 = slide.0.max(max);
            slide.1 += sum;
            slide.2 += n;
        }
    }
    let to_slide = |(max, sum, n): (f32, f64, usize)| Slide {
        max: max / height,
        mean: if n == 0 {
            0.0
        } else {
            (sum / n as f64) as f32 / height
        },
    };
    FootReport {
        label: leg.label.clone(),
        ankle: name(leg.ankle),
        toe: leg.toe.map(name),
        contacts,
        before: to_slide(slides[0]),
        after: to_slide(slides[1]),
        stretch: 0.0,
        unreached: 0,
        knee_step_deg: 0.0,
    }
}

/// The warning for a clip in which no foot has a contact, saying why.
fn no_contacts(
    clip: &str,
    speeds: &[diagnose::FootSpeeds],
    fps: f32,
    options: &FootlockOptions,
) -> Warning {
    let location = format!("clip {clip:?}");
    match diagnose::no_contact_cause(speeds, fps, options) {
        None => Warning::NoContacts {
            location,
            message: "no foot contact found: the feet slow down while on the ground, but not for long enough; the legs are left as they were".into(),
            suggested_fps: None,
        },
        Some(cause) => {
            let mut message = format!(
                "no foot contact found: no foot stays under the contact speed of {} heights/s for {} s while on the ground (the slowest does {:.3}); the feet's median speed is {:.1} m/s taking the skeleton as {} m tall; the legs are left as they were",
                options.speed,
                options.min_contact,
                cause.slowest,
                cause.median_m_s,
                diagnose::HUMAN_HEIGHT_M
            );
            if let Some((factor, fps_suggested)) = cause.rate {
                message += &format!(
                    "; that is faster than a human's feet move most of the time, so the clip likely plays about {factor:.1}x too fast: it may have been recorded at {fps_suggested} fps, not {fps:.0}"
                );
            }
            Warning::NoContacts {
                location,
                message,
                suggested_fps: cause.rate.map(|(_, r)| r),
            }
        }
    }
}
