//! Joint-name conventions of the skeletons rigport meets (CMU ASF, cgspeed BVH, Mixamo,
//! Bandai, Pinocchio, the demo), the one place names are read: the conventions' body roles
//! ([`CONVENTIONS`], the retarget maps' fallback), finding the feet by name or as named, and
//! the name helpers. Names are evidence only where the structure cannot tell
//! (`crate::retarget::roles`): which side a chain is on when the pose does not show it, end
//! sites and twist joints.

use rigport_model::{JointIndex, Skeleton};

use crate::footlock::{FootlockError, Leg};

/// Ankle and toe joint names per side, for the skeletons rigport meets most: `(label,
/// [(left ankle, left toe), (right ankle, right toe)])`. Names compare without case and
/// after any namespace prefix (`mixamorig:LeftFoot` is `LeftFoot`).
///
/// - CMU ASF/AMC: bones `lfoot`/`ltoes`; rigport puts each ASF joint at its bone's start,
///   so `lfoot` is the ankle and `ltoes` the ball of the foot.
/// - cgspeed's CMU BVH and Mixamo (and most Maya/MotionBuilder HumanIK exports):
///   `LeftFoot`/`LeftToeBase`.
/// - Bandai Namco Research motion dataset BVH: `Foot_L`/`Toes_L`.
/// - The demo character: `foot_l`/`toe_l`.
pub const NAMED_FEET: [(&str, [(&str, &str); 2]); 4] = [
    ("CMU ASF", [("lfoot", "ltoes"), ("rfoot", "rtoes")]),
    (
        "cgspeed BVH / Mixamo",
        [("LeftFoot", "LeftToeBase"), ("RightFoot", "RightToeBase")],
    ),
    (
        "Bandai Namco BVH",
        [("Foot_L", "Toes_L"), ("Foot_R", "Toes_R")],
    ),
    ("rigport demo", [("foot_l", "toe_l"), ("foot_r", "toe_r")]),
];

/// A naming convention: `(role, joint name)` pairs. Names compare without case and after
/// any namespace prefix (`mixamorig:LeftArm` is `LeftArm`).
#[derive(Clone, Copy, Debug)]
pub struct Convention {
    /// A label for reports.
    pub label: &'static str,
    /// `(role, joint name)`.
    pub joints: &'static [(&'static str, &'static str)],
    /// The joint at the pelvis (where the hips' position is measured).
    pub pelvis: &'static str,
}

/// CMU's ASF skeletons as rigport names them: each ASF bone becomes a joint at the bone's
/// start, so `lfemur` is at the hip, `ltibia` at the knee, `lfoot` at the ankle.
pub const CMU_ASF: Convention = Convention {
    label: "CMU ASF",
    pelvis: "root",
    joints: &[
        ("Hips", "root"),
        ("Spine", "lowerback"),
        ("Spine1", "upperback"),
        ("Chest", "thorax"),
        ("Neck", "lowerneck"),
        ("Neck1", "upperneck"),
        ("Head", "head"),
        ("LeftShoulder", "lclavicle"),
        ("LeftUpperArm", "lhumerus"),
        ("LeftLowerArm", "lradius"),
        ("LeftHand", "lwrist"),
        ("RightShoulder", "rclavicle"),
        ("RightUpperArm", "rhumerus"),
        ("RightLowerArm", "rradius"),
        ("RightHand", "rwrist"),
        ("LeftUpperLeg", "lfemur"),
        ("LeftLowerLeg", "ltibia"),
        ("LeftFoot", "lfoot"),
        ("LeftToes", "ltoes"),
        ("RightUpperLeg", "rfemur"),
        ("RightLowerLeg", "rtibia"),
        ("RightFoot", "rfoot"),
        ("RightToes", "rtoes"),
    ],
};

/// cgspeed's BVH conversion of the CMU database (`LowerBack`, `Spine`, `Spine1`).
pub const CGSPEED_BVH: Convention = Convention {
    label: "cgspeed BVH",
    pelvis: "Hips",
    joints: &[
        ("Hips", "Hips"),
        ("Spine", "LowerBack"),
        ("Spine1", "Spine"),
        ("Chest", "Spine1"),
        ("Neck", "Neck"),
        ("Neck1", "Neck1"),
        ("Head", "Head"),
        ("LeftShoulder", "LeftShoulder"),
        ("LeftUpperArm", "LeftArm"),
        ("LeftLowerArm", "LeftForeArm"),
        ("LeftHand", "LeftHand"),
        ("RightShoulder", "RightShoulder"),
        ("RightUpperArm", "RightArm"),
        ("RightLowerArm", "RightForeArm"),
        ("RightHand", "RightHand"),
        ("LeftUpperLeg", "LeftUpLeg"),
        ("LeftLowerLeg", "LeftLeg"),
        ("LeftFoot", "LeftFoot"),
        ("LeftToes", "LeftToeBase"),
        ("RightUpperLeg", "RightUpLeg"),
        ("RightLowerLeg", "RightLeg"),
        ("RightFoot", "RightFoot"),
        ("RightToes", "RightToeBase"),
    ],
};

/// Mixamo and most HumanIK exports (`Spine`, `Spine1`, `Spine2`; `mixamorig:` prefixes).
pub const MIXAMO: Convention = Convention {
    label: "Mixamo",
    pelvis: "Hips",
    joints: &[
        ("Hips", "Hips"),
        ("Spine", "Spine"),
        ("Spine1", "Spine1"),
        ("Chest", "Spine2"),
        ("Neck", "Neck"),
        ("Head", "Head"),
        ("LeftShoulder", "LeftShoulder"),
        ("LeftUpperArm", "LeftArm"),
        ("LeftLowerArm", "LeftForeArm"),
        ("LeftHand", "LeftHand"),
        ("RightShoulder", "RightShoulder"),
        ("RightUpperArm", "RightArm"),
        ("RightLowerArm", "RightForeArm"),
        ("RightHand", "RightHand"),
        ("LeftUpperLeg", "LeftUpLeg"),
        ("LeftLowerLeg", "LeftLeg"),
        ("LeftFoot", "LeftFoot"),
        ("LeftToes", "LeftToeBase"),
        ("RightUpperLeg", "RightUpLeg"),
        ("RightLowerLeg", "RightLeg"),
        ("RightFoot", "RightFoot"),
        ("RightToes", "RightToeBase"),
    ],
};

/// The Bandai Namco Research motion dataset's BVH (`UpperArm_L`, `Toes_R`).
pub const BANDAI_NAMCO_BVH: Convention = Convention {
    label: "Bandai Namco BVH",
    pelvis: "Hips",
    joints: &[
        ("Hips", "Hips"),
        ("Spine", "Spine"),
        ("Chest", "Chest"),
        ("Neck", "Neck"),
        ("Head", "Head"),
        ("LeftShoulder", "Shoulder_L"),
        ("LeftUpperArm", "UpperArm_L"),
        ("LeftLowerArm", "LowerArm_L"),
        ("LeftHand", "Hand_L"),
        ("RightShoulder", "Shoulder_R"),
        ("RightUpperArm", "UpperArm_R"),
        ("RightLowerArm", "LowerArm_R"),
        ("RightHand", "Hand_R"),
        ("LeftUpperLeg", "UpperLeg_L"),
        ("LeftLowerLeg", "LowerLeg_L"),
        ("LeftFoot", "Foot_L"),
        ("LeftToes", "Toes_L"),
        ("RightUpperLeg", "UpperLeg_R"),
        ("RightLowerLeg", "LowerLeg_R"),
        ("RightFoot", "Foot_R"),
        ("RightToes", "Toes_R"),
    ],
};

/// rigport's demo character, a Pinocchio-style rig: each joint sits at the head of the
/// bone it drives and is named after the bone's end point (`shin_l` is at the hip and
/// turns the thigh, `toe_l` is at the ankle and turns the foot). It has no toe-tip joint.
pub const RIGPORT_DEMO: Convention = Convention {
    label: "rigport demo",
    pelvis: "hips",
    joints: &[
        ("Hips", "hips"),
        ("Spine", "spine"),
        ("Spine1", "chest"),
        ("Chest", "neck"),
        ("Neck", "head"),
        ("Head", "head_top"),
        ("LeftShoulder", "upper_arm_l"),
        ("LeftUpperArm", "forearm_l"),
        ("LeftLowerArm", "hand_l"),
        ("LeftHand", "fingertip_l"),
        ("RightShoulder", "upper_arm_r"),
        ("RightUpperArm", "forearm_r"),
        ("RightLowerArm", "hand_r"),
        ("RightHand", "fingertip_r"),
        ("LeftUpperLeg", "shin_l"),
        ("LeftLowerLeg", "foot_l"),
        ("LeftFoot", "toe_l"),
        ("RightUpperLeg", "shin_r"),
        ("RightLowerLeg", "foot_r"),
        ("RightFoot", "toe_r"),
    ],
};

/// Pinocchio's `HumanSkeleton` (skeleton.cpp) as rigport names it: one joint per bone,
/// `bone_<k>` at the head of the bone ending at Pinocchio joint `k`, and `root` at joint 0
/// (the shoulders). Pinocchio's spine hangs from the shoulders (`bone_1` shoulders to
/// back, `bone_2` back to hips), so the source's hips drive the root, its spine `bone_1`,
/// its chest `bone_2` (the order of the hierarchy kept: a map may not reverse it); the hip
/// bones `bone_4`/`bone_8` follow `bone_2`, and the pelvis point is their head. The
/// template has no hand or toe joints. Which side is left is decided from the rest pose
/// ([`crate::retarget::auto_map`]): Pinocchio's `l` joints lie at -x of a template that faces +z, the
/// character's right.
pub const PINOCCHIO_HUMAN: Convention = Convention {
    label: "Pinocchio human template",
    pelvis: "bone_4",
    joints: &[
        ("Hips", "root"),
        ("Spine", "bone_1"),
        ("Chest", "bone_2"),
        ("Neck", "bone_3"),
        ("LeftShoulder", "bone_12"),
        ("LeftUpperArm", "bone_13"),
        ("LeftLowerArm", "bone_14"),
        ("RightShoulder", "bone_15"),
        ("RightUpperArm", "bone_16"),
        ("RightLowerArm", "bone_17"),
        ("LeftUpperLeg", "bone_5"),
        ("LeftLowerLeg", "bone_6"),
        ("LeftFoot", "bone_7"),
        ("RightUpperLeg", "bone_9"),
        ("RightLowerLeg", "bone_10"),
        ("RightFoot", "bone_11"),
    ],
};

/// Every built-in convention, in the order [`crate::retarget::auto_map`] tries them on ties.
pub const CONVENTIONS: [Convention; 6] = [
    CMU_ASF,
    CGSPEED_BVH,
    MIXAMO,
    BANDAI_NAMCO_BVH,
    RIGPORT_DEMO,
    PINOCCHIO_HUMAN,
];

/// Pinocchio's `HumanSkeleton` (skeleton.cpp) as rigport names it (one joint per bone,
/// `bone_<k>` at the head of the bone that ends at Pinocchio joint `k`): the left leg is
/// hip `bone_5` (Pinocchio `lthigh`), knee `bone_6`, ankle `bone_7` (the bone from `lankle`
/// to `lfoot`); the right leg `bone_9`, `bone_10`, `bone_11`. The template has no toe
/// joint. `(joint, its parent)` pairs that must all hold, so another 18-joint Pinocchio
/// skeleton is not taken for a human.
const PINOCCHIO_HUMAN_PARENTS: [(&str, &str); 17] = [
    ("bone_1", "root"),
    ("bone_2", "bone_1"),
    ("bone_3", "root"),
    ("bone_4", "bone_2"),
    ("bone_5", "bone_4"),
    ("bone_6", "bone_5"),
    ("bone_7", "bone_6"),
    ("bone_8", "bone_2"),
    ("bone_9", "bone_8"),
    ("bone_10", "bone_9"),
    ("bone_11", "bone_10"),
    ("bone_12", "root"),
    ("bone_13", "bone_12"),
    ("bone_14", "bone_13"),
    ("bone_15", "root"),
    ("bone_16", "bone_15"),
    ("bone_17", "bone_16"),
];

/// Which side of the body a joint's name puts it on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NamedSide {
    /// The character's left.
    Left,
    /// The character's right.
    Right,
}

/// The body words CMU's ASF bone names put after their `l`/`r` side letter (`lfemur`).
const CMU_PARTS: [&str; 12] = [
    "hipjoint", "femur", "tibia", "foot", "toes", "clavicle", "humerus", "radius", "wrist", "hand",
    "fingers", "thumb",
];

/// The side a joint's name states, in the conventions rigport meets: a `Left`/`Right`
/// word anywhere (`LeftUpLeg`, `mixamorig:RightArm`, `upperarm_left`), an `L`/`R` token
/// before or after a separator (`UpperLeg_L`, `L_Hip`, `thigh.l`, `Bip01 L Thigh`), an
/// upper-case `L`/`R` before an upper-case letter (cgspeed's `LHipJoint`, `RThumb`) or
/// CMU's lower-case `l`/`r` before a body word (`lfemur`). `None` when the name says
/// nothing (`Hips`, `bone_5`, `j12`).
pub fn named_side(name: &str) -> Option<NamedSide> {
    let bare = bare(name);
    let lower = bare.to_ascii_lowercase();
    let has_left = lower.contains("left");
    let has_right = lower.contains("right");
    if has_left != has_right {
        return Some(if has_left {
            NamedSide::Left
        } else {
            NamedSide::Right
        });
    }
    let side = |c: char| match c.to_ascii_lowercase() {
        'l' => Some(NamedSide::Left),
        'r' => Some(NamedSide::Right),
        _ => None,
    };
    let tokens: Vec<&str> = bare
        .split(['_', '.', ' ', '-'])
        .filter(|t| !t.is_empty())
        .collect();
    if tokens.len() > 1 {
        for t in &tokens {
            if t.len() == 1 {
                if let Some(s) = t.chars().next().and_then(side) {
                    return Some(s);
                }
            }
        }
    }
    let mut chars = bare.chars();
    if let (Some(first), Some(second)) = (chars.next(), chars.next()) {
        if matches!(first, 'L' | 'R') && second.is_ascii_uppercase() {
            return side(first);
        }
        if matches!(first, 'l' | 'r') && CMU_PARTS.contains(&&lower[1..]) {
            return side(first);
        }
    }
    None
}

/// Whether a joint's name marks an end site rather than a joint that turns anything: the
/// BVH importer names an `End Site` `<parent>_end`, Mixamo `HeadTop_End`, 3ds Max `... Nub`.
pub fn is_end_site(name: &str) -> bool {
    let lower = bare(name).to_ascii_lowercase();
    lower.ends_with("end") || lower.ends_with("nub") || lower.ends_with("site")
}

/// Whether a joint's name marks a twist (roll) joint, which sits along a bone rather than
/// at a joint of the body (`upperarm_twist_01`, `LeftArmRoll`).
pub fn is_twist(name: &str) -> bool {
    let lower = bare(name).to_ascii_lowercase();
    lower.contains("twist") || lower.contains("roll")
}

/// A joint name without its namespace (`mixamorig:LeftFoot` -> `LeftFoot`).
fn bare(name: &str) -> &str {
    name.rsplit([':', '|']).next().unwrap_or(name)
}

/// Whether two joint names name the same joint under the conventions' rule: equal
/// without case and after any namespace prefix (`mixamorig:LeftFoot` is `leftfoot`).
///
/// ```
/// use rigport_ik::naming::same_joint_name;
/// assert!(same_joint_name("mixamorig:LeftFoot", "leftfoot"));
/// assert!(!same_joint_name("LeftFoot", "LeftToeBase"));
/// ```
pub fn same_joint_name(a: &str, b: &str) -> bool {
    bare(a).eq_ignore_ascii_case(bare(b))
}

/// The joint whose bare name equals `wanted` (ignoring case); the first in skeleton order.
pub(crate) fn find_bare(skeleton: &Skeleton, wanted: &str) -> Option<JointIndex> {
    skeleton
        .joints()
        .iter()
        .position(|j| bare(&j.name).eq_ignore_ascii_case(wanted))
        .map(|i| JointIndex(i as u32))
}

/// Whether `skeleton` is Pinocchio's human template, joint for joint
/// ([`PINOCCHIO_HUMAN_PARENTS`]).
pub(crate) fn is_pinocchio_human(skeleton: &Skeleton) -> bool {
    skeleton.len() == PINOCCHIO_HUMAN_PARENTS.len() + 1
        && PINOCCHIO_HUMAN_PARENTS.iter().all(|(joint, parent)| {
            skeleton
                .find(joint)
                .and_then(|j| skeleton.joint(j).parent)
                .is_some_and(|p| skeleton.joint(p).name == *parent)
        })
}

/// The leg of an ankle: its parent (knee) and grandparent (hip).
///
/// # Errors
/// [`FootlockError::NotALeg`] when the ankle has fewer than two ancestors, or the toe is not
/// a descendant of the ankle.
pub fn leg_of(
    skeleton: &Skeleton,
    label: &str,
    ankle: JointIndex,
    toe: Option<JointIndex>,
) -> Result<Leg, FootlockError> {
    let name = |j: JointIndex| skeleton.joint(j).name.clone();
    let not_a_leg = |why: &str| FootlockError::NotALeg {
        joint: name(ankle),
        why: why.to_string(),
    };
    let knee = skeleton
        .joint(ankle)
        .parent
        .ok_or_else(|| not_a_leg("it has no parent (knee)"))?;
    let hip = skeleton
        .joint(knee)
        .parent
        .ok_or_else(|| not_a_leg("its parent has no parent (hip)"))?;
    if let Some(toe) = toe {
        let mut cur = skeleton.joint(toe).parent;
        while cur.is_some_and(|c| c != ankle) {
            cur = cur.and_then(|c| skeleton.joint(c).parent);
        }
        if cur.is_none() {
            return Err(FootlockError::NotALeg {
                joint: name(toe),
                why: format!("it is not below the ankle {:?}", name(ankle)),
            });
        }
    }
    Ok(Leg {
        label: label.to_string(),
        hip,
        knee,
        ankle,
        toe,
    })
}

/// Finds the feet by name (see [`NAMED_FEET`] and Pinocchio's human template): the first
/// convention whose ankles exist; a toe is used when that convention's toe joint exists.
/// Returns the legs (left, then right, where found) and the convention's label.
///
/// # Errors
/// [`FootlockError::NoFeet`] when no convention matches, [`FootlockError::NotALeg`] when a
/// named ankle has no knee and hip above it.
pub fn find_feet(skeleton: &Skeleton) -> Result<(Vec<Leg>, &'static str), FootlockError> {
    for (convention, sides) in NAMED_FEET {
        let mut legs = Vec::new();
        for ((ankle, toe), side) in sides.iter().zip(["left", "right"]) {
            if let Some(a) = find_bare(skeleton, ankle) {
                legs.push(leg_of(skeleton, side, a, find_bare(skeleton, toe))?);
            }
        }
        if !legs.is_empty() {
            return Ok((legs, convention));
        }
    }
    let is_human = is_pinocchio_human(skeleton);
    if is_human {
        let mut legs = Vec::new();
        for (side, ankle) in [("left", "bone_7"), ("right", "bone_11")] {
            if let Some(a) = skeleton.find(ankle) {
                legs.push(leg_of(skeleton, side, a, None)?);
            }
        }
        return Ok((legs, "Pinocchio human template"));
    }
    Err(FootlockError::NoFeet)
}

/// The legs of explicitly named feet: `(ankle, optional toe)` joint names, matched exactly.
/// Labels are the ankles' names.
///
/// # Errors
/// [`FootlockError::UnknownJoint`] for a name the skeleton lacks, [`FootlockError::NotALeg`]
/// as [`leg_of`], [`FootlockError::SharedLeg`] when two feet share a leg joint.
pub fn named_feet(
    skeleton: &Skeleton,
    feet: &[(String, Option<String>)],
) -> Result<Vec<Leg>, FootlockError> {
    let find = |name: &str| {
        skeleton
            .find(name)
            .ok_or_else(|| FootlockError::UnknownJoint {
                name: name.to_string(),
            })
    };
    let mut legs: Vec<Leg> = Vec::with_capacity(feet.len());
    for (ankle, toe) in feet {
        let a = find(ankle)?;
        let t = toe.as_deref().map(find).transpose()?;
        legs.push(leg_of(skeleton, ankle, a, t)?);
    }
    check_disjoint(skeleton, &legs)?;
    Ok(legs)
}

/// Two legs may not share a hip, knee or ankle (each joint gets one solve per frame).
fn check_disjoint(skeleton: &Skeleton, legs: &[Leg]) -> Result<(), FootlockError> {
    for (i, a) in legs.iter().enumerate() {
        for b in &legs[i + 1..] {
            let ja = [a.hip, a.knee, a.ankle];
            if let Some(&shared) = [b.hip, b.knee, b.ankle].iter().find(|j| ja.contains(j)) {
                return Err(FootlockError::SharedLeg {
                    joint: skeleton.joint(shared).name.clone(),
                });
            }
        }
    }
    Ok(())
}

/// The legs for `specs`, each `ANKLE` or `ANKLE,TOE` (joint names, matched exactly); with
/// no specs, the feet [`find_feet`] finds. Also returns how they were found (the naming
/// convention, or `"named"`).
///
/// # Errors
/// As [`named_feet`] and [`find_feet`].
pub fn resolve_feet(
    skeleton: &Skeleton,
    specs: &[String],
) -> Result<(Vec<Leg>, &'static str), FootlockError> {
    if specs.is_empty() {
        return find_feet(skeleton);
    }
    let feet: Vec<(String, Option<String>)> = specs
        .iter()
        .map(|f| match f.split_once(',') {
            Some((a, t)) => (a.trim().to_string(), Some(t.trim().to_string())),
            None => (f.trim().to_string(), None),
        })
        .collect();
    Ok((named_feet(skeleton, &feet)?, "named"))
}
